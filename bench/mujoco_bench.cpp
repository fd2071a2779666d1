// Per-step solve time of the package's solvers against MuJoCo's own PGS, CG and Newton on
// the same MuJoCo steps, at matched residual (the package's natural-map residual of the
// pyramidal LCP, the one measure every solver is judged by).
//
//   mujoco_bench [--model PATH]... [--first N] [--count N] [--target R] [--repeat N]
//                [--ours pgs,newton,apgd,lemke] [--mujoco pgs,cg,newton|none]
//                [--storage auto|dense|block_sparse] [--lemke-max-rows N] [--csv FILE]
//                [--threads N] [--islands on|off] [--mujoco-tolerance T] [--cone pyramidal|elliptic]
//
// Default models: MuJoCo's 22_humanoids and humanoid100 (libmujoco-samples), pyramidal cone
// (--cone elliptic: each contact a Coulomb disc, the problem no longer an LCP).
// Each model runs a reference trajectory with MuJoCo's own default solver (Newton); the steps
// first .. first+count−1 are measured. For each measured step (its state and MuJoCo's warm
// start qacc_warmstart copied from the trajectory):
//   - the problem W = efc_AR, d_free = efc_b over the contact and limit rows is extracted
//     (W dense up to 200 rows, block-sparse above; --storage forces one, and the solver names
//     then carry _dense / _sparse);
//   - ours: ContactSolver with tolerance = R (stopping rule: the residual), warm-started from
//     our own solution of the previous measured step, time = the core's solve time;
//   - MuJoCo's solver S: tolerance 0 (runs every iteration) and the fewest iterations k whose
//     efc_force has residual ≤ R (doubling, then bisection), time = mj_fwdConstraint at k.
//     MuJoCo's PGS also needs efc_AR (mj_projectConstraint), timed apart ("mujoco_AR"); CG
//     and Newton do not. Ours is given W = efc_AR, so its time excludes that build too.
//   - with --mujoco-tolerance T > 0, also MuJoCo's solver S at its own stopping rule
//     (opt.tolerance = T, opt.iterations as the model sets it): row "mujoco_S_tol", its
//     iterations MuJoCo's solver_iter.
// Times are the minimum of --repeat runs. CSV: model,step,time,contacts,rows,solver,
// iterations,residual,reached,seconds. A summary table (median per step) goes to stdout, and
// for ours_pgs on one-row problems (scalar rows, scalar_rows.h) the bytes its sweeps read per
// second beside the machine's stream bandwidth (a triad a = b + s c over 3 × 64 MB, best of 5).
#include "cli_options.h"
#include "lcp_contact_solver/core/contact_solver.h"
#include "lcp_contact_solver/core/islands.h"
#include "lcp_contact_solver/core/kernels/scalar_rows.h"
#include "lcp_contact_solver/scene/mujoco_comparison.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <variant>
#include <vector>

using namespace lcp_contact_solver;
using namespace lcp_contact_solver::scene;

namespace {

struct Options {
  std::vector<std::string> models;
  int first = 200;
  int count = 40;
  double target = 1e-6;
  int repeat = 3;
  std::vector<std::string> ours = {"pgs", "newton", "apgd", "lemke"};
  int lemke_max_rows = 1000;
  std::vector<std::string> mujoco = {"pgs", "cg", "newton"};
  MujocoExtractOptions::Storage storage = MujocoExtractOptions::Storage::kAuto;
  std::string csv;
  int threads = 0;                // SolverParams::threads of ours (0 = the core count)
  bool islands = true;            // SolverParams::islands of ours
  double mujoco_tolerance = 0.0;  // > 0: MuJoCo's solvers also at their own stopping rule
  std::string cone = "pyramidal";  // the models' cone: "pyramidal" (an LCP) or "elliptic" (discs)
};

struct Row {
  std::string model, solver;
  int step = 0, contacts = 0, rows = 0, iterations = 0;
  double time = 0, residual = 0, seconds = 0;
  bool reached = false;
  double sweep_bytes = 0;  // ours on scalar rows: bytes a full sweep reads (0 otherwise)
};

// Best-of-5 STREAM triad bandwidth (bytes/s), counted as STREAM does: 24 bytes per element.
double triadBandwidth() {
  const std::size_t n = std::size_t(8) << 20;  // 64 MB per array
  std::vector<double> a(n, 0.0), b(n, 1.0), c(n, 2.0);
  double best = 1e300;
  for (int r = 0; r < 5; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    const double scale = 1.0 + 1e-3 * r;
    for (std::size_t i = 0; i < n; ++i) a[i] = b[i] + scale * c[i];
    best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  volatile double sink = a[n / 2];
  (void)sink;
  return 24.0 * double(n) / best;
}

// Bytes one scalar-row sweep reads at most: per stored entry an index and a value (the d it
// updates stays in cache), per row the column start, inverse diagonal, kind, λ and d.
double scalarSweepBytes(const core::Problem& p) {
  if (!core::fitsScalarRows(p)) return 0.0;
  const auto& W = std::get<core::BlockSparseMatrix>(p.W);
  return 12.0 * double(W.values.size()) + 29.0 * double(W.blockCount());
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// MuJoCo's solver `solver` with `iterations` on a copy of `snapshot`: its solve time and the
// residual of its forces on `mp`.
std::pair<double, double> runMujoco(const MujocoWorld& snapshot, MujocoWorld& scratch,
                                    const MujocoProblem& mp, int solver, int iterations, int repeat,
                                    double tolerance = 0.0) {
  double best = 1e300, residual = 0.0;
  for (int r = 0; r < repeat; ++r) {
    scratch.copyDataFrom(snapshot);
    mjModel* m = scratch.model();
    m->opt.solver = solver;
    m->opt.iterations = iterations;
    m->opt.tolerance = tolerance;
    double seconds = 0.0;
    forwardToConstraints(m, scratch.data(), true, &seconds);
    best = std::min(best, seconds);
    residual = problemResidual(mp, mp.fromEfcForce(scratch.data()->efc_force));
  }
  return {best, residual};
}

// The fewest iterations reaching the target (doubling, then bisection), up to `cap`.
int fewestIterations(const MujocoWorld& snapshot, MujocoWorld& scratch, const MujocoProblem& mp, int solver,
                     double target, int cap) {
  int hi = 1;
  while (hi < cap && runMujoco(snapshot, scratch, mp, solver, hi, 1).second > target) hi *= 2;
  hi = std::min(hi, cap);
  if (runMujoco(snapshot, scratch, mp, solver, hi, 1).second > target) return cap;
  int lo = hi / 2;  // fails (or 0)
  while (hi - lo > 1) {
    const int mid = (lo + hi) / 2;
    if (runMujoco(snapshot, scratch, mp, solver, mid, 1).second <= target)
      hi = mid;
    else
      lo = mid;
  }
  return hi;
}

void benchModel(const std::string& path, const Options& o, std::vector<Row>* rows) {
  MujocoOptions mo;
  mo.cone = o.cone;
  std::string error;
  auto world = MujocoWorld::load(path, mo, &error);
  if (!world) {
    std::cerr << "mujoco_bench: " << error << "\n";
    std::exit(2);
  }
  const int model_iterations = world->model()->opt.iterations;  // MuJoCo's own cap, before runMujoco edits it
  auto scratch = world->clone();
  auto snapshot = world->clone();
  std::string name = path.substr(path.find_last_of('/') + 1);
  name = name.substr(0, name.find_last_of('.'));

  std::map<std::string, core::ContactSolver> ours;
  for (const std::string& s : o.ours) {
    core::SolverParams p;
    if (!core::parseSolverName(s, &p.solver)) {
      std::cerr << "mujoco_bench: unknown solver " << s << "\n";
      std::exit(2);
    }
    p.tolerance = o.target;
    p.threads = o.threads;
    p.islands = o.islands;
    p.maxIt = s == "lemke" ? 1000000 : 100000;
    ours.emplace(s, core::ContactSolver(p));
  }
  std::vector<int> mj_solvers;
  for (const std::string& s : o.mujoco) {
    int solver = 0;
    if (!parseMujocoSolver(s, &solver, &error)) {
      std::cerr << "mujoco_bench: " << error << "\n";
      std::exit(2);
    }
    mj_solvers.push_back(solver);
  }
  MujocoExtractOptions extract;
  extract.storage = o.storage;
  const std::string suffix = o.storage == MujocoExtractOptions::Storage::kDense         ? "_dense"
                             : o.storage == MujocoExtractOptions::Storage::kBlockSparse ? "_sparse"
                                                                                        : "";

  for (int step = 0; step < o.first + o.count; ++step) {
    if (step >= o.first) {
      snapshot->copyDataFrom(*world);  // the state of this step, MuJoCo's warm start included
      scratch->copyDataFrom(*snapshot);
      forwardToConstraints(scratch->model(), scratch->data(), false);
      MujocoProblem mp;
      error = extractProblem(scratch->model(), scratch->data(), extract, &mp);
      if (!error.empty()) {
        std::cerr << "mujoco_bench: " << name << " step " << step << ": " << error << "\n";
        std::exit(2);
      }
      if (!mp.problem.contacts.empty()) {
        Row base;
        base.model = name;
        base.step = step;
        base.time = mp.time;
        base.contacts = mp.ncon;
        base.rows = mp.problem.rowCount();
        // efc_AR, which MuJoCo's PGS builds and ours is given.
        double ar = 1e300;
        for (int r = 0; r < o.repeat; ++r)
          ar = std::min(ar, computeConstraintAR(scratch->model(), scratch->data()));
        Row r0 = base;
        r0.solver = "mujoco_AR";
        r0.seconds = ar;
        r0.reached = true;
        rows->push_back(r0);
        for (auto& [solver_name, solver] : ours) {
          if (solver_name == "lemke" && base.rows > o.lemke_max_rows) continue;
          Row r = base;
          r.solver = "ours_" + solver_name + suffix;
          r.seconds = 1e300;
          r.sweep_bytes = solver_name == "pgs" ? scalarSweepBytes(mp.problem) : 0.0;
          core::ContactSolver used = solver;
          for (int k = 0; k < o.repeat; ++k) {
            core::ContactSolver trial = solver;  // the same warm start each repeat
            const core::SolveResult result = trial.solve(mp.problem);
            r.seconds = std::min(r.seconds, result.solve_time);
            r.iterations = result.iterations;
            r.residual = result.residual;
            r.reached = result.residual <= o.target;
            used = trial;
          }
          solver = used;
          rows->push_back(r);
        }
        for (int s : mj_solvers) {
          Row r = base;
          r.solver = std::string("mujoco_") + mujocoSolverName(s);
          const int cap = s == mjSOL_PGS ? 100000 : 10000;
          r.iterations = fewestIterations(*snapshot, *scratch, mp, s, o.target, cap);
          const auto [seconds, residual] = runMujoco(*snapshot, *scratch, mp, s, r.iterations, o.repeat);
          r.seconds = seconds;
          r.residual = residual;
          r.reached = residual <= o.target;
          rows->push_back(r);
          if (o.mujoco_tolerance > 0.0) {  // MuJoCo at its own stopping rule
            Row t = base;
            t.solver = std::string("mujoco_") + mujocoSolverName(s) + "_tol";
            const auto [own_seconds, own_residual] =
                runMujoco(*snapshot, *scratch, mp, s, model_iterations, o.repeat, o.mujoco_tolerance);
            t.seconds = own_seconds;
            t.residual = own_residual;
            t.iterations = scratch->data()->solver_iter;
            t.reached = own_residual <= o.target;
            rows->push_back(t);
          }
        }
        const std::size_t stored = std::holds_alternative<core::BlockSparseMatrix>(mp.problem.W)
                                       ? std::get<core::BlockSparseMatrix>(mp.problem.W).values.size()
                                       : std::size_t(base.rows) * base.rows;
        const core::Islands islands = core::findIslands(mp.problem);
        std::size_t largest = 0;
        for (const auto& list : islands.contacts) largest = std::max(largest, list.size());
        std::fprintf(
            stderr,
            "%s step %d: %d contacts, %d rows, %zu stored W entries, %d islands (largest %zu contacts)\n",
            name.c_str(), step, base.contacts, base.rows, stored, islands.count(), largest);
      }
    }
    forwardToConstraints(world->model(), world->data(), true);  // the reference trajectory
    error = integrateEuler(world->model(), world->data());
    if (!error.empty()) {
      std::cerr << "mujoco_bench: " << error << "\n";
      std::exit(2);
    }
  }
}

// Fills o from the command line (CLI11); -1 to go on, else the exit code (0 after --help).
int parseOptions(int argc, char** argv, Options* options) {
  Options& o = *options;
  CLI::App app{
      "mujoco_bench: per-step solve time of ours against MuJoCo's PGS, CG and Newton at matched residual"};
  app.option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  std::string ours, mujoco, storage = "auto", islands = "on";
  app.add_option("--model", o.models, "a MuJoCo model (repeatable; default 22_humanoids and humanoid100)")
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  app.add_option("--first", o.first, "first measured step")->capture_default_str();
  app.add_option("--count", o.count, "steps measured")->capture_default_str();
  app.add_option("--target", o.target, "target residual (the package's measure)")->capture_default_str();
  app.add_option("--repeat", o.repeat, "runs per measurement, the minimum counts")->capture_default_str();
  app.add_option("--ours", ours, "our solvers (comma list)")->default_str("pgs,newton,apgd,lemke");
  app.add_option("--mujoco", mujoco, "MuJoCo's solvers (comma list), or none")->default_str("pgs,cg,newton");
  app.add_option("--storage", storage, "W's storage for ours")
      ->check(CLI::IsMember({"auto", "dense", "block_sparse"}))
      ->capture_default_str();
  app.add_option("--lemke-max-rows", o.lemke_max_rows, "lemke not run above this many rows")
      ->capture_default_str();
  app.add_option("--csv", o.csv, "the CSV to write (default: none)");
  app.add_option("--threads", o.threads, "threads of ours (0 = the core count)")->capture_default_str();
  app.add_option("--islands", islands, "on|off: islands of ours (anything but off is on)")
      ->capture_default_str();
  app.add_option("--cone", o.cone, "the models' friction cone (elliptic: Coulomb discs)")
      ->check(CLI::IsMember({"pyramidal", "elliptic"}))
      ->capture_default_str();
  app.add_option("--mujoco-tolerance", o.mujoco_tolerance,
                 "T > 0: MuJoCo's solvers also at their own stopping rule")
      ->capture_default_str();
  if (const int code = lcs_bench::parseArguments(app, argc, argv); code >= 0) return code;
  o.repeat = std::max(1, o.repeat);
  o.threads = std::max(0, o.threads);
  if (app.count("--ours")) o.ours = lcs_bench::splitList(ours);
  if (app.count("--mujoco")) o.mujoco = mujoco == "none" ? std::vector<std::string>() : lcs_bench::splitList(mujoco);
  if (storage == "dense")
    o.storage = MujocoExtractOptions::Storage::kDense;
  else if (storage == "block_sparse")
    o.storage = MujocoExtractOptions::Storage::kBlockSparse;
  if (app.count("--islands")) o.islands = islands != "off";
  return -1;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  if (const int code = parseOptions(argc, argv, &o); code >= 0) return code;
  if (o.models.empty())
    o.models = {"/usr/share/mujoco/model/humanoid/22_humanoids.xml",
                "/usr/share/mujoco/model/humanoid100/humanoid100.xml"};

  std::vector<Row> rows;
  for (const std::string& m : o.models) benchModel(m, o, &rows);

  if (!o.csv.empty()) {
    std::ofstream csv(o.csv);
    csv << "model,step,time,contacts,rows,solver,iterations,residual,reached,seconds\n";
    for (const Row& r : rows)
      csv << r.model << ',' << r.step << ',' << r.time << ',' << r.contacts << ',' << r.rows << ','
          << r.solver << ',' << r.iterations << ',' << r.residual << ',' << (r.reached ? 1 : 0) << ','
          << r.seconds << '\n';
  }

  // Summary: per model and solver, medians over the measured steps.
  std::printf("target residual %.0e (package measure), MuJoCo %s, times: min of %d runs, median over steps\n",
              o.target, mj_versionString(), o.repeat);
  std::printf("%-14s %-20s %6s %7s %6s %12s %10s %12s\n", "model", "solver", "steps", "reached", "rows",
              "iterations", "ms/step", "max residual");
  std::map<std::pair<std::string, std::string>, std::vector<const Row*>> groups;
  std::vector<std::pair<std::string, std::string>> order;
  for (const Row& r : rows) {
    auto key = std::make_pair(r.model, r.solver);
    if (!groups.count(key)) order.push_back(key);
    groups[key].push_back(&r);
  }
  for (const auto& key : order) {
    const auto& g = groups[key];
    std::vector<double> t, it, n;
    int reached = 0;
    double worst = 0;
    for (const Row* r : g) {
      t.push_back(r->seconds);
      it.push_back(r->iterations);
      n.push_back(r->rows);
      reached += r->reached;
      worst = std::max(worst, r->residual);
    }
    std::printf("%-14s %-20s %6zu %7d %6.0f %12.0f %10.3f %12.1e\n", key.first.c_str(), key.second.c_str(),
                g.size(), reached, median(n), median(it), 1e3 * median(t), worst);
  }
  // Sweep bandwidth of ours on scalar rows: bytes of a full sweep × sweeps / solve time (setup
  // and the stopping test included, so a lower bound of the sweep's own rate; with islands,
  // sweeps = the largest island's count, an upper bound of the bytes).
  bool header = false;
  for (const auto& key : order) {
    std::vector<double> rate, kb;
    for (const Row* r : groups[key])
      if (r->sweep_bytes > 0 && r->seconds > 0) {
        rate.push_back(r->sweep_bytes * r->iterations / r->seconds);
        kb.push_back(r->sweep_bytes / 1024.0);
      }
    if (rate.empty()) continue;
    if (!header) {
      std::printf("stream triad: %.1f GB/s\n", triadBandwidth() / 1e9);
      header = true;
    }
    std::printf("%-14s %-20s scalar-row sweep: %.0f KB per sweep, %.2f GB/s (median over steps)\n",
                key.first.c_str(), key.second.c_str(), median(kb), median(rate) / 1e9);
  }
  return 0;
}
