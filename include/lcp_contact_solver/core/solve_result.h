#pragma once

#include "lcp_contact_solver/core/solver_params.h"

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace lcp_contact_solver::core {

enum class ContactState : std::uint8_t {
  kOpen = 0,     // no force: separating or just touching
  kStick = 1,    // force strictly inside the friction cone (bilateral rows: always)
  kSlip = 2,     // force on the cone boundary
  kIgnored = 3,  // excluded by minW or maxF; force zero
  kClosed = 4,   // force and no friction to stick or slip with: frictionless, or μ = 0
};
constexpr int kContactStateCount = 5;

enum class SolveStatus : std::uint8_t {
  kConverged = 0,     // residual reached the tolerance
  kMaxIterations,     // iteration or pivot cap reached first; best iterate returned
  kZeroDiagonal,      // a row has W_ii <= 0 and minW does not exclude it: GS cannot run
  kNotApplicable,     // this solver cannot treat this problem (e.g. Lemke + friction)
  kRayTermination,    // Lemke ended on a secondary ray: no solution found
  kNumericalFailure,  // a pivot or step became non-finite; best finite iterate kept
  kInvalidInput,      // the problem or parameters failed validation
  kTimeBudget,        // SolverParams::time_budget ran out; best iterate returned
};

const char* statusName(SolveStatus status);
const char* stateName(ContactState state);

struct SolveResult {
  Eigen::VectorXd forces;            // λ, one entry per row (N, or N·s for impulses)
  Eigen::VectorXd d;                 // W λ + d_free with the W that was solved (regularized)
  std::vector<ContactState> states;  // one per contact
  SolveStatus status = SolveStatus::kInvalidInput;
  bool converged = false;
  // Sweeps (pgs, nlgs), pivots (lemke), iterations (apgd), nlgs sweeps + Newton steps
  // (newton); summed over maxF re-solves. On a problem solved by islands, the most any island
  // took (the islands run side by side).
  int iterations = 0;
  // The work: `iterations` summed over the islands too (equal to it on a problem solved whole).
  int total_iterations = 0;
  int resolves = 0;  // extra solves triggered by maxF
  // The solver's own stopping measure at exit (the residual of the problem it solved: for
  // a pyramid friction model, the pyramid's natural-map residual).
  double solver_error = 0.0;
  // Solver-independent residual (residual.h): always the Coulomb disc natural map, so a
  // pyramid solution (friction_model below) keeps a nonzero residual where it slides or
  // sticks outside the disc; its own pyramid residual is in solver_error.
  double residual = 0.0;
  // The friction law the forces solve: kCoulombDisc unless pgs or lemke solved a problem
  // with friction under a pyramid SolverParams::friction_model.
  FrictionModel friction_model = FrictionModel::kCoulombDisc;
  double solve_time = 0.0;  // wall time of the solve, seconds
  // Name of the solver that ran; for auto the path of the portfolio, "auto:" and the
  // members in the order they ran joined by "->" (e.g. "auto:newton->prox"); on a problem
  // solved by islands, the path of the island that took longest.
  std::string solver;
  // auto: (member, seconds) per stage of that path, in order; empty for a fixed solver.
  std::vector<std::pair<std::string, double>> stages;
  // The unbuilt Gauss-Seidel ran on the problem's body form (build_lcp = false): W was
  // never assembled. False for every built solve.
  bool unbuilt = false;
  std::string message;                   // human-readable detail for non-converged statuses
  std::vector<double> residual_history;  // per sweep/pivot, only with displayDebug
};

}  // namespace lcp_contact_solver::core
