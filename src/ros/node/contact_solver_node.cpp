#include "lcp_contact_solver/ros/node/contact_solver_node.h"

#include "lcp_contact_solver/core/residual.h"
#include "lcp_contact_solver/ros/node/cycle_log.h"
#include "lcp_contact_solver/ros/node/markers.h"

#include <lcp_contact_solver/ConstraintForces.h>
#include <lcp_contact_solver/SolverStats.h>
#include <visualization_msgs/MarkerArray.h>

#include <boost/make_shared.hpp>

#include <algorithm>
#include <atomic>
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

// The pairing window's clock (see the timer in setUpTopics).
ros::Time wallNow() {
  const ros::WallTime now = ros::WallTime::now();
  return ros::Time(now.sec, now.nsec);
}

// When roscpp had the whole message, on the node's wall clock: its receipt time (taken by the
// network thread, before the message waited for the input thread and was deserialized there)
// is ROS time, so it is placed on the wall clock only under wall time; with /use_sim_time the
// callback's own time stands. So a pair's latency counts from its bytes' arrival.
ros::Time arrivalOf(const ros::Time& receipt) {
  const ros::Time wall = wallNow();
  if (ros::Time::isSimTime() || receipt.isZero()) return wall;
  const double waited = (ros::Time::now() - receipt).toSec();
  return waited > 0.0 && waited < 1.0 ? wall - ros::Duration(waited) : wall;
}

// For warnings throttled in wall time: rosconsole's *_THROTTLE count ROS time, and with
// /use_sim_time a simulator whose runs last under the period (or whose clock restarts or
// stops) never gets them (found by the simulator-restart rostest). True at most once per
// `period` wall seconds per `last`.
bool wallThrottle(std::atomic<double>* last, double period) {
  const double now = ros::WallTime::now().toSec();
  double previous = last->load();
  return now - previous >= period && last->compare_exchange_strong(previous, now);
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
      inputs_(accepted_.overload, static_cast<std::size_t>(accepted_.queue_size)),
      updater_(nh, pnh, pnh.getNamespace()) {
  setUpDiagnostics();
  setUpReconfigure();
  solver_thread_ = std::thread([this] { solverLoop(); });
  setUpTopics();
}

ContactSolverNode::~ContactSolverNode() {
  if (input_spinner_) input_spinner_->stop();
  contacts_sub_.shutdown();
  compliance_sub_.shutdown();
  running_ = false;
  inputs_.stop();
  if (solver_thread_.joinable()) solver_thread_.join();
}

void ContactSolverNode::setUpTopics() {
  const int queue = active_.queue_size;
  forces_pub_ = nh_.advertise<lcp_contact_solver::ConstraintForces>("constraint_forces", queue);
  // Deep: one stats message per array, also for a burst of dropped ones.
  stats_pub_ = pnh_.advertise<SolverStats>("stats", std::max(queue, 1000));
  markers_pub_ = pnh_.advertise<visualization_msgs::MarkerArray>("markers", 1);
  solve_service_ = pnh_.advertiseService("solve_contacts", &ContactSolverNode::onSolveService, this);

  // The input callbacks only hand the messages to inputs_ (cheap) on a thread and callback
  // queue of their own, so neither a solve nor the timers and services delay them, and
  // roscpp's receive queues (which drop silently) stay short: the backlog is in inputs_,
  // where it is counted. Found by the overload rostest on a loaded machine: with the input
  // callbacks on the shared queue, a compliance dropped there became a "no_compliance".
  // TCP_NODELAY: without it the sender's kernel batches small messages (Nagle), and at
  // rates of ~1 kHz bursts overflow the queues (bench/soak.sh: a third of the pairs lost).
  constexpr int kReceiveQueue = 10000;  // ~10 s at 1 kHz before roscpp could drop one
  // Message events: their receipt time is when the bytes arrived (arrivalOf).
  using ContactsEvent = const ros::MessageEvent<ContactArray const>&;
  using ComplianceEvent = const ros::MessageEvent<Compliance const>&;
  ros::SubscribeOptions contacts;
  contacts.initByFullCallbackType<ContactsEvent>("contacts", kReceiveQueue, [this](ContactsEvent e) {
    onContacts(e.getConstMessage(), arrivalOf(e.getReceiptTime()));
  });
  contacts.callback_queue = &input_callbacks_;
  contacts.transport_hints = ros::TransportHints().tcpNoDelay();
  contacts_sub_ = nh_.subscribe(contacts);
  ros::SubscribeOptions compliance;
  compliance.initByFullCallbackType<ComplianceEvent>("compliance", kReceiveQueue, [this](ComplianceEvent e) {
    onCompliance(e.getConstMessage(), arrivalOf(e.getReceiptTime()));
  });
  compliance.callback_queue = &input_callbacks_;
  compliance.transport_hints = ros::TransportHints().tcpNoDelay();
  compliance_sub_ = nh_.subscribe(compliance);
  input_spinner_ = std::make_unique<ros::AsyncSpinner>(1, &input_callbacks_);
  input_spinner_->start();

  const double period = std::min(0.25, active_.pairing_window / 4.0);
  // Wall time: the pairing window is about messages in transit, and with /use_sim_time a
  // stopped /clock must not stop reports (nor a fast one call pairs unpaired in transit).
  timer_ = nh_.createWallTimer(ros::WallDuration(period), &ContactSolverNode::onTimer, this);
}

void ContactSolverNode::setUpReconfigure() {
  reconfigure_ = std::make_unique<dynamic_reconfigure::Server<Config>>(reconfigure_mutex_, pnh_);
  // Start from the loaded parameters (showTranslation comes from a list the server does
  // not read), then let the server call back once with them.
  reconfigure_->updateConfig(toConfig(accepted_));
  reconfigure_->setCallback([this](Config& config, std::uint32_t level) { onReconfigure(config, level); });
}

void ContactSolverNode::setUpDiagnostics() {
  updater_.setHardwareID("lcp_contact_solver");
  solve_rate_ = std::make_unique<SolveRateStatus>(active_.diagnostics_min_rate, active_.diagnostics_max_rate);
  updater_.add(*solve_rate_);
  updater_.add("solver", this, &ContactSolverNode::diagnose);
}

// ---- callbacks ------------------------------------------------------------------------

void ContactSolverNode::onContacts(const ContactArray::ConstPtr& contacts, const ros::Time& arrival) {
  solve_rate_->contactsReceived();
  inputs_.addContacts(contacts, arrival);
}

void ContactSolverNode::onCompliance(const Compliance::ConstPtr& compliance, const ros::Time& arrival) {
  inputs_.addCompliance(compliance, arrival);
}

void ContactSolverNode::solverLoop() {
  std::vector<UnsolvedInput> dropped;
  InputPair pair;
  while (running_) {
    dropped.clear();
    const bool got = inputs_.take(std::chrono::milliseconds(100), &pair, &dropped);
    for (const UnsolvedInput& input : dropped) reportUnsolved(input);
    if (got) onPair(pair);
  }
}

void ContactSolverNode::onPair(const InputPair& pair) {
  const ContactArray::ConstPtr& contacts = pair.contacts;
  const Compliance::ConstPtr& compliance = pair.compliance;
  const double queue_time = (ros::WallTime::now() - pair.complete).toSec();
  std::lock_guard<std::mutex> lock(solve_mutex_);
  applyAcceptedSettings();
  // Stamps going back mean the simulator restarted (or its clock was reset): the contact
  // ids it sends now name other contacts, so the previous forces must not seed them.
  if (!last_stamp_.isZero() && contacts->header.stamp < last_stamp_) {
    static std::atomic<double> last_warning{0.0};
    if (wallThrottle(&last_warning, 1.0))
      ROS_WARN_STREAM("Contacts at " << stampText(contacts->header.stamp) << " come after "
                                     << stampText(last_stamp_) << ": time jumped back (simulator restart?); "
                                     << "the warm start is reset");
    cycle_.resetWarmStart();
  }
  last_stamp_ = contacts->header.stamp;

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
  stats->queue_time = queue_time;
  stats->latency = (ros::WallTime::now() - pair.complete).toSec();
  {
    std::lock_guard<std::mutex> health_lock(health_mutex_);
    health_.max_queue_time = std::max(health_.max_queue_time, stats->queue_time);
    health_.max_latency = std::max(health_.max_latency, stats->latency);
  }
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
  lcs::core::SolverParams params = latestSettings().solver;
  for (const std::string& assignment : request.param_overrides) {
    const std::string error = applyOverride(assignment, &params);
    if (!error.empty()) return fail(error);
  }
  if (const std::string error = lcs::core::validateParams(params); !error.empty()) return fail(error);

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
  response.message =
      response.stats.status + (cycle.result.message.empty() ? "" : ": " + cycle.result.message);
  return true;
}

void ContactSolverNode::onReconfigure(Config& config, std::uint32_t /*level*/) {
  std::lock_guard<std::mutex> lock(settings_mutex_);
  NodeSettings next = accepted_;
  const std::string error = fromConfig(config, &next);
  if (!error.empty()) {
    ROS_ERROR_STREAM("dynamic_reconfigure change refused: " << error
                                                            << "; the previous values stay in force");
    config = toConfig(accepted_);  // the reply shows what is in force
    return;
  }
  accepted_ = next;
  settings_changed_ = true;
  // dynamic_reconfigure writes showTranslation_x/_y/_z to the parameter server; the SOFA
  // list beside them must say the same, or `rosparam get` shows a stale position.
  const auto& t = accepted_.display.showTranslation;
  pnh_.setParam("showTranslation", std::vector<double>(t.begin(), t.end()));
}

void ContactSolverNode::onTimer(const ros::WallTimerEvent& /*event*/) {
  for (const UnsolvedInput& input : inputs_.takeExpired(wallNow(), active_.pairing_window))
    reportUnsolved(input);
  updater_.update();
}

void ContactSolverNode::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
  const InputCounts inputs = inputs_.counts();
  std::lock_guard<std::mutex> lock(health_mutex_);
  if (health_.problems_since_report > 0 || !health_.last_converged) {
    status.summaryf(diagnostic_msgs::DiagnosticStatus::WARN,
                    "last solve: %s; %lu rejected/unpaired/failed inputs since the last report",
                    health_.last_status.c_str(), static_cast<unsigned long>(health_.problems_since_report));
  } else {
    status.summaryf(diagnostic_msgs::DiagnosticStatus::OK, "last solve: %s", health_.last_status.c_str());
  }
  status.add("last residual", health_.last_residual);
  status.add("solves", health_.solves);
  status.add("non-converged solves", health_.not_converged);
  status.add("rejected inputs", health_.rejected);
  status.add("unpaired contact arrays", inputs.unpaired);
  // Every ContactArray received is in exactly one of the five counts below.
  status.add("contact arrays received", inputs.arrays_received);
  status.add("outcome: solved", health_.solves);
  status.add("outcome: rejected", health_.rejected);
  status.add("outcome: unpaired (no compliance)", inputs.unpaired);
  status.add("outcome: dropped (node behind)", inputs.dropped);
  status.add("outcome: waiting or being solved",
             inputs.arrays_received - health_.solves - health_.rejected - inputs.unpaired - inputs.dropped);
  status.add("compliances without contact array", inputs.compliances_unpaired);
  status.add("overload policy", std::string(overloadPolicyName(inputs_.policy())));
  status.add("max queue time since last report (s)", health_.max_queue_time);
  status.add("max latency since last report (s)", health_.max_latency);
  health_.problems_since_report = 0;
  health_.max_queue_time = 0.0;
  health_.max_latency = 0.0;
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

void ContactSolverNode::recordSolve(const lcs::core::SolveResult& result) {
  solve_rate_->solved();
  std::lock_guard<std::mutex> lock(health_mutex_);
  ++health_.solves;
  health_.last_residual = result.residual;
  health_.last_status = lcs::core::statusName(result.status);
  health_.last_converged = result.converged;
  if (!result.converged) {
    ++health_.not_converged;
    ++health_.problems_since_report;
  }
}

void ContactSolverNode::reject(const std_msgs::Header& header, std::uint8_t status_code,
                               const std::string& message) {
  {
    std::lock_guard<std::mutex> lock(health_mutex_);
    ++health_.rejected;
    ++health_.problems_since_report;
  }
  ROS_ERROR_STREAM_THROTTLE(1.0, "Rejected contacts at " << stampText(header.stamp) << ": " << message);
  stats_pub_.publish(boost::make_shared<SolverStats>(rejectedStatsMsg(header, status_code, message)));
}

bool ContactSolverNode::publishForces(const std_msgs::Header& header, CycleOutput* cycle) {
  if (!cycle->has_forces) {
    ROS_ERROR_STREAM_THROTTLE(
        1.0, "Contacts at " << stampText(header.stamp) << ": a force is not finite; nothing published");
    return false;
  }
  forces_pub_.publish(boost::make_shared<lcp_contact_solver::ConstraintForces>(std::move(cycle->forces)));
  return true;
}

bool ContactSolverNode::publishMarkers(const std_msgs::Header& header,
                                       const std::vector<ContactFrame>& frames,
                                       const lcs::core::Problem& problem,
                                       const lcs::core::SolveResult& result) {
  if (!shouldBuildMarkers(markers_pub_.getNumSubscribers())) return false;
  const std::vector<double> mu = lcs::core::effectiveMu(problem, active_.solver.mu);
  markers_pub_.publish(boost::make_shared<visualization_msgs::MarkerArray>(
      buildMarkers(header, frames, problem, result, mu, active_.display)));
  return true;
}

void ContactSolverNode::logCycle(const lcs::core::Problem& problem, const lcs::core::SolveResult& result) {
  ROS_INFO_STREAM(cycleSummary(problem, result, lcs::core::effectiveMu(problem, active_.solver.mu)));
  if (!result.residual_history.empty()) {
    std::ostringstream history;
    for (double r : result.residual_history) history << ' ' << r;
    ROS_DEBUG_STREAM("residual per iteration:" << history.str());
  }
}

void ContactSolverNode::reportUnsolved(const UnsolvedInput& input) {
  {
    std::lock_guard<std::mutex> lock(health_mutex_);
    ++health_.problems_since_report;
  }
  static std::atomic<double> last_warning{0.0};
  if (wallThrottle(&last_warning, 1.0))
    ROS_WARN_STREAM("Contacts at " << stampText(input.header.stamp) << " not solved: " << input.reason);
  const std::uint8_t code = input.behind ? SolverStats::DROPPED : SolverStats::NO_COMPLIANCE;
  stats_pub_.publish(boost::make_shared<SolverStats>(rejectedStatsMsg(input.header, code, input.reason)));
}

NodeSettings ContactSolverNode::latestSettings() {
  std::lock_guard<std::mutex> lock(settings_mutex_);
  return accepted_;
}

}  // namespace lcp_contact_solver_ros
