// The example simulator node (`scene_simulator`): steps a scene (config/scenes) at a fixed
// dt with the solver node in the loop.
//
// Each step: SceneSimulator::buildStep() (FCL contacts, free motion, W, d_free) → publish
// /clock (sim time of the step start), then `contacts` and `compliance` with that stamp →
// wait for the `constraint_forces` message with the same stamp (at most ~force_timeout
// wall seconds) → λ per row by contact id → applyForces(λ) (semi-implicit Euler) → tf of
// every dynamic body and, while subscribed, `~body_markers`.
//
// A step without contacts publishes nothing to the solver (it refuses empty arrays) and
// integrates without contact forces. When the forces do not come in time — or the solver's
// `contact_solver/stats` says the solve gave none — the step integrates without contact
// forces, the miss is counted (diagnostics, status lines, summary) and a throttled warning
// is logged; with no solver connected at all the step does not wait. ~force_timeout <= 0
// waits for ever instead, even for a solver that went away (strict lockstep).
//
// Stamps are simulated time (ros::Time(k·dt) for step k), also published on /clock: run
// the other nodes with /use_sim_time true (demo.launch does) so their clocks follow.
#pragma once

#include "lcp_contact_solver/ros/sim/solver_link.h"
#include "lcp_contact_solver/scene/scene_simulator.h"

#include <diagnostic_updater/diagnostic_updater.h>
#include <ros/ros.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_broadcaster.h>

#include <Eigen/Core>

#include <cstdint>
#include <memory>
#include <ostream>
#include <string>

namespace lcp_contact_solver_ros {

namespace lcs = ::lcp_contact_solver;

// The shared parameters (duration, rate_factor, force_timeout, wait_for_solver, linger,
// frame_id (also tf parent and markers), publish_clock, status_period: solver_link.h) and:
struct SimulatorSettings : LinkSettings {
  std::string scene = "box_stack";      // <scene_dir>/<scene>.urdf + .yaml
  std::string scene_dir;                // empty: <package>/config/scenes
  double dt = 0.0;                      // s; 0 = the scene's dt
  double marker_period = 0.04;          // simulated s between ~body_markers (while subscribed)
  int min_subscribers = 1;              // subscribers `contacts` must have before the first step
  bool print_status = false;            // status lines and the final summary on stdout (demo)
  double rest_linear_velocity = 1e-3;   // m/s: slower bodies (and ...)
  double rest_angular_velocity = 1e-2;  // rad/s: ... slower spin) are "at rest" in the summary
};

// Reads every private parameter present over the defaults in `settings`. Empty string, or a
// sentence naming the parameter of the wrong type or invalid value.
std::string loadSimulatorSettings(const ros::NodeHandle& pnh, SimulatorSettings* settings);

// What happened to the steps so far (the misses by cause: SolverLink::counters()).
struct SimulatorCounters {
  std::int64_t steps = 0;
  std::int64_t steps_with_contacts = 0;
  std::int64_t forces_applied = 0;  // steps integrated with the solver's forces
};

class SceneSimulatorNode {
 public:
  // Reads the parameters and loads the scene. Throws std::invalid_argument for a bad
  // parameter and lcp_contact_solver::scene::SceneError for a bad scene.
  SceneSimulatorNode(const ros::NodeHandle& nh, const ros::NodeHandle& pnh);
  ~SceneSimulatorNode();

  // Waits for the solver, then steps until ~duration (or shutdown). Callbacks run on the
  // calling thread (global callback queue). Returns false when the solver never connected
  // or ROS shut down before the end; true when the run completed (misses included: see
  // counters()).
  bool run();

  // One step (public for tests). Returns the step's statistics.
  lcs::scene::StepStats step();

  // The final summary: run totals and per dynamic body its position, velocity and
  // whether it is at rest. Also logged (INFO) and printed with ~print_status at the end of run().
  void writeSummary(std::ostream& out) const;

  const SimulatorCounters& counters() const { return counters_; }
  const LinkCounters& linkCounters() const { return link_.counters(); }
  const lcs::scene::SceneSimulator& simulator() const { return *sim_; }
  const SimulatorSettings& settings() const { return settings_; }
  ros::Time stampOf(std::int64_t step_index) const { return stepStamp(step_index, dt_); }

 private:
  void onSolverStats(const lcp_contact_solver::SolverStats& msg);
  void exchange(const lcs::scene::StepProblem& sp, const ros::Time& stamp, Eigen::VectorXd* lambda);
  void publishStaticTransforms();
  void publishState(const ros::Time& stamp);
  void reportPeriod(const lcs::scene::StepStats& stats);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);

  ros::NodeHandle nh_;
  ros::NodeHandle pnh_;
  SimulatorSettings settings_;
  std::unique_ptr<lcs::scene::SceneSimulator> sim_;
  double dt_ = 0.01;
  SolverLink link_;

  ros::Publisher markers_pub_;
  tf2_ros::TransformBroadcaster tf_;
  tf2_ros::StaticTransformBroadcaster static_tf_;
  diagnostic_updater::Updater updater_;

  SimulatorCounters counters_;
  std::string last_miss_;  // what happened at the last miss (diagnostics)
  double next_marker_time_ = 0.0;
  bool header_printed_ = false;
  double run_wall_time_ = 0.0;

  // Solver stats gathered over the current status period.
  struct PeriodStats {
    int solves = 0;
    double iterations = 0.0;  // sum
    double max_residual = 0.0;
    double solve_time = 0.0;  // sum, s
    std::int64_t misses_at_start = 0;
  } period_;
};

}  // namespace lcp_contact_solver_ros
