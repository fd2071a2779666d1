// Time and minor page faults per solve of a stream whose row count changes from one solve to
// the next, as a simulator's steps do: dense problems of `--contacts` and `--contacts` - 1
// contacts, solved alternately (after one untimed solve of each), every normal pressed in
// (d_free < 0, as in a resting stack), W = A Aᵀ / rows + 0.1 I with A random (seeded). A
// solver that frees its n x n factorization storage after each solve pays the pages again on
// the next one; thread_workspace.h keeps it up to kKeptDenseRows. Solvers take turns in rounds
// (the fastest round counts) so that all of them see the same mixture of machine states.
//   storage_stream [--contacts 200] [--friction] [--solvers newton,prox,auto] [--solves 10] [--rounds 5]
#include "lcp_contact_solver/core/contact_solver.h"

#include "timing_util.h"

#include <CLI/CLI.hpp>

#include <sys/resource.h>

#include <algorithm>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

namespace core = lcp_contact_solver::core;

namespace {

long minorFaults() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_minflt;
}

core::Problem pressedStack(int contacts, bool friction, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal;
  const int per_contact = friction ? 3 : 1;
  const int rows = per_contact * contacts;
  Eigen::MatrixXd A(rows, rows / 2);
  for (Eigen::Index i = 0; i < A.size(); ++i) A.data()[i] = normal(rng);
  core::Problem problem;
  problem.W = Eigen::MatrixXd(A * A.transpose() / rows + 0.1 * Eigen::MatrixXd::Identity(rows, rows));
  problem.d_free.resize(rows);
  for (int c = 0; c < contacts; ++c) {
    problem.d_free[per_contact * c] = -1.0 - std::abs(normal(rng));  // pressed in
    for (int t = 1; t < per_contact; ++t) problem.d_free[per_contact * c + t] = 0.1 * normal(rng);
    core::Contact contact;
    contact.id = c;
    contact.type = friction ? core::ContactType::kFrictional : core::ContactType::kFrictionless;
    contact.rows = per_contact;
    contact.mu = 0.5;
    problem.contacts.push_back(contact);
  }
  return problem;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"storage_stream: time and page faults per solve of a dense stream whose size changes"};
  int contacts = 200;
  bool friction = false;
  std::string solvers = "newton,prox,auto";
  double tolerance = 1e-8;
  int solves = 10;
  int rounds = 5;
  app.add_option("--contacts", contacts, "contacts of the larger problem")->capture_default_str()->check(CLI::Range(2, 2000));
  app.add_flag("--friction", friction, "frictional contacts (3 rows each) instead of frictionless ones");
  app.add_option("--solvers", solvers, "our solvers (comma list of `solver` values)")->capture_default_str();
  app.add_option("--tolerance", tolerance, "the tolerance of every solve")->capture_default_str();
  app.add_option("--solves", solves, "solves per round (alternating the two sizes)")->capture_default_str()->check(CLI::PositiveNumber);
  app.add_option("--rounds", rounds, "rounds")->capture_default_str()->check(CLI::PositiveNumber);
  CLI11_PARSE(app, argc, argv);

  const core::Problem problems[2] = {pressedStack(contacts, friction, 1), pressedStack(contacts - 1, friction, 2)};
  std::string fault;
  std::vector<lcs_bench::RepeatedSolver> entries = lcs_bench::repeatedSolvers(solvers, tolerance, &fault);
  if (!fault.empty()) {
    std::fprintf(stderr, "storage_stream: %s\n", fault.c_str());
    return 2;
  }
  for (const lcs_bench::RepeatedSolver& e : entries)
    for (const core::Problem& p : problems) core::solveProblem(p, e.params);  // untimed: first-use costs
  for (int round = 0; round < rounds; ++round) {
    for (lcs_bench::RepeatedSolver& e : entries) {
      const long faults = minorFaults();
      const auto start = lcs_bench::Clock::now();
      for (int k = 0; k < solves; ++k) e.last = core::solveProblem(problems[k % 2], e.params);
      e.best = std::min(e.best, lcs_bench::secondsSince(start) / solves);
      e.faults += minorFaults() - faults;
    }
  }
  std::printf("rows %d and %d (%s), dense W\n", problems[0].rowCount(), problems[1].rowCount(),
              friction ? "frictional" : "frictionless");
  std::printf("%-10s %12s %12s %-12s %10s %12s  %s\n", "solver", "us/solve", "faults/solve", "status", "iterations",
              "residual", "path");
  for (const lcs_bench::RepeatedSolver& e : entries)
    std::printf("%-10s %12.1f %12.1f %-12s %10d %12.3g  %s\n", e.name.c_str(), e.best * 1e6,
                e.faults / (static_cast<double>(rounds) * solves), core::statusName(e.last.status), e.last.iterations,
                e.last.residual, e.last.solver.c_str());
  return 0;
}
