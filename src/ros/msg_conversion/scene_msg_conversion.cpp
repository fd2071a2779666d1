#include "lcp_contact_solver/ros/msg_conversion/scene_msg_conversion.h"

#include "lcp_contact_solver/ros/msg_conversion/msg_conversion.h"
#include "lcp_contact_solver/ros/msg_conversion/msg_primitives.h"

#include <Eigen/Geometry>

#include <cmath>
#include <cstdint>
#include <unordered_map>
#include <vector>

namespace lcp_contact_solver_ros {

namespace {

namespace scene = lcs::scene;

// Muted, distinct colours for dynamic bodies (cycled). Muted so that the solver's saturated
// contact colours (stick green, slip red, closed cyan, magenta force arrows) stand out.
std_msgs::ColorRGBA paletteColor(int index) {
  static const float kPalette[][3] = {{0.45f, 0.55f, 0.75f}, {0.75f, 0.68f, 0.50f}, {0.55f, 0.50f, 0.70f},
                                      {0.50f, 0.65f, 0.62f}, {0.70f, 0.55f, 0.55f}, {0.60f, 0.62f, 0.45f},
                                      {0.40f, 0.48f, 0.58f}, {0.68f, 0.60f, 0.68f}};
  const auto& c = kPalette[index % (sizeof(kPalette) / sizeof(kPalette[0]))];
  return rgba(c[0], c[1], c[2], 1.0f);
}

}  // namespace

lcs::ContactArray toContactArrayMsg(const scene::StepProblem& step, const std_msgs::Header& header) {
  // The scene's contacts are core ContactFrames: sliced into the shared writer's input.
  const std::vector<ContactFrame> frames(step.frames.begin(), step.frames.end());
  std::vector<ContactBodies> bodies(step.frames.size());
  for (std::size_t i = 0; i < step.frames.size(); ++i)
    bodies[i] = {step.frames[i].body_a_name, step.frames[i].body_b_name};
  return toContactArrayMsg(step.problem, frames, bodies, header);
}

lcs::Compliance toComplianceMsg(const scene::StepProblem& step, const std_msgs::Header& header) {
  lcs::Compliance msg = toComplianceMsg(step.problem);  // W, or the body form (compliance: bodies)
  msg.header = header;
  return msg;
}

std::string toStepForces(const lcs::ConstraintForces& forces, const lcs::core::Problem& problem,
                         Eigen::VectorXd* lambda) {
  const std::vector<int> offsets = problem.rowOffsets();
  *lambda = Eigen::VectorXd::Zero(offsets.back());
  std::unordered_map<std::int64_t, std::size_t> index;
  for (std::size_t i = 0; i < problem.contacts.size(); ++i) index.emplace(problem.contacts[i].id, i);
  std::vector<bool> seen(problem.contacts.size(), false);
  Eigen::VectorXd out = Eigen::VectorXd::Zero(offsets.back());
  for (const lcs::ContactForce& f : forces.forces) {
    const auto it = index.find(f.id);
    if (it == index.end())
      return "the forces name contact id " + std::to_string(f.id) + ", which is not in the step";
    const std::size_t i = it->second;
    if (seen[i]) return "the forces give contact id " + std::to_string(f.id) + " twice";
    seen[i] = true;
    const int rows = offsets[i + 1] - offsets[i];
    if (static_cast<int>(f.lambda.size()) != rows)
      return "the forces give " + std::to_string(f.lambda.size()) + " rows for contact id " +
             std::to_string(f.id) + ", which has " + std::to_string(rows);
    for (int k = 0; k < rows; ++k) {
      if (!std::isfinite(f.lambda[k]))
        return "the force of contact id " + std::to_string(f.id) + " is not finite";
      out[offsets[i] + k] = f.lambda[k];
    }
  }
  for (std::size_t i = 0; i < seen.size(); ++i)
    if (!seen[i]) return "the forces give nothing for contact id " + std::to_string(problem.contacts[i].id);
  *lambda = std::move(out);
  return "";
}

geometry_msgs::TransformStamped toTransformMsg(const scene::RigidBody& body, const std_msgs::Header& header) {
  geometry_msgs::TransformStamped t;
  t.header = header;
  t.child_frame_id = body.name;
  t.transform.translation = toVector3(body.position);
  t.transform.rotation = toQuaternion(body.orientation.normalized());
  return t;
}

visualization_msgs::MarkerArray bodyMarkers(const scene::Scene& scene, const std_msgs::Header& header) {
  visualization_msgs::MarkerArray array;
  int dynamic_index = 0;
  for (const scene::RigidBody& body : scene.bodies) {
    const std_msgs::ColorRGBA color = body.is_static
                                          ? rgba(0.6f, 0.6f, 0.62f, body.name == "ground_plane" ? 0.5f : 1.0f)
                                          : paletteColor(dynamic_index);
    if (!body.is_static) ++dynamic_index;
    const Eigen::Isometry3d link = body.pose();
    for (std::size_t k = 0; k < body.shapes.size(); ++k) {
      const scene::CollisionShape& shape = body.shapes[k];
      visualization_msgs::Marker m;
      m.header = header;
      m.ns = body.name;
      m.id = static_cast<int>(k);
      m.action = visualization_msgs::Marker::ADD;
      const Eigen::Isometry3d pose = link * shape.origin;
      m.pose.position = toPoint(pose.translation());
      m.pose.orientation = toQuaternion(Eigen::Quaterniond(pose.rotation()).normalized());
      switch (shape.type) {
        case scene::ShapeType::kBox:
          m.type = visualization_msgs::Marker::CUBE;
          m.scale = toVector3(shape.size);
          break;
        case scene::ShapeType::kSphere:
          m.type = visualization_msgs::Marker::SPHERE;
          m.scale = toVector3(Eigen::Vector3d::Constant(2.0 * shape.size.x()));
          break;
        case scene::ShapeType::kCylinder:
          m.type = visualization_msgs::Marker::CYLINDER;
          m.scale = toVector3(Eigen::Vector3d(2.0 * shape.size.x(), 2.0 * shape.size.x(), shape.size.y()));
          break;
      }
      m.color = color;
      array.markers.push_back(m);
    }
  }
  return array;
}

}  // namespace lcp_contact_solver_ros
