// What softness and erp cost and buy (docs/SOLVERS.md "Penetration correction and softness"):
// steps a shipped scene in-process for every (erp, softness) pair and writes one CSV row
// each: Gauss-Seidel sweeps per step to the tolerance, solve time, the resting penetration
// and how much the bodies still move. Stiffer contacts (less softness) are harder to solve;
// softer ones sink further. Not a test: numbers depend on the machine.
//
//   stabilization_tradeoff [--scene box_stack] [--steps 300] [--tolerance 1e-6] [--out file.csv]
#include "lcp_contact_solver/scene/scene.h"
#include "lcp_contact_solver/scene/scene_simulator.h"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

namespace lcs = lcp_contact_solver;
namespace scene = lcp_contact_solver::scene;

namespace {

struct Options {
  std::string scenes_dir = LCS_SCENES_DIR;
  std::string scene = "box_stack";
  int steps = 300;
  double tolerance = 1e-6;
  std::string out = "stabilization.csv";
};

// The command line (CLI11); exits after --help (0) or a bad option (2).
Options parse(int argc, char** argv) {
  Options o;
  CLI::App app{"stabilization_tradeoff: what softness and erp cost and buy (in-process, CSV)"};
  app.option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  app.add_option("--scene", o.scene, "the shipped scene stepped")->capture_default_str();
  app.add_option("--scenes-dir", o.scenes_dir, "where the scenes are")->capture_default_str();
  app.add_option("--steps", o.steps, "steps per (erp, softness) pair")->capture_default_str();
  app.add_option("--tolerance", o.tolerance, "nlgs tolerance")->capture_default_str();
  app.add_option("--out", o.out, "the CSV to write")->capture_default_str();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    std::exit(app.exit(e) == 0 ? 0 : 2);
  }
  return o;
}

struct Row {
  double erp, softness;
  double mean_sweeps = 0, max_sweeps = 0, mean_solve_ms = 0;
  double max_depth = 0;  // deepest contact at the end (m)
  double max_speed = 0;  // fastest body at the end (m/s)
  int unconverged = 0;
};

Row run(const Options& o, double erp, double softness) {
  scene::Scene s = scene::loadNamedScene(o.scenes_dir, o.scene);
  s.params.erp = erp;
  s.params.softness = softness;
  s.params.solver.solver = lcs::core::SolverKind::kNlgs;
  s.params.solver.tolerance = o.tolerance;
  s.params.solver.maxIt = 5000;
  scene::SceneSimulator sim(std::move(s));
  Row row{erp, softness};
  int counted = 0;
  for (int k = 0; k < o.steps; ++k) {
    sim.step();
    const lcs::core::SolveResult& r = sim.lastSolve();
    if (sim.lastProblem().problem.contacts.empty()) continue;
    if (k < o.steps / 3) continue;  // the settling transient is not the steady cost
    ++counted;
    row.mean_sweeps += r.iterations;
    row.max_sweeps = std::max(row.max_sweeps, static_cast<double>(r.iterations));
    row.mean_solve_ms += 1e3 * r.solve_time;
    row.unconverged += r.converged ? 0 : 1;
  }
  if (counted > 0) {
    row.mean_sweeps /= counted;
    row.mean_solve_ms /= counted;
  }
  for (const scene::SceneContact& f : sim.lastProblem().frames)
    row.max_depth = std::max(row.max_depth, f.depth);
  for (const scene::RigidBody& b : sim.scene().bodies)
    if (!b.is_static) row.max_speed = std::max(row.max_speed, b.linear_velocity.norm());
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  const Options o = parse(argc, argv);
  std::ofstream csv(o.out);
  if (!csv) {
    std::cerr << "cannot write " << o.out << "\n";
    return 1;
  }
  csv << "scene,erp,softness,mean_sweeps,max_sweeps,mean_solve_ms,unconverged_steps,max_depth_m,max_speed_"
         "mps\n";
  std::printf("%-10s %5s %9s %12s %10s %14s %12s %12s\n", "scene", "erp", "softness", "mean sweeps",
              "max sweeps", "mean solve ms", "depth (mm)", "speed (m/s)");
  for (double erp : {0.1, 0.2, 0.5}) {
    for (double softness : {0.0, 1e-7, 1e-6, 1e-5, 1e-4}) {
      const Row r = run(o, erp, softness);
      csv << o.scene << "," << r.erp << "," << r.softness << "," << r.mean_sweeps << "," << r.max_sweeps
          << "," << r.mean_solve_ms << "," << r.unconverged << "," << r.max_depth << "," << r.max_speed
          << "\n";
      std::printf("%-10s %5.2f %9.0e %12.1f %10.0f %14.3f %12.4f %12.2e\n", o.scene.c_str(), r.erp,
                  r.softness, r.mean_sweeps, r.max_sweeps, r.mean_solve_ms, 1e3 * r.max_depth, r.max_speed);
    }
  }
  return 0;
}
