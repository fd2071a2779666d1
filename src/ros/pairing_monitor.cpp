#include "lcp_contact_solver/ros/pairing_monitor.h"

namespace lcp_contact_solver_ros {

void PairingMonitor::expect(const std_msgs::Header& header, const ros::Time& now) {
  waiting_[header.stamp] = Waiting{header, now};
}

void PairingMonitor::paired(const ros::Time& stamp) { waiting_.erase(stamp); }

std::vector<std_msgs::Header> PairingMonitor::takeExpired(const ros::Time& now, double window) {
  std::vector<std_msgs::Header> expired;
  for (auto it = waiting_.begin(); it != waiting_.end();) {
    if ((now - it->second.received).toSec() > window) {
      expired.push_back(it->second.header);
      it = waiting_.erase(it);
    } else {
      ++it;
    }
  }
  return expired;
}

}  // namespace lcp_contact_solver_ros
