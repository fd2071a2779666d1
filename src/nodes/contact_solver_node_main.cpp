#include "lcp_contact_solver/ros/node/contact_solver_node.h"

#include <stdexcept>

int main(int argc, char** argv) {
  ros::init(argc, argv, "contact_solver");
  // The handles outlive the try block: when the last one goes, roscpp shuts down and
  // rosconsole with it, and the fatal line below would never be printed.
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  try {
    lcp_contact_solver_ros::ContactSolverNode node(nh, pnh);
    ros::spin();
  } catch (const std::invalid_argument& e) {
    ROS_FATAL_STREAM("Invalid parameter: " << e.what());
    return 1;
  }
  return 0;
}
