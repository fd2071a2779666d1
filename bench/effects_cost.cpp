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
#include "timing_util.h"
#include "scene_problems.h"

#include "lcp_contact_solver/core/contact_solver.h"
#include "lcp_contact_solver/scene/contact_generator.h"
#include "lcp_contact_solver/scene/scene.h"
#include "lcp_contact_solver/scene/scene_params.h"
#include "lcp_contact_solver/scene/scene_simulator.h"

#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace lcs = lcp_contact_solver;
namespace sc = lcp_contact_solver::scene;
using lcs_bench::Clock;
using lcs_bench::ContactModel;
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

int usage(int code) {
  std::fprintf(code ? stderr : stdout,
               "usage: effects_cost [--bases 5,9,16] [--balls 40,120,350] [--steps 30] [--gen-balls 100,400]\n"
               "                    [--budget S] [--rounds N] [--torsional M] [--rolling M] [--out FILE.csv]\n");
  return code;
}

std::ofstream g_csv;

void csvHeader() {
  g_csv << "section,problem,variant,contacts,rows,frictionless_contacts,solver,ran,mode,tolerance,iterations,seconds,"
           "us_per_sweep,us_marginal_sweep,residual,status,broadphase_pairs,skipped_disabled,narrowphase_tests,load1\n";
}

struct CsvRow {
  CsvRow(std::string section_, std::string problem_, std::string variant_, int contacts_, int rows_,
         int frictionless_, std::string solver_, std::string ran_, std::string mode_)
      : section(std::move(section_)), problem(std::move(problem_)), variant(std::move(variant_)),
        contacts(contacts_), rows(rows_), frictionless(frictionless_), solver(std::move(solver_)),
        ran(std::move(ran_)), mode(std::move(mode_)) {}
  std::string section, problem, variant;
  int contacts = 0, rows = 0, frictionless = 0;
  std::string solver, ran, mode;
  double tolerance = 0.0;
  long iterations = 0;
  double seconds = 0.0, us_per_sweep = std::nan(""), us_marginal = std::nan(""), residual = std::nan("");
  std::string status;
  long broadphase = -1, skipped = -1, narrowphase = -1;
};

std::string num(double v, const char* fmt = "%.6g") {
  if (!std::isfinite(v)) return "";
  char b[64];
  std::snprintf(b, sizeof(b), fmt, v);
  return b;
}

void csvWrite(const CsvRow& r) {
  g_csv << r.section << ',' << r.problem << ',' << r.variant << ',' << r.contacts << ',' << r.rows << ','
        << r.frictionless << ',' << r.solver << ',' << r.ran << ',' << r.mode << ',' << num(r.tolerance) << ','
        << r.iterations << ',' << num(r.seconds) << ',' << num(r.us_per_sweep) << ',' << num(r.us_marginal) << ','
        << num(r.residual) << ','
        << r.status << ',' << (r.broadphase >= 0 ? std::to_string(r.broadphase) : "") << ','
        << (r.skipped >= 0 ? std::to_string(r.skipped) : "") << ','
        << (r.narrowphase >= 0 ? std::to_string(r.narrowphase) : "") << ',' << num(lcs_bench::loadAverage1(), "%.2f")
        << '\n';
  g_csv.flush();
}

int frictionlessCount(const lcs::core::Problem& p) {
  int n = 0;
  for (const lcs::core::Contact& c : p.contacts) n += c.type == lcs::core::ContactType::kFrictionless ? 1 : 0;
  return n;
}

// Body pair of a scene contact id: id = (A << 40) | (B << 16) | slot.
std::int64_t pairOf(std::int64_t id) { return id >> 16; }

// "Half of the body pairs": every other pair in order of first appearance.
std::vector<bool> halfThePairs(const lcs::core::Problem& p) {
  std::map<std::int64_t, int> index;
  std::vector<bool> pick(p.contacts.size());
  for (std::size_t i = 0; i < p.contacts.size(); ++i) {
    auto it = index.emplace(pairOf(p.contacts[i].id), static_cast<int>(index.size())).first;
    pick[i] = it->second % 2 == 1;
  }
  return pick;
}

struct Variant {
  std::string name;
  lcs::core::Problem problem;
};

std::vector<Variant> variantsOf(const lcs::core::Problem& p6, double mu_tor, double mu_roll) {
  using T = lcs::core::ContactType;
  const ContactModel frictional{T::kFrictional, 3, 0.5, 0.0, 0.0};
  const ContactModel frictional0{T::kFrictional, 3, 0.0, 0.0, 0.0};
  const ContactModel frictionless{T::kFrictionless, 1, 0.0, 0.0, 0.0};
  const ContactModel torsional{T::kTorsional, 4, 0.5, mu_tor, 0.0};
  const ContactModel rolling{T::kRolling, 6, 0.5, mu_tor, mu_roll};
  const std::vector<bool> half = halfThePairs(p6);
  std::vector<ContactModel> mixed1, mixed3;
  for (bool h : half) {
    mixed1.push_back(h ? frictionless : frictional);
    mixed3.push_back(h ? frictional0 : frictional);
  }
  return {
      {"mu0.5", lcs_bench::deriveUniform(p6, frictional)},
      {"mu0_3row", lcs_bench::deriveUniform(p6, frictional0)},
      {"frictionless", lcs_bench::deriveUniform(p6, frictionless)},
      {"mixed_1row", lcs_bench::deriveProblem(p6, mixed1)},
      {"mixed_3row", lcs_bench::deriveProblem(p6, mixed3)},
      {"torsional", lcs_bench::deriveUniform(p6, torsional)},
      {"rolling", lcs_bench::deriveUniform(p6, rolling)},
  };
}

// Results kept for the printed table: [problem][variant][key] = value.
std::map<std::string, std::map<std::string, std::map<std::string, double>>> g_table;
std::map<std::string, std::map<std::string, std::map<std::string, std::string>>> g_ran;

struct ToTol {
  lcs::core::SolverKind kind;
  double tol;
};
const ToTol kToTol[] = {{lcs::core::SolverKind::kNlgs, 1e-4}, {lcs::core::SolverKind::kAuto, 1e-4}, {lcs::core::SolverKind::kAuto, 1e-6}};
const lcs::core::SolverKind kSweepSolvers[] = {lcs::core::SolverKind::kNlgs, lcs::core::SolverKind::kAuto};

// Every measurement of every variant of one problem, in `rounds` interleaved rounds.
void measureProblem(const std::string& problem_name, const std::vector<Variant>& variants, double budget, int rounds) {
  const int sweeps = 20;  // 5 + 20 sweeps from a cold start: the early sweeps, where contacts still move
  const std::size_t nv = variants.size();
  std::vector<std::array<lcs_bench::SweepAcc, 2>> sweep_acc(nv);
  std::vector<std::array<lcs_bench::SolveAcc, 3>> tol_acc(nv);
  lcs_bench::interleavedRounds(rounds, nv, [&](std::size_t i) {
    for (int k = 0; k < 2; ++k) {
      lcs::core::SolverParams params;
      params.solver = kSweepSolvers[k];
      lcs_bench::sweepRound(variants[i].problem, params, sweeps, &sweep_acc[i][k]);
    }
    for (int k = 0; k < 3; ++k)
      lcs_bench::solveRound(variants[i].problem, lcs_bench::toleranceParams(kToTol[k].kind, kToTol[k].tol, budget, 100000),
                            &tol_acc[i][k]);
  });
  for (std::size_t i = 0; i < nv; ++i) {
    const Variant& v = variants[i];
    const lcs::core::Problem& p = v.problem;
    const int rows = p.rowCount(), nc = static_cast<int>(p.contacts.size()), nf = frictionlessCount(p);
    auto& tab = g_table[problem_name][v.name];
    auto& ran = g_ran[problem_name][v.name];
    tab["contacts"] = nc;
    tab["rows"] = rows;
    for (int k = 0; k < 2; ++k) {
      const lcs_bench::SweepTiming st = lcs_bench::sweepTiming(sweep_acc[i][k]);
      CsvRow r{"solve", problem_name, v.name, nc, rows, nf, lcs::core::solverName(kSweepSolvers[k]), st.solver, "per_sweep"};
      r.iterations = st.sweeps;
      r.seconds = st.per_sweep * st.sweeps;
      r.us_per_sweep = 1e6 * st.per_sweep;
      r.us_marginal = 1e6 * st.marginal;
      r.residual = st.result.residual;
      r.status = lcs::core::statusName(st.result.status);
      csvWrite(r);
      tab[std::string("sweep_") + lcs::core::solverName(kSweepSolvers[k])] = 1e6 * st.per_sweep;
      tab[std::string("marginal_") + lcs::core::solverName(kSweepSolvers[k])] = 1e6 * st.marginal;
      ran[std::string("sweep_") + lcs::core::solverName(kSweepSolvers[k])] = st.solver;
    }
    for (int k = 0; k < 3; ++k) {
      const lcs_bench::SolveAcc& a = tol_acc[i][k];
      CsvRow r{"solve", problem_name, v.name, nc, rows, nf, lcs::core::solverName(kToTol[k].kind), a.result.solver,
               "to_tolerance"};
      r.tolerance = kToTol[k].tol;
      r.iterations = a.result.iterations;
      r.seconds = a.best;
      r.residual = a.result.residual;
      r.status = lcs::core::statusName(a.result.status);
      csvWrite(r);
      const std::string key = std::string(lcs::core::solverName(kToTol[k].kind)) + "@" + num(kToTol[k].tol, "%.0e");
      tab["t_" + key] = a.result.converged ? 1e3 * a.best : std::nan("");
      tab["it_" + key] = a.result.iterations;
      ran["t_" + key] = a.result.solver;
    }
    std::fprintf(stderr, "  %-16s %-13s %5d contacts %6d rows: nlgs %.3f us/sweep, auto(%s) %.3f us/sweep\n",
                 problem_name.c_str(), v.name.c_str(), nc, rows, tab["sweep_nlgs"], ran["sweep_auto"].c_str(),
                 tab["sweep_auto"]);
  }
}

// ---- (d) contact generation ------------------------------------------------------------

// n balls of r = 0.05 m, 0.2 kg in a square bin of static walls, as a loose lattice (the
// geometry of bench/scene_problems.cpp's sphere piles, written here because that generator
// does not hand out its simulator).
std::string pileUrdf(int n) {
  const double r = 0.05, pitch = 0.104;
  int side = 2;
  while (side * side * side < n) ++side;
  const double inner = side * pitch + 0.01, wall = 0.05, height = 0.3 + 0.11 * (n / (side * side) + 1);
  std::ostringstream u;
  u.precision(17);
  u << "<?xml version=\"1.0\"?>\n<robot name=\"pile\">\n  <link name=\"world\"/>\n";
  auto wallBox = [&](const std::string& name, double sx, double sy, double x, double y) {
    u << "  <link name=\"" << name << "\"><collision><geometry><box size=\"" << sx << " " << sy << " " << height
      << "\"/></geometry></collision></link>\n  <joint name=\"" << name
      << "_joint\" type=\"fixed\"><parent link=\"world\"/><child link=\"" << name << "\"/><origin xyz=\"" << x << " "
      << y << " " << 0.5 * height << "\"/></joint>\n";
  };
  const double h = 0.5 * (inner + wall);
  wallBox("wall_north", inner + 2 * wall, wall, 0, h);
  wallBox("wall_south", inner + 2 * wall, wall, 0, -h);
  wallBox("wall_east", wall, inner, h, 0);
  wallBox("wall_west", wall, inner, -h, 0);
  int k = 0;
  for (int layer = 0; k < n; ++layer) {
    const int per_row = layer % 2 == 0 ? side : side - 1;
    const double shift = layer % 2 == 0 ? 0.0 : 0.5 * pitch;
    for (int i = 0; i < per_row && k < n; ++i)
      for (int j = 0; j < per_row && k < n; ++j) {
        const double x = (i - 0.5 * (side - 1)) * pitch + shift + 0.003 * std::sin(1.7 * k);
        const double y = (j - 0.5 * (side - 1)) * pitch + shift + 0.003 * std::cos(2.3 * k);
        const double z = r + 0.002 + layer * 0.09;
        const std::string name = "ball_" + std::to_string(++k);
        u << "  <link name=\"" << name << "\"><inertial><mass value=\"0.2\"/><inertia ixx=\"0.0002\" ixy=\"0\" "
          << "ixz=\"0\" iyy=\"0.0002\" iyz=\"0\" izz=\"0.0002\"/></inertial><collision><geometry><sphere "
          << "radius=\"0.05\"/></geometry></collision></link>\n  <joint name=\"" << name
          << "_joint\" type=\"floating\"><parent link=\"world\"/><child link=\"" << name << "\"/><origin xyz=\"" << x
          << " " << y << " " << z << "\"/></joint>\n";
      }
  }
  u << "</robot>\n";
  return u.str();
}

struct GenTiming {
  double generate = 0.0, build = 0.0, step = 0.0, step_solve = 0.0;  // s per call (fastest)
  sc::ContactGenerationStats stats;
  int contacts = 0, rows = 0, frictionless = 0;
  std::string step_status;
};

// The fastest of the repeats: on a shared machine the least disturbed one.
double fastest(const std::vector<double>& v) {
  return v.empty() ? std::nan("") : *std::min_element(v.begin(), v.end());
}

GenTiming timeGeneration(const sc::Scene& settled, int reps) {
  GenTiming g;
  {
    sc::ContactGenerator gen(settled);
    gen.generate();  // the id memory of a running simulation
    std::vector<double> t;
    for (int k = 0; k < reps; ++k) {
      const double c0 = lcs_bench::threadCpuSeconds();
      const std::vector<sc::SceneContact> frames = gen.generate();
      t.push_back(lcs_bench::threadCpuSeconds() - c0);
      g.contacts = static_cast<int>(frames.size());
    }
    g.generate = fastest(t);
    g.stats = gen.lastStats();
  }
  std::vector<double> tb, ts, tsolve;
  for (int k = 0; k < std::max(2, reps / 10); ++k) {
    {
      sc::SceneSimulator sim(settled);
      const double c0 = lcs_bench::threadCpuSeconds();
      const sc::StepProblem& sp = sim.buildStep();
      tb.push_back(lcs_bench::threadCpuSeconds() - c0);
      g.rows = sp.problem.rowCount();
      g.frictionless = frictionlessCount(sp.problem);
    }
    {
      sc::SceneSimulator sim(settled);
      const double c0 = lcs_bench::threadCpuSeconds();
      const sc::StepStats st = sim.step();
      ts.push_back(lcs_bench::threadCpuSeconds() - c0);
      tsolve.push_back(st.time_solve);
      g.step_status = st.solved ? lcs::core::statusName(st.status) : "no_contacts";
    }
  }
  g.build = fastest(tb);
  g.step = fastest(ts);
  g.step_solve = fastest(tsolve);
  return g;
}

struct GenRow {
  std::string variant;
  GenTiming t;
};

std::vector<GenRow> measureGeneration(const std::string& scenes_dir, int n, int reps) {
  sc::SceneParams params = sc::loadSceneParams(scenes_dir + "/sphere_pile.yaml");
  params.solver.solver = lcs::core::SolverKind::kAuto;
  params.solver.tolerance = 1e-4;
  params.solver.maxIt = 500;
  sc::Scene scene = sc::loadSceneFromUrdfString(pileUrdf(n), params, "effects_pile");
  sc::SceneSimulator sim(std::move(scene));
  for (int k = 0; k < 40; ++k) sim.step();  // settle: the balls fall into a pile
  const sc::Scene& settled = sim.scene();

  // (ii) every ball-ball pair disabled: n(n-1)/2 of the n(n-1)/2 + 5n candidate pairs.
  std::vector<std::string> balls;
  for (const sc::RigidBody& b : settled.bodies)
    if (!b.is_static) balls.push_back(b.name);
  sc::Scene disabled = settled;
  for (std::size_t i = 0; i < balls.size(); ++i)
    for (std::size_t j = i + 1; j < balls.size(); ++j) disabled.params.disable_collisions.emplace_back(balls[i], balls[j]);

  // (iii) mixed: half of the touching ball-ball pairs frictionless via friction_pairs.
  sc::Scene mixed = settled;
  {
    sc::ContactGenerator gen(settled);
    std::set<std::pair<int, int>> touching;
    for (const sc::SceneContact& f : gen.generate())
      if (!settled.bodies[f.body_a].is_static && !settled.bodies[f.body_b].is_static)
        touching.emplace(f.body_a, f.body_b);
    int k = 0;
    for (const auto& [a, b] : touching)
      if (k++ % 2 == 0) mixed.params.friction_pairs.push_back({settled.bodies[a].name, settled.bodies[b].name, 0.0});
  }
  std::fprintf(stderr, "  pile of %d balls: %zu ball-ball pairs disabled; %zu friction_pairs with mu = 0 (mixed)\n", n,
               disabled.params.disable_collisions.size(), mixed.params.friction_pairs.size());
  // Interleaved rounds; each time is the fastest over them.
  std::vector<GenRow> rows = {{"all_pairs", {}}, {"ball_ball_disabled", {}}, {"mixed_friction_pairs", {}}};
  const sc::Scene* scenes[3] = {&settled, &disabled, &mixed};
  const int rounds = 5;
  bool first[3] = {true, true, true};
  lcs_bench::interleavedRounds(rounds, 3, [&](std::size_t k) {
    const GenTiming g = timeGeneration(*scenes[k], std::max(1, reps / rounds));
    if (first[k]) {
      rows[k].t = g;
      first[k] = false;
      return;
    }
    GenTiming& t = rows[k].t;
    t.generate = std::min(t.generate, g.generate);
    t.build = std::min(t.build, g.build);
    t.step = std::min(t.step, g.step);
    t.step_solve = std::min(t.step_solve, g.step_solve);
  });
  return rows;
}

// Copies the two scene YAMLs the generators read into a temporary folder with torsional and
// rolling friction set, so every contact of the generated problems has 6 rows.
std::string rollingScenesDir(double torsional, double rolling) {
  char tmpl[] = "/tmp/effects_cost_scenes_XXXXXX";
  if (!mkdtemp(tmpl)) throw std::runtime_error("cannot create a temporary folder");
  const std::string dir = tmpl;
  for (const char* name : {"box_stack.yaml", "sphere_pile.yaml"}) {
    std::ifstream in(std::string(LCS_SCENES_DIR) + "/" + name);
    std::stringstream text;
    text << in.rdbuf();
    if (text.str().find("torsional_friction") != std::string::npos || text.str().find("rolling_friction") != std::string::npos)
      throw std::runtime_error(std::string(name) + " already sets torsional/rolling friction");
    std::ofstream out(dir + "/" + name);
    out << text.str() << "\ntorsional_friction: " << torsional << "\nrolling_friction: " << rolling << "\n";
  }
  return dir;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h") return usage(0);
    if (i + 1 >= argc) return usage(2);
    const std::string v = argv[++i];
    if (a == "--bases") o.bases = lcs_bench::parseIntList(v);
    else if (a == "--balls") o.balls = lcs_bench::parseIntList(v);
    else if (a == "--gen-balls") o.gen_balls = lcs_bench::parseIntList(v);
    else if (a == "--steps") o.steps = std::stoi(v);
    else if (a == "--budget") o.budget = std::stod(v);
    else if (a == "--rounds") o.rounds = std::stoi(v);
    else if (a == "--torsional") o.torsional = std::stod(v);
    else if (a == "--rolling") o.rolling = std::stod(v);
    else if (a == "--out") o.out = v;
    else return usage(2);
  }
  g_csv.open(o.out);
  if (!g_csv) {
    std::fprintf(stderr, "effects_cost: cannot write %s\n", o.out.c_str());
    return 1;
  }
  csvHeader();
  std::printf("effects_cost: load average %s at the start, %ld cores\n", lcs_bench::loadAverageText().c_str(),
              sysconf(_SC_NPROCESSORS_ONLN));

  const auto t_gen = Clock::now();
  const std::string dir = rollingScenesDir(o.torsional, o.rolling);
  std::vector<lcs_bench::SceneProblem> problems;
  try {
    problems = lcs_bench::makeSceneProblems(dir, o.bases, o.balls, o.steps);
  } catch (const std::exception& e) {
    std::filesystem::remove_all(dir);
    std::fprintf(stderr, "effects_cost: %s\n", e.what());
    return 1;
  }
  std::filesystem::remove_all(dir);
  std::fprintf(stderr, "generated %zu problems (6-row contacts) in %.1f s\n", problems.size(), secondsSince(t_gen));

  std::vector<std::string> names;
  for (const lcs_bench::SceneProblem& sp : problems) {
    if (sp.problem.contacts.empty()) continue;
    for (const lcs::core::Contact& c : sp.problem.contacts)
      if (c.rows != 6) throw std::runtime_error(sp.name + ": a contact without 6 rows");
    names.push_back(sp.name);
    measureProblem(sp.name, variantsOf(sp.problem, o.torsional, o.rolling), o.budget, o.rounds);
  }

  // ---- tables ----
  auto cell = [](double v, const char* fmt = "%.3g") { return std::isfinite(v) ? num(v, fmt) : std::string("✗"); };
  auto ratio = [](double a, double b) {
    return std::isfinite(a) && std::isfinite(b) && b > 0 ? num(a / b, "%.2f") : std::string("–");
  };
  std::printf("\n(a)(b)(c) per sweep, µs (fixed sweeps, cold; auto runs what it picks: pgs without friction)\n");
  std::printf("| problem | contacts | variant | rows | nlgs µs/sweep | ÷ mu0.5 | auto (ran) µs/sweep | ÷ mu0.5 |\n");
  std::printf("|---|---:|---|---:|---:|---:|---:|---:|\n");
  for (const std::string& n : names) {
    const auto& t = g_table[n];
    for (const char* vn : {"mu0.5", "mu0_3row", "frictionless", "mixed_1row", "mixed_3row", "torsional", "rolling"}) {
      const auto& m = t.at(vn);
      const auto& ref = t.at("mu0.5");
      std::printf("| %s | %.0f | %s | %.0f | %s | %s | %s (%s) | %s |\n", n.c_str(), m.at("contacts"), vn, m.at("rows"),
                  cell(m.at("sweep_nlgs")).c_str(),
                  ratio(m.at("sweep_nlgs"), ref.at("sweep_nlgs")).c_str(), cell(m.at("sweep_auto")).c_str(),
                  g_ran[n][vn]["sweep_auto"].c_str(), ratio(m.at("sweep_auto"), ref.at("sweep_auto")).c_str());
    }
  }
  std::printf("\nto a tolerance, ms, fastest of the repeats (✗ = not reached within the budget), sweeps/iterations in brackets\n");
  std::printf("| problem | variant | nlgs 1e-4 | auto 1e-4 (ran) | auto 1e-6 (ran) |\n|---|---|---:|---:|---:|\n");
  for (const std::string& n : names)
    for (const char* vn : {"mu0.5", "mu0_3row", "frictionless", "mixed_1row", "mixed_3row", "torsional", "rolling"}) {
      const auto& m = g_table[n][vn];
      auto& ran = g_ran[n][vn];
      std::printf("| %s | %s | %s (%.0f) | %s (%.0f, %s) | %s (%.0f, %s) |\n", n.c_str(), vn,
                  cell(m.at("t_nlgs@1e-04")).c_str(), m.at("it_nlgs@1e-04"), cell(m.at("t_auto@1e-04")).c_str(),
                  m.at("it_auto@1e-04"), ran["t_auto@1e-04"].c_str(), cell(m.at("t_auto@1e-06")).c_str(),
                  m.at("it_auto@1e-06"), ran["t_auto@1e-06"].c_str());
    }

  // ---- (d) ----
  std::printf("\n(d) contact generation at the same poses (fastest call of the repeats)\n");
  std::printf("| pile | variant | broadphase pairs | skipped (disabled) | narrowphase tests | contacts | rows | "
              "generate() µs | buildStep() µs | step() ms (status) |\n|---|---|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (int n : o.gen_balls) {
    const int reps = n <= 150 ? 200 : 50;
    const std::vector<GenRow> rows = measureGeneration(LCS_SCENES_DIR, n, reps);
    for (const GenRow& g : rows) {
      const std::string pname = "pile_" + std::to_string(n);
      CsvRow r{"generation", pname, g.variant, g.t.contacts, g.t.rows, g.t.frictionless, "", "", "generate"};
      r.iterations = reps;
      r.seconds = g.t.generate;
      r.broadphase = g.t.stats.broadphase_pairs;
      r.skipped = g.t.stats.skipped_disabled;
      r.narrowphase = g.t.stats.narrowphase_tests;
      csvWrite(r);
      r.mode = "buildStep";
      r.seconds = g.t.build;
      csvWrite(r);
      r.mode = "step";
      r.seconds = g.t.step;
      r.status = g.t.step_status;
      csvWrite(r);
      r.mode = "step_solve_wall";
      r.seconds = g.t.step_solve;
      csvWrite(r);
      std::printf("| %s | %s | %d | %d | %d | %d | %d | %.0f | %.0f | %.2f (%s) |\n", pname.c_str(),
                  g.variant.c_str(), g.t.stats.broadphase_pairs, g.t.stats.skipped_disabled,
                  g.t.stats.narrowphase_tests, g.t.contacts, g.t.rows, 1e6 * g.t.generate, 1e6 * g.t.build,
                  1e3 * g.t.step, g.t.step_status.c_str());
    }
    std::printf("| %s | disabled ÷ all | | | %s | | | %s | %s | %s |\n", ("pile_" + std::to_string(n)).c_str(),
                ratio(rows[1].t.stats.narrowphase_tests, rows[0].t.stats.narrowphase_tests).c_str(),
                ratio(rows[1].t.generate, rows[0].t.generate).c_str(), ratio(rows[1].t.build, rows[0].t.build).c_str(),
                ratio(rows[1].t.step, rows[0].t.step).c_str());
    std::printf("| %s | mixed ÷ all | | | | | | %s | %s | %s |\n", ("pile_" + std::to_string(n)).c_str(),
                ratio(rows[2].t.generate, rows[0].t.generate).c_str(), ratio(rows[2].t.build, rows[0].t.build).c_str(),
                ratio(rows[2].t.step, rows[0].t.step).c_str());
    std::fflush(stdout);
  }
  std::printf("\neffects_cost: load average %s at the end; CSV %s\n", lcs_bench::loadAverageText().c_str(),
              o.out.c_str());
  return 0;
}
