// Work-precision study: every solver of ours and every available peer on every problem, over
// a tolerance sweep; one CSV row per (problem, solver, setting) with the median wall time and
// the residual measured by the core's solver-independent natural map (residual.h), recomputed
// from the returned forces for every solver alike. See docs/BENCHMARKS.md.
//
//   work_precision [--problems DIR] [--scenes DIR] [--out FILE] [--budget S]
//                  [--families fc3d,lcp,scenes] [--filter SUBSTRING] [--solvers a,b,...]
//                  [--quick] [--regret FILE]
//
// At the end it writes the "auto regret" table (markdown, --regret, default
// bench/results/auto_regret.md): per problem and tolerance, auto's time over the fastest of
// our other solvers and over the fastest peer that reached the same residual.
#include "peers.h"
#include "scene_problems.h"

#include "lcp_contact_solver/core/contact_solver.h"
#include "lcp_contact_solver/core/problem_io.h"
#include "lcp_contact_solver/core/residual.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <dirent.h>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#ifndef LCS_PROBLEMS_DIR
#define LCS_PROBLEMS_DIR "../shared/problems"
#endif
#ifndef LCS_SCENES_DIR
#define LCS_SCENES_DIR "config/scenes"
#endif

namespace lcs = lcp_contact_solver;
using lcs_bench::Peer;
using lcs_bench::PeerOutcome;
using lcs_bench::Setting;
using lcs_bench::SweepKind;

namespace lcs_bench {

bool isFc3d(const lcs::core::Problem& problem) {
  if (problem.contacts.empty()) return false;
  for (const lcs::core::Contact& c : problem.contacts)
    if (c.type != lcs::core::ContactType::kFrictional || c.rows != 3) return false;
  return true;
}

bool isLcp(const lcs::core::Problem& problem) {
  if (problem.contacts.empty()) return false;
  for (const lcs::core::Contact& c : problem.contacts)
    if (c.type != lcs::core::ContactType::kFrictionless) return false;
  return true;
}

}  // namespace lcs_bench

namespace {

using Clock = std::chrono::steady_clock;
const double kNaN = std::numeric_limits<double>::quiet_NaN();

struct Options {
  std::string problems_dir = LCS_PROBLEMS_DIR;
  std::string scenes_dir = LCS_SCENES_DIR;
  std::string out = "bench/results/work_precision.csv";
  std::string regret = "bench/results/auto_regret.md";
  double budget = 2.0;          // s, per solve
  double min_time = 0.05;       // s, repeat until the repeats add up to this...
  int min_repeats = 3;          // ...and at least this many
  int max_repeats = 25;
  double single_above = 0.5;    // s, a first run longer than this is not repeated
  std::set<std::string> families = {"fc3d", "lcp", "scenes"};
  std::string filter;
  std::set<std::string> solvers;  // empty = all
  std::vector<double> tolerances = {1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10};
  std::vector<int> pyramid_bases = {2, 3, 5, 9, 16};
  std::vector<int> pile_balls = {4, 12, 40, 120, 350};
  int scene_steps = 30;
};

struct BenchProblem {
  std::string family;
  std::string name;
  lcs::core::Problem problem;
  std::string note;
};

// ---- the residual of every answer ---------------------------------------------------------

double discResidual(const lcs::core::Problem& problem, const Eigen::VectorXd& forces) {
  if (forces.size() != problem.rowCount() || !forces.allFinite()) return std::numeric_limits<double>::infinity();
  Eigen::VectorXd d;
  lcs::core::multiply(problem.W, forces, d);
  d += problem.d_free;
  return lcs::core::naturalMapResidual(problem, lcs::core::effectiveMu(problem, 0.6), forces, d);
}

// Natural map of the box friction model that Bullet solves: normal row as a unilateral row,
// each tangent row boxed in [-mu max(λn, 0), mu max(λn, 0)] with the normal force fixed.
double boxResidual(const lcs::core::Problem& problem, const Eigen::VectorXd& forces) {
  if (forces.size() != problem.rowCount() || !forces.allFinite()) return std::numeric_limits<double>::infinity();
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

// ---- our solvers ----------------------------------------------------------------------------

struct OurSolver {
  std::string name;
  lcs::core::SolverKind kind;
  lcs::core::FrictionModel model = lcs::core::FrictionModel::kCoulombDisc;
  double sor = 1.0;
  bool direct = false;       // one setting, no tolerance (Lemke)
  bool friction = true;      // runs on fc3d / scenes
  bool lcp = true;           // runs on LCPs
  int max_rows = 0;          // larger problems are not run (0 = no limit)
};

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

// ---- one measured setting -------------------------------------------------------------------

struct Row {
  std::string family, problem, solver, setting;
  int contacts = 0, rows = 0;
  double tolerance = kNaN;
  std::string status;
  bool converged = false;
  int iterations = -1;
  double time_median = kNaN, time_min = kNaN;
  int repeats = 0;
  double residual = kNaN, model_residual = kNaN, peer_error = kNaN;
};

std::string fmt(double v) {
  if (std::isnan(v)) return "";
  if (std::isinf(v)) return "inf";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

void writeHeader(std::ostream& os) {
  os << "family,problem,contacts,rows,solver,setting,tolerance,status,converged,iterations,"
        "time_s,time_min_s,repeats,residual,model_residual,peer_error\n";
}

std::vector<Row> g_rows;  // every row written, for the regret table

void writeRow(std::ostream& os, const Row& r) {
  g_rows.push_back(r);
  os << r.family << ',' << r.problem << ',' << r.contacts << ',' << r.rows << ',' << r.solver << ','
     << r.setting << ',' << fmt(r.tolerance) << ',' << r.status << ',' << (r.converged ? 1 : 0) << ','
     << r.iterations << ',' << fmt(r.time_median) << ',' << fmt(r.time_min) << ',' << r.repeats << ','
     << fmt(r.residual) << ',' << fmt(r.model_residual) << ',' << fmt(r.peer_error) << '\n';
  os.flush();
}

// Runs `once` (which returns its own wall time) adaptively: at least min_repeats runs and
// min_time in total, a single run when the first is slow; median and minimum.
template <class F>
void timeRepeated(const Options& opt, F once, Row* row) {
  std::vector<double> times;
  double total = 0.0;
  for (;;) {
    const double t = once();
    times.push_back(t);
    total += t;
    if (times.size() == 1 && t >= opt.single_above) break;
    if (static_cast<int>(times.size()) >= opt.max_repeats) break;
    if (static_cast<int>(times.size()) >= opt.min_repeats && total >= opt.min_time) break;
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
    timeRepeated(opt, [&] {
      const auto t0 = Clock::now();
      result = lcs::core::solveProblem(bp.problem, params);
      return std::chrono::duration<double>(Clock::now() - t0).count();
    }, &row);
    row.status = lcs::core::statusName(result.status);
    row.converged = result.converged;
    row.iterations = result.iterations;
    row.residual = result.residual;
    // The independent recomputation must agree with the core's own report.
    const double check = discResidual(bp.problem, result.forces);
    if (std::abs(check - result.residual) > 1e-9 * std::max(1.0, check))
      std::cerr << "warning: " << bp.name << " " << s.name << ": core residual " << result.residual
                << " vs recomputed " << check << "\n";
    row.model_residual = result.friction_model == lcs::core::FrictionModel::kCoulombDisc ? result.residual
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
    timeRepeated(opt, [&] {
      peer.beforeSolve();
      const auto t0 = Clock::now();
      outcome = peer.solve(run);
      return std::chrono::duration<double>(Clock::now() - t0).count();
    }, &row);
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

// ---- the auto regret table ------------------------------------------------------------------

// A row reached tolerance tol: its residual (disc, recomputed) is at most tol and it ended
// without a failure. Direct methods (Lemke) count at every tolerance their residual meets.
bool reached(const Row& r, double tol) {
  if (std::isnan(r.time_median) || !(r.residual <= tol)) return false;
  return r.status == "converged" || r.setting == "direct" || r.setting.rfind("it=", 0) == 0;
}

double geomean(const std::vector<double>& v) {
  if (v.empty()) return kNaN;
  double s = 0.0;
  for (double x : v) s += std::log(x);
  return std::exp(s / static_cast<double>(v.size()));
}

void writeRegret(const Options& opt, const std::vector<Row>& rows) {
  // (problem, tolerance) -> auto's time, fastest own, fastest peer, fastest Siconos
  struct Cell {
    double auto_time = kNaN;
    bool auto_ok = false, auto_ran = false;
    double own = kNaN, peer = kNaN, siconos = kNaN;
    std::string own_name, peer_name;
  };
  std::map<std::pair<std::string, double>, Cell> cells;
  std::set<std::string> own_names;
  for (const OurSolver& s : ourSolvers()) own_names.insert(s.name);
  std::vector<std::string> order;
  for (const Row& r : rows) {
    const std::string key = r.family + "/" + r.problem;
    if (std::find(order.begin(), order.end(), key) == order.end()) order.push_back(key);
    for (double tol : opt.tolerances) {
      // A tolerance-swept row speaks for its own tolerance; direct and iteration-capped rows
      // for every tolerance their residual meets.
      const bool swept = !std::isnan(r.tolerance);
      if (swept && std::abs(r.tolerance - tol) > 1e-3 * tol) continue;
      Cell& c = cells[{key, tol}];
      if (r.solver == "auto") {
        c.auto_ran = c.auto_ran || !std::isnan(r.time_median);
        if (reached(r, tol)) { c.auto_time = r.time_median; c.auto_ok = true; }
        continue;
      }
      if (!reached(r, tol)) continue;
      auto better = [&](double& slot, std::string* name) {
        if (std::isnan(slot) || r.time_median < slot) {
          slot = r.time_median;
          if (name) *name = r.solver;
        }
      };
      if (own_names.count(r.solver)) better(c.own, &c.own_name);
      else {
        better(c.peer, &c.peer_name);
        if (r.solver.rfind("siconos", 0) == 0) better(c.siconos, nullptr);
      }
    }
  }
  std::ofstream md(opt.regret);
  if (!md) {
    std::cerr << "work_precision: cannot write " << opt.regret << "\n";
    return;
  }
  md << "Summary per tolerance (geometric means over the problems where both sides reached it;\n"
        "\"auto missed\" counts problems some own solver solved and auto did not):\n\n"
        "| tolerance | problems | auto / fastest own: geo mean | max | > 1.5x | auto missed | auto / best Siconos: geo mean (n) | Siconos solved, auto not | auto / fastest peer: geo mean (n) |\n"
        "|---|---|---|---|---|---|---|---|---|\n";
  for (double tol : opt.tolerances) {
    std::vector<double> own, sic, peer;
    int problems = 0, missed = 0, over = 0, sic_missed = 0;
    double worst = kNaN;
    for (const std::string& key : order) {
      const auto it = cells.find({key, tol});
      if (it == cells.end() || !it->second.auto_ran) continue;
      const Cell& c = it->second;
      ++problems;
      if (!std::isnan(c.own)) {
        if (!c.auto_ok) ++missed;
        else {
          const double q = c.auto_time / c.own;
          own.push_back(q);
          if (q > 1.5) ++over;
          if (std::isnan(worst) || q > worst) worst = q;
        }
      }
      if (!std::isnan(c.siconos)) {
        if (c.auto_ok) sic.push_back(c.auto_time / c.siconos);
        else ++sic_missed;
      }
      if (!std::isnan(c.peer) && c.auto_ok) peer.push_back(c.auto_time / c.peer);
    }
    md << "| " << fmt(tol) << " | " << problems << " | " << fmt(geomean(own)) << " | " << fmt(worst) << " | " << over
       << " | " << missed << " | " << fmt(geomean(sic)) << " (" << sic.size() << ") | " << sic_missed << " | "
       << fmt(geomean(peer)) << " (" << peer.size() << ") |\n";
  }
  md << "\nPer problem: auto / fastest own solver (that solver), \"-\" where no own solver reached the\n"
        "tolerance, \"MISS\" where one did and auto did not.\n\n| problem |";
  for (double tol : opt.tolerances) md << ' ' << fmt(tol) << " |";
  md << "\n|---|";
  for (std::size_t i = 0; i < opt.tolerances.size(); ++i) md << "---|";
  md << '\n';
  for (const std::string& key : order) {
    bool any = false;
    for (double tol : opt.tolerances) {
      const auto it = cells.find({key, tol});
      any = any || (it != cells.end() && it->second.auto_ran);
    }
    if (!any) continue;
    md << "| " << key << " |";
    for (double tol : opt.tolerances) {
      const auto it = cells.find({key, tol});
      if (it == cells.end() || std::isnan(it->second.own)) { md << " - |"; continue; }
      const Cell& c = it->second;
      if (!c.auto_ok) { md << " MISS (" << c.own_name << ") |"; continue; }
      char buf[64];
      std::snprintf(buf, sizeof buf, " %.2f (%s) |", c.auto_time / c.own, c.own_name.c_str());
      md << buf;
    }
    md << '\n';
  }
  std::cerr << "work_precision: wrote the auto regret table to " << opt.regret << "\n";
}

// ---- problems -------------------------------------------------------------------------------

std::vector<std::string> listDir(const std::string& dir) {
  std::vector<std::string> files;
  if (DIR* d = opendir(dir.c_str())) {
    while (dirent* e = readdir(d)) {
      const std::string n = e->d_name;
      if (n == "." || n == ".." || n == "README.md") continue;
      files.push_back(dir + "/" + n);
    }
    closedir(d);
  }
  std::sort(files.begin(), files.end());
  return files;
}

std::string baseName(const std::string& path) {
  std::string n = path.substr(path.find_last_of('/') + 1);
  for (const char* ext : {".hdf5.dat", ".dat", ".hdf5"})
    if (n.size() > std::strlen(ext) && n.compare(n.size() - std::strlen(ext), std::string::npos, ext) == 0) {
      n.resize(n.size() - std::strlen(ext));
      break;
    }
  return n;
}

std::vector<BenchProblem> loadProblems(const Options& opt) {
  std::vector<BenchProblem> out;
  for (const std::string family : {"fc3d", "lcp"}) {
    if (!opt.families.count(family)) continue;
    for (const std::string& path : listDir(opt.problems_dir + "/" + family)) {
      if (!opt.filter.empty() && path.find(opt.filter) == std::string::npos) continue;
      BenchProblem bp;
      bp.family = family;
      bp.name = baseName(path);
      try {
        bp.problem = lcs::core::readProblemFile(path);
      } catch (const std::exception& e) {
        std::cerr << "skipping " << path << ": " << e.what() << "\n";
        continue;
      }
      out.push_back(std::move(bp));
    }
  }
  if (opt.families.count("scenes")) {
    const auto t0 = Clock::now();
    for (lcs_bench::SceneProblem& sp :
         lcs_bench::makeSceneProblems(opt.scenes_dir, opt.pyramid_bases, opt.pile_balls, opt.scene_steps)) {
      if (!opt.filter.empty() && sp.name.find(opt.filter) == std::string::npos) continue;
      BenchProblem bp;
      bp.family = "scenes";
      bp.name = sp.name;
      bp.problem = std::move(sp.problem);
      double min_dn = std::numeric_limits<double>::infinity();
      const std::vector<int> off = bp.problem.rowOffsets();
      for (std::size_t c = 0; c < bp.problem.contacts.size(); ++c) min_dn = std::min(min_dn, bp.problem.d_free[off[c]]);
      std::cerr << "scene problem " << bp.name << ": " << sp.bodies << " bodies, " << bp.problem.contacts.size()
                << " contacts, " << bp.problem.rowCount() << " rows after " << sp.steps
                << " steps, min normal d_free " << min_dn << " m\n";
      out.push_back(std::move(bp));
    }
    std::cerr << "scene problems generated in " << std::chrono::duration<double>(Clock::now() - t0).count()
              << " s\n";
  }
  return out;
}

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) if (!item.empty()) out.push_back(item);
  return out;
}

int usage(const char* msg) {
  std::cerr << "work_precision: " << msg << "\n"
            << "usage: work_precision [--problems DIR] [--scenes DIR] [--out FILE] [--budget S]\n"
               "       [--families fc3d,lcp,scenes] [--filter SUBSTRING] [--solvers a,b]\n"
               "       [--tolerances 1e-2,1e-4,...] [--quick] [--regret FILE]\n";
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw std::runtime_error("missing value after " + a);
      return argv[++i];
    };
    try {
      if (a == "--problems") opt.problems_dir = value();
      else if (a == "--scenes") opt.scenes_dir = value();
      else if (a == "--out") opt.out = value();
      else if (a == "--regret") opt.regret = value();
      else if (a == "--budget") opt.budget = std::stod(value());
      else if (a == "--filter") opt.filter = value();
      else if (a == "--tolerances") {
        opt.tolerances.clear();
        for (const std::string& t : split(value())) opt.tolerances.push_back(std::stod(t));
      }
      else if (a == "--families") { const auto v = split(value()); opt.families = {v.begin(), v.end()}; }
      else if (a == "--solvers") { const auto v = split(value()); opt.solvers = {v.begin(), v.end()}; }
      else if (a == "--quick") {
        opt.tolerances = {1e-2, 1e-4, 1e-6, 1e-8};
        opt.pyramid_bases = {2, 5};
        opt.pile_balls = {12};
        opt.budget = std::min(opt.budget, 1.0);
        opt.min_repeats = 1;
        opt.min_time = 0.0;
      } else if (a == "--help" || a == "-h") return usage("work-precision benchmark"), 0;
      else return usage(("unknown argument " + a).c_str());
    } catch (const std::exception& e) {
      return usage(e.what());
    }
  }

  std::ofstream csv(opt.out);
  if (!csv) {
    std::cerr << "work_precision: cannot write " << opt.out << "\n";
    return 1;
  }
  writeHeader(csv);

  std::vector<std::unique_ptr<Peer>> peers;
#ifdef LCS_BENCH_HAVE_SICONOS
  for (auto& p : lcs_bench::makeSiconosPeers()) peers.push_back(std::move(p));
#else
  std::cerr << "work_precision: built without Siconos numerics (scripts/install-deps bench)\n";
#endif
#ifdef LCS_BENCH_HAVE_BULLET
  for (auto& p : lcs_bench::makeBulletPeers()) peers.push_back(std::move(p));
#else
  std::cerr << "work_precision: built without Bullet (scripts/install-deps bench)\n";
#endif

  const auto start = Clock::now();
  const std::vector<BenchProblem> problems = loadProblems(opt);
  auto wanted = [&](const std::string& name) { return opt.solvers.empty() || opt.solvers.count(name) > 0; };
  for (const BenchProblem& bp : problems) {
    const bool lcp = lcs_bench::isLcp(bp.problem);
    const auto t0 = Clock::now();
    for (const OurSolver& s : ourSolvers()) {
      if (!wanted(s.name) || (lcp ? !s.lcp : !s.friction)) continue;
      if (s.max_rows > 0 && bp.problem.rowCount() > s.max_rows) {
        std::cerr << "  " << s.name << ": not run above " << s.max_rows << " rows\n";
        continue;
      }
      runOurs(opt, bp, s, csv);
    }
    for (auto& peer : peers) {
      if (!wanted(peer->name()) || !peer->applies(bp.problem)) continue;
      // Dantzig is O(n^3) without any budget: not run above 1500 rows.
      if (peer->name() == "bullet-dantzig" && bp.problem.rowCount() > 1500) {
        std::cerr << "  bullet-dantzig: not run above 1500 rows\n";
        continue;
      }
      runPeer(opt, bp, *peer, csv);
    }
    std::cerr << bp.family << "/" << bp.name << " (" << bp.problem.contacts.size() << " contacts): "
              << std::chrono::duration<double>(Clock::now() - t0).count() << " s\n";
  }
  writeRegret(opt, g_rows);
  std::cerr << "work_precision: " << problems.size() << " problems in "
            << std::chrono::duration<double>(Clock::now() - start).count() << " s, wrote " << opt.out << "\n";
  return 0;
}
