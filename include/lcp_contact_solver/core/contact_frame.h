// The one contact frame type and the one rule every layer uses to complete a frame from its
// normal, so the scene, the node and a user's simulator that leaves tangents out all get the
// same friction rows.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace lcp_contact_solver::core {

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

// Where a contact is and its unit directions: the one contact frame of every layer. The
// scene's contacts are one (scene::SceneContact adds what the scene knows), the ROS layer
// reads one from each message contact and writes messages from them. Defaults: the rule's
// tangents of the default normal +z.
struct ContactFrame {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();    // unit; the force on body A is +λ_n n
  Eigen::Vector3d tangent1 = Eigen::Vector3d::UnitY();  // unit, (n, t1, t2) right-handed
  Eigen::Vector3d tangent2 = -Eigen::Vector3d::UnitX();
  // True when the tangents were not given but derived by tangentsFromNormal: a message
  // written from the frame leaves them out (zero), and its reader derives the same ones.
  bool derived_tangents = false;
};

// A frame whose tangents follow the rule above (derived_tangents set).
inline ContactFrame frameFromNormal(const Eigen::Vector3d& position, const Eigen::Vector3d& unit_normal) {
  ContactFrame f;
  f.position = position;
  f.normal = unit_normal;
  tangentsFromNormal(unit_normal, &f.tangent1, &f.tangent2);
  f.derived_tangents = true;
  return f;
}

}  // namespace lcp_contact_solver::core
