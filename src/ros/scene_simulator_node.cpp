#include "lcp_contact_solver/ros/scene_simulator_node.h"

#include "lcp_contact_solver/ros/scene_msg_conversion.h"
#include "lcp_contact_solver/scene/scene.h"

#include <lcp_contact_solver/Compliance.h>
#include <lcp_contact_solver/ContactArray.h>
#include <ros/callback_queue.h>
#include <ros/package.h>
#include <rosgraph_msgs/Clock.h>
#include <visualization_msgs/MarkerArray.h>

#include <boost/make_shared.hpp>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace lcp_contact_solver_ros {

namespace {

namespace scene = lcs::scene;

// Callbacks are served in slices this long while waiting (wall s).
constexpr double kSpinSlice = 0.01;

template <typename T>
std::string readParam(const ros::NodeHandle& pnh, const std::string& name, T* value, const char* expected) {
  if (!pnh.hasParam(name)) return "";
  if (!pnh.getParam(name, *value)) return "parameter " + pnh.resolveName(name) + " must be " + expected;
  return "";
}

bool finite(double v) { return std::isfinite(v); }

std::string validate(const SimulatorSettings& s) {
  if (s.scene.empty()) return "parameter scene must name a scene (e.g. box_stack)";
  if (!finite(s.duration) || s.duration < 0.0) return "parameter duration must be >= 0 (0 runs for ever)";
  if (!finite(s.rate_factor) || s.rate_factor < 0.0)
    return "parameter rate_factor must be >= 0 (0 runs as fast as possible)";
  if (!finite(s.force_timeout)) return "parameter force_timeout must be finite (<= 0 waits for ever)";
  if (!finite(s.dt) || s.dt < 0.0) return "parameter dt must be >= 0 (0 keeps the scene's dt)";
  if (s.frame_id.empty()) return "parameter frame_id must not be empty";
  if (!finite(s.marker_period) || s.marker_period <= 0.0) return "parameter marker_period must be > 0";
  if (!finite(s.wait_for_solver)) return "parameter wait_for_solver must be finite (<= 0 waits for ever)";
  if (s.min_subscribers < 0) return "parameter min_subscribers must be >= 0";
  if (!finite(s.status_period) || s.status_period <= 0.0) return "parameter status_period must be > 0";
  if (!finite(s.rest_linear_velocity) || s.rest_linear_velocity <= 0.0)
    return "parameter rest_linear_velocity must be > 0";
  if (!finite(s.rest_angular_velocity) || s.rest_angular_velocity <= 0.0)
    return "parameter rest_angular_velocity must be > 0";
  if (!finite(s.linger) || s.linger < 0.0) return "parameter linger must be >= 0";
  return "";
}

SimulatorSettings loadOrThrow(const ros::NodeHandle& pnh) {
  SimulatorSettings settings;
  const std::string error = loadSimulatorSettings(pnh, &settings);
  if (!error.empty()) throw std::invalid_argument(error);
  return settings;
}

std::string resolveSceneDir(const SimulatorSettings& settings) {
  if (!settings.scene_dir.empty()) return settings.scene_dir;
  const std::string package = ros::package::getPath("lcp_contact_solver");
  if (package.empty())
    throw std::invalid_argument("parameter scene_dir is not set and the package lcp_contact_solver was not found");
  return package + "/config/scenes";
}

scene::Scene loadScene(const SimulatorSettings& settings) {
  scene::Scene s = scene::loadNamedScene(resolveSceneDir(settings), settings.scene);
  if (settings.dt > 0.0) s.params.dt = settings.dt;
  return s;
}

std::string stampText(const ros::Time& stamp) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(3) << stamp.toSec() << " s";
  return out.str();
}

}  // namespace

std::string loadSimulatorSettings(const ros::NodeHandle& pnh, SimulatorSettings* s) {
  for (const std::string& error : {
           readParam(pnh, "scene", &s->scene, "a string"), readParam(pnh, "scene_dir", &s->scene_dir, "a string"),
           readParam(pnh, "duration", &s->duration, "a number"),
           readParam(pnh, "rate_factor", &s->rate_factor, "a number"),
           readParam(pnh, "force_timeout", &s->force_timeout, "a number"), readParam(pnh, "dt", &s->dt, "a number"),
           readParam(pnh, "frame_id", &s->frame_id, "a string"),
           readParam(pnh, "publish_clock", &s->publish_clock, "true or false"),
           readParam(pnh, "marker_period", &s->marker_period, "a number"),
           readParam(pnh, "wait_for_solver", &s->wait_for_solver, "a number"),
           readParam(pnh, "min_subscribers", &s->min_subscribers, "an integer"),
           readParam(pnh, "print_status", &s->print_status, "true or false"),
           readParam(pnh, "status_period", &s->status_period, "a number"),
           readParam(pnh, "rest_linear_velocity", &s->rest_linear_velocity, "a number"),
           readParam(pnh, "rest_angular_velocity", &s->rest_angular_velocity, "a number"),
           readParam(pnh, "linger", &s->linger, "a number")}) {
    if (!error.empty()) return error;
  }
  return validate(*s);
}

SceneSimulatorNode::SceneSimulatorNode(const ros::NodeHandle& nh, const ros::NodeHandle& pnh)
    : nh_(nh),
      pnh_(pnh),
      settings_(loadOrThrow(pnh)),
      sim_(std::make_unique<scene::SceneSimulator>(loadScene(settings_))),
      dt_(sim_->params().dt),
      updater_(nh, pnh, pnh.getNamespace()) {
  contacts_pub_ = nh_.advertise<lcp_contact_solver::ContactArray>("contacts", 10);
  compliance_pub_ = nh_.advertise<lcp_contact_solver::Compliance>("compliance", 10);
  if (settings_.publish_clock) clock_pub_ = nh_.advertise<rosgraph_msgs::Clock>("/clock", 10);
  markers_pub_ = pnh_.advertise<visualization_msgs::MarkerArray>("body_markers", 1);
  forces_sub_ = nh_.subscribe("constraint_forces", 10, &SceneSimulatorNode::onForces, this);
  stats_sub_ = nh_.subscribe("contact_solver/stats", 10, &SceneSimulatorNode::onSolverStats, this);
  updater_.setHardwareID("scene_simulator");
  updater_.add("simulator", this, &SceneSimulatorNode::diagnose);
}

SceneSimulatorNode::~SceneSimulatorNode() = default;

ros::Time stepStamp(std::int64_t step_index, double dt) {
  ros::Time stamp;
  stamp.fromNSec(static_cast<std::uint64_t>(std::llround(static_cast<double>(step_index) * dt * 1e9)));
  return stamp;
}

// ---- callbacks ------------------------------------------------------------------------

void SceneSimulatorNode::onForces(const lcp_contact_solver::ConstraintForces::ConstPtr& msg) {
  if (!awaiting_ || msg->header.stamp != awaiting_stamp_) {
    ++counters_.stale_forces;
    ROS_DEBUG_STREAM("Ignoring forces stamped " << stampText(msg->header.stamp) << " (not the current step)");
    return;
  }
  received_ = msg;
}

void SceneSimulatorNode::onSolverStats(const lcp_contact_solver::SolverStats::ConstPtr& msg) {
  if (msg->success) {
    ++period_.solves;
    period_.iterations += msg->iterations;
    period_.max_residual = std::max(period_.max_residual, msg->residual);
    period_.solve_time += msg->solve_time;
  }
  if (awaiting_ && msg->header.stamp == awaiting_stamp_ && !received_) {
    if (!msg->success)
      solver_failure_ = msg->status + (msg->message.empty() ? "" : ": " + msg->message);
    else if (!msg->forces_published)
      solver_failure_ = "the solver did not publish the forces";
  }
}

// ---- run ------------------------------------------------------------------------------

bool SceneSimulatorNode::waitForSolver() {
  auto connected = [this] {
    const auto need = static_cast<std::uint32_t>(settings_.min_subscribers);
    return contacts_pub_.getNumSubscribers() >= need && compliance_pub_.getNumSubscribers() >= need &&
           forces_sub_.getNumPublishers() > 0;
  };
  const bool forever = settings_.wait_for_solver <= 0.0;
  const ros::WallTime start = ros::WallTime::now();
  bool told = false;
  while (ros::ok() && !connected()) {
    const double waited = (ros::WallTime::now() - start).toSec();
    if (!forever && waited >= settings_.wait_for_solver) break;
    if (!told && waited > 1.0) {
      ROS_INFO_STREAM("Waiting for the contact solver: " << contacts_pub_.getNumSubscribers() << " of "
                                                         << settings_.min_subscribers << " subscribers on "
                                                         << contacts_pub_.getTopic() << ", "
                                                         << forces_sub_.getNumPublishers() << " publisher of "
                                                         << forces_sub_.getTopic());
      told = true;
    }
    ros::getGlobalCallbackQueue()->callAvailable(ros::WallDuration(kSpinSlice));
  }
  if (!connected()) {
    if (ros::ok())
      ROS_FATAL_STREAM("No contact solver within " << settings_.wait_for_solver << " s: " << contacts_pub_.getTopic()
                                                   << " has " << contacts_pub_.getNumSubscribers() << " subscribers ("
                                                   << settings_.min_subscribers << " needed), "
                                                   << forces_sub_.getTopic() << " has "
                                                   << forces_sub_.getNumPublishers() << " publishers");
    return false;
  }
  return true;
}

bool SceneSimulatorNode::run() {
  const scene::Scene& s = sim_->scene();
  std::ostringstream run_length, rate;
  if (settings_.duration > 0.0) run_length << settings_.duration << " s"; else run_length << "unbounded";
  if (settings_.rate_factor > 0.0) rate << settings_.rate_factor; else rate << "as fast as possible";
  ROS_INFO_STREAM("Scene '" << s.name << "': " << s.bodies.size() << " bodies (" << s.dynamicBodyCount()
                            << " dynamic), dt " << dt_ << " s, duration " << run_length.str()
                            << ", real-time factor " << rate.str());
  if (settings_.publish_clock) publishClock(stampOf(0));
  if (!waitForSolver()) return false;
  publishStaticTransforms();
  publishState(stampOf(0));

  const std::int64_t total =
      settings_.duration > 0.0 ? static_cast<std::int64_t>(std::llround(settings_.duration / dt_)) : -1;
  run_start_ = ros::WallTime::now();
  while (ros::ok() && (total < 0 || counters_.steps < total)) {
    step();
    pace(run_start_);
  }
  run_wall_time_ = (ros::WallTime::now() - run_start_).toSec();

  std::ostringstream summary;
  writeSummary(summary);
  if (settings_.print_status) {  // the table on stdout, one line in the log
    std::cout << summary.str() << std::flush;
    ROS_INFO_STREAM("Simulation " << (ros::ok() ? "finished" : "interrupted") << ": " << counters_.steps << " steps, "
                                  << counters_.misses() << " without the solver's forces");
  } else {
    ROS_INFO_STREAM("Simulation " << (ros::ok() ? "finished" : "interrupted") << "\n" << summary.str());
  }
  updater_.force_update();
  linger();
  return true;
}

// roscpp writes published messages from its own thread: a node that exits right after its
// last publish can close the connections before a busy subscriber has read them.
void SceneSimulatorNode::linger() {
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(settings_.linger);
  while (ros::ok() && ros::WallTime::now() < end)
    ros::getGlobalCallbackQueue()->callAvailable(ros::WallDuration(kSpinSlice));
}

scene::StepStats SceneSimulatorNode::step() {
  const scene::StepProblem& sp = sim_->buildStep();
  const ros::Time stamp = stampOf(sp.step_index);
  publishClock(stamp);
  Eigen::VectorXd lambda = Eigen::VectorXd::Zero(sp.problem.rowCount());
  if (!sp.problem.contacts.empty()) {
    ++counters_.steps_with_contacts;
    std_msgs::Header header;
    header.stamp = stamp;
    header.frame_id = settings_.frame_id;
    auto contacts = boost::make_shared<lcp_contact_solver::ContactArray>(toContactArrayMsg(sp, header));
    auto compliance = boost::make_shared<lcp_contact_solver::Compliance>(toComplianceMsg(sp, header));
    awaiting_ = true;
    awaiting_stamp_ = stamp;
    received_.reset();
    solver_failure_.clear();
    compliance_pub_.publish(compliance);
    contacts_pub_.publish(contacts);
    switch (waitForForces(stamp)) {
      case Outcome::kForces: {
        const std::string error = toStepForces(*received_, sp.problem, &lambda);
        if (error.empty()) {
          ++counters_.forces_applied;
        } else {
          ++counters_.bad_forces;
          last_miss_ = "step at " + stampText(stamp) + ": " + error;
          ROS_WARN_STREAM_THROTTLE(1.0, "Forces for the step at " << stampText(stamp) << " do not fit: " << error
                                                                  << "; integrating without contact forces");
        }
        break;
      }
      case Outcome::kTimeout:
        ++counters_.force_timeouts;
        last_miss_ = "step at " + stampText(stamp) + ": no forces within " + std::to_string(settings_.force_timeout) + " s";
        ROS_WARN_STREAM_THROTTLE(1.0, "No forces for the step at " << stampText(stamp) << " within "
                                                                   << settings_.force_timeout
                                                                   << " s; integrating without contact forces ("
                                                                   << counters_.force_timeouts << " timeouts so far)");
        break;
      case Outcome::kNoSolver:
        ++counters_.force_timeouts;
        last_miss_ = "step at " + stampText(stamp) + ": no solver publishes " + forces_sub_.getTopic();
        ROS_WARN_STREAM_THROTTLE(1.0, "No solver publishes " << forces_sub_.getTopic() << " (step at " << stampText(stamp)
                                                             << "); integrating without contact forces");
        break;
      case Outcome::kSolverFailed:
        ++counters_.solver_failures;
        last_miss_ = "step at " + stampText(stamp) + ": " + solver_failure_;
        ROS_WARN_STREAM_THROTTLE(1.0, "The solver gave no forces for the step at "
                                          << stampText(stamp) << " (" << solver_failure_
                                          << "); integrating without contact forces");
        break;
      case Outcome::kShutdown:
        break;
    }
    awaiting_ = false;
    received_.reset();
  }
  const scene::StepStats stats = sim_->applyForces(lambda);
  ++counters_.steps;
  publishState(stampOf(stats.step_index + 1));
  reportPeriod(stats);
  return stats;
}

SceneSimulatorNode::Outcome SceneSimulatorNode::waitForForces(const ros::Time& stamp) {
  const bool forever = settings_.force_timeout <= 0.0;
  const ros::WallTime start = ros::WallTime::now();
  ros::WallTime next_note = start + ros::WallDuration(5.0);
  while (true) {
    if (received_) return Outcome::kForces;
    if (!solver_failure_.empty()) return Outcome::kSolverFailed;
    if (!ros::ok()) return Outcome::kShutdown;
    // The solver went away: do not wait for it step after step.
    if (!forever && forces_sub_.getNumPublishers() == 0) return Outcome::kNoSolver;
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
    ros::getGlobalCallbackQueue()->callAvailable(ros::WallDuration(slice));
  }
}

void SceneSimulatorNode::pace(const ros::WallTime& start) {
  if (settings_.rate_factor <= 0.0) {
    ros::getGlobalCallbackQueue()->callAvailable();  // serve callbacks without waiting
    return;
  }
  const ros::WallTime target = start + ros::WallDuration(sim_->time() / settings_.rate_factor);
  while (ros::ok()) {
    const double remaining = (target - ros::WallTime::now()).toSec();
    if (remaining <= 0.0) break;
    ros::getGlobalCallbackQueue()->callAvailable(ros::WallDuration(std::min(remaining, kSpinSlice)));
  }
}

// ---- output ---------------------------------------------------------------------------

void SceneSimulatorNode::publishClock(const ros::Time& stamp) {
  if (!settings_.publish_clock) return;
  rosgraph_msgs::Clock clock;
  clock.clock = stamp;
  clock_pub_.publish(clock);
}

void SceneSimulatorNode::publishStaticTransforms() {
  std::vector<geometry_msgs::TransformStamped> transforms;
  std_msgs::Header header;
  header.stamp = stampOf(0);
  header.frame_id = settings_.frame_id;
  for (const scene::RigidBody& body : sim_->scene().bodies)
    if (body.is_static && body.name != settings_.frame_id) transforms.push_back(toTransformMsg(body, header));
  if (!transforms.empty()) static_tf_.sendTransform(transforms);
}

void SceneSimulatorNode::publishState(const ros::Time& stamp) {
  std_msgs::Header header;
  header.stamp = stamp;
  header.frame_id = settings_.frame_id;
  std::vector<geometry_msgs::TransformStamped> transforms;
  for (const scene::RigidBody& body : sim_->scene().bodies)
    if (!body.is_static && body.name != settings_.frame_id) transforms.push_back(toTransformMsg(body, header));
  if (!transforms.empty()) tf_.sendTransform(transforms);

  const double t = stamp.toSec();
  if (t + 1e-9 >= next_marker_time_ && markers_pub_.getNumSubscribers() > 0) {
    markers_pub_.publish(boost::make_shared<visualization_msgs::MarkerArray>(bodyMarkers(sim_->scene(), header)));
    next_marker_time_ = t + settings_.marker_period;
  }
}

void SceneSimulatorNode::reportPeriod(const scene::StepStats& stats) {
  // By step count, not by summed time: 100 steps of 0.01 s do not add up to exactly 1.
  const std::int64_t every = std::max<std::int64_t>(1, std::llround(settings_.status_period / dt_));
  if ((stats.step_index + 1) % every != 0) return;
  const double time = stampOf(stats.step_index + 1).toSec();
  if (settings_.print_status) {
    std::ostringstream line;
    if (!header_printed_) {
      line << "  sim time  contacts  rows  iterations   residual  solve ms  missed\n";
      header_printed_ = true;
    }
    line << std::fixed << std::setprecision(2) << std::setw(8) << time << " s" << std::setw(10)
         << stats.contacts << std::setw(6) << stats.rows;
    if (period_.solves > 0) {
      line << std::setw(12) << std::setprecision(1) << period_.iterations / period_.solves << std::setw(11)
           << std::scientific << std::setprecision(1) << period_.max_residual << std::fixed << std::setw(10)
           << std::setprecision(3) << 1e3 * period_.solve_time / period_.solves;
    } else {
      line << std::setw(12) << "-" << std::setw(11) << "-" << std::setw(10) << "-";
    }
    line << std::setw(8) << counters_.misses() - period_.misses_at_start << '\n';
    std::cout << line.str() << std::flush;
  }
  updater_.force_update();
  period_ = PeriodStats();
  period_.misses_at_start = counters_.misses();
}

void SceneSimulatorNode::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
  if (counters_.misses() > 0) {
    status.summaryf(diagnostic_msgs::DiagnosticStatus::WARN,
                    "%ld of %ld steps with contacts integrated without contact forces; last: %s",
                    static_cast<long>(counters_.misses()), static_cast<long>(counters_.steps_with_contacts),
                    last_miss_.c_str());
  } else {
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, "every step with contacts got its forces");
  }
  status.add("scene", sim_->scene().name);
  status.add("simulated time (s)", sim_->time());
  status.add("steps", counters_.steps);
  status.add("steps with contacts", counters_.steps_with_contacts);
  status.add("forces applied", counters_.forces_applied);
  status.add("force timeouts", counters_.force_timeouts);
  status.add("solver failures", counters_.solver_failures);
  status.add("mismatched forces", counters_.bad_forces);
  status.add("late forces ignored", counters_.stale_forces);
}

void SceneSimulatorNode::writeSummary(std::ostream& out) const {
  const scene::Scene& s = sim_->scene();
  std::ostringstream text;
  text << std::fixed << std::setprecision(2);
  text << "scene " << s.name << ": " << counters_.steps << " steps, " << sim_->time() << " s simulated";
  if (run_wall_time_ > 0.0)
    text << " in " << run_wall_time_ << " s wall (real-time factor " << sim_->time() / run_wall_time_ << ")";
  text << "\nforces: " << counters_.forces_applied << " of " << counters_.steps_with_contacts
       << " steps with contacts from the solver; " << counters_.force_timeouts << " timeouts, "
       << counters_.solver_failures << " solver failures, " << counters_.bad_forces << " mismatched\n";
  std::size_t width = 4;
  for (const scene::RigidBody& b : s.bodies)
    if (!b.is_static) width = std::max(width, b.name.size());
  text << std::left << std::setw(static_cast<int>(width)) << "body" << std::right << std::setw(10) << "x [m]"
       << std::setw(10) << "y [m]" << std::setw(10) << "z [m]" << std::setw(12) << "|v| [m/s]" << std::setw(13)
       << "|w| [rad/s]" << "  state\n";
  for (const scene::RigidBody& b : s.bodies) {
    if (b.is_static) continue;
    const double v = b.linear_velocity.norm(), w = b.angular_velocity.norm();
    const bool at_rest = v < settings_.rest_linear_velocity && w < settings_.rest_angular_velocity;
    auto shown = [](double x) { return std::abs(x) < 5e-5 ? 0.0 : x; };  // no "-0.0000"
    text << std::left << std::setw(static_cast<int>(width)) << b.name << std::right << std::fixed
         << std::setprecision(4) << std::setw(10) << shown(b.position.x()) << std::setw(10) << shown(b.position.y())
         << std::setw(10) << shown(b.position.z()) << std::scientific << std::setprecision(2) << std::setw(12) << v
         << std::setw(13) << w << "  " << (at_rest ? "at rest" : "moving") << '\n';
  }
  out << text.str();
}

}  // namespace lcp_contact_solver_ros
