// A scene: rigid bodies loaded from a URDF, with the parameters of its YAML file.
//
// URDF conventions (a URDF is a tree with one root):
//   - the root link is the world: static (typically an empty link named "world");
//   - a link attached by a `floating` joint is a free (dynamic) rigid body; the joint's
//     origin is its initial pose relative to the parent's initial pose. It needs an
//     <inertial> with mass > 0 and a positive definite inertia;
//   - a link attached by a `fixed` joint to a static link is static (ground, walls, ramps);
//     its <inertial>, if any, is ignored;
//   - other joint types, and fixed joints to a dynamic link (composite bodies), are refused;
//   - <collision> geometry: box, sphere, cylinder (any number per link, each with its own
//     origin). Meshes are refused (FCL's mesh contacts are per triangle, without the
//     face manifolds a resting body needs). A link without collision geometry never collides.
// Every fault is a SceneError whose message names the file and the link (or joint).
#pragma once

#include "lcp_contact_solver/scene/scene_params.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <string>
#include <vector>

namespace lcp_contact_solver {
namespace scene {

enum class ShapeType { kBox, kSphere, kCylinder };
const char* shapeTypeName(ShapeType type);

struct CollisionShape {
  ShapeType type = ShapeType::kBox;
  // box: full side lengths (x, y, z); sphere: (radius, 0, 0); cylinder: (radius, length, 0),
  // axis along the shape frame's z.
  Eigen::Vector3d size = Eigen::Vector3d::Zero();
  Eigen::Isometry3d origin = Eigen::Isometry3d::Identity();  // shape frame in the link frame
};

struct RigidBody {
  std::string name;  // the URDF link name
  bool is_static = true;

  // Mass properties (dynamic bodies only).
  double mass = 0.0;                                        // kg
  Eigen::Vector3d com_local = Eigen::Vector3d::Zero();      // centre of mass in the link frame
  Eigen::Matrix3d inertia_local = Eigen::Matrix3d::Zero();  // about the COM, link-frame axes (kg m²)
  Eigen::Matrix3d inv_inertia_local = Eigen::Matrix3d::Zero();

  std::vector<CollisionShape> shapes;

  // State. The pose is the link frame's; velocities are those of the centre of mass, world frame.
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d linear_velocity = Eigen::Vector3d::Zero();   // m/s
  Eigen::Vector3d angular_velocity = Eigen::Vector3d::Zero();  // rad/s

  // External wrench at the centre of mass (world frame) for the next step; the simulator
  // clears it after each step. Gravity is added separately from SceneParams::gravity.
  Eigen::Vector3d external_force = Eigen::Vector3d::Zero();   // N
  Eigen::Vector3d external_torque = Eigen::Vector3d::Zero();  // N m

  Eigen::Isometry3d pose() const;
  Eigen::Vector3d comWorld() const { return position + orientation * com_local; }
  // I⁻¹ in world axes (zero for static bodies).
  Eigen::Matrix3d inverseInertiaWorld() const;
  Eigen::Matrix3d inertiaWorld() const;
  bool hasCollision() const { return !shapes.empty(); }
};

struct Scene {
  std::string name;
  std::vector<RigidBody> bodies;  // URDF depth-first order, then "ground_plane" if enabled
  SceneParams params;

  // Index of the body with this name, or -1.
  int bodyIndex(const std::string& name) const;
  // Index of the body with this name; throws SceneError when there is none.
  int requireBody(const std::string& name) const;
  int dynamicBodyCount() const;
};

// Builds a scene from URDF text and parameters (joint_origins, initial_velocities,
// ground_plane, friction and disable lists are applied and checked against the bodies).
// `source` names the URDF in messages. Throws SceneError.
Scene loadSceneFromUrdfString(const std::string& urdf_xml, const SceneParams& params,
                              const std::string& source = "<urdf>");
Scene loadSceneFromUrdfFile(const std::string& urdf_path, const SceneParams& params);
// URDF file plus YAML file.
Scene loadScene(const std::string& urdf_path, const std::string& yaml_path);
// `<dir>/<name>.urdf` + `<dir>/<name>.yaml` (the layout of config/scenes/).
Scene loadNamedScene(const std::string& dir, const std::string& name);

}  // namespace scene
}  // namespace lcp_contact_solver
