// The node's parameters: SOFA's solver fields (core SolverParams, core/solver_param_table.def)
// plus the node-only ones (node_param_table.def: the defaults below must match it, which
// test_param_table checks), read from the private namespace, from dynamic_reconfigure, or
// from the service's "name=value" overrides, and validated before use.
#pragma once

#include "lcp_contact_solver/core/solver_params.h"
#include "lcp_contact_solver/ros/node/input_queue.h"

#include <lcp_contact_solver/ContactSolverConfig.h>
#include <ros/node_handle.h>

#include <array>
#include <string>
#include <vector>

namespace lcp_contact_solver_ros {

namespace lcs = ::lcp_contact_solver;

// What the debug markers show and how.
struct DisplayOptions {
  double force_arrow_scale = 0.01;  // m per N
  bool show_w_heatmap = true;
  double showCellWidth = 0.0;                              // m; SOFA's default, <= 0 hides the heat map
  std::array<double, 3> showTranslation{{0.0, 0.0, 0.0}};  // m, header frame
  int heatmap_max_rows = 64;                               // the heat map shows the leading rows only
  double cone_height = 0.05;                               // m
  double marker_lifetime = 0.5;                            // s
};

// SOFA's defaults, with the node's row limit.
lcs::core::SolverParams defaultSolverParams();

struct NodeSettings {
  lcs::core::SolverParams solver = defaultSolverParams();
  DisplayOptions display;
  double pairing_window = 0.5;  // s
  int queue_size = 10;
  // What the node does when pairs come faster than it solves (input_queue.h).
  OverloadPolicy overload = OverloadPolicy::kQueue;
  double diagnostics_min_rate = 1.0;     // Hz
  double diagnostics_max_rate = 2000.0;  // Hz
};

// Reads every parameter present in `pnh` over the defaults in `settings`. Returns an
// empty string, or a sentence naming the parameter of the wrong type or invalid value.
std::string loadSettings(const ros::NodeHandle& pnh, NodeSettings* settings);

// Empty string when valid, otherwise a sentence naming the bad field.
std::string validateSettings(const NodeSettings& settings);

// Applies one "name=value" override of a solver parameter (service requests).
std::string applyOverride(const std::string& assignment, lcs::core::SolverParams* params);

// The names applyOverride accepts.
std::vector<std::string> overridableNames();

// The runtime-changeable part of `settings` as a dynamic_reconfigure config, and back.
// fromConfig keeps the startup-only fields of `settings`.
lcp_contact_solver::ContactSolverConfig toConfig(const NodeSettings& settings);
std::string fromConfig(const lcp_contact_solver::ContactSolverConfig& config, NodeSettings* settings);

}  // namespace lcp_contact_solver_ros
