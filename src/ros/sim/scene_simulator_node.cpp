#include "lcp_contact_solver/ros/sim/scene_simulator_node.h"

#include "lcp_contact_solver/ros/msg_conversion/scene_msg_conversion.h"
#include "lcp_contact_solver/scene/scene.h"

#include <lcp_contact_solver/Compliance.h>
#include <lcp_contact_solver/ContactArray.h>
#include <ros/package.h>
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

bool finite(double v) { return std::isfinite(v); }

std::string validate(const SimulatorSettings& s) {
  if (s.scene.empty()) return "parameter scene must name a scene (e.g. box_stack)";
  if (!finite(s.dt) || s.dt < 0.0) return "parameter dt must be >= 0 (0 keeps the scene's dt)";
  if (!finite(s.marker_period) || s.marker_period <= 0.0) return "parameter marker_period must be > 0";
  if (s.min_subscribers < 0) return "parameter min_subscribers must be >= 0";
  if (!finite(s.rest_linear_velocity) || s.rest_linear_velocity <= 0.0)
    return "parameter rest_linear_velocity must be > 0";
  if (!finite(s.rest_angular_velocity) || s.rest_angular_velocity <= 0.0)
    return "parameter rest_angular_velocity must be > 0";
  return "";
}

SolverLink::Options linkOptions(const SimulatorSettings& s) {
  SolverLink::Options options;
  options.min_subscribers = static_cast<std::uint32_t>(s.min_subscribers);
  return options;
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
    throw std::invalid_argument(
        "parameter scene_dir is not set and the package lcp_contact_solver was not found");
  return package + "/config/scenes";
}

scene::Scene loadScene(const SimulatorSettings& settings) {
  scene::Scene s = scene::loadNamedScene(resolveSceneDir(settings), settings.scene);
  if (settings.dt > 0.0) s.params.dt = settings.dt;
  return s;
}

}  // namespace

std::string loadSimulatorSettings(const ros::NodeHandle& pnh, SimulatorSettings* s) {
  return loadSettings(pnh, s,
                      {LCS_PARAM_FIELD(s, scene), LCS_PARAM_FIELD(s, scene_dir), LCS_PARAM_FIELD(s, dt),
                       LCS_PARAM_FIELD(s, marker_period), LCS_PARAM_FIELD(s, min_subscribers),
                       LCS_PARAM_FIELD(s, print_status), LCS_PARAM_FIELD(s, rest_linear_velocity),
                       LCS_PARAM_FIELD(s, rest_angular_velocity)},
                      [s] { return validate(*s); });
}

SceneSimulatorNode::SceneSimulatorNode(const ros::NodeHandle& nh, const ros::NodeHandle& pnh)
    : nh_(nh),
      pnh_(pnh),
      settings_(loadOrThrow(pnh)),
      sim_(std::make_unique<scene::SceneSimulator>(loadScene(settings_))),
      dt_(sim_->params().dt),
      link_(nh, settings_, linkOptions(settings_)),
      updater_(nh, pnh, pnh.getNamespace()) {
  markers_pub_ = pnh_.advertise<visualization_msgs::MarkerArray>("body_markers", 1);
  link_.onEveryStats([this](const lcp_contact_solver::SolverStats& msg) { onSolverStats(msg); });
  updater_.setHardwareID("scene_simulator");
  updater_.add("simulator", this, &SceneSimulatorNode::diagnose);
}

SceneSimulatorNode::~SceneSimulatorNode() = default;

// ---- callbacks ------------------------------------------------------------------------

void SceneSimulatorNode::onSolverStats(const lcp_contact_solver::SolverStats& msg) {
  if (!msg.success) return;
  ++period_.solves;
  period_.iterations += msg.iterations;
  period_.max_residual = std::max(period_.max_residual, msg.residual);
  period_.solve_time += msg.solve_time;
}

// ---- run ------------------------------------------------------------------------------

bool SceneSimulatorNode::run() {
  const scene::Scene& s = sim_->scene();
  std::ostringstream run_length, rate;
  if (settings_.duration > 0.0)
    run_length << settings_.duration << " s";
  else
    run_length << "unbounded";
  if (settings_.rate_factor > 0.0)
    rate << settings_.rate_factor;
  else
    rate << "as fast as possible";
  ROS_INFO_STREAM("Scene '" << s.name << "': " << s.bodies.size() << " bodies (" << s.dynamicBodyCount()
                            << " dynamic), dt " << dt_ << " s, duration " << run_length.str()
                            << ", real-time factor " << rate.str());
  link_.publishClock(stampOf(0));
  if (!link_.waitForSolver()) return false;
  publishStaticTransforms();
  publishState(stampOf(0));

  const std::int64_t total =
      settings_.duration > 0.0 ? static_cast<std::int64_t>(std::llround(settings_.duration / dt_)) : -1;
  link_.startRun();
  while (ros::ok() && (total < 0 || counters_.steps < total)) {
    step();
    link_.pace(sim_->time());
  }
  run_wall_time_ = link_.runWallTime();

  std::ostringstream summary;
  writeSummary(summary);
  link_.logSummary("Simulation", settings_.print_status, summary.str(), counters_.steps);
  updater_.force_update();
  link_.linger();
  return true;
}

scene::StepStats SceneSimulatorNode::step() {
  const scene::StepProblem& sp = sim_->buildStep();
  const ros::Time stamp = stampOf(sp.step_index);
  link_.publishClock(stamp);
  Eigen::VectorXd lambda = Eigen::VectorXd::Zero(sp.problem.rowCount());
  if (!sp.problem.contacts.empty()) {
    ++counters_.steps_with_contacts;
    exchange(sp, stamp, &lambda);
  }
  const scene::StepStats stats = sim_->applyForces(lambda);
  ++counters_.steps;
  publishState(stampOf(stats.step_index + 1));
  reportPeriod(stats);
  return stats;
}

// Sends the step's problem and leaves the solver's forces in λ, or λ = 0 after a miss.
void SceneSimulatorNode::exchange(const scene::StepProblem& sp, const ros::Time& stamp,
                                  Eigen::VectorXd* lambda) {
  std_msgs::Header header;
  header.stamp = stamp;
  header.frame_id = settings_.frame_id;
  auto contacts = boost::make_shared<lcp_contact_solver::ContactArray>(toContactArrayMsg(sp, header));
  auto compliance = boost::make_shared<lcp_contact_solver::Compliance>(toComplianceMsg(sp, header));
  const std::string at = "step at " + stampText(stamp);
  switch (link_.exchange(stamp, contacts, compliance)) {
    case SolverLink::Outcome::kForces: {
      const std::string error = toStepForces(link_.forces(), sp.problem, lambda);
      if (error.empty()) {
        ++counters_.forces_applied;
      } else {
        link_.countBadForces();
        last_miss_ = at + ": " + error;
        ROS_WARN_STREAM_THROTTLE(1.0, "Forces for the " << at << " do not fit: " << error
                                                        << "; integrating without contact forces");
      }
      break;
    }
    case SolverLink::Outcome::kTimeout:
      last_miss_ = at + ": no forces within " + std::to_string(settings_.force_timeout) + " s";
      ROS_WARN_STREAM_THROTTLE(1.0, "No forces for the " << at << " within " << settings_.force_timeout
                                                         << " s; integrating without contact forces ("
                                                         << link_.counters().force_timeouts
                                                         << " timeouts so far)");
      break;
    case SolverLink::Outcome::kNoSolver:
      last_miss_ = at + ": no solver publishes " + link_.forcesTopic();
      ROS_WARN_STREAM_THROTTLE(1.0, "No solver publishes " << link_.forcesTopic() << " (" << at
                                                           << "); integrating without contact forces");
      break;
    case SolverLink::Outcome::kSolverFailed:
      last_miss_ = at + ": " + link_.failure();
      ROS_WARN_STREAM_THROTTLE(1.0, "The solver gave no forces for the "
                                        << at << " (" << link_.failure()
                                        << "); integrating without contact forces");
      break;
    case SolverLink::Outcome::kShutdown: break;
  }
}

// ---- output ---------------------------------------------------------------------------

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
    if (!body.is_static && body.name != settings_.frame_id)
      transforms.push_back(toTransformMsg(body, header));
  if (!transforms.empty()) tf_.sendTransform(transforms);

  const double t = stamp.toSec();
  if (t + 1e-9 >= next_marker_time_ && markers_pub_.getNumSubscribers() > 0) {
    markers_pub_.publish(
        boost::make_shared<visualization_msgs::MarkerArray>(bodyMarkers(sim_->scene(), header)));
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
    line << std::setw(8) << link_.counters().misses() - period_.misses_at_start << '\n';
    std::cout << line.str() << std::flush;
  }
  updater_.force_update();
  period_ = PeriodStats();
  period_.misses_at_start = link_.counters().misses();
}

void SceneSimulatorNode::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
  if (link_.counters().misses() > 0) {
    status.summaryf(diagnostic_msgs::DiagnosticStatus::WARN,
                    "%ld of %ld steps with contacts integrated without contact forces; last: %s",
                    static_cast<long>(link_.counters().misses()),
                    static_cast<long>(counters_.steps_with_contacts), last_miss_.c_str());
  } else {
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, "every step with contacts got its forces");
  }
  status.add("scene", sim_->scene().name);
  status.add("simulated time (s)", sim_->time());
  status.add("steps", counters_.steps);
  status.add("steps with contacts", counters_.steps_with_contacts);
  status.add("forces applied", counters_.forces_applied);
  status.add("force timeouts", link_.counters().force_timeouts);
  status.add("solver failures", link_.counters().solver_failures);
  status.add("mismatched forces", link_.counters().bad_forces);
  status.add("late forces ignored", link_.counters().stale_forces);
}

void SceneSimulatorNode::writeSummary(std::ostream& out) const {
  const scene::Scene& s = sim_->scene();
  std::ostringstream text;
  text << std::fixed << std::setprecision(2);
  text << "scene " << s.name << ": " << counters_.steps << " steps, " << sim_->time() << " s simulated";
  if (run_wall_time_ > 0.0)
    text << " in " << run_wall_time_ << " s wall (real-time factor " << sim_->time() / run_wall_time_ << ")";
  text << "\nforces: " << counters_.forces_applied << " of " << counters_.steps_with_contacts
       << " steps with contacts from the solver; " << link_.counters().force_timeouts << " timeouts, "
       << link_.counters().solver_failures << " solver failures, " << link_.counters().bad_forces
       << " mismatched\n";
  std::size_t width = 4;
  for (const scene::RigidBody& b : s.bodies)
    if (!b.is_static) width = std::max(width, b.name.size());
  text << std::left << std::setw(static_cast<int>(width)) << "body" << std::right << std::setw(10) << "x [m]"
       << std::setw(10) << "y [m]" << std::setw(10) << "z [m]" << std::setw(12) << "|v| [m/s]"
       << std::setw(13) << "|w| [rad/s]"
       << "  state\n";
  for (const scene::RigidBody& b : s.bodies) {
    if (b.is_static) continue;
    const double v = b.linear_velocity.norm(), w = b.angular_velocity.norm();
    const bool at_rest = v < settings_.rest_linear_velocity && w < settings_.rest_angular_velocity;
    auto shown = [](double x) { return std::abs(x) < 5e-5 ? 0.0 : x; };  // no "-0.0000"
    text << std::left << std::setw(static_cast<int>(width)) << b.name << std::right << std::fixed
         << std::setprecision(4) << std::setw(10) << shown(b.position.x()) << std::setw(10)
         << shown(b.position.y()) << std::setw(10) << shown(b.position.z()) << std::scientific
         << std::setprecision(2) << std::setw(12) << v << std::setw(13) << w << "  "
         << (at_rest ? "at rest" : "moving") << '\n';
  }
  out << text.str();
}

}  // namespace lcp_contact_solver_ros
