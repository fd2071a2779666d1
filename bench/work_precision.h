// What the parts of the work-precision study (bench/work_precision.cpp) share: its options,
// the problems it loads, our solvers' table and the CSV row every measurement becomes.
#pragma once

#include "peers.h"

#include "lcp_contact_solver/core/contact_solver.h"
#include "lcp_contact_solver/core/problem.h"

#include <chrono>
#include <iosfwd>
#include <limits>
#include <set>
#include <string>
#include <vector>

#ifndef LCS_PROBLEMS_DIR
#define LCS_PROBLEMS_DIR "../shared/problems"
#endif
#ifndef LCS_MUJOCO_MODEL_DIR
#define LCS_MUJOCO_MODEL_DIR "/usr/share/mujoco/model"
#endif
#ifndef LCS_SCENES_DIR
#define LCS_SCENES_DIR "config/scenes"
#endif

namespace lcs_bench::work_precision {

namespace lcs = ::lcp_contact_solver;
using Clock = std::chrono::steady_clock;
const double kNaN = std::numeric_limits<double>::quiet_NaN();

struct Options {
  std::string problems_dir = LCS_PROBLEMS_DIR;
  std::string scenes_dir = LCS_SCENES_DIR;
  std::string out = "bench/results/work_precision.csv";
  std::string regret = "bench/results/auto_regret.md";
  double budget = 2.0;     // s, per solve
  double min_time = 0.05;  // s, repeat until the repeats add up to this...
  int min_repeats = 3;     // ...and at least this many
  int max_repeats = 1000;  // ...and at most this many (25 had timed a 1 µs solve over 25 µs: up to 1.8x noise)
  double single_above = 0.5;  // s, a first run longer than this is not repeated
  std::set<std::string> families = {"fc3d", "lcp", "scenes", "mujoco"};
  std::string filter;
  std::set<std::string> solvers;  // empty = all
  std::vector<double> tolerances = {1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10};
  std::vector<int> pyramid_bases = {2, 3, 5, 9, 16};
  std::vector<int> pile_balls = {4, 12, 40, 120, 350};
  int scene_steps = 30;
  // The mujoco family (work_precision_mujoco.cpp; only when built with MuJoCo).
  std::vector<std::string> mujoco_models = {
      LCS_MUJOCO_MODEL_DIR "/humanoid/22_humanoids.xml", LCS_MUJOCO_MODEL_DIR "/humanoid100/humanoid100.xml",
      LCS_MUJOCO_MODEL_DIR "/composite/particle.xml", LCS_MUJOCO_MODEL_DIR "/composite/rope.xml"};
  std::vector<int> mujoco_steps = {100, 300};
  std::string sweep_cost;  // --sweep-cost: the CSV of sweep_cost.cpp, instead of the study
};

struct BenchProblem {
  std::string family;
  std::string name;
  lcs::core::Problem problem;
  std::string note;
};

struct OurSolver {
  std::string name;
  lcs::core::SolverKind kind;
  lcs::core::FrictionModel model = lcs::core::FrictionModel::kCoulombDisc;
  double sor = 1.0;
  bool direct = false;   // one setting, no tolerance (Lemke)
  bool friction = true;  // runs on fc3d / scenes
  bool lcp = true;       // runs on LCPs
  int max_rows = 0;      // larger problems are not run (0 = no limit)
};

// One measured setting: a row of the CSV.
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
  std::string path;  // ours: SolveResult::solver (auto's members, e.g. auto:newton->prox)
  int total_iterations = -1;  // ours: SolveResult::total_iterations (summed over islands); -1: iterations
};

// ---- problems (work_precision_problems.cpp) ----
// The fc3d and lcp problem files of the wanted families, the generated scene problems, then
// the MuJoCo steps.
std::vector<BenchProblem> loadProblems(const Options& opt);
// The steps of MuJoCo's models (work_precision_mujoco.cpp; without MuJoCo, none).
void addMujocoProblems(const Options& opt, std::vector<BenchProblem>* out);

// ---- sweep_cost.cpp ----
// Per problem: one Gauss-Seidel sweep's and one dense Cholesky's time, as CSV.
void writeSweepCosts(const std::vector<BenchProblem>& problems, std::ostream& csv);

// ---- runs (work_precision_runs.cpp) ----
std::vector<OurSolver> ourSolvers();
// "%.6g", "" for NaN, "inf" for infinity.
std::string fmt(double v);
void writeHeader(std::ostream& os);
// Every row written so far, in order (the regret table is made from them).
const std::vector<Row>& writtenRows();
// One CSV row per tolerance (or the one direct setting) of each of our solvers on bp, every
// setting timed in the same rounds (work_precision_runs.cpp).
void runOurs(const Options& opt, const BenchProblem& bp, const std::vector<const OurSolver*>& solvers,
             std::ostream& csv);
// One CSV row per setting of the peer's sweep on bp.
void runPeer(const Options& opt, const BenchProblem& bp, Peer& peer, std::ostream& csv);

}  // namespace lcs_bench::work_precision
