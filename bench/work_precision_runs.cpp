// The runs of the work-precision study: our solvers over the tolerance sweep, each peer over
// its own sweep, adaptively repeated; one CSV row per setting, the residual of every answer
// recomputed here the same way for all.
#include "work_precision.h"

#include "lcp_contact_solver/core/residual.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <limits>
#include <ostream>
#include <string>
#include <vector>

namespace lcs_bench::work_precision {

namespace {

// ---- the residual of every answer ---------------------------------------------------------

double discResidual(const lcs::core::Problem& problem, const Eigen::VectorXd& forces) {
  if (forces.size() != problem.rowCount() || !forces.allFinite())
    return std::numeric_limits<double>::infinity();
  Eigen::VectorXd d;
  lcs::core::multiply(problem.W, forces, d);
  d += problem.d_free;
  return lcs::core::naturalMapResidual(problem, lcs::core::effectiveMu(problem, 0.6), forces, d);
}

// Natural map of the box friction model that Bullet solves: normal row as a unilateral row,
// each tangent row boxed in [-mu max(λn, 0), mu max(λn, 0)] with the normal force fixed.
double boxResidual(const lcs::core::Problem& problem, const Eigen::VectorXd& forces) {
  if (forces.size() != problem.rowCount() || !forces.allFinite())
    return std::numeric_limits<double>::infinity();
  Eigen::VectorXd d;
  lcs::core::multiply(problem.W, forces, d);
  d += problem.d_free;
  const std::vector<double> mu = lcs::core::effectiveMu(problem, 0.6);
  const std::vector<int> off = problem.rowOffsets();
  double sum = 0.0;
  for (std::size_t c = 0; c < problem.contacts.size(); ++c) {
    const lcs::core::Contact& contact = problem.contacts[c];
    const int o = off[c];
    if (contact.type == lcs::core::ContactType::kBilateral) {
      for (int k = 0; k < contact.rows; ++k) sum += d[o + k] * d[o + k];
      continue;
    }
    const double en = forces[o] - std::max(0.0, forces[o] - d[o]);
    sum += en * en;
    if (contact.type == lcs::core::ContactType::kFrictional) {
      const double limit = mu[c] * std::max(0.0, forces[o]);
      for (int k = 1; k < 3; ++k) {
        const double et = forces[o + k] - std::clamp(forces[o + k] - d[o + k], -limit, limit);
        sum += et * et;
      }
    }
  }
  const double nq = problem.d_free.norm();
  return std::sqrt(sum) / (nq > 0.0 ? nq : 1.0);
}

// ---- one measured setting -------------------------------------------------------------------

std::vector<Row> g_rows;  // every row written, for the regret table

void writeRow(std::ostream& os, const Row& r) {
  g_rows.push_back(r);
  os << r.family << ',' << r.problem << ',' << r.contacts << ',' << r.rows << ',' << r.solver << ','
     << r.setting << ',' << fmt(r.tolerance) << ',' << r.status << ',' << (r.converged ? 1 : 0) << ','
     << r.iterations << ',' << fmt(r.time_median) << ',' << fmt(r.time_min) << ',' << r.repeats << ','
     << fmt(r.residual) << ',' << fmt(r.model_residual) << ',' << fmt(r.peer_error) << ',' << r.path << '\n';
  os.flush();
}

// Runs `once` (which returns its own wall time) adaptively: at least min_repeats runs and
// min_time in total, a single run when the first is slow; median and minimum.
// A fast first run is a warm-up and is not counted: it pays for the cold caches and page
// faults of whichever solver happens to be timed first on a freshly built problem (auto, in
// the study's order): humanoid100 elliptic step 300 at 1e-2 read auto 1.72x nlgs, 1.30x after.
template <class F>
void timeRepeated(const Options& opt, F once, Row* row) {
  std::vector<double> times;
  double total = 0.0;
  const double first = once();
  if (first >= opt.single_above) {
    times.push_back(first);
  } else {
    for (;;) {
      const double t = once();
      times.push_back(t);
      total += t;
      if (static_cast<int>(times.size()) >= opt.max_repeats) break;
      if (static_cast<int>(times.size()) >= opt.min_repeats && total >= opt.min_time) break;
    }
  }
  std::sort(times.begin(), times.end());
  const std::size_t n = times.size();
  row->time_median = n % 2 ? times[n / 2] : 0.5 * (times[n / 2 - 1] + times[n / 2]);
  row->time_min = times.front();
  row->repeats = static_cast<int>(n);
}

// A setting that ran out of time or iterations: tighter tolerances cannot do better with the
// same caps, so they are recorded as "skipped" instead of being run. (A method that stops
// early with a failure, e.g. PROX when r = 0 already meets a loose tolerance, is not a reason
// to skip the tighter settings.)
bool failedSetting(const Row& r) { return r.status == "time_budget" || r.status == "max_iterations"; }

Row skippedRow(const Row& base, const std::string& why) {
  Row r = base;
  r.status = why;
  r.converged = false;
  r.iterations = -1;
  r.time_median = r.time_min = r.residual = r.model_residual = r.peer_error = kNaN;
  r.repeats = 0;
  return r;
}

std::string tolLabel(double t) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "tol=%.0e", t);
  return buf;
}

}  // namespace

// ---- our solvers ----------------------------------------------------------------------------

std::vector<OurSolver> ourSolvers() {
  using K = lcs::core::SolverKind;
  using F = lcs::core::FrictionModel;
  return {
      {"auto", K::kAuto},
      {"nlgs", K::kNlgs, F::kCoulombDisc, 1.0, false, true, false},
      {"nlgs-sor1.3", K::kNlgs, F::kCoulombDisc, 1.3, false, true, false},
      {"apgd", K::kApgd},
      {"newton", K::kNewton},
      {"prox", K::kProx},
      {"pgs", K::kPgs, F::kCoulombDisc, 1.0, false, false, true},
      {"lemke", K::kLemke, F::kCoulombDisc, 1.0, true, false, true},
      {"pgs-pyramid4", K::kPgs, F::kPyramid4, 1.0, false, true, false},
      // a dense tableau of (m + 2) columns per contact: 1000 rows are already ~200 MB
      {"lemke-pyramid4", K::kLemke, F::kPyramid4, 1.0, true, true, false, 1000},
  };
}

std::string fmt(double v) {
  if (std::isnan(v)) return "";
  if (std::isinf(v)) return "inf";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

void writeHeader(std::ostream& os) {
  os << "family,problem,contacts,rows,solver,setting,tolerance,status,converged,iterations,"
        "time_s,time_min_s,repeats,residual,model_residual,peer_error,path\n";
}

const std::vector<Row>& writtenRows() { return g_rows; }

void runOurs(const Options& opt, const BenchProblem& bp, const OurSolver& s, std::ostream& csv) {
  Row base;
  base.family = bp.family;
  base.problem = bp.name;
  base.contacts = static_cast<int>(bp.problem.contacts.size());
  base.rows = bp.problem.rowCount();
  base.solver = s.name;
  std::vector<double> tols = s.direct ? std::vector<double>{kNaN} : opt.tolerances;
  bool skip = false;
  for (double tol : tols) {
    Row row = base;
    row.setting = s.direct ? "direct" : tolLabel(tol);
    row.tolerance = tol;
    if (skip) {
      writeRow(csv, skippedRow(row, "skipped"));
      continue;
    }
    lcs::core::SolverParams params;
    params.solver = s.kind;
    params.friction_model = s.model;
    params.sor = s.sor;
    params.tolerance = s.direct ? 1e-12 : tol;
    params.maxIt = s.direct ? 1000000 : 10000000;
    params.time_budget = opt.budget;
    params.initial_guess = false;
    lcs::core::SolveResult result;
    timeRepeated(
        opt,
        [&] {
          const auto t0 = Clock::now();
          result = lcs::core::solveProblem(bp.problem, params);
          return std::chrono::duration<double>(Clock::now() - t0).count();
        },
        &row);
    row.status = lcs::core::statusName(result.status);
    row.converged = result.converged;
    row.iterations = result.iterations;
    row.residual = result.residual;
    row.path = result.solver;
    // The independent recomputation must agree with the core's own report.
    const double check = discResidual(bp.problem, result.forces);
    if (std::abs(check - result.residual) > 1e-9 * std::max(1.0, check))
      std::cerr << "warning: " << bp.name << " " << s.name << ": core residual " << result.residual
                << " vs recomputed " << check << "\n";
    row.model_residual = result.friction_model == lcs::core::FrictionModel::kCoulombDisc
                             ? result.residual
                             : result.solver_error;
    writeRow(csv, row);
    // auto changes its kernel with the tolerance, so a failure at one setting says nothing
    // about the next.
    if (failedSetting(row) && s.kind != lcs::core::SolverKind::kAuto) skip = true;
  }
}

void runPeer(const Options& opt, const BenchProblem& bp, Peer& peer, std::ostream& csv) {
  Row base;
  base.family = bp.family;
  base.problem = bp.name;
  base.contacts = static_cast<int>(bp.problem.contacts.size());
  base.rows = bp.problem.rowCount();
  base.solver = peer.name();
  peer.prepare(bp.problem);
  const bool box = peer.name().rfind("bullet", 0) == 0;

  // Seconds per iteration, from a short untimed probe: caps the iterations of each setting so
  // a setting cannot run much past the budget (the peers have no wall-clock budget).
  double per_iteration = 0.0;
  if (peer.sweep() != SweepKind::kDirect) {
    Setting probe{"probe", 1e-14, 5};
    peer.beforeSolve();
    const auto t0 = Clock::now();
    const PeerOutcome o = peer.solve(probe);
    const double t = std::chrono::duration<double>(Clock::now() - t0).count();
    per_iteration = t / std::max(1, o.iterations > 0 ? o.iterations : 5);
  }
  auto capFor = [&](double per_it) {
    return per_it > 0.0 ? static_cast<int>(std::clamp(1.5 * opt.budget / per_it, 10.0, 1e6)) : 1000000;
  };
  int cap = capFor(per_iteration);

  std::vector<Setting> settings;
  switch (peer.sweep()) {
    case SweepKind::kDirect: settings.push_back({"direct", kNaN, 0}); break;
    case SweepKind::kTolerance:
      for (double tol : opt.tolerances) settings.push_back({tolLabel(tol), tol, 0});
      break;
    case SweepKind::kIterations:
      for (int it : {3, 10, 30, 100, 300, 1000, 3000, 10000, 30000, 100000})
        settings.push_back({"it=" + std::to_string(it), kNaN, it});
      break;
  }
  bool skip = false;
  for (const Setting& setting : settings) {
    Row row = base;
    row.setting = setting.label;
    row.tolerance = setting.tolerance;
    if (skip || (peer.sweep() == SweepKind::kIterations && setting.max_iterations > cap)) {
      writeRow(csv, skippedRow(row, skip ? "skipped" : "skipped_budget"));
      continue;
    }
    Setting run = setting;
    if (peer.sweep() == SweepKind::kTolerance) run.max_iterations = cap;
    PeerOutcome outcome;
    timeRepeated(
        opt,
        [&] {
          peer.beforeSolve();
          const auto t0 = Clock::now();
          outcome = peer.solve(run);
          return std::chrono::duration<double>(Clock::now() - t0).count();
        },
        &row);
    row.status = outcome.status;
    // The peers have no wall-clock budget: a run longer than ours may take is a time-out,
    // whatever the method says (our kernels stop at the budget with status time_budget).
    if (row.time_median > opt.budget) row.status = "time_budget";
    // Refine the iteration cap from what this run cost.
    if (outcome.iterations > 0) {
      per_iteration = std::max(per_iteration, row.time_median / outcome.iterations);
      cap = capFor(per_iteration);
    }
    row.converged = outcome.claims_success && row.status == "converged";
    row.iterations = outcome.iterations;
    row.residual = discResidual(bp.problem, outcome.forces);
    row.model_residual = box ? boxResidual(bp.problem, outcome.forces) : row.residual;
    row.peer_error = outcome.self_error;
    writeRow(csv, row);
    if (failedSetting(row) && peer.sweep() == SweepKind::kTolerance) skip = true;
    if (peer.sweep() == SweepKind::kIterations && row.time_median > opt.budget) skip = true;
  }
  peer.release();
}

}  // namespace lcs_bench::work_precision
