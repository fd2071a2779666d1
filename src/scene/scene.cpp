// URDF → Scene (see scene.h for the conventions).
#include "lcp_contact_solver/scene/scene.h"

#include <console_bridge/console.h>
#include <urdf_parser/urdf_parser.h>

#include <Eigen/Eigenvalues>

#include <cmath>
#include <fstream>
#include <mutex>
#include <set>
#include <sstream>

namespace lcp_contact_solver {
namespace scene {

const char* shapeTypeName(ShapeType type) {
  switch (type) {
    case ShapeType::kBox: return "box";
    case ShapeType::kSphere: return "sphere";
    case ShapeType::kCylinder: return "cylinder";
  }
  return "?";
}

Eigen::Isometry3d RigidBody::pose() const {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = orientation.toRotationMatrix();
  T.translation() = position;
  return T;
}

Eigen::Matrix3d RigidBody::inverseInertiaWorld() const {
  if (is_static) return Eigen::Matrix3d::Zero();
  const Eigen::Matrix3d R = orientation.toRotationMatrix();
  return R * inv_inertia_local * R.transpose();
}

Eigen::Matrix3d RigidBody::inertiaWorld() const {
  if (is_static) return Eigen::Matrix3d::Zero();
  const Eigen::Matrix3d R = orientation.toRotationMatrix();
  return R * inertia_local * R.transpose();
}

int Scene::bodyIndex(const std::string& body_name) const {
  for (std::size_t i = 0; i < bodies.size(); ++i)
    if (bodies[i].name == body_name) return static_cast<int>(i);
  return -1;
}

int Scene::requireBody(const std::string& body_name) const {
  const int i = bodyIndex(body_name);
  if (i < 0) throw SceneError("scene '" + name + "' has no body named '" + body_name + "'");
  return i;
}

int Scene::dynamicBodyCount() const {
  int n = 0;
  for (const RigidBody& b : bodies) n += b.is_static ? 0 : 1;
  return n;
}

namespace {

// Collects urdfdom's console_bridge messages during a parse so the exception can carry them
// (urdfdom reports why a parse failed only through console_bridge).
class CaptureHandler : public console_bridge::OutputHandler {
 public:
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_WARN) {
      if (!messages.empty()) messages += "; ";
      messages += text;
    }
  }
  std::string messages;
};

std::mutex& parseMutex() {
  static std::mutex m;
  return m;
}

Eigen::Isometry3d toIsometry(const urdf::Pose& p) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Quaterniond(p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z)
                   .normalized()
                   .toRotationMatrix();
  T.translation() = Eigen::Vector3d(p.position.x, p.position.y, p.position.z);
  return T;
}

const char* jointTypeName(int type) {
  switch (type) {
    case urdf::Joint::REVOLUTE: return "revolute";
    case urdf::Joint::CONTINUOUS: return "continuous";
    case urdf::Joint::PRISMATIC: return "prismatic";
    case urdf::Joint::FLOATING: return "floating";
    case urdf::Joint::PLANAR: return "planar";
    case urdf::Joint::FIXED: return "fixed";
    default: return "unknown";
  }
}

class Builder {
 public:
  Builder(const urdf::ModelInterface& model, const SceneParams& params, std::string source)
      : model_(model), params_(params), source_(std::move(source)) {}

  [[noreturn]] void failLink(const std::string& link, const std::string& what) const {
    throw SceneError(source_ + ": link '" + link + "': " + what);
  }

  void visit(const urdf::LinkConstSharedPtr& link, const Eigen::Isometry3d& world_T_link, bool is_static,
             std::vector<RigidBody>* out) {
    RigidBody body;
    body.name = link->name;
    body.is_static = is_static;
    body.position = world_T_link.translation();
    body.orientation = Eigen::Quaterniond(world_T_link.linear()).normalized();
    if (!is_static) readInertial(*link, &body);
    readCollisions(*link, &body);
    out->push_back(std::move(body));

    // Children in the order urdfdom lists them (sorted by joint name): deterministic.
    for (const urdf::JointSharedPtr& joint : link->child_joints) {
      const urdf::LinkConstSharedPtr child = model_.getLink(joint->child_link_name);
      if (!child)
        failLink(joint->child_link_name, "is the child of joint '" + joint->name + "' but does not exist");
      bool child_static = false;
      if (joint->type == urdf::Joint::FLOATING) {
        child_static = false;
      } else if (joint->type == urdf::Joint::FIXED) {
        if (!is_static)
          failLink(child->name, "is attached by the fixed joint '" + joint->name + "' to the dynamic link '" +
                                    link->name +
                                    "': composite bodies are not supported (put the geometry "
                                    "in one link, or attach it with a floating joint)");
        child_static = true;
      } else {
        failLink(child->name, std::string("is attached by the ") + jointTypeName(joint->type) + " joint '" +
                                  joint->name +
                                  "': a scene has only free bodies (floating joints) and "
                                  "static ones (fixed joints to static links)");
      }
      const Eigen::Isometry3d parent_T_child = jointOrigin(*joint);
      visit(child, world_T_link * parent_T_child, child_static, out);
    }
  }

  Eigen::Isometry3d jointOrigin(const urdf::Joint& joint) {
    Eigen::Isometry3d T = toIsometry(joint.parent_to_joint_origin_transform);
    auto it = params_.joint_origins.find(joint.name);
    if (it != params_.joint_origins.end()) {
      used_overrides_.insert(joint.name);
      const JointOriginOverride& o = it->second;
      if (o.has_xyz) T.translation() = o.xyz;
      if (o.has_rpy) {
        // URDF's convention: R = Rz(yaw) Ry(pitch) Rx(roll).
        T.linear() = (Eigen::AngleAxisd(o.rpy.z(), Eigen::Vector3d::UnitZ()) *
                      Eigen::AngleAxisd(o.rpy.y(), Eigen::Vector3d::UnitY()) *
                      Eigen::AngleAxisd(o.rpy.x(), Eigen::Vector3d::UnitX()))
                         .toRotationMatrix();
      }
    }
    return T;
  }

  void readInertial(const urdf::Link& link, RigidBody* body) const {
    if (!link.inertial)
      failLink(link.name, "is a free body (floating joint) but has no <inertial>: give its mass and inertia");
    const urdf::Inertial& in = *link.inertial;
    if (!std::isfinite(in.mass) || in.mass <= 0.0)
      failLink(link.name,
               "is a free body with mass " + std::to_string(in.mass) + ": the mass must be > 0 (kg)");
    Eigen::Matrix3d I;
    I << in.ixx, in.ixy, in.ixz, in.ixy, in.iyy, in.iyz, in.ixz, in.iyz, in.izz;
    if (!I.allFinite()) failLink(link.name, "has a non-finite inertia");
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(I);
    const Eigen::Vector3d ev = eig.eigenvalues();
    if (ev.minCoeff() <= 1e-12 * std::max(1.0, ev.maxCoeff()))
      failLink(link.name, "has an inertia that is not positive definite (ixx, iyy, izz must be > 0)");
    const Eigen::Isometry3d link_T_inertial = toIsometry(in.origin);
    const Eigen::Matrix3d R = link_T_inertial.linear();
    body->mass = in.mass;
    body->com_local = link_T_inertial.translation();
    body->inertia_local = R * I * R.transpose();
    body->inv_inertia_local = body->inertia_local.inverse();
  }

  void readCollisions(const urdf::Link& link, RigidBody* body) const {
    std::vector<urdf::CollisionSharedPtr> collisions = link.collision_array;
    if (collisions.empty() && link.collision) collisions.push_back(link.collision);
    for (const urdf::CollisionSharedPtr& c : collisions) {
      if (!c || !c->geometry) failLink(link.name, "has a <collision> without geometry");
      CollisionShape shape;
      shape.origin = toIsometry(c->origin);
      const urdf::Geometry& g = *c->geometry;
      switch (g.type) {
        case urdf::Geometry::BOX: {
          const auto& box = static_cast<const urdf::Box&>(g);
          shape.type = ShapeType::kBox;
          shape.size = Eigen::Vector3d(box.dim.x, box.dim.y, box.dim.z);
          if (!shape.size.allFinite() || shape.size.minCoeff() <= 0.0)
            failLink(link.name, "has a collision box with a side <= 0");
          break;
        }
        case urdf::Geometry::SPHERE: {
          const auto& sphere = static_cast<const urdf::Sphere&>(g);
          shape.type = ShapeType::kSphere;
          shape.size = Eigen::Vector3d(sphere.radius, 0.0, 0.0);
          if (!std::isfinite(sphere.radius) || sphere.radius <= 0.0)
            failLink(link.name, "has a collision sphere with radius <= 0");
          break;
        }
        case urdf::Geometry::CYLINDER: {
          const auto& cyl = static_cast<const urdf::Cylinder&>(g);
          shape.type = ShapeType::kCylinder;
          shape.size = Eigen::Vector3d(cyl.radius, cyl.length, 0.0);
          if (!std::isfinite(cyl.radius) || !std::isfinite(cyl.length) || cyl.radius <= 0.0 ||
              cyl.length <= 0.0)
            failLink(link.name, "has a collision cylinder with radius or length <= 0");
          break;
        }
        case urdf::Geometry::MESH:
          failLink(link.name, "has unsupported collision geometry 'mesh' (supported: box, sphere, cylinder)");
        default: failLink(link.name, "has unsupported collision geometry (supported: box, sphere, cylinder)");
      }
      body->shapes.push_back(shape);
    }
  }

  const std::set<std::string>& usedOverrides() const { return used_overrides_; }

 private:
  const urdf::ModelInterface& model_;
  const SceneParams& params_;
  std::string source_;
  std::set<std::string> used_overrides_;
};

}  // namespace

Scene loadSceneFromUrdfString(const std::string& urdf_xml, const SceneParams& params,
                              const std::string& source) {
  if (std::string err = validateSceneParams(params); !err.empty())
    throw SceneError(source + ": scene parameters: " + err);

  urdf::ModelInterfaceSharedPtr model;
  std::string parse_messages;
  {
    std::lock_guard<std::mutex> lock(parseMutex());
    CaptureHandler capture;
    console_bridge::useOutputHandler(&capture);
    model = urdf::parseURDF(urdf_xml);
    console_bridge::restorePreviousOutputHandler();
    parse_messages = capture.messages;
  }
  if (!model)
    throw SceneError(source + ": not a valid URDF" + (parse_messages.empty() ? "" : ": " + parse_messages));
  const urdf::LinkConstSharedPtr root = model->getRoot();
  if (!root) throw SceneError(source + ": the URDF has no root link");

  Scene scene;
  scene.name = model->getName();
  scene.params = params;
  Builder builder(*model, params, source);
  builder.visit(root, Eigen::Isometry3d::Identity(), /*is_static=*/true, &scene.bodies);

  for (const auto& kv : params.joint_origins) {
    if (!builder.usedOverrides().count(kv.first)) {
      if (model->getJoint(kv.first))
        throw SceneError(source + ": joint_origins: joint '" + kv.first + "' is not fixed or floating");
      throw SceneError(source + ": joint_origins: the URDF has no joint named '" + kv.first + "'");
    }
  }

  if (params.ground_plane.enabled) {
    const std::string ground = "ground_plane";
    if (scene.bodyIndex(ground) >= 0)
      throw SceneError(source + ": link 'ground_plane' exists and ground_plane is enabled: rename one");
    RigidBody g;
    g.name = ground;
    g.is_static = true;
    CollisionShape box;
    box.type = ShapeType::kBox;
    box.size = Eigen::Vector3d(2.0 * params.ground_plane.half_extent, 2.0 * params.ground_plane.half_extent,
                               params.ground_plane.thickness);
    box.origin.translation() =
        Eigen::Vector3d(0.0, 0.0, params.ground_plane.height - 0.5 * params.ground_plane.thickness);
    g.shapes.push_back(box);
    scene.bodies.push_back(g);
  }

  // Names in the YAML must be bodies of the scene.
  auto require = [&](const std::string& name, const std::string& where) {
    if (scene.bodyIndex(name) < 0) throw SceneError(source + ": " + where + ": no body named '" + name + "'");
  };
  for (const PairFriction& f : params.friction_pairs) {
    require(f.body_a, "friction_pairs");
    require(f.body_b, "friction_pairs");
  }
  for (const PairRestitution& r : params.restitution_pairs) {
    require(r.body_a, "restitution_pairs");
    require(r.body_b, "restitution_pairs");
  }
  for (const auto& d : params.disable_collisions) {
    require(d.first, "disable_collisions");
    require(d.second, "disable_collisions");
  }
  for (const auto& [name, v] : params.initial_velocities) {
    require(name, "initial_velocities");
    RigidBody& b = scene.bodies[scene.bodyIndex(name)];
    if (b.is_static) throw SceneError(source + ": initial_velocities: link '" + name + "' is static");
    b.linear_velocity = v.linear;
    b.angular_velocity = v.angular;
  }
  return scene;
}

Scene loadSceneFromUrdfFile(const std::string& urdf_path, const SceneParams& params) {
  std::ifstream in(urdf_path);
  if (!in) throw SceneError(urdf_path + ": cannot open the URDF file");
  std::stringstream ss;
  ss << in.rdbuf();
  return loadSceneFromUrdfString(ss.str(), params, urdf_path);
}

Scene loadScene(const std::string& urdf_path, const std::string& yaml_path) {
  return loadSceneFromUrdfFile(urdf_path, loadSceneParams(yaml_path));
}

Scene loadNamedScene(const std::string& dir, const std::string& name) {
  return loadScene(dir + "/" + name + ".urdf", dir + "/" + name + ".yaml");
}

}  // namespace scene
}  // namespace lcp_contact_solver
