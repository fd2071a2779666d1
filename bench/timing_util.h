// Timing helpers of the runtime benchmarks (`make bench-runtime`: bench/effects_cost.cpp,
// bench/scaling.cpp, bench/latency.cpp): CPU-time measurement in interleaved rounds (the
// fastest counts), the machine's load, the bytes of a compliance, and taking a sub-problem
// on the same geometry (fewer rows per contact, other types and μ). Header-only, benchmarks
// only (never a test).
#pragma once

#include "lcp_contact_solver/core/body_compliance.h"
#include "lcp_contact_solver/core/contact_solver.h"
#include "lcp_contact_solver/core/problem.h"
#include "lcp_contact_solver/core/solver_param_table.h"

#include <Eigen/Core>

#include <time.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

namespace lcs_bench {

namespace lcs = ::lcp_contact_solver;
using Clock = std::chrono::steady_clock;

inline double secondsSince(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// The 1-minute load average (/proc/loadavg), or -1.
inline double loadAverage1() {
  std::ifstream in("/proc/loadavg");
  double l = -1.0;
  in >> l;
  return l;
}

inline std::string loadAverageText() {
  std::ifstream in("/proc/loadavg");
  std::string a, b, c;
  in >> a >> b >> c;
  return a + " " + b + " " + c;
}

// The items of a comma list ("auto,newton"; empty items skipped).
inline std::vector<std::string> splitList(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream in(s);
  std::string item;
  while (std::getline(in, item, ','))
    if (!item.empty()) out.push_back(item);
  return out;
}

// One solver of a benchmark that repeats solves in rounds (solve_repeat, storage_stream): its
// `solver` value and parameters, its fastest round's time per solve, the minor page faults
// over every round (where measured) and its last answer.
struct RepeatedSolver {
  std::string name;
  lcs::core::SolverParams params;
  double best = std::numeric_limits<double>::infinity();
  long faults = 0;
  lcs::core::SolveResult last;
};

// The solvers of a comma list of `solver` values, at `tolerance` with maxIt 100 000; on an
// unknown value none, and the parameter table's message in *error.
inline std::vector<RepeatedSolver> repeatedSolvers(const std::string& list, double tolerance, std::string* error) {
  std::vector<RepeatedSolver> out;
  for (const std::string& name : splitList(list)) {
    RepeatedSolver s;
    s.name = name;
    s.params.tolerance = tolerance;
    s.params.maxIt = 100000;
    *error = lcs::core::setParam(&s.params, "solver", name);
    if (!error->empty()) return {};
    out.push_back(std::move(s));
  }
  return out;
}

inline std::vector<int> parseIntList(const std::string& s) {
  std::vector<int> out;
  for (const std::string& item : splitList(s)) out.push_back(std::stoi(item));
  return out;
}

// Bytes of the stored compliance (values + index arrays; not the vectors' spare capacity).
inline std::size_t bytesOf(const lcs::core::BlockSparseMatrix& W) {
  return W.values.size() * sizeof(double) +
         (W.block_col.size() + W.value_start.size() + W.row_start.size() + W.block_offset.size()) *
             sizeof(int);
}
inline std::size_t bytesOf(const lcs::core::BodyCompliance& B) {
  return B.body_compliance.size() * sizeof(lcs::core::BodyMatrix) +
         B.contacts.size() * sizeof(lcs::core::ContactJacobian) +
         static_cast<std::size_t>(B.diagonal.size()) * sizeof(double);
}
inline std::size_t bytesOfCompliance(const lcs::core::Problem& p) {
  if (p.bodies) return bytesOf(*p.bodies);
  if (const auto* d = std::get_if<Eigen::MatrixXd>(&p.W))
    return static_cast<std::size_t>(d->size()) * sizeof(double);
  return bytesOf(std::get<lcs::core::BlockSparseMatrix>(p.W));
}

// What one contact becomes in a derived problem: its first `rows` rows of the source (the
// normal first, then t1, t2, spin, rolling t1, rolling t2), a type and friction.
struct ContactModel {
  lcs::core::ContactType type = lcs::core::ContactType::kFrictional;
  int rows = 3;
  double mu = 0.5, mu_torsional = 0.0, mu_rolling = 0.0;
};

// The same geometry with fewer rows per contact: W's block (i, j) becomes its leading
// rows_i × rows_j corner and d_free keeps the leading rows of each contact. For rigid
// contacts W = J M⁻¹ Jᵀ row by row, so this is exactly the problem the scene would build if
// it asked each contact for those rows only. The body form, if any, is dropped.
inline lcs::core::Problem deriveProblem(const lcs::core::Problem& src,
                                        const std::vector<ContactModel>& models) {
  const int nc = static_cast<int>(src.contacts.size());
  if (static_cast<int>(models.size()) != nc)
    throw std::invalid_argument("deriveProblem: one model per contact");
  const std::vector<int> off = src.rowOffsets();
  lcs::core::Problem out;
  out.name = src.name;
  out.contacts = src.contacts;
  std::vector<int> sizes(nc), keep_rows;
  for (int i = 0; i < nc; ++i) {
    const ContactModel& m = models[i];
    if (m.rows > src.contacts[i].rows)
      throw std::invalid_argument("deriveProblem: more rows than the source has");
    lcs::core::Contact& c = out.contacts[i];
    c.type = m.type;
    c.rows = m.rows;
    c.mu = m.mu;
    c.mu_torsional = m.mu_torsional;
    c.mu_rolling = m.mu_rolling;
    sizes[i] = m.rows;
    for (int r = 0; r < m.rows; ++r) keep_rows.push_back(off[i] + r);
  }
  out.d_free.resize(static_cast<int>(keep_rows.size()));
  for (int k = 0; k < static_cast<int>(keep_rows.size()); ++k) out.d_free[k] = src.d_free[keep_rows[k]];
  if (const auto* dense = std::get_if<Eigen::MatrixXd>(&src.W)) {
    const int n = static_cast<int>(keep_rows.size());
    Eigen::MatrixXd W(n, n);
    for (int b = 0; b < n; ++b)
      for (int a = 0; a < n; ++a) W(a, b) = (*dense)(keep_rows[a], keep_rows[b]);
    out.W = std::move(W);
  } else {
    const lcs::core::BlockSparseMatrix& S = std::get<lcs::core::BlockSparseMatrix>(src.W);
    lcs::core::BlockSparseMatrix T = lcs::core::BlockSparseMatrix::withBlockSizes(sizes);
    for (int i = 0; i < nc; ++i) {
      T.beginRow();
      const int ri = src.contacts[i].rows;
      for (int k = S.row_start[i]; k < S.row_start[i + 1]; ++k) {
        const int j = S.block_col[k];
        const int rj = src.contacts[j].rows;
        Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> block(
            S.values.data() + S.value_start[k], ri, rj);
        T.addBlock(j, block.topLeftCorner(sizes[i], sizes[j]));
      }
    }
    out.W = std::move(T);
  }
  return out;
}

// Every contact the same model.
inline lcs::core::Problem deriveUniform(const lcs::core::Problem& src, const ContactModel& m) {
  return deriveProblem(src, std::vector<ContactModel>(src.contacts.size(), m));
}

// CPU time of the calling thread (user + system), s. The benchmarks time with it because
// the machine they run on is shared (load ~4 on 2 cores): a solve is descheduled for a random
// part of its wall time, which CPU time does not count.
inline double threadCpuSeconds() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// Time per Gauss-Seidel sweep (pgs/nlgs, or what auto resolves to at a fixed sweep count),
// SOFA's stopping rule at an unreachable tolerance so that no residual is evaluated per sweep
// and every run does exactly its sweeps, cold start:
//   per_sweep = t(warm + sweeps) / (warm + sweeps), the whole solve divided (setup included);
//   marginal  = (t(warm + sweeps) - t(warm)) / sweeps, the sweep alone (noisier: a difference);
//   setup     = t(warm) - warm * marginal.
// Measured in rounds (sweepRound), which the benchmarks interleave across the variants they
// compare, so that a slow spell of the shared machine does not fall on one variant only;
// each time is the fastest over all rounds.
struct SweepAcc {
  double best_short = std::numeric_limits<double>::infinity();
  double best_long = std::numeric_limits<double>::infinity();
  int it_short = 0, it_long = 0;
  lcs::core::SolveResult result;  // of the fastest long run
};

inline void sweepRound(const lcs::core::Problem& problem, lcs::core::SolverParams params, int sweeps,
                       SweepAcc* acc, double min_total = 0.02, int min_pairs = 2, int warm = 5) {
  params.stopping_rule = lcs::core::StoppingRule::kSofa;
  params.tolerance = 1e-300;
  params.time_budget = 0.0;
  params.initial_guess = false;
  lcs::core::SolverParams short_params = params, long_params = params;
  short_params.maxIt = warm;
  long_params.maxIt = warm + sweeps;
  double total = 0.0;
  for (int k = 0; k < min_pairs || (total < min_total && k < 2000); ++k) {
    double c0 = threadCpuSeconds();
    lcs::core::SolveResult a = lcs::core::solveProblem(problem, short_params);
    const double ts = threadCpuSeconds() - c0;
    c0 = threadCpuSeconds();
    lcs::core::SolveResult b = lcs::core::solveProblem(problem, long_params);
    const double tl = threadCpuSeconds() - c0;
    total += ts + tl;
    acc->best_short = std::min(acc->best_short, ts);
    acc->it_short = a.iterations;
    if (tl < acc->best_long) {
      acc->best_long = tl;
      acc->it_long = b.iterations;
      acc->result = std::move(b);
    }
  }
}

struct SweepTiming {
  double per_sweep = std::numeric_limits<double>::quiet_NaN();  // s, whole solve / sweeps
  double marginal = std::numeric_limits<double>::quiet_NaN();   // s
  double setup = std::numeric_limits<double>::quiet_NaN();      // s
  int sweeps = 0;                                               // of the long run
  std::string solver;                                           // what ran
  lcs::core::SolveResult result;
};

inline SweepTiming sweepTiming(const SweepAcc& acc) {
  SweepTiming out;
  out.solver = acc.result.solver;
  out.sweeps = acc.it_long;
  out.result = acc.result;
  if (acc.it_long > 0) out.per_sweep = acc.best_long / acc.it_long;
  const int d = acc.it_long - acc.it_short;
  if (d > 0) {
    out.marginal = std::max(0.0, (acc.best_long - acc.best_short) / d);
    out.setup = std::max(0.0, acc.best_short - acc.it_short * out.marginal);
  }
  return out;
}

// Calls measure(i) for every variant i, `rounds` times over, the variants interleaved within
// a round: a slow spell of the shared machine then falls on every variant instead of one.
// The accumulators measure(i) feeds (SweepAcc, SolveAcc) keep the fastest run.
template <class Measure>
void interleavedRounds(int rounds, std::size_t variants, Measure&& measure) {
  for (int round = 0; round < rounds; ++round)
    for (std::size_t i = 0; i < variants; ++i) measure(i);
}

// Parameters of a cold solve to `tolerance` (no warm start), capped by `time_budget` s and
// `max_iterations`, for solveRound.
inline lcs::core::SolverParams toleranceParams(lcs::core::SolverKind solver, double tolerance,
                                               double time_budget, int max_iterations) {
  lcs::core::SolverParams params;
  params.solver = solver;
  params.tolerance = tolerance;
  params.maxIt = max_iterations;
  params.time_budget = time_budget;
  params.initial_guess = false;
  return params;
}

// A solve to a tolerance, in rounds like sweepRound: one run per round (none once a run took
// longer than `single_run` s); the fastest counts.
struct SolveAcc {
  double best = std::numeric_limits<double>::infinity();  // s CPU
  double wall = std::numeric_limits<double>::infinity();  // s wall of that run
  int runs = 0;
  lcs::core::SolveResult result;
};

inline void solveRound(const lcs::core::Problem& problem, const lcs::core::SolverParams& params,
                       SolveAcc* acc, double min_total = 0.01, double single_run = 0.3) {
  if (acc->runs > 0 && acc->best > single_run) return;
  double total = 0.0;
  do {
    const double c0 = threadCpuSeconds();
    const auto t0 = Clock::now();
    lcs::core::SolveResult r = lcs::core::solveProblem(problem, params);
    const double w = secondsSince(t0);
    const double s = threadCpuSeconds() - c0;
    total += s;
    ++acc->runs;
    if (s < acc->best) {
      acc->best = s;
      acc->wall = w;
      acc->result = std::move(r);
    }
  } while (total < min_total && acc->best <= single_run);
}

}  // namespace lcs_bench
