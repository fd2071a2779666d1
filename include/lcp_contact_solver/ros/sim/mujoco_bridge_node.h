// The MuJoCo bridge (`mujoco_bridge`): MuJoCo beside the contact solver node.
//
// Each step: MuJoCo's forward pipeline up to its constraint problem (forwardToConstraints) →
// the problem (scene/mujoco_adapter.h: W = efc_AR, d_free = efc_b over the contact, limit
// and equality rows) → /clock, then `contacts` and `compliance` with the step's stamp →
// wait for `constraint_forces` with that stamp (at most ~force_timeout wall seconds) → then
//
//   cross_check: MuJoCo steps with its own forces (its solver ran in the same step), ours are
//                compared with efc_force and the difference is reported;
//   drive:       MuJoCo steps with ours in place of its solver: qacc = qacc_smooth + M⁻¹ Jᵀ f,
//                then MuJoCo's semi-implicit Euler (mj_Euler). With ~compare its solver
//                also runs, only to report the difference.
//
// Whenever MuJoCo's solver ran for the step (cross_check, drive with ~compare) and someone
// listens, `~reference_forces` carries MuJoCo's own forces of that step (efc_force) as a
// ConstraintForces message with the step's stamp, in the node's layout for the same
// ContactArray (ids, rows, frames): a bag of contacts, compliance and reference_forces lets
// `replay --reference-topic /mujoco_bridge/reference_forces` compare our solve with MuJoCo's
// (scripts/record-mujoco-bags).
//
// Every step with rows publishes a `~step_report` (diagnostic_msgs/DiagnosticStatus, values
// by key: step, time, contacts, rows, our residual, MuJoCo's and our solve time, max
// abs/rel difference per contact state, penetration, energy); ~print_summary prints status
// lines and a final summary on stdout. When the forces do not come (timeout, a solve that
// gave none, forces that do not fit), cross_check skips the comparison and drive falls back
// to MuJoCo's own solver for the step; both are counted and warned about.
#pragma once

#include "lcp_contact_solver/core/solve_result.h"
#include "lcp_contact_solver/ros/sim/mujoco_bridge_settings.h"
#include "lcp_contact_solver/ros/sim/solver_link.h"
#include "lcp_contact_solver/scene/mujoco_adapter.h"

#include <diagnostic_msgs/DiagnosticStatus.h>
#include <ros/ros.h>

#include <Eigen/Core>

#include <cstdint>
#include <memory>
#include <ostream>
#include <string>

namespace lcp_contact_solver_ros {

namespace lcs = ::lcp_contact_solver;

// The steps so far (the misses by cause: SolverLink::counters()).
struct MujocoBridgeCounters {
  std::int64_t steps = 0;
  std::int64_t steps_with_rows = 0;
  std::int64_t forces_applied = 0;  // steps whose forces came (drive: integrated with them)
  std::int64_t extract_errors = 0;  // steps whose MuJoCo rows could not be converted
  std::int64_t fallbacks = 0;       // drive: steps integrated with MuJoCo's own solver
  std::int64_t compared = 0;        // steps compared with MuJoCo's forces
  std::int64_t over_warn = 0;       // compared steps above ~max_rel_warn
};

// Figures of the run (the summary).
struct MujocoBridgeTotals {
  int max_contacts = 0, last_contacts = 0, max_rows = 0;
  double max_residual = 0.0, last_residual = 0.0;
  double max_abs_diff = 0.0, max_rel_diff = 0.0;
  double state_max_rel[lcs::core::kContactStateCount] =
      {};  // per contact state (open, stick, slip, ignored, closed)
  std::int64_t state_count[lcs::core::kContactStateCount] = {};
  double max_penetration = 0.0, last_penetration = 0.0;
  double first_energy = 0.0, last_energy = 0.0;
  double our_solve_time = 0.0;  // s, summed (from the solver's stats)
  std::int64_t our_solves = 0;
  double mujoco_solve_time = 0.0;  // s, summed
  std::int64_t mujoco_solves = 0;
  // ~reference: the largest distance of a body to its place in MuJoCo's own run (m), the
  // largest energy difference (J), steps whose contact pairs differ from MuJoCo's.
  double max_ref_position_diff = 0.0, max_ref_energy_diff = 0.0;
  std::int64_t ref_contact_pair_steps_differ = 0;
};

class MujocoBridgeNode {
 public:
  // Reads the parameters and loads the model. Throws std::invalid_argument for a bad
  // parameter or a model that does not load.
  MujocoBridgeNode(const ros::NodeHandle& nh, const ros::NodeHandle& pnh);
  ~MujocoBridgeNode();

  // Waits for the solver, then steps until ~steps (or shutdown). False when the solver never
  // connected or ROS shut down first.
  bool run();
  // One step (public for tests).
  void step();

  void writeSummary(std::ostream& out) const;
  const MujocoBridgeCounters& counters() const { return counters_; }
  const LinkCounters& linkCounters() const { return link_.counters(); }
  const MujocoBridgeTotals& totals() const { return totals_; }

 private:
  static SolverLink::Options linkOptions(const MujocoBridgeNode* node);
  // The step's rows to the solver and back, with its ~step_report (mujoco_time < 0: MuJoCo's
  // solver did not run); true when drive mode applied our forces.
  bool exchange(const lcs::scene::MujocoProblem& mp, const ros::Time& stamp, double mujoco_time);
  std::string receive(SolverLink::Outcome outcome, const lcs::scene::MujocoProblem& mp,
                      Eigen::VectorXd* lambda);
  bool useForces(const lcs::scene::MujocoProblem& mp, const Eigen::VectorXd& lambda, const ros::Time& stamp,
                 bool mujoco_solves, diagnostic_msgs::DiagnosticStatus* report);
  void compare(const lcs::scene::MujocoProblem& mp, const Eigen::VectorXd& lambda, const ros::Time& stamp,
               diagnostic_msgs::DiagnosticStatus* report);
  void statusLine(int contacts, int rows);
  // ~reference: forward the reference copy to its constraints (same step as ours) and
  // compare; then, after our step, step it.
  void forwardReference();
  void stepReference();
  // A ~step_report value (numbers with all their digits); the contact states' names.
  static void addValue(diagnostic_msgs::DiagnosticStatus* status, const std::string& key,
                       const std::string& value);
  static void addValue(diagnostic_msgs::DiagnosticStatus* status, const std::string& key, double value);
  static const char* const kStateNames[lcs::core::kContactStateCount];

  ros::NodeHandle nh_;
  ros::NodeHandle pnh_;
  MujocoBridgeSettings settings_;
  std::unique_ptr<lcs::scene::MujocoWorld> world_;
  std::unique_ptr<lcs::scene::MujocoWorld> reference_;  // ~reference: MuJoCo's own run
  // The reference's distance at the current step (for its ~step_report).
  double ref_position_diff_ = 0.0, ref_energy_ = 0.0;
  int ref_contacts_ = 0, ref_pairs_differ_ = 0;
  lcs::scene::MujocoExtractOptions extract_;
  bool drive_ = false;
  double dt_ = 0.005;

  SolverLink link_;
  ros::Publisher report_pub_;
  ros::Publisher reference_pub_;  // ~reference_forces

  MujocoBridgeCounters counters_;
  MujocoBridgeTotals totals_;
  double run_wall_time_ = 0.0;
  double next_status_time_ = 0.0;
  bool header_printed_ = false;
  // Over the current status period.
  double period_max_rel_ = 0.0;
  double period_max_residual_ = 0.0;
};

}  // namespace lcp_contact_solver_ros
