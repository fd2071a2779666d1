#include "lcp_contact_solver/ros/sim/sim_time_guard.h"

#include <ros/console.h>
#include <ros/param.h>

namespace lcp_contact_solver_ros {

SimTimeGuard::SimTimeGuard(const ros::NodeHandle& pnh) { pnh.param("restore_use_sim_time", restore_, false); }

SimTimeGuard::~SimTimeGuard() {
  if (!restore_) return;
  // The master may be gone already (roslaunch started it and is stopping): nothing to do.
  if (ros::param::del("/use_sim_time")) ROS_INFO("/use_sim_time removed: tools started now use wall time");
}

}  // namespace lcp_contact_solver_ros
