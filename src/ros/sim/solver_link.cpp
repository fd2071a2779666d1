#include "lcp_contact_solver/ros/sim/solver_link.h"

#include <ros/callback_queue.h>
#include <rosgraph_msgs/Clock.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <iostream>
#include <sstream>

namespace lcp_contact_solver_ros {

namespace {

// Callbacks are served in slices this long while waiting (wall s).
constexpr double kSpinSlice = 0.01;

bool finite(double v) { return std::isfinite(v); }

void serve(double seconds) { ros::getGlobalCallbackQueue()->callAvailable(ros::WallDuration(seconds)); }

// What a parameter of this setting's type must be, for the error message.
const char* expectedValue(const std::variant<double*, int*, bool*, std::string*>& setting) {
  switch (setting.index()) {
    case 0: return "a number";
    case 1: return "an integer";
    case 2: return "true or false";
    default: return "a string";
  }
}

}  // namespace

std::string readParams(const ros::NodeHandle& pnh, std::initializer_list<ParamField> fields) {
  for (const ParamField& field : fields) {
    if (!pnh.hasParam(field.name)) continue;
    const bool read =
        std::visit([&](auto* setting) { return pnh.getParam(field.name, *setting); }, field.setting);
    if (!read) return "parameter " + pnh.resolveName(field.name) + " must be " + expectedValue(field.setting);
  }
  return "";
}

std::string loadLinkSettings(const ros::NodeHandle& pnh, LinkSettings* s) {
  const std::string error = readParams(
      pnh, {LCS_PARAM_FIELD(s, duration), LCS_PARAM_FIELD(s, rate_factor), LCS_PARAM_FIELD(s, force_timeout),
            LCS_PARAM_FIELD(s, wait_for_solver), LCS_PARAM_FIELD(s, linger), LCS_PARAM_FIELD(s, frame_id),
            LCS_PARAM_FIELD(s, publish_clock), LCS_PARAM_FIELD(s, status_period)});
  return error.empty() ? validateLinkSettings(*s) : error;
}

std::string loadSettings(const ros::NodeHandle& pnh, LinkSettings* link,
                         std::initializer_list<ParamField> fields,
                         const std::function<std::string()>& validate) {
  std::string error = loadLinkSettings(pnh, link);
  if (error.empty()) error = readParams(pnh, fields);
  return error.empty() ? validate() : error;
}

std::string validateLinkSettings(const LinkSettings& s) {
  if (!finite(s.duration) || s.duration < 0.0) return "parameter duration must be >= 0 (0 runs for ever)";
  if (!finite(s.rate_factor) || s.rate_factor < 0.0)
    return "parameter rate_factor must be >= 0 (0 runs as fast as possible)";
  if (!finite(s.force_timeout)) return "parameter force_timeout must be finite (<= 0 waits for ever)";
  if (!finite(s.wait_for_solver)) return "parameter wait_for_solver must be finite (<= 0 waits for ever)";
  if (!finite(s.linger) || s.linger < 0.0) return "parameter linger must be >= 0";
  if (s.frame_id.empty()) return "parameter frame_id must not be empty";
  if (!finite(s.status_period) || s.status_period <= 0.0) return "parameter status_period must be > 0";
  return "";
}

ros::Time stepStamp(std::int64_t step_index, double dt) {
  ros::Time stamp;
  stamp.fromNSec(static_cast<std::uint64_t>(std::llround(static_cast<double>(step_index) * dt * 1e9)));
  return stamp;
}

std::string stampText(const ros::Time& stamp) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(3) << stamp.toSec() << " s";
  return out.str();
}

SolverLink::SolverLink(ros::NodeHandle nh, const LinkSettings& settings, Options options)
    : nh_(std::move(nh)), settings_(settings), options_(std::move(options)) {
  contacts_pub_ = nh_.advertise<lcp_contact_solver::ContactArray>("contacts", 10);
  compliance_pub_ = nh_.advertise<lcp_contact_solver::Compliance>("compliance", 10);
  if (settings_.publish_clock) clock_pub_ = nh_.advertise<rosgraph_msgs::Clock>("/clock", 10);
  forces_sub_ = nh_.subscribe("constraint_forces", 10, &SolverLink::onForces, this);
  stats_sub_ = nh_.subscribe("contact_solver/stats", 10, &SolverLink::onStats, this);
}

// ---- callbacks ------------------------------------------------------------------------

void SolverLink::onForces(const lcp_contact_solver::ConstraintForces::ConstPtr& msg) {
  if (!awaiting_ || msg->header.stamp != awaiting_stamp_) {
    ++counters_.stale_forces;
    ROS_DEBUG_STREAM("Ignoring forces stamped " << stampText(msg->header.stamp) << " (not the current step)");
    return;
  }
  received_ = msg;
}

void SolverLink::onStats(const lcp_contact_solver::SolverStats::ConstPtr& msg) {
  if (stats_callback_) stats_callback_(*msg);
  if (!awaiting_ || msg->header.stamp != awaiting_stamp_) return;
  stats_ = msg;
  if (received_) return;
  if (!msg->success)
    solver_failure_ = msg->status + (msg->message.empty() ? "" : ": " + msg->message);
  else if (!msg->forces_published)
    solver_failure_ = "the solver did not publish the forces";
}

// ---- connection -----------------------------------------------------------------------

bool SolverLink::connected() const {
  const std::uint32_t need = options_.min_subscribers;
  return contacts_pub_.getNumSubscribers() >= need && compliance_pub_.getNumSubscribers() >= need &&
         forces_sub_.getNumPublishers() > 0 && (!options_.also_ready || options_.also_ready());
}

bool SolverLink::waitForSolver() {
  const bool forever = settings_.wait_for_solver <= 0.0;
  const ros::WallTime start = ros::WallTime::now();
  bool told = false;
  while (ros::ok() && !connected()) {
    const double waited = (ros::WallTime::now() - start).toSec();
    if (!forever && waited >= settings_.wait_for_solver) break;
    if (!told && waited > 1.0) {
      ROS_INFO_STREAM("Waiting for the contact solver: "
                      << contacts_pub_.getNumSubscribers() << " of " << options_.min_subscribers
                      << " subscribers on " << contacts_pub_.getTopic() << ", "
                      << forces_sub_.getNumPublishers() << " publisher of " << forces_sub_.getTopic());
      told = true;
    }
    serve(kSpinSlice);
  }
  if (connected()) return true;
  if (ros::ok())
    ROS_FATAL_STREAM("No contact solver within "
                     << settings_.wait_for_solver << " s: " << contacts_pub_.getTopic() << " has "
                     << contacts_pub_.getNumSubscribers() << " subscribers (" << options_.min_subscribers
                     << " needed), " << forces_sub_.getTopic() << " has " << forces_sub_.getNumPublishers()
                     << " publishers");
  return false;
}

// ---- one step -------------------------------------------------------------------------

SolverLink::Outcome SolverLink::exchange(const ros::Time& stamp,
                                         const lcp_contact_solver::ContactArray::ConstPtr& contacts,
                                         const lcp_contact_solver::Compliance::ConstPtr& compliance) {
  awaiting_ = true;
  awaiting_stamp_ = stamp;
  received_.reset();
  stats_.reset();
  solver_failure_.clear();
  compliance_pub_.publish(compliance);
  contacts_pub_.publish(contacts);
  const Outcome outcome = waitForForces(stamp);
  awaiting_ = false;
  if (outcome == Outcome::kTimeout || outcome == Outcome::kNoSolver) ++counters_.force_timeouts;
  if (outcome == Outcome::kSolverFailed) ++counters_.solver_failures;
  return outcome;
}

SolverLink::Outcome SolverLink::waitForForces(const ros::Time& stamp) {
  const bool forever = settings_.force_timeout <= 0.0;
  const ros::WallTime start = ros::WallTime::now();
  ros::WallTime next_note = start + ros::WallDuration(5.0);
  while (true) {
    if (received_) {
      waitForStats();
      return Outcome::kForces;
    }
    if (!solver_failure_.empty()) return Outcome::kSolverFailed;
    if (!ros::ok()) return Outcome::kShutdown;
    // The solver went away: do not wait for it step after step.
    if (!forever && options_.stop_when_solver_leaves && forces_sub_.getNumPublishers() == 0)
      return Outcome::kNoSolver;
    const ros::WallTime now = ros::WallTime::now();
    double slice = kSpinSlice;
    if (!forever) {
      const double remaining = settings_.force_timeout - (now - start).toSec();
      if (remaining <= 0.0) return Outcome::kTimeout;
      slice = std::min(slice, remaining);
    } else if (now >= next_note) {
      ROS_WARN_STREAM("Still waiting for the forces of the step at " << stampText(stamp) << " ("
                                                                     << (now - start).toSec() << " s)");
      next_note = now + ros::WallDuration(5.0);
    }
    serve(slice);
  }
}

void SolverLink::waitForStats() {
  const ros::WallTime got = ros::WallTime::now();
  while (!stats_ && ros::ok() && (ros::WallTime::now() - got).toSec() < options_.stats_grace) serve(0.002);
}

// ---- between and after steps ----------------------------------------------------------

void SolverLink::publishClock(const ros::Time& stamp) {
  if (!settings_.publish_clock) return;
  rosgraph_msgs::Clock clock;
  clock.clock = stamp;
  clock_pub_.publish(clock);
}

void SolverLink::pace(double sim_time) {
  if (settings_.rate_factor <= 0.0) {
    ros::getGlobalCallbackQueue()->callAvailable();  // serve callbacks without waiting
    return;
  }
  const ros::WallTime target = run_start_ + ros::WallDuration(sim_time / settings_.rate_factor);
  while (ros::ok()) {
    const double remaining = (target - ros::WallTime::now()).toSec();
    if (remaining <= 0.0) break;
    serve(std::min(remaining, kSpinSlice));
  }
}

// roscpp writes published messages from its own thread: a node that exits right after its
// last publish can close the connections before a busy subscriber has read them.
void SolverLink::linger() {
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(settings_.linger);
  while (ros::ok() && ros::WallTime::now() < end) serve(kSpinSlice);
}

void SolverLink::logSummary(const std::string& what, bool print, const std::string& summary,
                            std::int64_t steps) const {
  const char* end = ros::ok() ? "finished" : "interrupted";
  if (print) {  // the table on stdout, one line in the log
    std::cout << summary << std::flush;
    ROS_INFO_STREAM(what << " " << end << ": " << steps << " steps, " << counters_.misses()
                         << " without the solver's forces");
  } else {
    ROS_INFO_STREAM(what << " " << end << "\n" << summary);
  }
}

}  // namespace lcp_contact_solver_ros
