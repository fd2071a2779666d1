// The replay's forces against forces in the bag, per cycle and over a whole replay: the
// node's own recorded output (a change detector: same code, same inputs give the same
// forces), or a reference from outside (MuJoCo's efc_force, recorded by the bridge), which
// checks correctness where the problem has one solution.
#pragma once

#include <lcp_contact_solver/ConstraintForces.h>
#include <ros/time.h>

#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

namespace lcp_contact_solver_ros {

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

// One cycle of a comparison (kept per cycle for the reference topic).
struct CycleDifference {
  ros::Time stamp;
  long cycle = -1;           // index in replay order; -1: a reference stamp no cycle had
  std::size_t contacts = 0;  // the replay's contacts (0 when it gave no forces)
  // Non-empty: not comparable (counts, ids or rows differ, or forces on one side only).
  std::string mismatch;
  double max_abs = 0.0;   // N
  double relative = 0.0;  // +inf when not comparable
};

// The comparison of a whole replay with forces in the bag.
struct Comparison {
  // Forces (cycles whose stamp has forces on both sides).
  std::size_t compared = 0;
  std::size_t mismatched = 0;         // counts, ids or rows differ
  std::size_t missing_reference = 0;  // replay gave forces, the bag has none for that stamp
  std::size_t missing_replay = 0;     // the bag has forces the replay did not produce
  double max_abs = 0.0;               // N
  double sum_sq = 0.0;
  std::size_t values = 0;
  double max_relative = 0.0;
  ros::Time worst_stamp;       // cycle of max_relative
  long worst_cycle = -1;       // its index in replay order
  std::string first_mismatch;  // the first mismatch, with its stamp
  // Stats (solved cycles with a recorded SolverStats of the same stamp).
  std::size_t stats_compared = 0;
  std::size_t iteration_differences = 0;
  std::size_t status_differences = 0;
  double max_residual_relative = 0.0;  // relativeDifference of the residuals
  ros::Time first_iteration_difference;

  // Adds one cycle: the forces of both sides (either may be null: forces on one side only).
  // Returns the cycle's figures.
  CycleDifference add(const lcp_contact_solver::ConstraintForces* replayed,
                      const lcp_contact_solver::ConstraintForces* reference, const ros::Time& stamp,
                      long cycle, const std::string& why_no_replay = "");

  double rms() const { return values > 0 ? std::sqrt(sum_sq / static_cast<double>(values)) : 0.0; }
  // Something to compare with was found in the bag.
  bool hasReference() const { return compared + mismatched + missing_reference + missing_replay > 0; }
  // The forces differ by more than `tolerance` (relative), or cannot be compared.
  bool exceeds(double tolerance) const;
};

}  // namespace lcp_contact_solver_ros
