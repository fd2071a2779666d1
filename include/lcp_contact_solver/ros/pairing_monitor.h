// Remembers contact arrays waiting for their compliance, so one whose partner never comes
// is reported after a window instead of vanishing silently in the synchronizer's queue.
#pragma once

#include <ros/time.h>
#include <std_msgs/Header.h>

#include <map>
#include <vector>

namespace lcp_contact_solver_ros {

class PairingMonitor {
 public:
  // A contact array arrived at `now` (receive time, not its stamp).
  void expect(const std_msgs::Header& header, const ros::Time& now);
  // Its compliance arrived: nothing to report.
  void paired(const ros::Time& stamp);
  // Removes and returns the headers waiting longer than `window` seconds.
  std::vector<std_msgs::Header> takeExpired(const ros::Time& now, double window);
  std::size_t waiting() const { return waiting_.size(); }

 private:
  struct Waiting {
    std_msgs::Header header;
    ros::Time received;
  };
  std::map<ros::Time, Waiting> waiting_;  // by stamp
};

}  // namespace lcp_contact_solver_ros
