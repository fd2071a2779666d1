// Position-error correction and constraint softness on the normal rows (Baumgarte / ODE's
// ERP and CFM), applied by ContactSolver before the kernel runs.
//
// A solve that only asks for d_n ≥ 0 leaves an existing penetration where it is, and a
// velocity-level one lets it grow by round-off step after step. Baumgarte's feedback asks
// instead for  Ċ + β C / h ≥ 0  with C = gap (< 0 penetrating). Multiplied by h it is
// position-level:  h·v_n + β·gap ≥ 0,  so for a contact with gap < 0:
//   position level (d in m, SOFA's d_free):   d_free_n += β · gap
//   velocity level (d in m/s):                d_free_n += β · gap / h
// and each solve removes the fraction β of the penetration. A positive gap is left to the
// caller's d_free (speculative contact). Softness s adds s·λ_n to d_n (W_nn += s): the
// contact gives way, and with β it is a spring of stiffness k = β / s (position level;
// β / (s·h) at velocity level), so a resting load F settles at a penetration F / k.
// β = 0 and s = 0 leave the problem untouched, and cost nothing.
#pragma once

#include "lcp_contact_solver/core/problem.h"
#include "lcp_contact_solver/core/solver_params.h"

#include <cstddef>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace lcp_contact_solver::core {

// The contact's β and s: its own, or the parameters' for kUseDefault. Bilateral: 0.
double effectiveErp(const Contact& contact, const SolverParams& params);
double effectiveSoftness(const Contact& contact, const SolverParams& params);

// True when some contact gets a correction (β > 0 and gap < 0) or softness (s > 0).
bool needsStabilization(const Problem& problem, const SolverParams& params);

// Applies both to *problem (d_free and the diagonal of W). Returns an empty string, or why
// it cannot (velocity level without a time step).
std::string applyStabilization(const SolverParams& params, Problem* problem);

// The values applyStabilizationInPlace overwrote, to put back bit for bit.
struct StabilizationUndo {
  std::vector<std::pair<Eigen::Index, double>> d_free;  // row, value before
  std::vector<std::pair<double*, double>> w;            // W's diagonal entry, value before
  std::shared_ptr<const BodyCompliance> bodies;         // the body form before softness
  bool bodies_changed = false;

  void restore(Problem* problem) const;
};

// applyStabilization without copying W: d_free's normal rows and W's normal diagonal are
// changed where they are, the old values kept in *undo. The numbers are those of
// applyStabilization. Returns false, with nothing changed, when it cannot: a block-sparse W
// without the diagonal block a soft contact needs (applyStabilization inserts one). On an
// error (*error set, as applyStabilization's) nothing is changed either.
bool applyStabilizationInPlace(const SolverParams& params, Problem* problem, StabilizationUndo* undo,
                               std::string* error);

}  // namespace lcp_contact_solver::core
