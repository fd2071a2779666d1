#include "lcp_contact_solver/ros/contact_solver_node.h"

#include <stdexcept>

int main(int argc, char** argv) {
  ros::init(argc, argv, "contact_solver");
  try {
    lcp_contact_solver_ros::ContactSolverNode node(ros::NodeHandle(), ros::NodeHandle("~"));
    ros::spin();
  } catch (const std::invalid_argument& e) {
    ROS_FATAL_STREAM("Invalid parameter: " << e.what());
    return 1;
  }
  return 0;
}
