#include "lcp_contact_solver/ros/contact_solver_node.h"

#include "lcp_contact_solver/core/residual.h"
#include "lcp_contact_solver/ros/cycle_log.h"
#include "lcp_contact_solver/ros/markers.h"

#include <lcp_contact_solver/ConstraintForces.h>
#include <lcp_contact_solver/SolverStats.h>
#include <visualization_msgs/MarkerArray.h>

#include <boost/make_shared.hpp>

#include <algorithm>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace lcp_contact_solver_ros {

namespace {

using lcp_contact_solver::SolverStats;

std::string stampText(const ros::Time& stamp) {
  std::ostringstream out;
  out << stamp;
  return out.str();
}

NodeSettings loadOrThrow(const ros::NodeHandle& pnh) {
  NodeSettings settings;
  const std::string error = loadSettings(pnh, &settings);
  if (!error.empty()) throw std::invalid_argument(error);
  return settings;
}

}  // namespace

ContactSolverNode::ContactSolverNode(const ros::NodeHandle& nh, const ros::NodeHandle& pnh)
    : nh_(nh),
      pnh_(pnh),
      accepted_(loadOrThrow(pnh)),
      active_(accepted_),
      cycle_(accepted_.solver),
      updater_(nh, pnh, pnh.getNamespace()) {
  setUpDiagnostics();
  setUpReconfigure();
  setUpTopics();
}

void ContactSolverNode::setUpTopics() {
  const int queue = active_.queue_size;
  forces_pub_ = nh_.advertise<lcp_contact_solver::ConstraintForces>("constraint_forces", queue);
  stats_pub_ = pnh_.advertise<SolverStats>("stats", queue);
  markers_pub_ = pnh_.advertise<visualization_msgs::MarkerArray>("markers", 1);
  solve_service_ = pnh_.advertiseService("solve_contacts", &ContactSolverNode::onSolveService, this);

  // onContacts must run before the synchronizer sees the array (callbacks run in
  // registration order), or an array whose compliance came first would be reported as
  // unpaired after it was solved.
  contacts_sub_.registerCallback(&ContactSolverNode::onContacts, this);
  sync_ = std::make_unique<message_filters::Synchronizer<SyncPolicy>>(SyncPolicy(queue), contacts_sub_,
                                                                        compliance_sub_);
  sync_->registerCallback(&ContactSolverNode::onPair, this);
  // TCP_NODELAY: without it the sender's kernel batches small messages (Nagle), and at
  // rates of ~1 kHz bursts overflow the queues (bench/soak.sh: a third of the pairs lost).
  contacts_sub_.subscribe(nh_, "contacts", queue, ros::TransportHints().tcpNoDelay());
  compliance_sub_.subscribe(nh_, "compliance", queue, ros::TransportHints().tcpNoDelay());

  const double period = std::min(0.25, active_.pairing_window / 4.0);
  timer_ = nh_.createTimer(ros::Duration(period), &ContactSolverNode::onTimer, this);
}

void ContactSolverNode::setUpReconfigure() {
  reconfigure_ = std::make_unique<dynamic_reconfigure::Server<Config>>(reconfigure_mutex_, pnh_);
  // Start from the loaded parameters (showTranslation comes from a list the server does
  // not read), then let the server call back once with them.
  reconfigure_->updateConfig(toConfig(accepted_));
  reconfigure_->setCallback([this](Config& config, std::uint32_t level) { onReconfigure(config, level); });
}

void ContactSolverNode::setUpDiagnostics() {
  min_rate_ = active_.diagnostics_min_rate;
  max_rate_ = active_.diagnostics_max_rate;
  updater_.setHardwareID("lcp_contact_solver");
  frequency_ = std::make_unique<diagnostic_updater::FrequencyStatus>(
      diagnostic_updater::FrequencyStatusParam(&min_rate_, &max_rate_), "solve rate");
  updater_.add(*frequency_);
  updater_.add("solver", this, &ContactSolverNode::diagnose);
}

// ---- callbacks ------------------------------------------------------------------------

void ContactSolverNode::onContacts(const ContactArray::ConstPtr& contacts) {
  std::lock_guard<std::mutex> lock(solve_mutex_);
  pairing_.expect(contacts->header, ros::Time::now());
}

void ContactSolverNode::onPair(const ContactArray::ConstPtr& contacts, const Compliance::ConstPtr& compliance) {
  std::lock_guard<std::mutex> lock(solve_mutex_);
  pairing_.paired(contacts->header.stamp);
  applyAcceptedSettings();

  // computeConstraintForces=false only saves building the message when nobody listens.
  const bool want_forces = active_.solver.computeConstraintForces || forces_pub_.getNumSubscribers() > 0;
  CycleOutput cycle = cycle_.solve(*contacts, *compliance, want_forces);
  if (cycle.rejected()) {
    reject(contacts->header, SolverStats::INVALID_INPUT, cycle.error);
    return;
  }
  recordSolve(cycle.result);

  auto stats = boost::make_shared<SolverStats>(cycle.stats);
  if (cycle.gave_forces) {
    stats->forces_published = want_forces && publishForces(contacts->header, &cycle);
  } else {
    ROS_ERROR_STREAM_THROTTLE(1.0, "Contacts at " << stampText(contacts->header.stamp) << ": solve failed ("
                                                  << stats->status << "): " << cycle.result.message);
  }
  stats->markers_published = publishMarkers(contacts->header, cycle.frames, cycle.problem, cycle.result);
  if (active_.solver.displayDebug) logCycle(cycle.problem, cycle.result);
  if (allFinite(*stats)) stats_pub_.publish(stats);
}

bool ContactSolverNode::onSolveService(lcp_contact_solver::SolveContacts::Request& request,
                                       lcp_contact_solver::SolveContacts::Response& response) {
  auto fail = [&response, &request](const std::string& message) {
    response.success = false;
    response.message = message;
    response.stats = rejectedStatsMsg(request.contacts.header, SolverStats::INVALID_INPUT, message);
    return true;  // the call itself succeeded; the reply says what was wrong
  };
  lcs::SolverParams params = latestSettings().solver;
  for (const std::string& assignment : request.param_overrides) {
    const std::string error = applyOverride(assignment, &params);
    if (!error.empty()) return fail(error);
  }
  if (const std::string error = lcs::validateParams(params); !error.empty()) return fail(error);

  // A fresh cycle solver: no warm start memory, the node's own one untouched.
  params.initial_guess = false;
  CycleSolver one_off(params);
  CycleOutput cycle = one_off.solve(request.contacts, request.compliance);
  if (cycle.rejected()) return fail(cycle.error);

  response.stats = cycle.stats;
  if (cycle.gave_forces) {
    if (!cycle.has_forces) return fail("the solve produced a non-finite force");
    response.forces = std::move(cycle.forces);
    response.stats.forces_published = true;
  }
  response.success = true;
  response.message = response.stats.status + (cycle.result.message.empty() ? "" : ": " + cycle.result.message);
  return true;
}

void ContactSolverNode::onReconfigure(Config& config, std::uint32_t /*level*/) {
  std::lock_guard<std::mutex> lock(settings_mutex_);
  NodeSettings next = accepted_;
  const std::string error = fromConfig(config, &next);
  if (!error.empty()) {
    ROS_ERROR_STREAM("dynamic_reconfigure change refused: " << error << "; the previous values stay in force");
    config = toConfig(accepted_);  // the reply shows what is in force
    return;
  }
  accepted_ = next;
  settings_changed_ = true;
}

void ContactSolverNode::onTimer(const ros::TimerEvent& /*event*/) {
  reportUnpaired();
  updater_.update();
}

void ContactSolverNode::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
  std::lock_guard<std::mutex> lock(solve_mutex_);
  if (health_.problems_since_report > 0 || !health_.last_converged) {
    status.summaryf(diagnostic_msgs::DiagnosticStatus::WARN, "last solve: %s; %lu rejected/unpaired/failed inputs since the last report",
                    health_.last_status.c_str(), static_cast<unsigned long>(health_.problems_since_report));
  } else {
    status.summaryf(diagnostic_msgs::DiagnosticStatus::OK, "last solve: %s", health_.last_status.c_str());
  }
  status.add("last residual", health_.last_residual);
  status.add("solves", health_.solves);
  status.add("non-converged solves", health_.not_converged);
  status.add("rejected inputs", health_.rejected);
  status.add("unpaired contact arrays", health_.unpaired);
  status.add("contact arrays waiting for compliance", pairing_.waiting());
  health_.problems_since_report = 0;
}

// ---- cycle steps ----------------------------------------------------------------------

void ContactSolverNode::applyAcceptedSettings() {
  NodeSettings next;
  {
    std::lock_guard<std::mutex> lock(settings_mutex_);
    if (!settings_changed_) return;
    next = accepted_;
    settings_changed_ = false;
  }
  const std::string error = cycle_.setParams(next.solver);
  if (!error.empty()) {  // validated when accepted; kept as a guard
    ROS_ERROR_STREAM("Parameters refused by the solver: " << error);
    return;
  }
  active_ = next;
}

void ContactSolverNode::recordSolve(const lcs::SolveResult& result) {
  frequency_->tick();
  ++health_.solves;
  health_.last_residual = result.residual;
  health_.last_status = lcs::statusName(result.status);
  health_.last_converged = result.converged;
  if (!result.converged) {
    ++health_.not_converged;
    ++health_.problems_since_report;
  }
}

void ContactSolverNode::reject(const std_msgs::Header& header, std::uint8_t status_code, const std::string& message) {
  ++health_.rejected;
  ++health_.problems_since_report;
  ROS_ERROR_STREAM_THROTTLE(1.0, "Rejected contacts at " << stampText(header.stamp) << ": " << message);
  stats_pub_.publish(boost::make_shared<SolverStats>(rejectedStatsMsg(header, status_code, message)));
}

bool ContactSolverNode::publishForces(const std_msgs::Header& header, CycleOutput* cycle) {
  if (!cycle->has_forces) {
    ROS_ERROR_STREAM_THROTTLE(1.0, "Contacts at " << stampText(header.stamp)
                                                  << ": a force is not finite; nothing published");
    return false;
  }
  forces_pub_.publish(boost::make_shared<lcp_contact_solver::ConstraintForces>(std::move(cycle->forces)));
  return true;
}

bool ContactSolverNode::publishMarkers(const std_msgs::Header& header, const std::vector<ContactFrame>& frames,
                                       const lcs::Problem& problem, const lcs::SolveResult& result) {
  if (!shouldBuildMarkers(markers_pub_.getNumSubscribers())) return false;
  const std::vector<double> mu = lcs::effectiveMu(problem, active_.solver.mu);
  markers_pub_.publish(boost::make_shared<visualization_msgs::MarkerArray>(
      buildMarkers(header, frames, problem, result, mu, active_.display)));
  return true;
}

void ContactSolverNode::logCycle(const lcs::Problem& problem, const lcs::SolveResult& result) {
  ROS_INFO_STREAM(cycleSummary(problem, result, lcs::effectiveMu(problem, active_.solver.mu)));
  if (!result.residual_history.empty()) {
    std::ostringstream history;
    for (double r : result.residual_history) history << ' ' << r;
    ROS_DEBUG_STREAM("residual per iteration:" << history.str());
  }
}

void ContactSolverNode::reportUnpaired() {
  std::lock_guard<std::mutex> lock(solve_mutex_);
  for (const std_msgs::Header& header : pairing_.takeExpired(ros::Time::now(), active_.pairing_window)) {
    ++health_.unpaired;
    ++health_.problems_since_report;
    const std::string message = "no compliance with stamp " + stampText(header.stamp) + " arrived within " +
                                std::to_string(active_.pairing_window) + " s";
    ROS_WARN_STREAM_THROTTLE(1.0, "Contacts at " << stampText(header.stamp) << " not solved: " << message);
    stats_pub_.publish(boost::make_shared<SolverStats>(rejectedStatsMsg(header, SolverStats::NO_COMPLIANCE, message)));
  }
}

NodeSettings ContactSolverNode::latestSettings() {
  std::lock_guard<std::mutex> lock(settings_mutex_);
  return accepted_;
}

}  // namespace lcp_contact_solver_ros
