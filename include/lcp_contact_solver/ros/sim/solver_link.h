// The simulator side of the lockstep with contact_solver_node, shared by the scene simulator
// and the MuJoCo bridge.
//
// Per step: /clock (the step's stamp) → `compliance` and `contacts` with that stamp → wait
// for `constraint_forces` with the same stamp (at most ~force_timeout wall seconds; <= 0 for
// ever), ended early when `contact_solver/stats` says the solve of that stamp gave no forces.
// Forces of any other stamp are late ones and ignored. Between steps `pace` keeps the
// simulated time at ~rate_factor × wall time; after the run `linger` keeps serving so the
// last messages reach slow subscribers. Callbacks run on the global queue, on the calling
// thread.
#pragma once

#include <lcp_contact_solver/Compliance.h>
#include <lcp_contact_solver/ConstraintForces.h>
#include <lcp_contact_solver/ContactArray.h>
#include <lcp_contact_solver/SolverStats.h>
#include <ros/ros.h>

#include <cstdint>
#include <functional>
#include <initializer_list>
#include <string>
#include <variant>

namespace lcp_contact_solver_ros {

// The private parameters every simulator beside the solver node reads.
struct LinkSettings {
  double duration = 0.0;           // simulated s to run; 0 = for ever
  double rate_factor = 1.0;        // simulated s per wall s; 0 = as fast as possible
  double force_timeout = 1.0;      // wall s to wait for the forces of a step; <= 0: for ever
  double wait_for_solver = 30.0;   // wall s to wait for the solver's connections; <= 0: for ever
  double linger = 1.0;             // wall s to keep serving after the run, so the last
                                   // messages reach slow subscribers before the node exits
  std::string frame_id = "world";  // frame of the contacts
  bool publish_clock = true;       // publish /clock with the simulated time
  double status_period = 1.0;      // simulated s between status lines
};

// One private parameter and the setting it goes to; the setting's type says what the
// parameter must be: a number (double), an integer (int), true or false (bool), a string.
struct ParamField {
  const char* name;
  std::variant<double*, int*, bool*, std::string*> setting;
};

// The field of a settings struct whose parameter has the member's own name.
#define LCS_PARAM_FIELD(settings, member) \
  ::lcp_contact_solver_ros::ParamField { #member, &(settings)->member }

// Reads each parameter present over its setting's value (the default): empty string, or
// "parameter <name> must be <what>" for the first of another type.
std::string readParams(const ros::NodeHandle& pnh, std::initializer_list<ParamField> fields);

// Reads the LinkSettings parameters present over `settings`, then validates them: empty
// string or a sentence naming the parameter.
std::string loadLinkSettings(const ros::NodeHandle& pnh, LinkSettings* settings);
std::string validateLinkSettings(const LinkSettings& settings);

// A simulator's settings: its LinkSettings part (loadLinkSettings), then its own `fields`,
// then `validate` of its own values. Empty string, or the first fault.
std::string loadSettings(const ros::NodeHandle& pnh, LinkSettings* link,
                         std::initializer_list<ParamField> fields,
                         const std::function<std::string()>& validate);

// The stamp of step k (its contacts, compliance, forces and /clock): ros::Time(k·dt),
// rounded to the nanosecond, so stamps stay exact multiples of dt however long the run.
ros::Time stepStamp(std::int64_t step_index, double dt);

// "12.340 s", for log lines.
std::string stampText(const ros::Time& stamp);

// The steps that got no forces, by cause.
struct LinkCounters {
  std::int64_t force_timeouts = 0;   // no forces within ~force_timeout, or no solver connected
  std::int64_t solver_failures = 0;  // the solver's stats said it gave no forces for the step
  std::int64_t bad_forces = 0;       // forces that did not match the step (ids, rows, values)
  std::int64_t stale_forces = 0;     // forces of an older step arriving late (ignored)
  std::int64_t misses() const { return force_timeouts + solver_failures + bad_forces; }
};

class SolverLink {
 public:
  enum class Outcome { kForces, kTimeout, kNoSolver, kSolverFailed, kShutdown };

  struct Options {
    std::uint32_t min_subscribers = 1;  // on `contacts` and `compliance` before the first step
    // A solver that went away ends the wait at once (kNoSolver) instead of at the timeout.
    bool stop_when_solver_leaves = true;
    // Wall s to wait for the stats of a solve once its forces came (they usually follow).
    double stats_grace = 0.0;
    std::function<bool()> also_ready;  // a further condition before the first step
  };

  // Advertises `contacts`, `compliance`, /clock (with publish_clock) on `nh` and subscribes
  // to `constraint_forces` and `contact_solver/stats`.
  SolverLink(ros::NodeHandle nh, const LinkSettings& settings, Options options);

  // Called with every stats message (before the link looks at it).
  void onEveryStats(std::function<void(const lcp_contact_solver::SolverStats&)> callback) {
    stats_callback_ = std::move(callback);
  }

  // Waits until the solver is connected (~wait_for_solver); false, with a fatal log line,
  // when it is not or ROS shut down.
  bool waitForSolver();

  // Publishes the step's messages, waits for its forces and counts a miss.
  Outcome exchange(const ros::Time& stamp, const lcp_contact_solver::ContactArray::ConstPtr& contacts,
                   const lcp_contact_solver::Compliance::ConstPtr& compliance);
  // What the last exchange received: the forces (kForces), the stats of its stamp (may be
  // null), why the solve gave none (kSolverFailed).
  const lcp_contact_solver::ConstraintForces& forces() const { return *received_; }
  const lcp_contact_solver::SolverStats::ConstPtr& stats() const { return stats_; }
  const std::string& failure() const { return solver_failure_; }
  // The forces of the last exchange did not fit the step.
  void countBadForces() { ++counters_.bad_forces; }

  void publishClock(const ros::Time& stamp);
  // Starts the wall clock of the run (pace, runWallTime).
  void startRun() { run_start_ = ros::WallTime::now(); }
  // Serves callbacks until `sim_time` / rate_factor wall seconds after startRun().
  void pace(double sim_time);
  double runWallTime() const { return (ros::WallTime::now() - run_start_).toSec(); }
  // Serves callbacks for ~linger wall seconds.
  void linger();

  // The summary on stdout (print) with one log line, or in the log.
  void logSummary(const std::string& what, bool print, const std::string& summary, std::int64_t steps) const;

  const LinkCounters& counters() const { return counters_; }
  const LinkSettings& settings() const { return settings_; }
  std::string forcesTopic() const { return forces_sub_.getTopic(); }

 private:
  void onForces(const lcp_contact_solver::ConstraintForces::ConstPtr& msg);
  void onStats(const lcp_contact_solver::SolverStats::ConstPtr& msg);
  bool connected() const;
  Outcome waitForForces(const ros::Time& stamp);
  void waitForStats();

  ros::NodeHandle nh_;
  LinkSettings settings_;
  Options options_;
  ros::Publisher contacts_pub_;
  ros::Publisher compliance_pub_;
  ros::Publisher clock_pub_;
  ros::Subscriber forces_sub_;
  ros::Subscriber stats_sub_;
  std::function<void(const lcp_contact_solver::SolverStats&)> stats_callback_;

  // The step waiting for its forces.
  bool awaiting_ = false;
  ros::Time awaiting_stamp_;
  lcp_contact_solver::ConstraintForces::ConstPtr received_;
  lcp_contact_solver::SolverStats::ConstPtr stats_;  // of awaiting_stamp_, if it came
  std::string solver_failure_;  // status of a solve that gave no forces for awaiting_stamp_

  LinkCounters counters_;
  ros::WallTime run_start_;
};

}  // namespace lcp_contact_solver_ros
