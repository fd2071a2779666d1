// Helpers to build small scenes in code for the scene tests.
#pragma once

#include "lcp_contact_solver/scene/scene.h"

#include <string>

namespace scene_test {

using lcp_contact_solver::scene::CollisionShape;
using lcp_contact_solver::scene::RigidBody;
using lcp_contact_solver::scene::Scene;
using lcp_contact_solver::scene::ShapeType;

inline CollisionShape boxShape(double x, double y, double z) {
  CollisionShape s;
  s.type = ShapeType::kBox;
  s.size = Eigen::Vector3d(x, y, z);
  return s;
}
inline CollisionShape sphereShape(double r) {
  CollisionShape s;
  s.type = ShapeType::kSphere;
  s.size = Eigen::Vector3d(r, 0, 0);
  return s;
}
inline CollisionShape cylinderShape(double r, double length) {
  CollisionShape s;
  s.type = ShapeType::kCylinder;
  s.size = Eigen::Vector3d(r, length, 0);
  return s;
}

inline RigidBody staticBody(const std::string& name, const CollisionShape& shape,
                            const Eigen::Vector3d& position = Eigen::Vector3d::Zero()) {
  RigidBody b;
  b.name = name;
  b.is_static = true;
  b.position = position;
  b.shapes.push_back(shape);
  return b;
}

// A dynamic body with the solid inertia of its (single) shape.
inline RigidBody dynamicBody(const std::string& name, const CollisionShape& shape, double mass,
                             const Eigen::Vector3d& position) {
  RigidBody b;
  b.name = name;
  b.is_static = false;
  b.mass = mass;
  b.position = position;
  b.shapes.push_back(shape);
  const Eigen::Vector3d s = shape.size;
  Eigen::Vector3d d = Eigen::Vector3d::Zero();
  switch (shape.type) {
    case ShapeType::kBox:
      d << s.y() * s.y() + s.z() * s.z(), s.x() * s.x() + s.z() * s.z(), s.x() * s.x() + s.y() * s.y();
      d *= mass / 12.0;
      break;
    case ShapeType::kSphere: d.setConstant(0.4 * mass * s.x() * s.x()); break;
    case ShapeType::kCylinder: {
      const double ixx = mass * (3 * s.x() * s.x() + s.y() * s.y()) / 12.0;
      d << ixx, ixx, 0.5 * mass * s.x() * s.x();
      break;
    }
  }
  b.inertia_local = d.asDiagonal();
  b.inv_inertia_local = b.inertia_local.inverse();
  return b;
}

// The ground: a static 20 m box whose top face is z = 0.
inline RigidBody ground(const std::string& name = "ground") {
  RigidBody g = staticBody(name, boxShape(20, 20, 1));
  g.shapes[0].origin.translation() = Eigen::Vector3d(0, 0, -0.5);
  return g;
}

}  // namespace scene_test
