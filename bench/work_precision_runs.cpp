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
     << fmt(r.residual) << ',' << fmt(r.model_residual) << ',' << fmt(r.peer_error) << ',' << r.path << ','
     << (r.total_iterations >= 0 ? r.total_iterations : r.iterations) << '\n';
  os.flush();
}

// Median, minimum and count of a setting's timed runs.
void setTimes(std::vector<double> times, Row* row) {
  std::sort(times.begin(), times.end());
  const std::size_t n = times.size();
  row->time_median = n % 2 ? times[n / 2] : 0.5 * (times[n / 2 - 1] + times[n / 2]);
  row->time_min = times.front();
  row->repeats = static_cast<int>(n);
}

// The peers' timing: runs `once` (which returns its own wall time) adaptively: at least
// min_repeats runs and min_time in total, a single run when the first is slow.
// A fast first run is a warm-up and is not counted: it pays for the cold caches and page
// faults of whichever solver happens to be timed first on a freshly built problem.
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
  setTimes(std::move(times), row);
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

// ---- our solvers' settings, timed in rounds ---------------------------------------------------
//
// This machine (a VM) runs a microsecond solve at one of two speeds about 1.6x apart, switching
// every few seconds. Timed one setting after another, a cell of the regret table compared two
// settings timed seconds apart and read up to 2.4x for the same work (lcp_CPS_5). So every
// setting of our solvers on one problem is timed in rounds: each round runs a chunk of each
// (a tenth of the time and repeats the setting needs, after an untimed warm-up solve when the
// solve is short), so all of them see the same mixture of speeds and keep warm caches.

struct OwnSetting {
  Row row;
  lcs::core::SolverParams params;
  double first = 0.0;  // the first pass's run
  bool timing = false;  // still being repeated
  std::vector<double> times;
  double total = 0.0;
};

constexpr int kRounds = 10;

double solveOnce(const BenchProblem& bp, const lcs::core::SolverParams& params, lcs::core::SolveResult* result) {
  const auto t0 = Clock::now();
  *result = lcs::core::solveProblem(bp.problem, params);
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// Status, iterations, residual and path of an answer; the residual recomputed independently.
void recordAnswer(const BenchProblem& bp, const lcs::core::SolveResult& result, Row* row) {
  row->status = lcs::core::statusName(result.status);
  row->converged = result.converged;
  row->iterations = result.iterations;
  row->total_iterations = result.total_iterations;
  row->residual = result.residual;
  row->path = result.solver;
  // The independent recomputation must agree with the core's own report.
  const double check = discResidual(bp.problem, result.forces);
  if (std::abs(check - result.residual) > 1e-9 * std::max(1.0, check))
    std::cerr << "warning: " << bp.name << " " << row->solver << ": core residual " << result.residual
              << " vs recomputed " << check << "\n";
  row->model_residual = result.friction_model == lcs::core::FrictionModel::kCoulombDisc ? result.residual
                                                                                          : result.solver_error;
}

bool enoughRepeats(const Options& opt, const OwnSetting& st) {
  const int n = static_cast<int>(st.times.size());
  return n >= opt.max_repeats || (n >= opt.min_repeats && st.total >= opt.min_time);
}

void timeInRounds(const Options& opt, const BenchProblem& bp, std::vector<OwnSetting>* settings) {
  const double chunk_time = opt.min_time / kRounds;
  const int chunk_repeats = std::max(1, opt.max_repeats / kRounds);
  lcs::core::SolveResult scratch;
  for (bool any = true; any;) {
    any = false;
    for (OwnSetting& st : *settings) {
      if (!st.timing) continue;
      if (st.first < chunk_time / 4) solveOnce(bp, st.params, &scratch);  // warm caches again
      double spent = 0.0;
      // At least one solve per chunk: --quick asks for no minimum time at all.
      for (int k = 0; k < chunk_repeats && (k == 0 || spent < chunk_time) && !enoughRepeats(opt, st); ++k) {
        const double t = solveOnce(bp, st.params, &scratch);
        st.times.push_back(t);
        st.total += t;
        spent += t;
      }
      st.timing = !enoughRepeats(opt, st);
      any = any || st.timing;
    }
  }
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
        "time_s,time_min_s,repeats,residual,model_residual,peer_error,path,total_iterations\n";
}

const std::vector<Row>& writtenRows() { return g_rows; }

void runOurs(const Options& opt, const BenchProblem& bp, const std::vector<const OurSolver*>& solvers,
             std::ostream& csv) {
  Row base;
  base.family = bp.family;
  base.problem = bp.name;
  base.contacts = static_cast<int>(bp.problem.contacts.size());
  base.rows = bp.problem.rowCount();
  // First pass, solver by solver: the answer of every setting (and which to skip).
  std::vector<OwnSetting> settings;
  for (const OurSolver* s : solvers) {
    base.solver = s->name;
    const std::vector<double> tols = s->direct ? std::vector<double>{kNaN} : opt.tolerances;
    bool skip = false;
    for (double tol : tols) {
      OwnSetting st;
      st.row = base;
      st.row.setting = s->direct ? "direct" : tolLabel(tol);
      st.row.tolerance = tol;
      if (skip) {
        st.row = skippedRow(st.row, "skipped");
        settings.push_back(std::move(st));
        continue;
      }
      st.params.solver = s->kind;
      st.params.friction_model = s->model;
      st.params.sor = s->sor;
      st.params.tolerance = s->direct ? 1e-12 : tol;
      st.params.maxIt = s->direct ? 1000000 : 10000000;
      st.params.time_budget = opt.budget;
      st.params.initial_guess = false;
      lcs::core::SolveResult result;
      st.first = solveOnce(bp, st.params, &result);
      recordAnswer(bp, result, &st.row);
      if (st.first >= opt.single_above)
        st.times.push_back(st.first);  // slow: this one run is the measurement
      else
        st.timing = true;  // fast: the first run was a warm-up (cold caches, page faults)
      // auto changes its kernel with the tolerance, so a failure at one setting says nothing
      // about the next.
      if (failedSetting(st.row) && s->kind != lcs::core::SolverKind::kAuto) skip = true;
      settings.push_back(std::move(st));
    }
  }
  timeInRounds(opt, bp, &settings);
  for (OwnSetting& st : settings) {
    if (!st.times.empty()) setTimes(st.times, &st.row);
    writeRow(csv, st.row);
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
