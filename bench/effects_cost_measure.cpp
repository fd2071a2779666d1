// The measurements of the effects-cost benchmark: every variant of a problem solved per sweep
// and to a tolerance in interleaved rounds, and contact generation on a settled pile with
// and without disabled pairs. CPU time of this thread, the fastest of the repeats.
#include "effects_cost.h"

#include "lcp_contact_solver/core/contact_solver.h"
#include "lcp_contact_solver/scene/scene_params.h"
#include "lcp_contact_solver/scene/scene_simulator.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

namespace lcs_bench::effects_cost {

namespace {

struct ToTol {
  lcs::core::SolverKind kind;
  double tol;
};
const ToTol kToTol[] = {{lcs::core::SolverKind::kNlgs, 1e-4},
                        {lcs::core::SolverKind::kAuto, 1e-4},
                        {lcs::core::SolverKind::kAuto, 1e-6}};
const lcs::core::SolverKind kSweepSolvers[] = {lcs::core::SolverKind::kNlgs, lcs::core::SolverKind::kAuto};

// The figures of one variant: CSV rows, and the values of the printed tables.
void recordVariant(const std::string& problem_name, const Variant& v,
                   const std::array<lcs_bench::SweepAcc, 2>& sweeps,
                   const std::array<lcs_bench::SolveAcc, 3>& to_tol, std::ostream& csv, SolveTables* tables) {
  const lcs::core::Problem& p = v.problem;
  const int rows = p.rowCount(), nc = static_cast<int>(p.contacts.size()), nf = frictionlessCount(p);
  auto& tab = tables->values[problem_name][v.name];
  auto& ran = tables->ran[problem_name][v.name];
  tab["contacts"] = nc;
  tab["rows"] = rows;
  for (int k = 0; k < 2; ++k) {
    const lcs_bench::SweepTiming st = lcs_bench::sweepTiming(sweeps[k]);
    CsvRow r{"solve",   problem_name, v.name, nc, rows, nf, lcs::core::solverName(kSweepSolvers[k]),
             st.solver, "per_sweep"};
    r.iterations = st.sweeps;
    r.seconds = st.per_sweep * st.sweeps;
    r.us_per_sweep = 1e6 * st.per_sweep;
    r.us_marginal = 1e6 * st.marginal;
    r.residual = st.result.residual;
    r.status = lcs::core::statusName(st.result.status);
    csvWrite(csv, r);
    tab[std::string("sweep_") + lcs::core::solverName(kSweepSolvers[k])] = 1e6 * st.per_sweep;
    tab[std::string("marginal_") + lcs::core::solverName(kSweepSolvers[k])] = 1e6 * st.marginal;
    ran[std::string("sweep_") + lcs::core::solverName(kSweepSolvers[k])] = st.solver;
  }
  for (int k = 0; k < 3; ++k) {
    const lcs_bench::SolveAcc& a = to_tol[k];
    CsvRow r{"solve",         problem_name,  v.name, nc, rows, nf, lcs::core::solverName(kToTol[k].kind),
             a.result.solver, "to_tolerance"};
    r.tolerance = kToTol[k].tol;
    r.iterations = a.result.iterations;
    r.seconds = a.best;
    r.residual = a.result.residual;
    r.status = lcs::core::statusName(a.result.status);
    csvWrite(csv, r);
    const std::string key =
        std::string(lcs::core::solverName(kToTol[k].kind)) + "@" + num(kToTol[k].tol, "%.0e");
    tab["t_" + key] = a.result.converged ? 1e3 * a.best : std::nan("");
    tab["it_" + key] = a.result.iterations;
    ran["t_" + key] = a.result.solver;
  }
  std::fprintf(stderr, "  %-16s %-13s %5d contacts %6d rows: nlgs %.3f us/sweep, auto(%s) %.3f us/sweep\n",
               problem_name.c_str(), v.name.c_str(), nc, rows, tab["sweep_nlgs"], ran["sweep_auto"].c_str(),
               tab["sweep_auto"]);
}

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

}  // namespace

int frictionlessCount(const lcs::core::Problem& p) {
  int n = 0;
  for (const lcs::core::Contact& c : p.contacts) n += c.type == lcs::core::ContactType::kFrictionless ? 1 : 0;
  return n;
}

void measureProblem(const std::string& problem_name, const std::vector<Variant>& variants, double budget,
                    int rounds, std::ostream& csv, SolveTables* tables) {
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
      lcs_bench::solveRound(variants[i].problem,
                            lcs_bench::toleranceParams(kToTol[k].kind, kToTol[k].tol, budget, 100000),
                            &tol_acc[i][k]);
  });
  for (std::size_t i = 0; i < nv; ++i)
    recordVariant(problem_name, variants[i], sweep_acc[i], tol_acc[i], csv, tables);
}

std::vector<GenRow> measureGeneration(const std::string& scenes_dir, int n, int reps) {
  sc::SceneParams params = sc::loadSceneParams(scenes_dir + "/sphere_pile.yaml");
  params.solver.solver = lcs::core::SolverKind::kAuto;
  params.solver.tolerance = 1e-4;
  params.solver.maxIt = 500;
  sc::Scene scene = sc::loadSceneFromUrdfString(pileUrdf(n), params, "effects_pile");
  sc::SceneSimulator sim(std::move(scene));
  for (int k = 0; k < 40; ++k) sim.step();  // settle: the balls fall into a pile
  const sc::Scene& settled = sim.scene();

  const sc::Scene disabled = withBallPairsDisabled(settled);
  const sc::Scene mixed = withHalfTouchingFrictionless(settled);
  std::fprintf(stderr,
               "  pile of %d balls: %zu ball-ball pairs disabled; %zu friction_pairs with mu = 0 (mixed)\n",
               n, disabled.params.disable_collisions.size(), mixed.params.friction_pairs.size());
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

}  // namespace lcs_bench::effects_cost
