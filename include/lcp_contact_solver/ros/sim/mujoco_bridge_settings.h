// The MuJoCo bridge's parameters (mujoco_bridge_node.h): the settings and their reader.
#pragma once

#include "lcp_contact_solver/ros/sim/solver_link.h"

#include <ros/node_handle.h>

#include <string>

namespace lcp_contact_solver_ros {

// The shared parameters (duration: simulated s to run when steps = 0, rate_factor,
// force_timeout, wait_for_solver, linger, frame_id (MuJoCo's world frame), publish_clock,
// status_period: solver_link.h) and:
struct MujocoBridgeSettings : LinkSettings {
  std::string model = "/usr/share/mujoco/model/humanoid/humanoid.xml";  // MJCF or MJB
  std::string mode = "cross_check";                                     // cross_check | drive
  std::string cone = "pyramidal";  // pyramidal | elliptic | model (keep the model's)
  // MuJoCo's own solver (cross_check, and drive with ~compare). The defaults run its PGS to
  // its fixed point, so a difference is ours: tolerance 0 runs every iteration.
  std::string mujoco_solver = "pgs";  // pgs | cg | newton | model
  int mujoco_iterations = 3000;       // <= 0: the model's
  double mujoco_tolerance = 0.0;      // < 0: the model's
  bool compare = true;                // drive: also run MuJoCo's solver to report the difference
  // drive: also step a second copy of the model from the same start with MuJoCo's own solver
  // and report the distance to it each step (body positions, energy, contact pairs): the
  // physics check where the forces differ by design (elliptic: MuJoCo's convex relaxation).
  bool reference = false;
  int steps = 0;                   // steps to run; 0 = for ever (or ~duration)
  double dt = 0.0;                 // MuJoCo's timestep override (s); 0 = the model's
  int min_report_subscribers = 0;  // also wait for this many ~step_report subscribers (tests)
  bool include_limits = true;      // joint/tendon limits as unilateral rows
  bool include_equalities = true;  // equality constraints as bilateral rows
  std::string storage = "auto";    // W: auto | dense | block_sparse
  int dense_max_rows = 200;        // auto: block-sparse above this many rows...
  double dense_min_fill = 0.25;    // ...unless at least this share of W's entries is nonzero
  double max_rel_warn = 1e-6;      // cross_check: warn when the relative difference exceeds it
  bool print_summary = false;      // status lines and the final summary on stdout (demo)
};

// Reads every private parameter present over the defaults. Empty string, or a sentence naming
// the parameter of the wrong type or value.
std::string loadMujocoBridgeSettings(const ros::NodeHandle& pnh, MujocoBridgeSettings* settings);

}  // namespace lcp_contact_solver_ros
