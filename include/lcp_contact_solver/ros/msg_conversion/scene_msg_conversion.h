// Messages of the example simulator (scene_simulator): a SceneSimulator step as the
// solver node's input, the node's forces back as one λ per row, body poses as tf and body
// shapes as markers. Free functions; the contact array and the compliance go through
// msg_conversion's toContactArrayMsg and toComplianceMsg (same storage as the step's W).
//
// Kept apart from msg_conversion.h so the solver's ROS library stays independent of the
// scene layer; this file links both.
#pragma once

#include "lcp_contact_solver/core/problem.h"
#include "lcp_contact_solver/scene/scene.h"
#include "lcp_contact_solver/scene/scene_simulator.h"

#include <geometry_msgs/TransformStamped.h>
#include <lcp_contact_solver/Compliance.h>
#include <lcp_contact_solver/ConstraintForces.h>
#include <lcp_contact_solver/ContactArray.h>
#include <std_msgs/Header.h>
#include <visualization_msgs/MarkerArray.h>

#include <Eigen/Core>

#include <string>

namespace lcp_contact_solver_ros {

namespace lcs = ::lcp_contact_solver;

// One ContactPoint per contact of the step, in problem order: id, body names, point,
// normal, both tangents (published explicitly: the scene's t1/t2, which follow the shared
// rule of core/contact_frame.h), the rows' d_free, μ (always explicit, never MU_DEFAULT),
// type and rows. Positions and directions are in the world frame: `header.frame_id` should
// name it.
lcs::ContactArray toContactArrayMsg(const lcs::scene::StepProblem& step, const std_msgs::Header& header);

// The step's compliance with `header` (toComplianceMsg of the step's problem: its W, or
// its body form with `compliance: bodies`).
lcs::Compliance toComplianceMsg(const lcs::scene::StepProblem& step, const std_msgs::Header& header);

// λ (one value per row of `problem`, N) from a ConstraintForces message, matched by contact
// id (not by position in the message). Returns an empty string, or one sentence naming the
// first fault (unknown or repeated id, missing contact, wrong number of rows, non-finite
// value); on a fault `lambda` is left zero.
std::string toStepForces(const lcs::ConstraintForces& forces, const lcs::core::Problem& problem,
                         Eigen::VectorXd* lambda);

// The pose of a body's link frame in the world frame: header.frame_id → body.name.
geometry_msgs::TransformStamped toTransformMsg(const lcs::scene::RigidBody& body,
                                               const std_msgs::Header& header);

// One marker per collision shape (namespace = body name, id = shape index): boxes, spheres
// and cylinders at their current world pose in header.frame_id. Static bodies are grey
// (the ground translucent), dynamic ones take colours from a fixed palette in body order.
visualization_msgs::MarkerArray bodyMarkers(const lcs::scene::Scene& scene, const std_msgs::Header& header);

}  // namespace lcp_contact_solver_ros
