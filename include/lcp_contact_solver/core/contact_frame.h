// The one rule every layer uses to complete a contact frame from its normal, so the scene,
// the node and a user's simulator that leaves tangents out all get the same friction rows.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace lcp_contact_solver {

// Components of |n| within this of the smallest count as tied (the first axis wins).
// Without it a resting normal (ε₁, ε₂, 1) with rounding-level ε flips t1 between n × x and
// n × y from one step to the next, turning the friction rows by 90° and ruining warm starts.
constexpr double kTangentTie = 1e-6;

// t1 = normalize(n × a), a the world axis least aligned with the unit normal n; t2 = n × t1,
// so (n, t1, t2) is right-handed.
inline void tangentsFromNormal(const Eigen::Vector3d& n, Eigen::Vector3d* t1, Eigen::Vector3d* t2) {
  const Eigen::Vector3d m = n.cwiseAbs();
  const double lowest = m.minCoeff();
  int axis = 0;
  while (axis < 2 && m[axis] > lowest + kTangentTie) ++axis;
  *t1 = n.cross(Eigen::Vector3d::Unit(axis)).normalized();
  *t2 = n.cross(*t1);
}

}  // namespace lcp_contact_solver
