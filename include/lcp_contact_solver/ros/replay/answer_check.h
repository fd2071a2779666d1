// An independent check of a recorded answer: the forces the node published for a problem,
// judged on that problem alone, with no second solve. A change detector (replaying a bag and
// comparing with the forces it recorded) only says the answer did not change; this says the
// recorded answer is right:
//   - the residual recomputed from the recorded λ and the problem's W and d_free (the core's
//     natural map, residual.h, after the same Baumgarte/softness the solve applied) agrees
//     with the residual the node reported in its SolverStats, and a converged solve's is at
//     most the tolerance (stopping_rule residual);
//   - each contact's recorded state is the one its λ gives (classifyContacts);
//   - physical invariants: unilateral rows push (λ ≥ 0), friction inside its cone (the disc
//     |λ_t| ≤ μ λ_n, or each tangent |λ_ti| ≤ μ λ_n for the pyramid models), ignored
//     contacts carry nothing.
#pragma once

#include "lcp_contact_solver/core/problem.h"
#include "lcp_contact_solver/core/solver_params.h"

#include <lcp_contact_solver/ConstraintForces.h>
#include <lcp_contact_solver/SolverStats.h>
#include <ros/time.h>

#include <cstddef>
#include <string>

namespace lcp_contact_solver_ros {

namespace lcs = ::lcp_contact_solver;

// One answer.
struct AnswerCheck {
  std::string unfit;      // non-empty: the forces do not fit the problem (counts, ids, rows, NaN)
  double residual = 0.0;  // recomputed (dimensionless, as SolverStats::residual)
  std::size_t state_differences = 0;
  std::size_t negative_normals = 0;  // unilateral rows with λ < 0
  std::size_t outside_cone = 0;      // friction beyond μ λ_n
  std::size_t ignored_with_force = 0;
  std::string first_violation;  // the first of the above, with its contact

  bool invariantsHold() const {
    return unfit.empty() && state_differences + negative_normals + outside_cone + ignored_with_force == 0;
  }
};

// Checks `forces` (the node's answer) on `problem` (as toProblem built it from the messages)
// solved with `params`.
AnswerCheck checkAnswer(const lcs::core::Problem& problem, const lcs::core::SolverParams& params,
                        const lcp_contact_solver::ConstraintForces& forces);

// The recomputed residual against the reported one: equal up to rounding (the same formula
// on the same numbers, W λ summed in another order): |a − b| ≤ 1e-6 max(a, b) + 1e-12.
bool residualsAgree(double recomputed, double reported);

// Over a whole replay: every recorded answer of the bag (cycles with recorded forces).
struct AnswerChecks {
  std::size_t checked = 0;
  std::size_t failed = 0;  // answers with at least one of the faults below
  std::size_t unfit = 0;
  std::size_t residual_differs = 0;      // recomputed ≠ the recorded SolverStats' residual
  std::size_t above_tolerance = 0;       // recorded as converged, recomputed residual > tolerance
  std::size_t invariant_failures = 0;    // states, signs, cone, ignored
  std::size_t without_stats = 0;         // no recorded SolverStats to hold the residual to
  double max_residual = 0.0;             // recomputed
  double max_residual_difference = 0.0;  // |recomputed − reported|
  std::string first_failure;             // with its stamp

  // `stats` may be null. Returns false when this answer failed.
  bool add(const AnswerCheck& check, const lcp_contact_solver::SolverStats* stats,
           const lcs::core::SolverParams& params, const ros::Time& stamp);
  bool passed() const { return failed == 0; }
};

}  // namespace lcp_contact_solver_ros
