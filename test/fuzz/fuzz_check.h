// Invariants of a core result, as a sentence ("" when they hold): the fuzz targets' oracle.
#pragma once

#include "lcp_contact_solver/core/contact_solver.h"
#include "lcp_contact_solver/core/residual.h"

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

namespace lcs_fuzz {

namespace lcs = ::lcp_contact_solver;

inline bool sameBits(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return a.size() == b.size() &&
         (a.size() == 0 ||
          std::memcmp(a.data(), b.data(), sizeof(double) * static_cast<std::size_t>(a.size())) == 0);
}

// Finite, sized, honest (converged ⟺ status ⟹ residual <= tolerance; failures carry a
// message), the reported residual is the one of the returned forces, ignored contacts
// have zero force.
inline std::string checkResult(const lcs::core::Problem& p, const lcs::core::SolverParams& params,
                               const lcs::core::SolveResult& r) {
  if (r.status == lcs::core::SolveStatus::kInvalidInput)
    return r.message.empty() ? "invalid_input without a message" : "";
  const int n = p.rowCount();
  if (r.forces.size() != n || r.d.size() != n || r.states.size() != p.contacts.size()) return "result sizes";
  if (!r.forces.allFinite()) return "non-finite force";
  if (!r.d.allFinite()) return "non-finite d";
  if (!std::isfinite(r.residual) || !std::isfinite(r.solver_error) || !std::isfinite(r.solve_time))
    return "non-finite residual, solver error or time";
  if (r.converged != (r.status == lcs::core::SolveStatus::kConverged))
    return "converged flag disagrees with the status";
  if (r.converged && params.stopping_rule == lcs::core::StoppingRule::kResidual &&
      r.friction_model == lcs::core::FrictionModel::kCoulombDisc && !(r.residual <= params.tolerance))
    return "converged with residual " + std::to_string(r.residual) + " > tolerance";
  if (!r.converged && r.message.empty())
    return std::string("status ") + lcs::core::statusName(r.status) + " without a message";
  std::vector<bool> ignored(p.contacts.size());
  for (std::size_t i = 0; i < p.contacts.size(); ++i)
    ignored[i] = r.states[i] == lcs::core::ContactState::kIgnored;
  const double residual =
      lcs::core::naturalMapResidual(p, lcs::core::effectiveMu(p, params.mu), r.forces, r.d, ignored);
  if (!(std::abs(residual - r.residual) <= 1e-9 * std::max(1.0, residual)))
    return "reported residual " + std::to_string(r.residual) + " is not the forces' " +
           std::to_string(residual);
  const std::vector<int> off = p.rowOffsets();
  for (std::size_t i = 0; i < p.contacts.size(); ++i)
    if (ignored[i])
      for (int k = 0; k < p.contacts[i].rows; ++k)
        if (r.forces[off[i] + k] != 0.0) return "an ignored contact has a force";
  return "";
}

// Two solves of the same input by fresh solvers must agree bit for bit.
inline std::string checkDeterministic(const lcs::core::SolveResult& a, const lcs::core::SolveResult& b) {
  if (a.status != b.status || a.iterations != b.iterations || !sameBits(a.forces, b.forces) ||
      !sameBits(a.d, b.d) || std::memcmp(&a.residual, &b.residual, sizeof(double)) != 0)
    return "two solves of the same input differ";
  return "";
}

}  // namespace lcs_fuzz
