#include "lcp_contact_solver/ros/replay/force_comparison.h"

#include <algorithm>
#include <limits>

namespace lcp_contact_solver_ros {

using lcp_contact_solver::ConstraintForces;

double relativeDifference(double a, double b) {
  const double scale = std::max(std::abs(a), std::abs(b));
  if (scale == 0.0) return 0.0;
  return std::abs(a - b) / scale;
}

ForceDifference compareForces(const ConstraintForces& forces, const ConstraintForces& reference) {
  ForceDifference diff;
  auto mismatch = [&diff](const std::string& why) {
    diff.mismatch = why;
    diff.relative = std::numeric_limits<double>::infinity();
    return diff;
  };
  if (forces.forces.size() != reference.forces.size())
    return mismatch(std::to_string(forces.forces.size()) + " contacts, recorded " +
                    std::to_string(reference.forces.size()));
  double scale = 0.0;
  for (std::size_t i = 0; i < forces.forces.size(); ++i) {
    const auto& f = forces.forces[i];
    const auto& r = reference.forces[i];
    if (f.id != r.id)
      return mismatch("contact " + std::to_string(i) + " has id " + std::to_string(f.id) + ", recorded " +
                      std::to_string(r.id));
    if (f.lambda.size() != r.lambda.size())
      return mismatch("contact " + std::to_string(i) + " has " + std::to_string(f.lambda.size()) + " rows, recorded " +
                      std::to_string(r.lambda.size()));
    for (std::size_t k = 0; k < f.lambda.size(); ++k) {
      const double d = std::abs(f.lambda[k] - r.lambda[k]);
      diff.max_abs = std::max(diff.max_abs, d);
      diff.sum_sq += d * d;
      ++diff.values;
      scale = std::max({scale, std::abs(f.lambda[k]), std::abs(r.lambda[k])});
    }
  }
  diff.relative = scale > 0.0 ? diff.max_abs / scale : 0.0;
  return diff;
}

bool Comparison::exceeds(double tolerance) const {
  return compared == 0 || mismatched > 0 || missing_reference > 0 || missing_replay > 0 || !(max_relative <= tolerance);
}

}  // namespace lcp_contact_solver_ros
