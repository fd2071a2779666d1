// Work-precision study: every solver of ours and every available peer on every problem, over
// a tolerance sweep; one CSV row per (problem, solver, setting) with the median wall time and
// the residual measured by the core's solver-independent natural map (residual.h), recomputed
// from the returned forces for every solver alike. See docs/BENCHMARKS.md.
//
//   work_precision [--problems DIR] [--scenes DIR] [--out FILE] [--budget S]
//                  [--families fc3d,lcp,scenes,mujoco] [--filter SUBSTRING] [--solvers a,b,...]
//                  [--quick] [--regret FILE] [--mujoco-models a.xml,b.xml,...] [--mujoco-steps 100,300]
//                  [--sweep-cost FILE]
//
// At the end it writes the "auto regret" table (markdown, --regret, default
// bench/results/auto_regret.md): per problem and tolerance, auto's time over the fastest of
// our other solvers and over the fastest peer that reached the same residual. With
// --sweep-cost it times a Gauss-Seidel sweep and a dense Cholesky on each problem instead
// (sweep_cost.cpp) and writes those to FILE.
//
// The parts: work_precision_problems.cpp (what is measured), work_precision_runs.cpp (our
// solvers and the peers, the CSV), auto_regret_table.cpp (the table).
#include "work_precision.h"
#include "auto_regret_table.h"
#include "timing_util.h"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace wp = lcs_bench::work_precision;
using lcs_bench::Peer;
using wp::Clock;

namespace {

using lcs_bench::splitList;

// Fills opt from the command line (CLI11); -1 to go on, else the exit code (0 after --help).
int parseOptions(int argc, char** argv, wp::Options* options) {
  wp::Options& opt = *options;
  CLI::App app{"work_precision: work-precision benchmark (every solver and peer over a tolerance sweep)"};
  app.option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  double budget = opt.budget;
  std::string families, solvers, tolerances, mujoco_models, mujoco_steps;  // comma lists
  app.add_option("--problems", opt.problems_dir, "the problem files (Siconos .dat, FCLIB .hdf5)")
      ->capture_default_str();
  app.add_option("--scenes", opt.scenes_dir, "the scenes directory")->capture_default_str();
  app.add_option("--out", opt.out, "the CSV to write")->capture_default_str();
  CLI::Option* budget_opt = app.add_option("--budget", budget, "wall-clock budget per solve (s)");
  budget_opt->capture_default_str();
  app.add_option("--families", families, "fc3d,lcp,scenes,mujoco (comma list)")
      ->default_str("fc3d,lcp,scenes,mujoco");
  app.add_option("--filter", opt.filter, "only problems whose name holds SUBSTRING");
  app.add_option("--solvers", solvers, "only these solvers and peers (comma list; default all)");
  CLI::Option* tolerances_opt = app.add_option("--tolerances", tolerances, "the tolerance sweep (comma list)")
                                    ->default_str("1e-2,1e-3,...,1e-10");
  CLI::Option* quick =
      app.add_flag("--quick", "a short run: 4 tolerances, small scenes, budget <= 1 s, 1 repeat");
  app.add_option("--regret", opt.regret, "the auto regret table to write (markdown)")->capture_default_str();
  app.add_option("--sweep-cost", opt.sweep_cost,
                 "instead of the study: time a sweep and a dense Cholesky per problem, CSV to FILE");
  // Any MuJoCo model can be studied, not only the four the study ships with: a model auto was
  // never tried on is the fairest test of how it decides.
  app.add_option("--mujoco-models", mujoco_models, "the mujoco family's models (comma list of MJCF files)")
      ->default_str("22_humanoids,humanoid100,particle,rope of MuJoCo's samples");
  app.add_option("--mujoco-steps", mujoco_steps, "the mujoco family's simulated steps taken as problems (comma list)")
      ->default_str("100,300");
  try {
    app.parse(argc, argv);
    if (app.count("--families")) {
      const auto v = splitList(families);
      opt.families = {v.begin(), v.end()};
    }
    if (app.count("--solvers")) {
      const auto v = splitList(solvers);
      opt.solvers = {v.begin(), v.end()};
    }
    if (app.count("--mujoco-models")) opt.mujoco_models = splitList(mujoco_models);
    if (app.count("--mujoco-steps")) {
      opt.mujoco_steps.clear();
      for (const std::string& step : splitList(mujoco_steps)) opt.mujoco_steps.push_back(std::stoi(step));
    }
    // --quick sets the tolerances and caps the budget: in command-line order, the later wins.
    for (const CLI::Option* given : app.parse_order()) {
      if (given == budget_opt) {
        opt.budget = budget;
      } else if (given == tolerances_opt) {
        opt.tolerances.clear();
        for (const std::string& t : splitList(tolerances)) opt.tolerances.push_back(std::stod(t));
      } else if (given == quick) {
        opt.tolerances = {1e-2, 1e-4, 1e-6, 1e-8};
        opt.pyramid_bases = {2, 5};
        opt.pile_balls = {12};
        opt.budget = std::min(opt.budget, 1.0);
        opt.min_repeats = 1;
        opt.min_time = 0.0;
      }
    }
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  } catch (const std::exception& e) {  // a bad number in --tolerances or --mujoco-steps
    std::cerr << "work_precision: bad --tolerances or --mujoco-steps value (" << e.what() << ")\n";
    return 2;
  }
  return -1;
}

std::vector<std::unique_ptr<Peer>> makePeers() {
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
  return peers;
}

// Every wanted solver of ours and every wanted peer that applies, on one problem.
void runProblem(const wp::Options& opt, const wp::BenchProblem& bp, std::vector<std::unique_ptr<Peer>>& peers,
                std::ostream& csv) {
  auto wanted = [&](const std::string& name) { return opt.solvers.empty() || opt.solvers.count(name) > 0; };
  const bool lcp = lcs_bench::isLcp(bp.problem);
  const auto t0 = Clock::now();
  const std::vector<wp::OurSolver> ours = wp::ourSolvers();
  std::vector<const wp::OurSolver*> run;
  for (const wp::OurSolver& s : ours) {
    if (!wanted(s.name) || (lcp ? !s.lcp : !s.friction)) continue;
    if (s.max_rows > 0 && bp.problem.rowCount() > s.max_rows) {
      std::cerr << "  " << s.name << ": not run above " << s.max_rows << " rows\n";
      continue;
    }
    run.push_back(&s);
  }
  wp::runOurs(opt, bp, run, csv);
  for (auto& peer : peers) {
    if (!wanted(peer->name()) || !peer->applies(bp.problem)) continue;
    // Dantzig is O(n^3) without any budget: not run above 1500 rows.
    if (peer->name() == "bullet-dantzig" && bp.problem.rowCount() > 1500) {
      std::cerr << "  bullet-dantzig: not run above 1500 rows\n";
      continue;
    }
    wp::runPeer(opt, bp, *peer, csv);
  }
  std::cerr << bp.family << "/" << bp.name << " (" << bp.problem.contacts.size()
            << " contacts): " << std::chrono::duration<double>(Clock::now() - t0).count() << " s\n";
}

}  // namespace

int main(int argc, char** argv) {
  wp::Options opt;
  if (const int code = parseOptions(argc, argv, &opt); code >= 0) return code;

  if (!opt.sweep_cost.empty()) {
    std::ofstream costs(opt.sweep_cost);
    if (!costs) {
      std::cerr << "work_precision: cannot write " << opt.sweep_cost << "\n";
      return 1;
    }
    wp::writeSweepCosts(wp::loadProblems(opt), costs);
    return 0;
  }
  std::ofstream csv(opt.out);
  if (!csv) {
    std::cerr << "work_precision: cannot write " << opt.out << "\n";
    return 1;
  }
  wp::writeHeader(csv);

  std::vector<std::unique_ptr<Peer>> peers = makePeers();

  const auto start = Clock::now();
  const std::vector<wp::BenchProblem> problems = wp::loadProblems(opt);
  for (const wp::BenchProblem& bp : problems) runProblem(opt, bp, peers, csv);
  wp::writeRegret(opt, wp::writtenRows());
  std::cerr << "work_precision: " << problems.size() << " problems in "
            << std::chrono::duration<double>(Clock::now() - start).count() << " s, wrote " << opt.out << "\n";
  return 0;
}
