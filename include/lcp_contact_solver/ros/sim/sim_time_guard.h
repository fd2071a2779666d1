// Puts /use_sim_time back when a simulator node that publishes /clock ends.
//
// A launch file that sets /use_sim_time true (demo.launch, mujoco_demo.launch) leaves it on
// a master that outlives the launch, and every ROS tool started afterwards waits for a
// /clock that never comes. With ~restore_use_sim_time true the simulator removes the
// parameter when it stops, by its end, an error or Ctrl-C (ROS's default: wall time).
#pragma once

#include <ros/node_handle.h>

namespace lcp_contact_solver_ros {

class SimTimeGuard {
 public:
  explicit SimTimeGuard(const ros::NodeHandle& pnh);
  ~SimTimeGuard();
  SimTimeGuard(const SimTimeGuard&) = delete;
  SimTimeGuard& operator=(const SimTimeGuard&) = delete;

 private:
  bool restore_ = false;
};

}  // namespace lcp_contact_solver_ros
