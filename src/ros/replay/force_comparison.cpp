#include "lcp_contact_solver/ros/replay/force_comparison.h"

#include "lcp_contact_solver/ros/replay/text.h"

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
      return mismatch("contact " + std::to_string(i) + " has " + std::to_string(f.lambda.size()) +
                      " rows, recorded " + std::to_string(r.lambda.size()));
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

CycleDifference Comparison::add(const ConstraintForces* replayed, const ConstraintForces* reference,
                                const ros::Time& stamp, long cycle, const std::string& why_no_replay) {
  CycleDifference out;
  out.stamp = stamp;
  out.cycle = cycle;
  if (replayed != nullptr) out.contacts = replayed->forces.size();
  auto not_comparable = [&](std::size_t* counter, const std::string& why) {
    ++*counter;
    out.mismatch = why;
    out.relative = std::numeric_limits<double>::infinity();
    if (first_mismatch.empty()) first_mismatch = "stamp " + stampDigits(stamp) + ": " + why;
    return out;
  };
  if (replayed == nullptr && reference == nullptr) return out;
  if (reference == nullptr) return not_comparable(&missing_reference, "no recorded forces");
  if (replayed == nullptr)
    return not_comparable(&missing_replay,
                          cycle < 0 ? "recorded forces, but no such cycle"
                                    : "recorded forces, the replay gave none" +
                                          (why_no_replay.empty() ? "" : " (" + why_no_replay + ")"));
  const ForceDifference d = compareForces(*replayed, *reference);
  if (!d.mismatch.empty()) return not_comparable(&mismatched, d.mismatch);
  ++compared;
  max_abs = std::max(max_abs, d.max_abs);
  sum_sq += d.sum_sq;
  values += d.values;
  if (d.relative > max_relative || worst_cycle < 0) {
    max_relative = std::max(max_relative, d.relative);
    worst_stamp = stamp;
    worst_cycle = cycle;
  }
  out.max_abs = d.max_abs;
  out.relative = d.relative;
  return out;
}

bool Comparison::exceeds(double tolerance) const {
  return compared == 0 || mismatched > 0 || missing_reference > 0 || missing_replay > 0 ||
         !(max_relative <= tolerance);
}

}  // namespace lcp_contact_solver_ros
