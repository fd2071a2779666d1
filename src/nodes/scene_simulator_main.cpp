// The example simulator node: see include/lcp_contact_solver/ros/scene_simulator_node.h.
#include "lcp_contact_solver/ros/scene_simulator_node.h"
#include "lcp_contact_solver/scene/scene_params.h"

#include <stdexcept>

int main(int argc, char** argv) {
  ros::init(argc, argv, "scene_simulator");
  try {
    lcp_contact_solver_ros::SceneSimulatorNode node(ros::NodeHandle(), ros::NodeHandle("~"));
    return node.run() ? 0 : 1;
  } catch (const std::invalid_argument& e) {
    ROS_FATAL_STREAM("Invalid parameter: " << e.what());
  } catch (const lcp_contact_solver::scene::SceneError& e) {
    ROS_FATAL_STREAM("Cannot load the scene: " << e.what());
  }
  return 1;
}
