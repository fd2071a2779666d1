#include "lcp_contact_solver/ros/node/cycle_solver.h"

namespace lcp_contact_solver_ros {

using lcp_contact_solver::SolverStats;

CycleSolver::CycleSolver(const lcs::core::SolverParams& params) : solver_(params) {}

std::string CycleSolver::setParams(const lcs::core::SolverParams& params) {
  return solver_.setParams(params);
}

CycleOutput CycleSolver::solve(const lcp_contact_solver::ContactArray& contacts,
                               const lcp_contact_solver::Compliance& compliance, bool build_forces) {
  CycleOutput out;
  // Not validated here: the core's solve runs the same check (one pass over W, not two).
  out.error = toProblem(contacts, compliance, solver_.params().max_rows, &out.problem, &out.frames,
                        /*validate=*/false);
  if (out.error.empty()) {
    out.result = solver_.solveInPlace(out.problem);                  // erp/softness without a copy of W
    if (out.result.status == lcs::core::SolveStatus::kInvalidInput)  // refused by the core's own checks
      out.error = out.result.message.empty() ? "invalid input" : out.result.message;
  }
  if (out.rejected()) {
    out.stats = rejectedStatsMsg(contacts.header, SolverStats::INVALID_INPUT, out.error);
    return out;
  }
  out.stats = toStatsMsg(contacts.header, out.problem, out.result);
  out.gave_forces = solveGaveForces(out.result);
  if (out.gave_forces && build_forces) {
    out.forces = toConstraintForcesMsg(contacts, out.frames, out.problem, out.result);
    out.has_forces = allFinite(out.forces);
    if (!out.has_forces) out.forces = lcp_contact_solver::ConstraintForces();
  }
  return out;
}

}  // namespace lcp_contact_solver_ros
