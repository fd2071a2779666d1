// The node class inside a nodelet manager: messages between nodelets pass as shared
// pointers without serialization.
#include "lcp_contact_solver/ros/node/contact_solver_node.h"

#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>

#include <memory>
#include <stdexcept>

namespace lcp_contact_solver_ros {

class ContactSolverNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    try {
      node_ = std::make_unique<ContactSolverNode>(getNodeHandle(), getPrivateNodeHandle());
    } catch (const std::invalid_argument& e) {
      // Leave the manager running; this nodelet stays inactive.
      NODELET_FATAL_STREAM("Invalid parameter, not starting: " << e.what());
    }
  }

  std::unique_ptr<ContactSolverNode> node_;
};

}  // namespace lcp_contact_solver_ros

PLUGINLIB_EXPORT_CLASS(lcp_contact_solver_ros::ContactSolverNodelet, nodelet::Nodelet)
