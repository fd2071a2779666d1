// auto against each of our own solvers on a family outside the study: stacks of boxes resting
// face on face (hard_case_util.h's boxStack, the portfolio tests' hard case), 2-10
// boxes, 4 or 8 points per face, alternate boxes 1, 10 or 100 times heavier. W is dense,
// rank-deficient (3k rows per face against 6 DoF per box) and, with the mass ratio,
// ill-conditioned: where only apgd converges and its residual sits on a plateau, auto's stall
// hand-overs decide its time. Writes one CSV row per problem, solver and tolerance (fastest of
// the repeats) and prints, per tolerance, auto's regret over the fastest own solver.
//   stacked_boxes [--tolerances 1e-3,1e-6] [--solvers auto,nlgs,apgd,newton,prox]
//                 [--out bench/results/stacked_boxes.csv] [--repeats 5] [--budget 2]
#include "../test/core/hard_case_util.h"

#include "cli_options.h"
#include "timing_util.h"

#include "lcp_contact_solver/core/contact_solver.h"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <string>
#include <vector>

namespace core = lcp_contact_solver::core;

namespace {

// The tests' stacks, pushed sideways and spun so that friction is active.
core::Problem boxStack(int boxes, int k, double ratio) {
  constexpr double kPush = 0.5, kMu = 0.8;
  return core::hard::boxStack(boxes, k, ratio, kPush, kMu);
}

struct Cell {
  bool converged = false;
  int iterations = 0;
  double seconds = 0.0;
  std::string path;
};

// The fastest of up to `repeats` solves (wall clock), fewer once they have taken a second in all.
Cell timeSolve(const core::Problem& p, const core::SolverParams& params, int repeats) {
  Cell cell;
  cell.seconds = 1e300;
  double spent = 0.0;
  for (int r = 0; r < repeats && spent < 1.0; ++r) {
    core::ContactSolver s(params);
    const auto t0 = lcs_bench::Clock::now();
    const core::SolveResult result = s.solve(p);
    const double dt = lcs_bench::secondsSince(t0);
    spent += dt;
    cell.seconds = std::min(cell.seconds, dt);
    cell.converged = result.converged;
    cell.iterations = result.iterations;
    cell.path = result.solver;
  }
  return cell;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"stacked_boxes: auto against our own solvers on stacks of boxes (outside the study)"};
  std::string tolerances = "1e-3,1e-6", solvers = "auto,nlgs,apgd,newton,prox";
  std::string out = "bench/results/stacked_boxes.csv";
  int repeats = 5;
  double budget = 2.0;
  app.add_option("--tolerances", tolerances, "comma list")->capture_default_str();
  app.add_option("--solvers", solvers, "comma list of `solver` values; auto's regret needs auto among them")
      ->capture_default_str();
  app.add_option("--out", out, "the CSV to write")->capture_default_str();
  app.add_option("--repeats", repeats, "solves per cell at most (fewer past a second)")->capture_default_str();
  app.add_option("--budget", budget, "time_budget of every solve (s)")->capture_default_str();
  if (const int status = lcs_bench::parseArguments(app, argc, argv); status >= 0) return status;
  std::string error;
  std::vector<lcs_bench::RepeatedSolver> runs = lcs_bench::repeatedSolvers(solvers, 0.0, &error);
  if (!error.empty()) {
    std::fprintf(stderr, "stacked_boxes: %s\n", error.c_str());
    return 2;
  }

  std::ofstream csv(out);
  csv << "problem,boxes,points,ratio,rows,solver,tolerance,converged,iterations,time_min_s,path\n";
  // Per tolerance: log regrets of auto over the fastest own solver that converged.
  std::map<double, std::vector<double>> regrets;
  std::map<double, std::vector<std::string>> above;
  for (const std::string& tol_text : lcs_bench::splitList(tolerances)) {
    const double tol = std::stod(tol_text);
    for (int boxes = 2; boxes <= 10; ++boxes)
      for (int points : {4, 8})
        for (double ratio : {1.0, 10.0, 100.0}) {
          const core::Problem p = boxStack(boxes, points, ratio);
          char name[64];
          std::snprintf(name, sizeof name, "stack_%d_%d_%g", boxes, points, ratio);
          double auto_time = -1.0, best = 1e300;
          for (lcs_bench::RepeatedSolver& run : runs) {
            run.params.tolerance = tol;
            run.params.time_budget = budget;
            const std::string& solver = run.name;
            const Cell c = timeSolve(p, run.params, repeats);
            csv << name << ',' << boxes << ',' << points << ',' << ratio << ',' << p.rowCount() << ',' << solver
                << ',' << tol << ',' << (c.converged ? 1 : 0) << ',' << c.iterations << ',' << c.seconds << ','
                << c.path << '\n';
            if (solver == "auto") auto_time = c.converged ? c.seconds : -1.0;
            else if (c.converged) best = std::min(best, c.seconds);
          }
          if (auto_time < 0.0 && best < 1e300) above[tol].push_back(std::string(name) + " missed by auto");
          if (auto_time > 0.0 && best < 1e300) {
            regrets[tol].push_back(std::log(auto_time / best));
            if (auto_time > 1.5 * best) {
              char cell[96];
              std::snprintf(cell, sizeof cell, "%s %.1fx", name, auto_time / best);
              above[tol].push_back(cell);
            }
          }
        }
  }
  for (const auto& [tol, logs] : regrets) {
    double sum = 0.0;
    for (double l : logs) sum += l;
    std::printf("tolerance %g: auto / fastest own, geometric mean %.2f over %zu problems; above 1.5x: %zu\n", tol,
                std::exp(sum / logs.size()), logs.size(), above[tol].size());
    for (const std::string& cell : above[tol]) std::printf("  %s\n", cell.c_str());
  }
  return 0;
}
