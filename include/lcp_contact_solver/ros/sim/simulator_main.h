// main() of a simulator node beside the solver (scene_simulator, mujoco_bridge).
#pragma once

#include "lcp_contact_solver/ros/sim/sim_time_guard.h"

#include <ros/ros.h>

#include <stdexcept>

namespace lcp_contact_solver_ros {

// Runs Node(nh, pnh).run(): 0 when it completed, 1 otherwise. A bad parameter
// (std::invalid_argument) or a `LoadError` is a fatal log line prefixed with `load_what`.
template <typename Node, typename LoadError>
int runSimulatorMain(int argc, char** argv, const char* name, const char* load_what) {
  ros::init(argc, argv, name);
  // The handles outlive the try block, or roscpp (and rosconsole) would shut down before
  // the fatal line is printed.
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  SimTimeGuard sim_time(pnh);
  try {
    Node node(nh, pnh);
    return node.run() ? 0 : 1;
  } catch (const std::invalid_argument& e) {
    ROS_FATAL_STREAM("Invalid parameter: " << e.what());
  } catch (const LoadError& e) {
    ROS_FATAL_STREAM(load_what << e.what());
  }
  return 1;
}

}  // namespace lcp_contact_solver_ros
