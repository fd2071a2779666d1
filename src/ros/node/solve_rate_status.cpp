#include "lcp_contact_solver/ros/node/solve_rate_status.h"

#include <diagnostic_msgs/DiagnosticStatus.h>

namespace lcp_contact_solver_ros {

using diagnostic_msgs::DiagnosticStatus;

SolveRateStatus::SolveRateStatus(double min_rate, double max_rate)
    : DiagnosticTask("solve rate"),
      min_rate_(min_rate),
      max_rate_(max_rate),
      window_start_(ros::WallTime::now()) {}

void SolveRateStatus::contactsReceived() {
  std::lock_guard<std::mutex> lock(mutex_);
  ++received_;
  ++received_total_;
  last_input_ = ros::WallTime::now();
}

void SolveRateStatus::solved() {
  std::lock_guard<std::mutex> lock(mutex_);
  ++solved_;
}

// Wall time: the rate a user cares about is per real second, also under simulated time
// (and a paused /clock must not freeze the window).
void SolveRateStatus::run(diagnostic_updater::DiagnosticStatusWrapper& status) {
  std::lock_guard<std::mutex> lock(mutex_);
  const ros::WallTime now = ros::WallTime::now();
  const double window = (now - window_start_).toSec();
  const double rate = window > 0.0 ? static_cast<double>(solved_) / window : 0.0;
  if (received_ == 0) {
    if (received_total_ == 0) {
      status.summary(DiagnosticStatus::OK, "waiting for contacts (none received yet)");
    } else {
      status.summaryf(DiagnosticStatus::OK, "waiting for contacts (last received %.1f s ago)",
                      (now - last_input_).toSec());
    }
  } else if (rate < min_rate_) {
    status.summaryf(DiagnosticStatus::WARN, "solving at %.1f Hz, below %.1f Hz", rate, min_rate_);
  } else if (rate > max_rate_) {
    status.summaryf(DiagnosticStatus::WARN, "solving at %.1f Hz, above %.1f Hz", rate, max_rate_);
  } else {
    status.summaryf(DiagnosticStatus::OK, "solving at %.1f Hz", rate);
  }
  status.add("contact arrays received", received_);
  status.add("solves", solved_);
  status.add("window (s)", window);
  status.add("rate (Hz)", rate);
  status.add("minimum acceptable rate (Hz)", min_rate_);
  status.add("maximum acceptable rate (Hz)", max_rate_);
  received_ = 0;
  solved_ = 0;
  window_start_ = now;
}

}  // namespace lcp_contact_solver_ros
