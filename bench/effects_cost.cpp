// Does a scene pay only for the effects it asks for? (issue #8; docs/BENCHMARKS.md "Paying
// only for what a scene uses"). In-process, ROS-free; a benchmark, never a test.
//
//   effects_cost [--bases 5,9,16] [--balls 40,120,350] [--steps 30] [--gen-balls 100,400]
//                [--budget 2] [--rounds 5] [--torsional 0.005] [--rolling 0.002] [--out FILE.csv]
//
// Problems: bench/scene_problems.h (brick pyramids with box_stack's bodies, sphere piles with
// sphere_pile's), generated with the scenes' torsional_friction and rolling_friction set (in
// a copy of their YAML files), so every contact is a 6-row rolling contact. Every variant
// below is derived from that one problem by keeping the leading rows of each contact
// (timing_util.h deriveProblem): the same geometry, the same W and d_free on the rows kept —
// exactly what the scene builds when its pairs ask for fewer rows.
//
//   (a) mu0.5        3-row frictional contacts, μ = 0.5 (the reference, "all frictional")
//       mu0_3row     3-row frictional contacts with μ = 0 (a frictional type given μ = 0)
//       frictionless 1-row frictionless contacts (what a scene with μ = 0 builds)
//   (b) mixed_1row   half of the body pairs μ = 0 as 1-row frictionless contacts, the rest μ = 0.5
//       mixed_3row   the same half as 3-row frictional contacts with μ = 0
//   (c) torsional    4 rows (μ = 0.5, μ_tor)        rolling  6 rows (μ, μ_tor, μ_roll)
//
// Each is solved cold by nlgs and by auto: per sweep (25 sweeps from a cold start, SOFA rule
// at an unreachable tolerance, the whole solve divided by 25; the marginal sweep without the
// setup is in the CSV; timing_util.h sweepRound) and to a tolerance (nlgs at 1e-4, auto at
// 1e-4 and 1e-6; wall-clock budget --budget s). The variants of a problem are measured in
// --rounds interleaved rounds and each figure is the fastest over the rounds.
//
//   (d) contact generation with disabled pairs against all pairs: a pile of n balls in a
//       bin settled in-process, then at the same poses ContactGenerator::generate() and
//       SceneSimulator::buildStep()/step() with (i) no pair disabled, (ii) every ball–ball
//       pair disabled (SceneParams::disable_collisions; most pairs of the scene), (iii) no
//       pair disabled but half of the touching ball–ball pairs made frictionless through
//       friction_pairs (a mixed scene), with the broadphase pairs, skipped pairs and
//       narrowphase tests of ContactGenerationStats.
//
// Times are CPU time of the benchmark's thread (timing_util.h: the machine is shared), the
// fastest of the repeats. CSV: one row per measurement (section, problem, variant, sizes,
// solver, mode, tolerance, iterations, seconds, µs per sweep, residual, status, generation
// counters, 1-min load; step_solve_wall is the core's wall-clock solve time of step()).
//
// The parts: effects_cost_scenes.cpp (the variants, the pile, the rolling scenes),
// effects_cost_measure.cpp (the measurements), effects_cost_report.cpp (CSV and tables).
#include "effects_cost.h"
#include "cli_options.h"
#include "scene_problems.h"

#include <unistd.h>

#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace lcs = lcp_contact_solver;
namespace ec = lcs_bench::effects_cost;
using lcs_bench::Clock;
using lcs_bench::secondsSince;

namespace {

struct Options {
  std::vector<int> bases = {5, 9, 16};
  std::vector<int> balls = {40, 120, 350};
  std::vector<int> gen_balls = {100, 400};
  int steps = 30;
  double budget = 2.0;
  int rounds = 5;
  double torsional = 0.005, rolling = 0.002;
  std::string out = "bench/results/effects_cost.csv";
};

// Fills o from the command line (CLI11); -1 to go on, else the exit code (0 after --help).
int parseOptions(int argc, char** argv, Options* options) {
  Options& o = *options;
  CLI::App app{"effects_cost: what each contact effect costs (in-process, CSV)"};
  app.option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  lcs_bench::addIntListOption(app, "--bases", &o.bases, "brick pyramids: bricks at the base, comma list",
                              "5,9,16");
  lcs_bench::addIntListOption(app, "--balls", &o.balls, "sphere piles: balls, comma list", "40,120,350");
  app.add_option("--steps", o.steps, "in-process steps before a pile problem is taken")
      ->capture_default_str();
  lcs_bench::addIntListOption(app, "--gen-balls", &o.gen_balls,
                              "contact generation: balls in the bin, comma list", "100,400");
  app.add_option("--budget", o.budget, "wall-clock budget of a solve to a tolerance (s)")
      ->capture_default_str();
  app.add_option("--rounds", o.rounds, "interleaved rounds; the fastest counts")->capture_default_str();
  app.add_option("--torsional", o.torsional, "torsional friction of the 6-row contacts")
      ->capture_default_str();
  app.add_option("--rolling", o.rolling, "rolling friction of the 6-row contacts")->capture_default_str();
  app.add_option("--out", o.out, "the CSV to write")->capture_default_str();
  return lcs_bench::parseArguments(app, argc, argv);
}

// The scene problems with 6-row contacts (generated from the rolling copies of the scenes).
bool generateProblems(const Options& o, std::vector<lcs_bench::SceneProblem>* problems) {
  const auto t_gen = Clock::now();
  const std::string dir = ec::rollingScenesDir(o.torsional, o.rolling);
  try {
    *problems = lcs_bench::makeSceneProblems(dir, o.bases, o.balls, o.steps);
  } catch (const std::exception& e) {
    std::filesystem::remove_all(dir);
    std::fprintf(stderr, "effects_cost: %s\n", e.what());
    return false;
  }
  std::filesystem::remove_all(dir);
  std::fprintf(stderr, "generated %zu problems (6-row contacts) in %.1f s\n", problems->size(),
               secondsSince(t_gen));
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  if (const int code = parseOptions(argc, argv, &o); code >= 0) return code;
  std::ofstream csv(o.out);
  if (!csv) {
    std::fprintf(stderr, "effects_cost: cannot write %s\n", o.out.c_str());
    return 1;
  }
  ec::csvHeader(csv);
  std::printf("effects_cost: load average %s at the start, %ld cores\n", lcs_bench::loadAverageText().c_str(),
              sysconf(_SC_NPROCESSORS_ONLN));

  std::vector<lcs_bench::SceneProblem> problems;
  if (!generateProblems(o, &problems)) return 1;

  ec::SolveTables tables;
  std::vector<std::string> names;
  for (const lcs_bench::SceneProblem& sp : problems) {
    if (sp.problem.contacts.empty()) continue;
    for (const lcs::core::Contact& c : sp.problem.contacts)
      if (c.rows != 6) throw std::runtime_error(sp.name + ": a contact without 6 rows");
    names.push_back(sp.name);
    ec::measureProblem(sp.name, ec::variantsOf(sp.problem, o.torsional, o.rolling), o.budget, o.rounds, csv,
                       &tables);
  }
  ec::printSolveTables(names, tables);

  ec::printGenerationHeader();
  for (int n : o.gen_balls) {
    const int reps = n <= 150 ? 200 : 50;
    ec::reportGeneration(csv, n, reps, ec::measureGeneration(LCS_SCENES_DIR, n, reps));
  }
  std::printf("\neffects_cost: load average %s at the end; CSV %s\n", lcs_bench::loadAverageText().c_str(),
              o.out.c_str());
  return 0;
}
