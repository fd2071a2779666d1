// What the unbuilt solve (build_lcp = false, core/body_compliance.h) costs against the
// built ones, on the scene problems of growing size (bench/scene_problems.h: brick pyramids
// and sphere piles): storage of the compliance, one-off setup, and time per Gauss-Seidel
// sweep of nlgs on a dense W, a block-sparse W and the body form. Never a test.
//
//   unbuilt_scaling [--bases 4,8,12,16] [--balls 100,300,1000] [--steps 30] [--sweeps 100]
//                   [--dense-max-rows 6000] [--out FILE]
//
// Per-sweep time is (t(10 + sweeps) - t(10)) / sweeps, each the best of 3 runs, with the
// SOFA stopping rule at an unreachable tolerance (no residual per sweep), so it is the sweep
// alone; setup = t(10) - 10 sweeps (local blocks, block-column index, assembling W for the
// built forms is listed apart). The forces after the same sweeps are compared with the
// block-sparse ones (they are the same iteration).
#include "cli_options.h"
#include "scene_problems.h"

#include "lcp_contact_solver/core/body_compliance.h"
#include "lcp_contact_solver/core/contact_solver.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

namespace lcs = lcp_contact_solver;
using Clock = std::chrono::steady_clock;

namespace {

double seconds(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

struct Timing {
  double total = 0.0;  // best of 3, s
  lcs::core::SolveResult result;
};

Timing timeSolve(const lcs::core::Problem& problem, lcs::core::SolverParams params, int sweeps) {
  params.maxIt = sweeps;
  Timing t;
  t.total = 1e300;
  for (int rep = 0; rep < 3; ++rep) {
    const auto t0 = Clock::now();
    lcs::core::SolveResult r = lcs::core::solveProblem(problem, params);
    const double s = seconds(t0, Clock::now());
    if (s < t.total) {
      t.total = s;
      t.result = std::move(r);
    }
  }
  return t;
}

std::size_t bytesOf(const lcs::core::BlockSparseMatrix& W) {
  return W.values.size() * sizeof(double) +
         (W.block_col.size() + W.value_start.size() + W.row_start.size() + W.block_offset.size()) *
             sizeof(int);
}

std::size_t bytesOf(const lcs::core::BodyCompliance& B) {
  return B.body_compliance.size() * sizeof(lcs::core::BodyMatrix) +
         B.contacts.size() * sizeof(lcs::core::ContactJacobian);
}

double relDiff(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  const double scale = std::max({a.cwiseAbs().maxCoeff(), b.cwiseAbs().maxCoeff(), 1e-300});
  return (a - b).cwiseAbs().maxCoeff() / scale;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<int> bases = {4, 8, 12, 16};
  std::vector<int> balls = {100, 300, 1000};
  int steps = 30, sweeps = 100, dense_max_rows = 6000;
  std::string out_path;
  CLI::App app{"unbuilt_scaling: the unbuilt solve against the built ones (storage, setup, sweep; CSV)"};
  app.option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  lcs_bench::addIntListOption(app, "--bases", &bases, "brick pyramids: bricks at the base, comma list",
                              "4,8,12,16");
  lcs_bench::addIntListOption(app, "--balls", &balls, "sphere piles: balls, comma list", "100,300,1000");
  app.add_option("--steps", steps, "in-process steps before a problem is taken")->capture_default_str();
  app.add_option("--sweeps", sweeps, "sweeps timed per run")->capture_default_str();
  app.add_option("--dense-max-rows", dense_max_rows, "dense W skipped above this many rows")
      ->capture_default_str();
  app.add_option("--out", out_path, "the CSV to write (default: stdout)");
  if (const int code = lcs_bench::parseArguments(app, argc, argv); code >= 0) return code;
  std::ofstream file;
  if (!out_path.empty()) file.open(out_path);
  std::ostream& out = out_path.empty() ? std::cout : file;
  out << "problem,bodies,contacts,rows,form,compliance_bytes,assemble_ms,setup_ms,sweep_us,sweep_us_per_row,"
         "max_rel_diff_vs_block_sparse\n";

  lcs::core::SolverParams params;
  params.solver = lcs::core::SolverKind::kNlgs;
  params.stopping_rule = lcs::core::StoppingRule::kSofa;
  params.tolerance = 1e-300;  // never reached: every run does exactly maxIt sweeps
  params.initial_guess = false;
  const int warm = 10;

  const auto t_gen = Clock::now();
  std::vector<lcs_bench::SceneProblem> problems =
      lcs_bench::makeSceneProblems(LCS_SCENES_DIR, bases, balls, steps);
  std::cerr << "generated " << problems.size() << " problems in " << seconds(t_gen, Clock::now()) << " s\n";

  for (const lcs_bench::SceneProblem& sp : problems) {
    const lcs::core::Problem& bodies = sp.body_form;
    const int rows = bodies.rowCount(), nc = static_cast<int>(bodies.contacts.size());
    if (nc == 0) continue;
    // The built forms, from the same body form (the scene's own block-sparse W equals it to
    // round-off; assembling here times it).
    auto t0 = Clock::now();
    lcs::core::Problem sparse = bodies;
    sparse.bodies.reset();
    sparse.W = bodies.bodies->assemble();
    const double assemble_sparse = seconds(t0, Clock::now());

    struct Row {
      std::string form;
      const lcs::core::Problem* problem;
      bool build_lcp;
      std::size_t bytes;
      double assemble;
    };
    std::vector<Row> forms = {
        {"block_sparse", &sparse, true, bytesOf(std::get<lcs::core::BlockSparseMatrix>(sparse.W)),
         assemble_sparse},
        {"unbuilt", &bodies, false, bytesOf(*bodies.bodies), 0.0},
    };
    lcs::core::Problem dense;
    if (rows <= dense_max_rows) {
      t0 = Clock::now();
      dense = sparse;
      dense.W = std::get<lcs::core::BlockSparseMatrix>(sparse.W).toDense();
      forms.insert(forms.begin(),
                   Row{"dense", &dense, true, static_cast<std::size_t>(rows) * rows * sizeof(double),
                       assemble_sparse + seconds(t0, Clock::now())});
    }
    Eigen::VectorXd reference;
    std::vector<std::string> lines;
    std::vector<Eigen::VectorXd> forces;
    for (const Row& f : forms) {
      lcs::core::SolverParams p = params;
      p.build_lcp = f.build_lcp;
      const Timing short_run = timeSolve(*f.problem, p, warm);
      const Timing long_run = timeSolve(*f.problem, p, warm + sweeps);
      if (f.build_lcp == long_run.result.unbuilt)
        std::cerr << sp.name << " " << f.form << ": wrong path taken\n";
      const double sweep = std::max(0.0, (long_run.total - short_run.total) / sweeps);
      const double setup = std::max(0.0, short_run.total - warm * sweep);
      char line[512];
      std::snprintf(line, sizeof(line), "%s,%d,%d,%d,%s,%zu,%.4f,%.4f,%.3f,%.5f,", sp.name.c_str(), sp.bodies,
                    nc, rows, f.form.c_str(), f.bytes, 1e3 * f.assemble, 1e3 * setup, 1e6 * sweep,
                    1e6 * sweep / rows);
      lines.push_back(line);
      forces.push_back(long_run.result.forces);
      if (f.form == "block_sparse") reference = long_run.result.forces;
      std::cerr << line << " (" << lcs::core::statusName(long_run.result.status) << ")\n";
    }
    for (std::size_t k = 0; k < lines.size(); ++k) out << lines[k] << relDiff(forces[k], reference) << "\n";
    out.flush();
  }
  return 0;
}
