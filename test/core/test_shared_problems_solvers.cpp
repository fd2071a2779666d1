// The added solvers on the shared reference problems (../shared/problems, Siconos test
// data written by others): what each must reach there.
#include "solvers_test_util.h"

#include "lcp_contact_solver/core/contact_solver.h"
#include "lcp_contact_solver/core/islands.h"
#include "lcp_contact_solver/core/residual.h"
#include "lcp_contact_solver/core/problem_io.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <utility>

namespace lcp_contact_solver::core {
namespace {

namespace fs = std::filesystem;

std::vector<std::string> fc3dFiles() {
  std::vector<std::string> files;
  for (const auto& entry : fs::directory_iterator(fs::path(LCS_PROBLEMS_DIR) / "fc3d"))
    if (entry.is_regular_file()) files.push_back(entry.path().string());
  std::sort(files.begin(), files.end());
  return files;
}

std::string baseName(const std::string& path) { return fs::path(path).filename().string(); }

bool startsWith(const std::string& text, const std::string& prefix) { return text.rfind(prefix, 0) == 0; }

SolverParams params(SolverKind kind, double tolerance, int max_it) {
  SolverParams p;
  p.solver = kind;
  p.tolerance = tolerance;
  p.maxIt = max_it;
  p.initial_guess = false;
  return p;
}

void expectFinite(const SolveResult& r, const std::string& what) {
  EXPECT_TRUE(r.forces.allFinite()) << what;
  EXPECT_TRUE(r.d.allFinite()) << what;
  EXPECT_TRUE(std::isfinite(r.residual)) << what;
}

// The first island of a shared fc3d problem with `rows` rows (an empty problem where none has).
Problem islandWithRows(const std::string& name, int rows) {
  const Problem whole = readProblemFile((fs::path(LCS_PROBLEMS_DIR) / "fc3d" / name).string());
  const Islands islands = findIslands(whole);
  const std::vector<int> offsets = whole.rowOffsets();
  for (const std::vector<int>& contacts : islands.contacts) {
    Problem candidate = islandProblem(whole, offsets, contacts);
    if (candidate.rowCount() == rows) return candidate;
  }
  return Problem{};
}

// auto on that island at `tol`: the apgd scout fails and Gauss-Seidel goes on from the
// probe's iterate (`auto:nlgs->apgd->nlgs`), to the tolerance recomputed from the forces.
void expectGaussSeidelResumesAfterTheScout(const std::string& name, int rows, double tol) {
  const Problem island = islandWithRows(name, rows);
  ASSERT_EQ(island.rowCount(), rows) << "the case needs " << name << "'s " << rows << "-row island";
  const SolveResult r = solveProblem(island, params(SolverKind::kAuto, tol, 100000));
  ASSERT_TRUE(r.converged) << r.solver << ": " << r.message;
  EXPECT_EQ(r.solver, "auto:nlgs->apgd->nlgs");
  EXPECT_LE(solvers_test::recomputedResidual(island, r.forces), tol);
}

// After a failed apgd scout, Gauss-Seidel goes on from the probe's last iterate where the
// probe's last stage said it needed at most half of newton's lower bound (n sweeps): the
// 72-row island of Capsules-i101-404 (multi-point, rank-deficient capsule contacts) at 9e-7,
// just below where its plan starts with Gauss-Seidel (next test), whose probe stops above the
// tolerance and whose scout fails. Independently: the residual recomputed from the forces.
TEST(SharedProblemsSolvers, AfterAFailedScoutGaussSeidelResumesFromTheProbesIterate) {
  expectGaussSeidelResumesAfterTheScout("Capsules-i101-404.dat", 72, 9e-7);
}

// Rank-deficient contacts of a moderate coupling (portfolio.cpp, firstOrderBySize): the
// capsule piles' islands of nearly parallel normal rows (a capsule on another along a line,
// coupling about 1.2) start with Gauss-Seidel down to 1e-6, without the apgd scout and newton
// that the strongly coupled face contacts of box stacks get; below 1e-6 the scout plan as
// before. Each solve converges (residual recomputed from the forces), and Gauss-Seidel first
// costs no more sweeps than plain nlgs alone (the probe's sweeps and the over-relaxation
// trial included), where the scout plan ran apgd from the start before it.
TEST(SharedProblemsSolvers, RankDeficientContactsOfModerateCouplingStartWithGaussSeidelDownToOneMicro) {
  struct Case {
    const char* file;
    int rows;
    double tol;
  };
  for (const Case& c : {Case{"Capsules-i100-1090.dat", 51, 2.6e-5}, Case{"Capsules-i101-404.dat", 72, 1e-6}}) {
    const Problem island = islandWithRows(c.file, c.rows);
    ASSERT_EQ(island.rowCount(), c.rows) << "the case needs " << c.file << "'s " << c.rows << "-row island";
    const SolveResult nlgs = solveProblem(island, params(SolverKind::kNlgs, c.tol, 100000));
    ASSERT_TRUE(nlgs.converged) << nlgs.message;
    const SolveResult r = solveProblem(island, params(SolverKind::kAuto, c.tol, 100000));
    ASSERT_TRUE(r.converged) << c.file << ": " << r.solver << ": " << r.message;
    EXPECT_EQ(r.solver, "auto:nlgs") << c.file;
    EXPECT_LE(r.iterations, nlgs.iterations) << c.file;
    EXPECT_LE(solvers_test::recomputedResidual(island, r.forces), c.tol) << c.file;
  }
  // Below 1e-6 on the same 51-row island: the scout, then newton (nlgs alone stalls there:
  // 4 577 sweeps to 9e-7).
  const Problem island = islandWithRows("Capsules-i100-1090.dat", 51);
  const SolveResult r = solveProblem(island, params(SolverKind::kAuto, 9e-7, 100000));
  ASSERT_TRUE(r.converged) << r.solver << ": " << r.message;
  EXPECT_EQ(r.solver, "auto:nlgs->apgd->newton");
  EXPECT_LE(solvers_test::recomputedResidual(island, r.forces), 9e-7);
}

// Past its cap of 100 iterations, an apgd scout goes on where its forecast reaches no
// further than it has run and the scout in all stays within newton's modeled cost
// (portfolio.cpp, scoutGoesOn): LMGC's periodic box of grains at 1e-4 (180 rows, multi-point
// contacts), whose scout at 80 iterations is 22x above the tolerance and forecasts 72 more,
// and where newton takes 2.7x apgd's time. Dropped at the cap, auto went on with newton:
// `auto:nlgs->apgd->newton`. Independently: the residual recomputed from the forces.
TEST(SharedProblemsSolvers, AScoutWhoseForecastIsShorterThanItsRunGoesOnPastItsCap) {
  const fs::path file = fs::path(LCS_PROBLEMS_DIR) / "fc3d" / "LMGC_100_PR_PerioBox-i00361-60-03000.hdf5";
  const Problem p = readProblemFile(file.string());
  const double tol = 1e-4;
  const SolveResult apgd = solveProblem(p, params(SolverKind::kApgd, tol, 100000));
  ASSERT_TRUE(apgd.converged) << apgd.message;
  const SolveResult r = solveProblem(p, params(SolverKind::kAuto, tol, 100000));
  ASSERT_TRUE(r.converged) << r.solver << ": " << r.message;
  EXPECT_EQ(r.solver, "auto:nlgs->apgd");
  EXPECT_LE(r.iterations, apgd.iterations + 10) << "the scout is apgd from the start, after a short probe";
  EXPECT_LE(solvers_test::recomputedResidual(p, r.forces), tol);
}

// `reference` and auto on the shared fc3d problem `name` at `tol`, both converged, auto's
// forces meeting the tolerance when the residual is recomputed from them.
std::pair<SolveResult, SolveResult> referenceAndAuto(const std::string& name, double tol, SolverKind reference) {
  const Problem p = readProblemFile((fs::path(LCS_PROBLEMS_DIR) / "fc3d" / name).string());
  SolveResult ref = solveProblem(p, params(reference, tol, 100000));
  SolveResult automatic = solveProblem(p, params(SolverKind::kAuto, tol, 100000));
  EXPECT_TRUE(ref.converged) << name << ": " << ref.message;
  EXPECT_TRUE(automatic.converged) << name << ": " << automatic.solver << ": " << automatic.message;
  EXPECT_LE(solvers_test::recomputedResidual(p, automatic.forces), tol) << name;
  return {std::move(ref), std::move(automatic)};
}

// The probe's rate put Gauss-Seidel before a planned apgd, on faces resting on faces, because
// its sweeps seemed to fit one slice; its first plain window after the probe says they no
// longer do, and apgd goes first again, from the start (portfolio.cpp, gs_before_apgd):
// BoxesStack1 at 1e-3, whose probe forecast 45 sweeps in all and whose window 118, where nlgs
// takes 226 and apgd 95 iterations. Before, auto swept 213 times. Independently: under 60 % of
// plain nlgs's sweeps, and the residual recomputed from the forces.
TEST(SharedProblemsSolvers, GaussSeidelWhoseForecastOutgrowsItsSliceHandsBackToApgd) {
  const auto [nlgs, r] = referenceAndAuto("BoxesStack1-i100000-32.hdf5.dat", 1e-3, SolverKind::kNlgs);
  EXPECT_NE(r.solver.find("nlgs->apgd"), std::string::npos) << r.solver;
  EXPECT_LT(10 * r.iterations, 6 * nlgs.iterations) << r.solver << " against nlgs's " << nlgs.iterations;
}

// A probe stage whose rate slowed within it forecasts from that slowing (portfolio.cpp,
// slowingSweepsToReach): BoxesStack1 at 1e-2, whose sweeps 3-10 slowed from 0.81 to 0.90 per
// sweep, stops after them and apgd runs from the start as planned, where the stage's mean rate
// had let it sweep on to 20 (plain nlgs takes 86). LMGC's box of grains at 1e-2 falls
// geometrically and its probe still sweeps to the tolerance, as many sweeps as nlgs alone.
// Independently: the residual recomputed from the forces (referenceAndAuto).
TEST(SharedProblemsSolvers, AProbeStageWhoseRateSlowedStopsBeforeAPlannedApgd) {
  const auto [apgd, stack] = referenceAndAuto("BoxesStack1-i100000-32.hdf5.dat", 1e-2, SolverKind::kApgd);
  EXPECT_EQ(stack.solver, "auto:nlgs->apgd");
  EXPECT_LE(stack.iterations, apgd.iterations + 10) << "at most ten probe sweeps before apgd";
  const auto [nlgs, grains] = referenceAndAuto("LMGC_100_PR_PerioBox-i00361-60-03000.hdf5", 1e-2, SolverKind::kNlgs);
  EXPECT_EQ(grains.solver, "auto:nlgs");
  EXPECT_EQ(grains.iterations, nlgs.iterations);
}

// On the scout's plans at a tight tolerance the probe's windows at Young's ω run as newton's
// warm-up (portfolio.cpp, omegaWindowsWithinWarmup), where plain sweeps from the start already
// fall slower than 0.95 per sweep: OneObject-i1028 at 1e-4 (0.979), whose second window
// forecast the rest within newton's cost, is solved by Gauss-Seidel at ω, `auto:nlgs`, where
// plain nlgs takes 196 sweeps and auto took newton's 7 slow steps after its scout (2.1x nlgs
// at ω = 1.3). OneObject-i100000 at 1e-6 (0.89 per sweep) runs none: the probe's three sweeps,
// the scout's twenty and newton's own iterations after those three. Independently: the residual
// recomputed from the forces.
TEST(SharedProblemsSolvers, TheProbeOverRelaxesWithinNewtonsWarmUpWherePlainSweepsAreSlowFromTheStart) {
  const auto [nlgs, slow] = referenceAndAuto("OneObject-i1028-138.hdf5.dat", 1e-4, SolverKind::kNlgs);
  EXPECT_EQ(slow.solver, "auto:nlgs");
  EXPECT_LT(2 * slow.iterations, nlgs.iterations) << slow.solver;
  const auto [newton, fast] = referenceAndAuto("OneObject-i100000-316.hdf5.dat", 1e-6, SolverKind::kNewton);
  EXPECT_EQ(fast.solver, "auto:nlgs->apgd->newton");
  EXPECT_LE(fast.iterations, newton.iterations + 20) << "no window's sweeps on top of the scout's";
}

// Where nlgs stalls near 1e-5..1e-6 (rank-deficient W), Newton goes to 1e-10.
TEST(SharedProblemsSolvers, NewtonReachesTenDigitsOnTheRankDeficientStacks) {
  for (const std::string name : {"BoxesStack1-i100000-32.hdf5.dat", "OneObject-i100000-316.hdf5.dat"}) {
    const Problem p = readProblemFile((fs::path(LCS_PROBLEMS_DIR) / "fc3d" / name).string());
    const SolveResult r = solveProblem(p, params(SolverKind::kNewton, 1e-10, 10000));
    expectFinite(r, name);
    EXPECT_EQ(r.status, SolveStatus::kConverged) << name << ": " << r.message;
    EXPECT_LE(r.residual, 1e-10) << name;
  }
}

// newton damps the steps its line search has to cut short (newton.cpp, "Rank-deficient
// W"): on the capsule piles' and OneObject's rank-deficient contacts, with a damping that
// only ever decreased, it took 208, 380 and 61 iterations to reach 1e-8 (the line search
// cutting step after step along J's near-null space); with it, 26, 17 and 29.
TEST(SharedProblemsSolvers, NewtonDampsTheStepsItsLineSearchCutsShort) {
  for (const std::string name :
       {"Capsules-i100-1090.dat", "Capsules-i101-404.dat", "OneObject-i1028-138.hdf5.dat"}) {
    const Problem p = readProblemFile((fs::path(LCS_PROBLEMS_DIR) / "fc3d" / name).string());
    const SolveResult r = solveProblem(p, params(SolverKind::kNewton, 1e-8, 100000));
    expectFinite(r, name);
    EXPECT_EQ(r.status, SolveStatus::kConverged) << name << ": " << r.message;
    EXPECT_LE(solvers_test::recomputedResidual(p, r.forces), 1e-8) << name;
    EXPECT_LT(r.iterations, 50) << name;
  }
}

TEST(SharedProblemsSolvers, NewtonReachesTheTightToleranceOnEveryFc3dProblem) {
  for (const std::string& file : fc3dFiles()) {
    const Problem p = readProblemFile(file);
    const SolveResult r = solveProblem(p, params(SolverKind::kNewton, 1e-9, 100000));
    expectFinite(r, file);
    EXPECT_EQ(r.solver, "newton");
    EXPECT_EQ(r.status, SolveStatus::kConverged) << file << ": " << r.message;
    EXPECT_LE(r.residual, 1e-8) << file;
  }
}

TEST(SharedProblemsSolvers, ApgdReachesOneMicroOnRoverAndCapsules) {
  int solved = 0;
  for (const std::string& file : fc3dFiles()) {
    const std::string name = baseName(file);
    if (!startsWith(name, "Rover") && !startsWith(name, "Capsules")) continue;
    const Problem p = readProblemFile(file);
    const SolveResult r = solveProblem(p, params(SolverKind::kApgd, 1e-6, 100000));
    expectFinite(r, file);
    EXPECT_EQ(r.solver, "apgd");
    EXPECT_EQ(r.status, SolveStatus::kConverged) << file << ": " << r.message;
    EXPECT_LE(r.residual, 1e-6) << file;
    ++solved;
  }
  EXPECT_EQ(solved, 16);
}

// Including the rank-deficient stacks where nlgs stalls near 1e-6.
TEST(SharedProblemsSolvers, ApgdReachesOneMicroOnTheStacks) {
  for (const std::string name : {"BoxesStack1-i100000-32.hdf5.dat", "OneObject-i100000-316.hdf5.dat",
                                 "LMGC_100_PR_PerioBox-i00361-60-03000.hdf5"}) {
    const Problem p = readProblemFile((fs::path(LCS_PROBLEMS_DIR) / "fc3d" / name).string());
    const SolveResult r = solveProblem(p, params(SolverKind::kApgd, 1e-6, 100000));
    expectFinite(r, name);
    EXPECT_EQ(r.status, SolveStatus::kConverged) << name << ": " << r.message;
    EXPECT_LE(r.residual, 1e-6) << name;
  }
}

using solvers_test::recomputedResidual;

// A limit cycle: on one 48-row island of a capsule pile, newton's rounds of Newton steps and
// nlgs bursts repeat the same residuals (3.9e-6, period 120 iterations). It says so at the
// first repeat instead of after five fruitless rounds (642 iterations), returns its best
// iterate (residual recomputed here from the forces), and auto carries the island.
TEST(SharedProblemsSolvers, NewtonEndsALimitCycleAtItsFirstRepeat) {
  const Problem whole = readProblemFile((fs::path(LCS_PROBLEMS_DIR) / "fc3d" / "Capsules-i101-404.dat").string());
  const Islands islands = findIslands(whole);
  ASSERT_GT(islands.count(), 12);
  const Problem island = islandProblem(whole, whole.rowOffsets(), islands.contacts[12]);
  ASSERT_EQ(island.rowCount(), 48);
  const SolveResult r = solveProblem(island, params(SolverKind::kNewton, 1e-6, 100000));
  expectFinite(r, "island 12");
  EXPECT_EQ(r.status, SolveStatus::kNumericalFailure) << r.message;
  EXPECT_NE(r.message.find("cycling"), std::string::npos) << r.message;
  EXPECT_LT(r.iterations, 400);
  const double residual = recomputedResidual(island, r.forces);
  EXPECT_NEAR(residual, r.residual, 1e-12);
  EXPECT_GT(residual, 1e-6);  // the cycle's floor: newton did not solve it
  EXPECT_LT(residual, 1e-5);
  const SolveResult a = solveProblem(island, params(SolverKind::kAuto, 1e-6, 100000));
  EXPECT_EQ(a.status, SolveStatus::kConverged) << a.message;
  EXPECT_LE(recomputedResidual(island, a.forces), 1e-6);
}

// A Gauss-Seidel drift to a separation is jumped (portfolio.cpp, kAutoDriftReach): on the
// same 48-row island plain nlgs sits near 5.6e-6 for hundreds of sweeps while load moves
// between the capsule contacts, until a normal force reaches zero. auto, whose Gauss-Seidel
// member stalls there, jumps along the slice's drift to that separation and converges in a
// fraction of nlgs's sweeps (before the jump: 1 305 iterations through apgd, newton and prox,
// against nlgs's 919). Independently: the residual recomputed from the forces.
TEST(SharedProblemsSolvers, AGaussSeidelDriftToASeparationIsJumped) {
  const Problem island = islandWithRows("Capsules-i101-404.dat", 48);  // island 12, its only 48-row one
  ASSERT_EQ(island.rowCount(), 48);
  const double tol = 1.2e-6;
  // The premise: plain sweeps are still on the plateau after 400.
  const SolveResult plateau = solveProblem(island, params(SolverKind::kNlgs, tol, 400));
  EXPECT_GT(recomputedResidual(island, plateau.forces), 4.0 * tol);
  const SolveResult nlgs = solveProblem(island, params(SolverKind::kNlgs, tol, 100000));
  ASSERT_TRUE(nlgs.converged) << nlgs.message;
  const SolveResult r = solveProblem(island, params(SolverKind::kAuto, tol, 100000));
  ASSERT_TRUE(r.converged) << r.solver << ": " << r.message;
  EXPECT_TRUE(startsWith(r.solver, "auto:nlgs")) << r.solver;
  EXPECT_LE(4 * r.iterations, nlgs.iterations) << r.solver;
  EXPECT_LE(recomputedResidual(island, r.forces), tol);
}

// Cut short, apgd says so and keeps its best iterate.
TEST(SharedProblemsSolvers, ApgdCutShortIsHonest) {
  const Problem p =
      readProblemFile((fs::path(LCS_PROBLEMS_DIR) / "fc3d" / "BoxesStack1-i100000-32.hdf5.dat").string());
  const SolveResult r = solveProblem(p, params(SolverKind::kApgd, 1e-10, 50));
  expectFinite(r, "BoxesStack1");
  EXPECT_EQ(r.status, SolveStatus::kMaxIterations);
  EXPECT_FALSE(r.converged);
  EXPECT_EQ(r.iterations, 50);
  EXPECT_LT(r.residual, 1e-1);
}

// Boxed pgs and Lemke solve the same pyramid problem on the small frictional files.
TEST(SharedProblemsSolvers, PyramidPgsAndLemkeAgree) {
  for (const std::string& file : fc3dFiles()) {
    const Problem p = readProblemFile(file);
    if (p.rowCount() > 30) continue;  // Lemke's dense tableau: the small problems only
    for (FrictionModel model : {FrictionModel::kPyramid4, FrictionModel::kPyramid8}) {
      SolverParams lemke_params = params(SolverKind::kLemke, 1e-9, 10000);
      lemke_params.friction_model = model;
      SolverParams pgs_params = params(SolverKind::kPgs, 1e-11, 100000);
      pgs_params.friction_model = model;
      const SolveResult lemke = solveProblem(p, lemke_params);
      const SolveResult pgs = solveProblem(p, pgs_params);
      const std::string what = baseName(file) + " " + frictionModelName(model);
      expectFinite(lemke, what);
      ASSERT_EQ(lemke.status, SolveStatus::kConverged) << what << ": " << lemke.message;
      ASSERT_EQ(pgs.status, SolveStatus::kConverged) << what << ": " << pgs.message;
      EXPECT_EQ(lemke.friction_model, model);
      EXPECT_EQ(pgs.friction_model, model);
      EXPECT_LE(lemke.solver_error, 1e-9) << what;
      // The velocities are unique even where W is singular and the forces are not.
      EXPECT_LE((lemke.d - pgs.d).norm(), 1e-6 * p.d_free.norm()) << what;
    }
  }
}

}  // namespace
}  // namespace lcp_contact_solver::core
