// `work_precision --sweep-cost FILE`: what one Gauss-Seidel sweep, one product with W (an apgd
// iteration's main cost) and one dense Cholesky of W cost on each problem of the study. The
// sweep and the Cholesky are the two figures auto's cost tests weigh against each other
// (portfolio.cpp: stickingCostSweeps counts a factorization in sweeps by flops, n³/3 against
// 2 × W's stored entries). A sweep is timed as the difference of two nlgs solves run to a fixed
// number of sweeps (a tolerance never met), so that nlgs's set-up cancels; the Cholesky is
// choleskyInPlace of W + I gathered dense, as the sticking path factors it (Eigen's LLT before
// 2026-12-08). Each is the fastest of its repeats.
#include "work_precision.h"

#include "lcp_contact_solver/core/contact_solver.h"
#include "lcp_contact_solver/core/kernels/kernels.h"

#include <algorithm>
#include <limits>
#include <ostream>
#include <variant>

namespace lcs_bench::work_precision {

namespace {

constexpr int kFewSweeps = 5;
constexpr int kManySweeps = 45;
constexpr int kMaxRows = 2048;  // twice the most the sticking path gathers dense (portfolio.cpp)

// The fastest of `repeats` calls of f, in seconds; at least `min_time` spent in all.
template <typename F>
double fastest(F&& f, int repeats, double min_time) {
  double best = std::numeric_limits<double>::infinity(), spent = 0.0;
  for (int k = 0; k < repeats || spent < min_time; ++k) {
    const Clock::time_point t0 = Clock::now();
    f();
    const double s = std::chrono::duration<double>(Clock::now() - t0).count();
    best = std::min(best, s);
    spent += s;
    if (k > 10000) break;
  }
  return best;
}

// Not timing_util.h's sweepRound: its fresh solveProblem per run lets the set-up vary between
// the two runs whose difference is the sweep (active_adhesion's pyramidal step once read 0.38
// instead of 4.1 µs); one ContactSolver repeated keeps the set-up the same on both sides.
double nlgsSeconds(const lcs::core::Problem& problem, int sweeps) {
  lcs::core::SolverParams p;
  p.solver = lcs::core::SolverKind::kNlgs;
  p.tolerance = std::numeric_limits<double>::min();  // never met: every sweep runs
  p.maxIt = sweeps;
  p.initial_guess = false;  // every solve from zero: near the solution a sweep can cost a third as much
  lcs::core::ContactSolver solver(p);
  const lcs::core::SolveResult r = solver.solve(problem);
  if (r.iterations != sweeps) return std::numeric_limits<double>::quiet_NaN();  // it stopped early
  return fastest([&] { solver.solve(problem); }, 5, 0.05);
}

Eigen::MatrixXd denseW(const lcs::core::Problem& problem) {
  if (const auto* dense = std::get_if<Eigen::MatrixXd>(&problem.W)) return *dense;
  return std::get<lcs::core::BlockSparseMatrix>(problem.W).toDense();
}

}  // namespace

void writeSweepCosts(const std::vector<BenchProblem>& problems, std::ostream& csv) {
  csv << "family,problem,rows,storage,stored,blocks,sweep_s,product_s,cholesky_s,cholesky_sweeps,flop_model_sweeps\n";
  for (const BenchProblem& bp : problems) {
    const lcs::core::Problem& problem = bp.problem;
    const int n = problem.rowCount();
    if (problem.bodies || n > kMaxRows) continue;  // the body form stores no W
    const auto* sparse = std::get_if<lcs::core::BlockSparseMatrix>(&problem.W);
    const double stored = sparse ? static_cast<double>(sparse->values.size()) : double(n) * n;
    const int blocks = sparse ? static_cast<int>(sparse->block_col.size()) : 1;
    const double sweep =
        (nlgsSeconds(problem, kManySweeps) - nlgsSeconds(problem, kFewSweeps)) / (kManySweeps - kFewSweeps);
    Eigen::VectorXd x = Eigen::VectorXd::Ones(n), y(n);
    const double product = fastest([&] { lcs::core::multiply(problem.W, x, y); }, 20, 0.02);
    Eigen::MatrixXd M = denseW(problem);
    M.diagonal().array() += 1.0;  // positive definite whatever W's rank: the time is the same
    Eigen::MatrixXd A(n, n);
    const double cholesky = fastest(
        [&] {
          A = M;
          lcs::core::choleskyInPlace(A);
        },
        5, 0.05);
    const double flop_model = double(n) * n * n / 3.0 / (2.0 * std::max(1.0, stored));
    csv << bp.family << ',' << bp.name << ',' << n << ',' << (sparse ? "block-sparse" : "dense") << ','
        << stored << ',' << blocks << ',' << fmt(sweep) << ',' << fmt(product) << ',' << fmt(cholesky) << ',' << fmt(cholesky / sweep)
        << ',' << fmt(flop_model) << '\n';
    csv.flush();
  }
}

}  // namespace lcs_bench::work_precision
