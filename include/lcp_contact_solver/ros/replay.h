// Offline replay of recorded solver traffic: reads a bag with rosbag::View (no roscore),
// pairs each ContactArray with the Compliance of the same stamp in the order the live
// node's ExactTime synchronizer would, solves every pair through the node's own
// CycleSolver (warm start by contact id across cycles), and compares the forces with
// those the node recorded in the bag. Used by the `replay` command
// (src/nodes/replay_main.cpp) and by the replay tests.
#pragma once

#include "lcp_contact_solver/core/solver_params.h"
#include "lcp_contact_solver/ros/cycle_solver.h"

#include <lcp_contact_solver/Compliance.h>
#include <lcp_contact_solver/ConstraintForces.h>
#include <lcp_contact_solver/ContactArray.h>
#include <lcp_contact_solver/SolverStats.h>
#include <ros/time.h>

#include <cmath>
#include <cstddef>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <ostream>
#include <string>
#include <vector>

namespace lcp_contact_solver_ros {

// ---- topics ----------------------------------------------------------------------------

// "/name" for "name" or "/name" (bags store resolved names, users type either).
std::string normalizeTopic(const std::string& name);

// ---- parameters ------------------------------------------------------------------------

// One "name=value": the names of the service's param_overrides (applyOverride) plus
// `initial_guess` (the warm start, which only matters across cycles).
std::string applyReplayOverride(const std::string& assignment, lcs::SolverParams* params);

// Reads a YAML file of the node's private parameters (config/default.yaml, or the one
// recorded beside a bag) over `params`. Solver parameters are applied; the node's other
// parameters (markers, pairing, queues, diagnostics, computeConstraintForces) are
// accepted and have no effect offline; an unknown name or a bad value is an error. Returns
// an empty string or one sentence naming the file and the fault.
std::string loadParamsFile(const std::string& path, lcs::SolverParams* params);

// Writes the solver parameters as such a YAML file (loadParamsFile reads it back exactly).
std::string writeParamsFile(const std::string& path, const lcs::SolverParams& params);

// The parameter file kept beside a recorded bag: "dir/name.bag" → "dir/name.params.yaml".
std::string paramsFileBeside(const std::string& bag_path);

// ---- pairing ---------------------------------------------------------------------------

// Pairs contact arrays with compliances by exact header.stamp, emitting a pair when its
// second message arrives, like message_filters' ExactTime policy (which is what the node
// uses). Messages that never find a partner stay in the pairer; nothing is dropped for
// age or queue length (a bag is complete, unlike a live topic).
class StampPairer {
 public:
  using ContactsPtr = lcp_contact_solver::ContactArray::ConstPtr;
  using CompliancePtr = lcp_contact_solver::Compliance::ConstPtr;
  struct Pair {
    ContactsPtr contacts;
    CompliancePtr compliance;
  };

  // True when `contacts` completes a pair (then written to *pair). A second message of
  // the same topic and stamp replaces the waiting one.
  bool addContacts(const ContactsPtr& contacts, Pair* pair);
  bool addCompliance(const CompliancePtr& compliance, Pair* pair);

  // Contact arrays still waiting for their compliance, in stamp order.
  std::vector<ContactsPtr> waitingContacts() const;
  std::size_t waitingCompliance() const { return compliance_.size(); }
  // Messages replaced by a later one with the same stamp.
  std::size_t duplicates() const { return duplicates_; }

 private:
  std::map<ros::Time, ContactsPtr> contacts_;
  std::map<ros::Time, CompliancePtr> compliance_;
  std::size_t duplicates_ = 0;
};

// ---- comparison ------------------------------------------------------------------------

// Difference between the forces of one cycle and a reference (every row's λ).
struct ForceDifference {
  std::string mismatch;  // non-empty: the two do not describe the same contacts (counts, ids, rows)
  double max_abs = 0.0;  // max |Δλ| (N)
  double sum_sq = 0.0;   // Σ Δλ²
  std::size_t values = 0;
  // max |Δλ| / max(‖λ‖∞, ‖λ_ref‖∞); 0 when both are zero; +inf on a mismatch.
  double relative = 0.0;
};
ForceDifference compareForces(const lcp_contact_solver::ConstraintForces& forces,
                              const lcp_contact_solver::ConstraintForces& reference);

// Relative difference of two numbers: |a − b| / max(|a|, |b|), 0 when both are zero.
double relativeDifference(double a, double b);

// The comparison of a whole replay with the bag's recorded output.
struct Comparison {
  // Forces (cycles whose stamp has forces on both sides).
  std::size_t compared = 0;
  std::size_t mismatched = 0;          // counts, ids or rows differ
  std::size_t missing_reference = 0;   // replay gave forces, the bag has none for that stamp
  std::size_t missing_replay = 0;      // the bag has forces the replay did not produce
  double max_abs = 0.0;                // N
  double sum_sq = 0.0;
  std::size_t values = 0;
  double max_relative = 0.0;
  ros::Time worst_stamp;               // cycle of max_relative
  long worst_cycle = -1;               // its index in replay order
  std::string first_mismatch;          // the first mismatch, with its stamp
  // Stats (solved cycles with a recorded SolverStats of the same stamp).
  std::size_t stats_compared = 0;
  std::size_t iteration_differences = 0;
  std::size_t status_differences = 0;
  double max_residual_relative = 0.0;  // relativeDifference of the residuals
  ros::Time first_iteration_difference;

  double rms() const { return values > 0 ? std::sqrt(sum_sq / static_cast<double>(values)) : 0.0; }
  // Something to compare with was found in the bag.
  bool hasReference() const { return compared + mismatched + missing_reference + missing_replay > 0; }
  // The forces differ by more than `tolerance` (relative), or cannot be compared.
  bool exceeds(double tolerance) const;
};

// ---- output helpers --------------------------------------------------------------------

// Per-cycle stats as CSV: stamp,contacts,rows,iterations,residual,converged,status,solve_time
class StatsCsvWriter {
 public:
  // Empty string, or why the file cannot be written.
  std::string open(const std::string& path);
  void write(const lcp_contact_solver::SolverStats& stats);
  bool good() const { return out_.good(); }
  static const char* header();
  static std::string row(const lcp_contact_solver::SolverStats& stats);

 private:
  std::ofstream out_;
};

// A one-line progress bar on a terminal; does nothing when disabled (not a terminal).
class ProgressBar {
 public:
  ProgressBar(std::FILE* stream, std::size_t total, bool enabled);
  void update(std::size_t done);
  void finish();

 private:
  std::FILE* stream_;
  std::size_t total_;
  bool enabled_;
  int last_permille_ = -1;
};

// True when the file descriptor of `stream` is a terminal.
bool isTerminal(std::FILE* stream);

// ---- replay ----------------------------------------------------------------------------

struct ReplayOptions {
  std::string bag;          // input
  std::string out_bag;      // "" = none
  std::string csv;          // "" = none
  // Input topics; an unset one is looked up by name ("contacts", "compliance") and, when
  // no topic has that name, by message type when exactly one topic has it.
  std::string contacts_topic, compliance_topic;
  // The recorded output of the node to compare with (optional; same lookup with
  // "constraint_forces" and "contact_solver/stats").
  std::string forces_topic, stats_topic;
  bool copy_inputs = true;  // the output bag also holds the input topics (replayable)
  bool keep_cycles = false; // keep every cycle's output in ReplayResult::cycles
  std::FILE* progress = nullptr;  // progress bar stream (nullptr: none)
};

struct ReplayCycle {
  ros::Time stamp;
  ros::Time bag_time;                      // receipt of the message that completed the pair
  lcp_contact_solver::SolverStats stats;   // as the node publishes it
  bool has_forces = false;
  lcp_contact_solver::ConstraintForces forces;
};

struct ReplayResult {
  std::string error;  // non-empty: the replay did not run (file, bag format, topics, output)
  std::vector<std::string> notes;  // topic choices and other remarks
  std::string contacts_topic, compliance_topic, forces_topic, stats_topic;  // "" = none
  std::string out_forces_topic, out_stats_topic;
  std::size_t contact_messages = 0, compliance_messages = 0;
  std::size_t cycles = 0;     // pairs solved or rejected
  std::size_t solved = 0;     // the core ran
  std::size_t rejected = 0;   // invalid input
  std::size_t with_forces = 0;
  std::size_t converged = 0;
  std::size_t unpaired = 0;   // contact arrays without compliance
  std::size_t unused_compliance = 0;
  std::size_t duplicates = 0;
  double max_residual = 0.0, sum_residual = 0.0;
  long total_iterations = 0;
  int max_iterations = 0;
  double total_solve_time = 0.0;
  ros::Time worst_residual_stamp;
  Comparison comparison;
  std::vector<ReplayCycle> cycles_kept;  // with ReplayOptions::keep_cycles

  double meanResidual() const { return solved > 0 ? sum_residual / static_cast<double>(solved) : 0.0; }
};

// Replays `options.bag` with `params`. Never throws; a fault is in ReplayResult::error.
ReplayResult replayBag(const ReplayOptions& options, const lcs::SolverParams& params);

// The end-of-run report: counts, residual summary, comparison with the recorded forces.
std::string formatSummary(const ReplayResult& result);

// The command line of `replay` (argv without the program name); returns the exit code:
// 0 done, 1 the comparison exceeds --tolerance-compare, 2 usage or input error.
int runReplayCommand(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

}  // namespace lcp_contact_solver_ros
