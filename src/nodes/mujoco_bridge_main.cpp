// The MuJoCo bridge: see include/lcp_contact_solver/ros/mujoco_bridge_node.h.
#include "lcp_contact_solver/ros/mujoco_bridge_node.h"

#include <stdexcept>

int main(int argc, char** argv) {
  ros::init(argc, argv, "mujoco_bridge");
  try {
    lcp_contact_solver_ros::MujocoBridgeNode node(ros::NodeHandle(), ros::NodeHandle("~"));
    return node.run() ? 0 : 1;
  } catch (const std::invalid_argument& e) {
    ROS_FATAL_STREAM("Invalid parameter: " << e.what());
  } catch (const std::runtime_error& e) {
    ROS_FATAL_STREAM("MuJoCo bridge stopped: " << e.what());
  }
  return 1;
}
