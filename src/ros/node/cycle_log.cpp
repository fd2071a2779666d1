#include "lcp_contact_solver/ros/node/cycle_log.h"

#include "lcp_contact_solver/core/contact_solver.h"
#include "lcp_contact_solver/core/residual.h"

#include <sstream>

namespace lcp_contact_solver_ros {

int worstContact(const lcs::core::Problem& problem, const lcs::core::SolveResult& result,
                 const std::vector<double>& mu, double* error) {
  const std::vector<int> offsets = problem.rowOffsets();
  int worst = -1;
  *error = 0.0;
  for (std::size_t i = 0; i < problem.contacts.size(); ++i) {
    if (result.states[i] == lcs::core::ContactState::kIgnored) continue;
    // A one-contact problem without d_free makes the core's residual the absolute error.
    lcs::core::Problem single;
    single.contacts = {problem.contacts[i]};
    const int rows = problem.contacts[i].rows;
    const double e = lcs::core::naturalMapResidual(single, {mu[i]}, result.forces.segment(offsets[i], rows),
                                                   result.d.segment(offsets[i], rows));
    if (worst < 0 || e > *error) {
      worst = static_cast<int>(i);
      *error = e;
    }
  }
  return worst;
}

std::string cycleSummary(const lcs::core::Problem& problem, const lcs::core::SolveResult& result,
                         const std::vector<double>& mu) {
  std::ostringstream out;
  out << problem.contacts.size() << " contacts, " << problem.rowCount() << " rows ("
      << (problem.bodies                                       ? "bodies, no"
          : std::holds_alternative<Eigen::MatrixXd>(problem.W) ? "dense"
                                                               : "block-sparse")
      << " W); " << result.solver << ": " << lcs::core::statusName(result.status) << " after "
      << result.iterations << " iterations, residual " << result.residual << ", " << result.solve_time * 1e3
      << " ms";
  double error = 0.0;
  const int worst = worstContact(problem, result, mu, &error);
  if (worst >= 0)
    out << "; worst contact " << worst << " (id " << problem.contacts[worst].id << ", "
        << lcs::core::stateName(result.states[worst]) << ") error " << error;
  if (!result.message.empty()) out << "; " << result.message;
  return out.str();
}

}  // namespace lcp_contact_solver_ros
