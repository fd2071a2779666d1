// The "solve rate" diagnostic: the node's solves per second over the last report period.
// diagnostic_updater's FrequencyStatus says ERROR "No events recorded" when nothing came in,
// which is how a healthy node looks while it waits for a simulator; this one says so (OK,
// "waiting for contacts") and warns only when contacts arrive and the rate is outside its band.
#pragma once

#include <diagnostic_updater/diagnostic_updater.h>
#include <ros/time.h>

#include <cstdint>
#include <mutex>

namespace lcp_contact_solver_ros {

class SolveRateStatus : public diagnostic_updater::DiagnosticTask {
 public:
  SolveRateStatus(double min_rate, double max_rate);

  void contactsReceived();  // a ContactArray reached the node
  void solved();            // a pair was solved
  void run(diagnostic_updater::DiagnosticStatusWrapper& status) override;

 private:
  const double min_rate_;
  const double max_rate_;
  std::mutex mutex_;
  std::uint64_t received_ = 0;  // since the last report
  std::uint64_t solved_ = 0;
  std::uint64_t received_total_ = 0;
  ros::WallTime window_start_;
  ros::WallTime last_input_;
};

}  // namespace lcp_contact_solver_ros
