// Islands: groups of contacts that W does not couple. Two contacts share an island when W
// has a nonzero entry (dense) or a stored block (block-sparse) between them, directly or
// through other contacts. Forces of different islands do not affect each other's d, so
// the problem is the product of the island problems: each is solved on its own, with its
// own stopping test (a settled island stops sweeping), on a pool of threads. Each island
// is solved exactly as it would be alone, and the merge is in island order, so the result
// does not depend on the thread count.
#pragma once

#include "lcp_contact_solver/core/kernels/kernels.h"
#include "lcp_contact_solver/core/problem.h"

#include <Eigen/Core>

#include <functional>
#include <vector>

namespace lcp_contact_solver::core {

// Below this many rows a problem is solved whole: building the island problems (a few
// thousand instructions each) costs more than a 30-row solve saves by stopping settled
// islands early (lcp_trivial, 9 one-row islands: 6.8 µs split, 2.0 µs whole).
constexpr int kMinRowsForIslands = 32;

struct Islands {
  std::vector<int> island_of;              // island of each contact
  std::vector<std::vector<int>> contacts;  // contacts of each island, ascending
  int count() const { return static_cast<int>(contacts.size()); }
};

// The islands of W: dense, block-sparse, or the body form (contacts sharing a body).
Islands findIslands(const Problem& problem);

// The problem restricted to `contacts` (ascending): their rows of W and d_free, same
// storage as `problem` (the body form: their bodies, renumbered). `offsets` are
// problem.rowOffsets().
Problem islandProblem(const Problem& problem, const std::vector<int>& offsets,
                      const std::vector<int>& contacts);

// A kernel run on one island's context (called concurrently for different islands).
using IslandKernel = std::function<KernelReport(const SolveContext&, Eigen::VectorXd&)>;

// The island problems of one solve, built once and reused by every maxF pass.
class IslandSolver {
 public:
  // `ctx.problem` must stay alive while this object is used.
  IslandSolver(const SolveContext& ctx, Islands islands);
  int count() const { return static_cast<int>(islands_.size()); }
  // Runs `kernel` on every island from its rows of `lambda` (ignored contacts taken from
  // `ctx`) and writes the results back. `threads` <= 1, or fewer than 200 rows, solves on
  // the calling thread. The report: the worst status (a failure, then time_budget, then
  // max_iterations), the largest iteration count, and with the residual stopping rule the
  // whole problem's error from the islands' (each normalised by its own d_free). Each
  // island's residual tolerance is set so that all islands meeting theirs implies the
  // whole problem meets params.tolerance; an island with more rows than all the others
  // together runs after them, with whatever of the tolerance they left (never less than
  // its own share), so that the result still does not depend on `threads`.
  KernelReport run(const SolveContext& ctx, const IslandKernel& kernel, Eigen::VectorXd& lambda, int threads);

 private:
  struct Island {
    std::vector<int> contacts;  // in the whole problem
    std::vector<int> rows;      // rows of the whole problem, in island order
    Problem problem;
    SolverParams params;
    double weight = 1.0;  // |d_free_i| / |d_free| (each 1 when zero): residual scale
    double tolerance = 0.0;  // its own share of the tolerance (params.tolerance between runs)
    SolveContext ctx;
    Eigen::VectorXd lambda;
    KernelReport report;
  };
  double dominantTolerance(const SolverParams& params) const;
  std::vector<Island> islands_;
  int dominant_ = -1;  // the island with more rows than all others together, if any
};

// Worker threads for `threads` = 0 (SolverParams::threads): the core count.
int defaultThreadCount();

}  // namespace lcp_contact_solver::core
