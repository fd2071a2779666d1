#include "lcp_contact_solver/core/solve_result.h"

namespace lcp_contact_solver::core {

const char* statusName(SolveStatus status) {
  switch (status) {
    case SolveStatus::kConverged: return "converged";
    case SolveStatus::kMaxIterations: return "max_iterations";
    case SolveStatus::kZeroDiagonal: return "zero_diagonal";
    case SolveStatus::kNotApplicable: return "not_applicable";
    case SolveStatus::kRayTermination: return "ray_termination";
    case SolveStatus::kNumericalFailure: return "numerical_failure";
    case SolveStatus::kInvalidInput: return "invalid_input";
    case SolveStatus::kTimeBudget: return "time_budget";
  }
  return "unknown";
}

const char* stateName(ContactState state) {
  switch (state) {
    case ContactState::kOpen: return "open";
    case ContactState::kStick: return "stick";
    case ContactState::kSlip: return "slip";
    case ContactState::kIgnored: return "ignored";
    case ContactState::kClosed: return "closed";
  }
  return "unknown";
}

}  // namespace lcp_contact_solver::core
