// Offline replay of recorded solver traffic: reads a bag with rosbag::View (no roscore),
// pairs each ContactArray with the Compliance of the same stamp in the order the live
// node's ExactTime synchronizer would (stamp_pairer.h), solves every pair through the
// node's own CycleSolver (warm start by contact id across cycles), and compares the forces
// with those the node recorded in the bag (force_comparison.h) and, when asked, with a
// reference from outside recorded beside them (MuJoCo's efc_force on the bridge's
// ~reference_forces). Used by the `replay` command (src/tools/replay) and by the replay tests.
#pragma once

#include "lcp_contact_solver/core/solver_params.h"
#include "lcp_contact_solver/ros/node/cycle_solver.h"
#include "lcp_contact_solver/ros/replay/answer_check.h"
#include "lcp_contact_solver/ros/replay/force_comparison.h"
#include "lcp_contact_solver/ros/replay/stamp_pairer.h"

#include <lcp_contact_solver/Compliance.h>
#include <lcp_contact_solver/ConstraintForces.h>
#include <lcp_contact_solver/ContactArray.h>
#include <lcp_contact_solver/SolverStats.h>
#include <ros/time.h>

#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace lcp_contact_solver_ros {

struct ReplayOptions {
  std::string bag;      // input
  std::string out_bag;  // "" = none
  std::string csv;      // "" = none
  // Input topics; an unset one is looked up by name ("contacts", "compliance") and, when
  // no topic has that name, by message type when exactly one topic has it.
  std::string contacts_topic, compliance_topic;
  // The recorded output of the node to compare with (optional; same lookup with
  // "constraint_forces" and "contact_solver/stats").
  std::string forces_topic, stats_topic;
  // Forces from outside to compare with ("" = none): ConstraintForces in the replay's
  // layout (one per contact, ids and rows of the ContactArray), e.g. the MuJoCo bridge's
  // /mujoco_bridge/reference_forces. Never taken as the recorded output by type.
  std::string reference_topic;
  // The parameters the bag was recorded with (its params file, without overrides). When
  // set, every recorded answer (forces_topic, with its stats) is checked on its own problem
  // (answer_check.h) into ReplayResult::answers, independently of the replay's solve.
  std::optional<lcs::core::SolverParams> recorded_params;
  bool copy_inputs = true;   // the output bag also holds the input topics (replayable)
  bool keep_cycles = false;  // keep every cycle's output in ReplayResult::cycles
  // Called after each contact array read: (arrays read, arrays in the bag). Empty: none.
  std::function<void(std::size_t done, std::size_t total)> progress;
};

struct ReplayCycle {
  ros::Time stamp;
  ros::Time bag_time;                     // receipt of the message that completed the pair
  lcp_contact_solver::SolverStats stats;  // as the node publishes it
  bool has_forces = false;
  lcp_contact_solver::ConstraintForces forces;
};

struct ReplayResult {
  std::string error;               // non-empty: the replay did not run (file, bag format, topics, output)
  std::vector<std::string> notes;  // topic choices and other remarks
  std::string contacts_topic, compliance_topic, forces_topic, stats_topic, reference_topic;  // "" = none
  std::string out_forces_topic, out_stats_topic;
  std::size_t contact_messages = 0, compliance_messages = 0;
  std::size_t cycles = 0;    // pairs solved or rejected
  std::size_t solved = 0;    // the core ran
  std::size_t rejected = 0;  // invalid input
  std::size_t with_forces = 0;
  std::size_t converged = 0;
  std::size_t unpaired = 0;  // contact arrays without compliance
  std::size_t unused_compliance = 0;
  std::size_t duplicates = 0;
  double max_residual = 0.0, sum_residual = 0.0;
  long total_iterations = 0;
  int max_iterations = 0;
  double total_solve_time = 0.0;
  ros::Time worst_residual_stamp;
  Comparison comparison;  // with the recorded output (forces_topic, stats_topic)
  // With the reference (reference_topic): overall, and every cycle and every reference
  // stamp no cycle had, in replay order.
  Comparison reference;
  AnswerChecks answers;  // with ReplayOptions::recorded_params
  std::vector<CycleDifference> reference_cycles;
  std::vector<ReplayCycle> cycles_kept;  // with ReplayOptions::keep_cycles

  double meanResidual() const { return solved > 0 ? sum_residual / static_cast<double>(solved) : 0.0; }
};

// Replays `options.bag` with `params`. Never throws; a fault is in ReplayResult::error.
ReplayResult replayBag(const ReplayOptions& options, const lcs::core::SolverParams& params);

}  // namespace lcp_contact_solver_ros
