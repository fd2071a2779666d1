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

#include "lcp_contact_solver/scene/scene_simulator.h"

#include <diagnostic_updater/diagnostic_updater.h>
#include <lcp_contact_solver/ConstraintForces.h>
#include <lcp_contact_solver/SolverStats.h>
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

struct SimulatorSettings {
  std::string scene = "box_stack";  // <scene_dir>/<scene>.urdf + .yaml
  std::string scene_dir;            // empty: <package>/config/scenes
  double duration = 0.0;            // simulated s to run; 0 = for ever
  double rate_factor = 1.0;         // simulated s per wall s; 0 = as fast as possible
  double force_timeout = 1.0;       // wall s to wait for the forces of a step; <= 0: for ever
  double dt = 0.0;                  // s; 0 = the scene's dt
  std::string frame_id = "world";   // frame of contacts, tf parent and markers
  bool publish_clock = true;        // publish /clock with the simulated time
  double marker_period = 0.04;      // simulated s between ~body_markers (while subscribed)
  double wait_for_solver = 30.0;    // wall s to wait for the solver's connections; <= 0: for ever
  int min_subscribers = 1;          // subscribers `contacts` must have before the first step
  bool print_status = false;        // status lines and the final summary on stdout (demo)
  double status_period = 1.0;       // simulated s between status lines / diagnostics
  double rest_linear_velocity = 1e-3;   // m/s: slower bodies (and ...)
  double rest_angular_velocity = 1e-2;  // rad/s: ... slower spin) are "at rest" in the summary
  double linger = 1.0;              // wall s to keep serving after the run, so the last
                                    // messages reach slow subscribers before the node exits
};

// Reads every private parameter present over the defaults in `settings`. Empty string, or a
// sentence naming the parameter of the wrong type or invalid value.
std::string loadSimulatorSettings(const ros::NodeHandle& pnh, SimulatorSettings* settings);

// The stamp of step k (its contacts, compliance, forces and /clock): ros::Time(k·dt),
// rounded to the nanosecond, so stamps stay exact multiples of dt however long the run.
ros::Time stepStamp(std::int64_t step_index, double dt);

// What happened to the steps so far.
struct SimulatorCounters {
  std::int64_t steps = 0;
  std::int64_t steps_with_contacts = 0;
  std::int64_t forces_applied = 0;   // steps integrated with the solver's forces
  std::int64_t force_timeouts = 0;   // no forces within ~force_timeout, or no solver connected
  std::int64_t solver_failures = 0;  // the solver's stats said it gave no forces for the step
  std::int64_t bad_forces = 0;       // forces that did not match the step (ids, rows, values)
  std::int64_t stale_forces = 0;     // forces of an older step arriving late (ignored)
  std::int64_t misses() const { return force_timeouts + solver_failures + bad_forces; }
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
  const lcs::scene::SceneSimulator& simulator() const { return *sim_; }
  const SimulatorSettings& settings() const { return settings_; }
  ros::Time stampOf(std::int64_t step_index) const { return stepStamp(step_index, dt_); }

 private:
  enum class Outcome { kForces, kTimeout, kNoSolver, kSolverFailed, kShutdown };

  void onForces(const lcp_contact_solver::ConstraintForces::ConstPtr& msg);
  void onSolverStats(const lcp_contact_solver::SolverStats::ConstPtr& msg);
  bool waitForSolver();
  Outcome waitForForces(const ros::Time& stamp);
  void publishClock(const ros::Time& stamp);
  void publishStaticTransforms();
  void publishState(const ros::Time& stamp);
  void pace(const ros::WallTime& start);
  void linger();
  void reportPeriod(const lcs::scene::StepStats& stats);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);

  ros::NodeHandle nh_;
  ros::NodeHandle pnh_;
  SimulatorSettings settings_;
  std::unique_ptr<lcs::scene::SceneSimulator> sim_;
  double dt_ = 0.01;

  ros::Publisher contacts_pub_;
  ros::Publisher compliance_pub_;
  ros::Publisher clock_pub_;
  ros::Publisher markers_pub_;
  ros::Subscriber forces_sub_;
  ros::Subscriber stats_sub_;
  tf2_ros::TransformBroadcaster tf_;
  tf2_ros::StaticTransformBroadcaster static_tf_;
  diagnostic_updater::Updater updater_;

  // The step waiting for its forces.
  bool awaiting_ = false;
  ros::Time awaiting_stamp_;
  lcp_contact_solver::ConstraintForces::ConstPtr received_;
  std::string solver_failure_;  // status of a solve that gave no forces for awaiting_stamp_

  SimulatorCounters counters_;
  std::string last_miss_;  // what happened at the last miss (diagnostics)
  double next_marker_time_ = 0.0;
  bool header_printed_ = false;
  ros::WallTime run_start_;
  double run_wall_time_ = 0.0;

  // Solver stats gathered over the current status period.
  struct PeriodStats {
    int solves = 0;
    double iterations = 0.0;     // sum
    double max_residual = 0.0;
    double solve_time = 0.0;     // sum, s
    std::int64_t misses_at_start = 0;
  } period_;
};

}  // namespace lcp_contact_solver_ros
