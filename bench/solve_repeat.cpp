// Time per solve of one problem file, for microsecond problems where a sweep of the study times
// each cell too briefly to compare two cores: every solver solves the same problem `--solves`
// times in a row (one ContactSolver per solve, as solveProblem), and the solvers take turns for
// `--rounds` rounds, so that all of them see the same mixture of machine states (this VM runs
// a microsecond solve at one of two speeds, switching every few seconds). Prints, per solver,
// the best round's time per solve and the answer's status, iterations, residual and path.
// With --between OTHER, each timed solve follows an untimed solve of another problem by the
// same solver (at most 30 iterations), so that nothing a kernel keeps per thread from its last
// solve (newton's sparse LU pattern, SparseSystem::matches) is of this problem: the time of a
// solve whose contacts changed since the last step, where the plain repetition times a scene
// whose contacts did not.
//   solve_repeat FILE [--tolerance T] [--solvers auto,newton,apgd] [--solves N] [--rounds R]
//                [--between OTHER]
#include "lcp_contact_solver/core/contact_solver.h"
#include "lcp_contact_solver/core/problem_io.h"

#include "timing_util.h"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

namespace core = lcp_contact_solver::core;

int main(int argc, char** argv) {
  CLI::App app{"solve_repeat: time per solve of one problem file, solvers in alternating rounds"};
  std::string file;
  double tolerance = 1e-6;
  std::string solvers = "auto,newton,apgd";
  int solves = 30000;
  int rounds = 10;
  app.add_option("file", file, "a problem file (Siconos .dat, FCLIB .hdf5)")->required();
  app.add_option("--tolerance", tolerance, "the tolerance of every solve")->capture_default_str();
  app.add_option("--solvers", solvers, "our solvers (comma list of `solver` values)")->capture_default_str();
  app.add_option("--solves", solves, "solves per round")->capture_default_str()->check(CLI::PositiveNumber);
  app.add_option("--rounds", rounds, "rounds")->capture_default_str()->check(CLI::PositiveNumber);
  std::string between_file;
  app.add_option("--between", between_file, "another problem file, solved (untimed) before each timed solve");
  CLI11_PARSE(app, argc, argv);

  const core::Problem problem = core::readProblemFile(file);
  const bool interleave = !between_file.empty();
  const core::Problem between = interleave ? core::readProblemFile(between_file) : core::Problem{};
  std::string fault;
  std::vector<lcs_bench::RepeatedSolver> entries = lcs_bench::repeatedSolvers(solvers, tolerance, &fault);
  if (!fault.empty()) {
    std::fprintf(stderr, "solve_repeat: %s\n", fault.c_str());
    return 2;
  }
  for (int round = 0; round < rounds; ++round) {
    for (lcs_bench::RepeatedSolver& e : entries) {
      double seconds = 0.0;
      if (interleave) {
        core::SolverParams between_params = e.params;
        between_params.maxIt = 30;
        for (int k = 0; k < solves; ++k) {
          core::solveProblem(between, between_params);
          const auto start = std::chrono::steady_clock::now();
          e.last = core::solveProblem(problem, e.params);
          seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        }
      } else {
        const auto start = std::chrono::steady_clock::now();
        for (int k = 0; k < solves; ++k) e.last = core::solveProblem(problem, e.params);
        seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      }
      e.best = std::min(e.best, seconds / solves);
    }
  }
  std::printf("%-10s %12s %-18s %10s %12s  %s\n", "solver", "us/solve", "status", "iterations", "residual", "path");
  for (const lcs_bench::RepeatedSolver& e : entries)
    std::printf("%-10s %12.3f %-18s %10d %12.3g  %s\n", e.name.c_str(), e.best * 1e6, core::statusName(e.last.status),
                e.last.iterations, e.last.residual, e.last.solver.c_str());
  return 0;
}
