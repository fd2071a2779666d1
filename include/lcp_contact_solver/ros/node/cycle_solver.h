// One solve cycle from messages to messages: ContactArray + Compliance → core Problem →
// ContactSolver (warm start by contact id across cycles) → SolverStats and, when the solve
// gave forces, ConstraintForces. The live node (contact_solver_node) and the offline
// replay (replay.h) both solve through this class, so the two paths cannot differ.
#pragma once

#include "lcp_contact_solver/core/contact_solver.h"
#include "lcp_contact_solver/core/problem.h"
#include "lcp_contact_solver/core/solve_result.h"
#include "lcp_contact_solver/core/solver_params.h"
#include "lcp_contact_solver/ros/msg_conversion/msg_conversion.h"

#include <lcp_contact_solver/Compliance.h>
#include <lcp_contact_solver/ConstraintForces.h>
#include <lcp_contact_solver/ContactArray.h>
#include <lcp_contact_solver/SolverStats.h>

#include <string>
#include <vector>

namespace lcp_contact_solver_ros {

struct CycleOutput {
  // Non-empty: the input was rejected (malformed messages, or refused by the core's own
  // checks) and nothing was solved; `stats` is then the rejection (status invalid_input).
  std::string error;
  lcs::core::Problem problem;             // the converted problem (empty when rejected early)
  std::vector<ContactFrame> frames;       // one per contact, from toProblem
  lcs::core::SolveResult result;          // the core's result (when solved)
  lcp_contact_solver::SolverStats stats;  // as the node publishes it on ~stats
  // The solve gave forces worth publishing (solveGaveForces) ...
  bool gave_forces = false;
  // ... and `forces` holds them (only when asked for and every number is finite).
  bool has_forces = false;
  lcp_contact_solver::ConstraintForces forces;

  bool rejected() const { return !error.empty(); }
};

class CycleSolver {
 public:
  explicit CycleSolver(const lcs::core::SolverParams& params);

  // Empty string on success; otherwise why the parameters were refused (the previous ones
  // stay in force). The warm start memory is kept.
  std::string setParams(const lcs::core::SolverParams& params);
  const lcs::core::SolverParams& params() const { return solver_.params(); }

  // Solves one pair (stamps are not compared here). With `build_forces` false the
  // ConstraintForces message is not built (the node's computeConstraintForces=false with
  // nobody subscribed); everything else is the same. `stats.forces_published` is left
  // false: whoever publishes sets it.
  CycleOutput solve(const lcp_contact_solver::ContactArray& contacts,
                    const lcp_contact_solver::Compliance& compliance, bool build_forces = true);

  void resetWarmStart() { solver_.resetWarmStart(); }
  lcs::core::ContactSolver& core() { return solver_; }

 private:
  lcs::core::ContactSolver solver_;
};

}  // namespace lcp_contact_solver_ros
