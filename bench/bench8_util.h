// Helpers shared by the issue #8 benchmarks (bench/effects_cost.cpp, bench/scaling.cpp,
// bench/latency.cpp): timing, the machine's load, the bytes of a compliance, and taking a
// sub-problem on the same geometry (fewer rows per contact, other types and μ). Header-only,
// benchmarks only (never a test).
#pragma once

#include "lcp_contact_solver/core/body_compliance.h"
#include "lcp_contact_solver/core/contact_solver.h"
#include "lcp_contact_solver/core/problem.h"

#include <Eigen/Core>

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

inline std::vector<int> parseIntList(const std::string& s) {
  std::vector<int> out;
  std::stringstream in(s);
  std::string item;
  while (std::getline(in, item, ','))
    if (!item.empty()) out.push_back(std::stoi(item));
  return out;
}

inline std::vector<double> parseDoubleList(const std::string& s) {
  std::vector<double> out;
  std::stringstream in(s);
  std::string item;
  while (std::getline(in, item, ','))
    if (!item.empty()) out.push_back(std::stod(item));
  return out;
}

// Bytes of the stored compliance (values + index arrays; not the vectors' spare capacity).
inline std::size_t bytesOf(const lcs::BlockSparseMatrix& W) {
  return W.values.size() * sizeof(double) +
         (W.block_col.size() + W.value_start.size() + W.row_start.size() + W.block_offset.size()) * sizeof(int);
}
inline std::size_t bytesOf(const lcs::BodyCompliance& B) {
  return B.body_compliance.size() * sizeof(lcs::BodyMatrix) + B.contacts.size() * sizeof(lcs::ContactJacobian) +
         static_cast<std::size_t>(B.diagonal.size()) * sizeof(double);
}
inline std::size_t bytesOfCompliance(const lcs::Problem& p) {
  if (p.bodies) return bytesOf(*p.bodies);
  if (const auto* d = std::get_if<Eigen::MatrixXd>(&p.W)) return static_cast<std::size_t>(d->size()) * sizeof(double);
  return bytesOf(std::get<lcs::BlockSparseMatrix>(p.W));
}

// What one contact becomes in a derived problem: its first `rows` rows of the source (the
// normal first, then t1, t2, spin, rolling t1, rolling t2), a type and friction.
struct ContactModel {
  lcs::ContactType type = lcs::ContactType::kFrictional;
  int rows = 3;
  double mu = 0.5, mu_torsional = 0.0, mu_rolling = 0.0;
};

// The same geometry with fewer rows per contact: W's block (i, j) becomes its leading
// rows_i × rows_j corner and d_free keeps the leading rows of each contact. For rigid
// contacts W = J M⁻¹ Jᵀ row by row, so this is exactly the problem the scene would build if
// it asked each contact for those rows only. The body form, if any, is dropped.
inline lcs::Problem deriveProblem(const lcs::Problem& src, const std::vector<ContactModel>& models) {
  const int nc = static_cast<int>(src.contacts.size());
  if (static_cast<int>(models.size()) != nc) throw std::invalid_argument("deriveProblem: one model per contact");
  const std::vector<int> off = src.rowOffsets();
  lcs::Problem out;
  out.name = src.name;
  out.contacts = src.contacts;
  std::vector<int> sizes(nc), keep_rows;
  for (int i = 0; i < nc; ++i) {
    const ContactModel& m = models[i];
    if (m.rows > src.contacts[i].rows) throw std::invalid_argument("deriveProblem: more rows than the source has");
    lcs::Contact& c = out.contacts[i];
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
    const lcs::BlockSparseMatrix& S = std::get<lcs::BlockSparseMatrix>(src.W);
    lcs::BlockSparseMatrix T = lcs::BlockSparseMatrix::withBlockSizes(sizes);
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
inline lcs::Problem deriveUniform(const lcs::Problem& src, const ContactModel& m) {
  return deriveProblem(src, std::vector<ContactModel>(src.contacts.size(), m));
}

struct Timed {
  double best = 0.0;    // s, fastest run
  double median = 0.0;  // s
  int runs = 0;
  lcs::SolveResult result;  // of the fastest run
};

// Solves `problem` cold (no warm start memory) until at least `min_total` seconds and
// `min_runs` runs have passed; a single run longer than `single_run` seconds is not repeated.
inline Timed timeSolve(const lcs::Problem& problem, const lcs::SolverParams& params, double min_total = 0.05,
                       int min_runs = 3, double single_run = 0.5) {
  Timed t;
  t.best = std::numeric_limits<double>::infinity();
  std::vector<double> times;
  double total = 0.0;
  while (static_cast<int>(times.size()) < min_runs || total < min_total) {
    const auto t0 = Clock::now();
    lcs::SolveResult r = lcs::solveProblem(problem, params);
    const double s = secondsSince(t0);
    times.push_back(s);
    total += s;
    if (s < t.best) {
      t.best = s;
      t.result = std::move(r);
    }
    if (times.size() == 1 && s > single_run) break;
    if (times.size() >= 1000) break;
  }
  std::sort(times.begin(), times.end());
  t.median = times[times.size() / 2];
  t.runs = static_cast<int>(times.size());
  return t;
}

// Time per Gauss-Seidel sweep (pgs/nlgs, or what auto resolves to at a fixed sweep count):
// (t(warm + sweeps) - t(warm)) / (their sweep difference), each the fastest of several runs,
// SOFA's stopping rule at an unreachable tolerance so no residual is evaluated per sweep and
// every run does exactly its sweeps. setup = t(warm) - warm sweeps.
struct SweepTiming {
  double per_sweep = std::numeric_limits<double>::quiet_NaN();  // s
  double setup = std::numeric_limits<double>::quiet_NaN();      // s
  int sweeps = 0;
  std::string solver;  // what ran
  lcs::SolveResult result;  // of the long run
};

inline SweepTiming timePerSweep(const lcs::Problem& problem, lcs::SolverParams params, int sweeps, int warm = 5,
                                double min_total = 0.03) {
  params.stopping_rule = lcs::StoppingRule::kSofa;
  params.tolerance = 1e-300;
  params.time_budget = 0.0;
  params.initial_guess = false;
  SweepTiming out;
  params.maxIt = warm;
  const Timed a = timeSolve(problem, params, min_total, 3, 1e9);
  params.maxIt = warm + sweeps;
  const Timed b = timeSolve(problem, params, min_total, 3, 1e9);
  out.solver = b.result.solver;
  out.sweeps = b.result.iterations - a.result.iterations;
  if (out.sweeps > 0) {
    out.per_sweep = std::max(0.0, (b.best - a.best) / out.sweeps);
    out.setup = std::max(0.0, a.best - a.result.iterations * out.per_sweep);
  }
  out.result = b.result;
  return out;
}

// Sweeps so that they take a few milliseconds: ~`row_sweeps` row updates in total.
inline int sweepsFor(int rows, double row_sweeps = 4e5, int lo = 20, int hi = 4000) {
  return std::clamp(static_cast<int>(row_sweeps / std::max(rows, 1)), lo, hi);
}

}  // namespace lcs_bench
