// auto, the portfolio (src/core/portfolio.cpp): problems built so that the first member fails or
// stalls and another must carry the solve. Every residual is recomputed here from the
// returned forces (d = W λ + d_free), independently of the solver's own report.
#include "hard_case_util.h"
#include "solvers_test_util.h"

#include "lcp_contact_solver/core/contact_solver.h"
#include "lcp_contact_solver/core/kernels/kernels.h"
#include "lcp_contact_solver/core/residual.h"

// GaussSeidelMemo's definition (private to the core): the kernel-level test below hands one
// to the Gauss-Seidel kernels as auto does.
#include "../../src/core/kernels/local_contact_laws.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

namespace lcp_contact_solver::core {
namespace {

using hard::Body;
using hard::boxStack;
using hard::World;

// A pyramid of unit cubes, `base` on the ground: each cube above rests on two, on four points
// at the corners of each overlap (a half face), the ground's cubes on their four bottom
// corners. Multi-point contacts whose points are spread over the faces: no two normal rows
// nearly parallel.
Problem cubePyramid(int base, double mu) {
  World w;
  const Eigen::Vector3d size(1.0, 1.0, 1.0);
  std::vector<std::vector<int>> rows;
  for (int r = 0; r < base; ++r) {
    rows.emplace_back();
    for (int k = 0; k < base - r; ++k)
      rows.back().push_back(w.add(hard::box(1.0, size, Eigen::Vector3d(0.5 * r + k, 0.0, 0.5 + r))));
  }
  auto corners = [&](int a, int b, double x0, double x1, double z) {
    for (double x : {x0, x1})
      for (double y : {-0.5, 0.5}) w.contact(a, b, Eigen::Vector3d(x, y, z), Eigen::Vector3d::UnitZ(), mu);
  };
  for (int k = 0; k < base; ++k) corners(rows[0][k], -1, k - 0.5, k + 0.5, 0.0);
  for (int r = 1; r < base; ++r)
    for (int k = 0; k < base - r; ++k) {
      const double x = 0.5 * r + k;  // resting on cubes k and k + 1 of the row below
      corners(rows[r][k], rows[r - 1][k], x - 0.5, x, r);
      corners(rows[r][k], rows[r - 1][k + 1], x, x + 0.5, r);
    }
  return w.problem();
}

SolverParams params(SolverKind kind, double tolerance, int max_it) {
  SolverParams p;
  p.solver = kind;
  p.tolerance = tolerance;
  p.maxIt = max_it;
  p.initial_guess = false;
  return p;
}

// The natural-map residual of the returned forces, from W and d_free alone.
double recomputedResidual(const Problem& p, const SolveResult& r) {
  return solvers_test::recomputedResidual(p, r.forces);
}

// An LCP: one frictionless contact per row of W.
Problem frictionlessLcp(const Eigen::MatrixXd& W, const Eigen::VectorXd& d_free) {
  Problem p;
  p.W = W;
  p.d_free = d_free;
  for (int i = 0; i < W.rows(); ++i) {
    Contact c;
    c.id = i;
    c.type = ContactType::kFrictionless;
    c.rows = 1;
    p.contacts.push_back(c);
  }
  return p;
}

// The path without the Gauss-Seidel probe every plan starts with (ten sweeps, more while
// their rate says they finish first; a plan that starts with Gauss-Seidel merges with it
// into one stage).
std::string afterProbe(const SolveResult& r) {
  for (const char* probe : {"auto:nlgs->", "auto:pgs->"})
    if (r.solver.rfind(probe, 0) == 0) return "auto:" + r.solver.substr(std::string(probe).size());
  return r.solver;
}

// The path after the probe and, before newton, the apgd scout that multi-point or
// rank-deficient contacts get (one apgd stage followed by newton).
std::string afterScout(const SolveResult& r) {
  const std::string path = afterProbe(r);
  return path.rfind("auto:apgd->newton", 0) == 0 ? "auto:" + path.substr(std::string("auto:apgd->").size()) : path;
}

// The plan started with `first` ("auto:lemke", ...), unless the probe's sweeps alone met the
// tolerance (path "auto:pgs" or "auto:nlgs", at most its largest allowance: 50 sweeps before
// apgd, one per row before newton).
void expectPlanStartsWith(const SolveResult& r, const std::string& first) {
  if ((r.solver == "auto:pgs" || r.solver == "auto:nlgs") && r.converged) {
    EXPECT_LE(r.iterations, std::max<long>(50, r.forces.size())) << r.solver;
    return;
  }
  EXPECT_EQ(afterProbe(r).rfind(first, 0), 0u) << r.solver;
}

// auto's answer on p at tol, checked: converged, its path after the probe starting with
// `path`, and the tolerance met by the residual recomputed from its forces.
SolveResult autoSolvesAlong(const Problem& p, double tol, const std::string& path) {
  const SolveResult r = solveProblem(p, params(SolverKind::kAuto, tol, 100000));
  EXPECT_TRUE(r.converged) << r.solver << ": " << r.message;
  EXPECT_EQ(afterProbe(r).rfind(path, 0), 0u) << r.solver;
  EXPECT_LE(recomputedResidual(p, r), tol) << r.solver;
  return r;
}

TEST(Portfolio, RankDeficientStackWhereNewtonStallsStillConverges) {
  const Problem p = boxStack(2, 8, 100.0, 0.5, 0.8);
  const double tol = 1e-8;
  const SolveResult newton = solveProblem(p, params(SolverKind::kNewton, tol, 20000));
  ASSERT_FALSE(newton.converged) << "the case must make plain newton stall: " << newton.message;
  const SolveResult r = solveProblem(p, params(SolverKind::kAuto, tol, 20000));
  ASSERT_EQ(r.status, SolveStatus::kConverged) << r.solver << ": " << r.message;
  EXPECT_LE(recomputedResidual(p, r), tol);
  EXPECT_NEAR(recomputedResidual(p, r), r.residual, 1e-12);
  EXPECT_LE(r.iterations, 20000);
  solvers_test::expectPath(r);
  EXPECT_EQ(afterScout(r).rfind("auto:newton->", 0), 0u) << r.solver;  // predicted first, then handed over
  // The proximal kernel on its own reaches the tolerance too.
  const SolveResult prox = solveProblem(p, params(SolverKind::kProx, tol, 20000));
  EXPECT_EQ(prox.status, SolveStatus::kConverged) << prox.message;
  EXPECT_LE(recomputedResidual(p, prox), tol);
}

// Heavier stacks where newton and prox both stall: the portfolio must end on the member
// that progresses (apgd here), within the same iteration cap.
TEST(Portfolio, StacksWhereOnlyOneMemberProgresses) {
  for (int boxes : {4, 6}) {
    const Problem p = boxStack(boxes, 4, 100.0, 0.5, 0.8);
    const double tol = 1e-8;
    const SolveResult apgd = solveProblem(p, params(SolverKind::kApgd, tol, 20000));
    ASSERT_TRUE(apgd.converged) << boxes;
    const SolveResult newton = solveProblem(p, params(SolverKind::kNewton, tol, 20000));
    EXPECT_FALSE(newton.converged) << boxes;
    const SolveResult r = solveProblem(p, params(SolverKind::kAuto, tol, 20000));
    ASSERT_EQ(r.status, SolveStatus::kConverged) << boxes << " " << r.solver << ": " << r.message;
    EXPECT_LE(recomputedResidual(p, r), tol) << boxes;
    EXPECT_LE(r.iterations, 20000);
    solvers_test::expectPath(r);
    EXPECT_NE(r.solver.find("apgd"), std::string::npos) << r.solver;
  }
}

// How many stages of an auto path a member ran ("auto:nlgs->apgd->nlgs": nlgs 2).
int stagesOf(const std::string& path, const std::string& member) {
  int stages = 0;
  std::size_t from = path.find(':') + 1;
  for (std::size_t to; from != 0; from = to == std::string::npos ? 0 : to + 2) {
    to = path.find("->", from);
    if (path.substr(from, to == std::string::npos ? std::string::npos : to - from) == member) ++stages;
  }
  return stages;
}

// Thirty boxes, alternately 100 times heavier, at 1e-3: apgd's residual sits on a plateau for
// thousands of iterations before it falls, while nlgs raises the residual in every slice and
// newton fails. Once every member ran and no last slice lowered the residual, the stall goes
// to the member that lowered it fastest over all its slices, not to the next in turn: nlgs runs
// once after the probe (its over-relaxation trial and slice), newton once. With the rotation in
// turn they came back four and two times with doubled slices (0.43 s of the solve's 2.4 s).
TEST(Portfolio, AStallWhereNoLastSliceProgressedGoesToTheFastestMemberOverall) {
  const double tol = 1e-3;
  const Problem thirty = boxStack(30, 4, 100.0, 0.5, 0.8);
  const SolveResult apgd = solveProblem(thirty, params(SolverKind::kApgd, tol, 100000));
  ASSERT_TRUE(apgd.converged);
  const SolveResult newton = solveProblem(thirty, params(SolverKind::kNewton, tol, 100000));
  ASSERT_FALSE(newton.converged);
  const SolveResult r = solveProblem(thirty, params(SolverKind::kAuto, tol, 100000));
  ASSERT_TRUE(r.converged) << r.solver << ": " << r.message;
  EXPECT_LE(recomputedResidual(thirty, r), tol);
  solvers_test::expectPath(r);
  EXPECT_EQ(r.solver.rfind("auto:nlgs->apgd->", 0), 0u) << r.solver;  // the probe, then the plan
  EXPECT_LE(stagesOf(r.solver, "nlgs"), 2) << r.solver;
  EXPECT_LE(stagesOf(r.solver, "newton"), 1) << r.solver;
  EXPECT_EQ(r.solver.substr(r.solver.size() - 6), "->apgd") << r.solver;
}

// Six boxes, eight points per face, alternately 100 times heavier, at 1e-3: newton fails, nlgs
// needs twice apgd's iterations, and prox lowers the residual a little in each slice (less than
// its factor of 10), while apgd, restarted from prox's iterate, first raises it. Chosen by the
// last slice's rate alone, prox was handed slice after slice, each twice as long (9 000 iterations
// in all, 0.3 s, where apgd alone takes 4 458 and 25 ms). The member that stalled now hands over
// to the one whose record (apgd's rate over all its slices) beats its last slice. Bounded by apgd's
// own iterations with room for the other members' slices; residual recomputed from the forces.
TEST(Portfolio, AMemberThatStalledHandsOverWhereAnotherHasTheBetterRecord) {
  const double tol = 1e-3;
  const Problem stack = boxStack(6, 8, 100.0, 0.5, 0.8);
  const SolveResult apgd = solveProblem(stack, params(SolverKind::kApgd, tol, 100000));
  ASSERT_TRUE(apgd.converged);
  ASSERT_FALSE(solveProblem(stack, params(SolverKind::kNewton, tol, 100000)).converged);
  const SolveResult r = solveProblem(stack, params(SolverKind::kAuto, tol, 100000));
  ASSERT_TRUE(r.converged) << r.solver << ": " << r.message;
  EXPECT_LE(recomputedResidual(stack, r), tol);
  solvers_test::expectPath(r);
  EXPECT_EQ(r.solver.substr(r.solver.size() - 6), "->apgd") << r.solver;
  EXPECT_LE(r.iterations, 3 * apgd.iterations / 2) << r.solver << ": apgd alone " << apgd.iterations;
}

// Contact 0's normal row and column are zero (W stays PSD): Gauss-Seidel cannot divide by
// W_nn and stops with zero_diagonal; the contact is separating (d_free_n > 0), so the
// answer exists and the next member finds it.
Problem zeroDiagonalProblem() {
  Problem p;
  // Rows 1..5 are A Aᵀ + I (positive definite, coupling both contacts into one island).
  Eigen::MatrixXd A(5, 5);
  A << 1.0, 0.2, 0.0, 0.3, 0.0,  //
      0.0, 0.8, 0.1, 0.0, 0.2,   //
      0.2, 0.0, 0.5, 0.1, 0.0,   //
      0.0, 0.3, 0.0, 0.9, 0.1,   //
      0.1, 0.0, 0.2, 0.0, 0.7;
  Eigen::MatrixXd W = Eigen::MatrixXd::Zero(6, 6);
  W.bottomRightCorner(5, 5) = A * A.transpose() + Eigen::MatrixXd::Identity(5, 5);
  p.W = W;
  p.d_free = Eigen::VectorXd(6);
  p.d_free << 0.1, 0.2, -0.1, -1.0, 0.3, 0.0;
  for (int i = 0; i < 2; ++i) {
    Contact c;
    c.id = i + 1;
    c.type = ContactType::kFrictional;
    c.rows = 3;
    c.mu = 0.5;
    p.contacts.push_back(c);
  }
  return p;
}

TEST(Portfolio, GaussSeidelCannotStartAndAnotherMemberCarriesIt) {
  const Problem p = zeroDiagonalProblem();
  ASSERT_EQ(validateProblem(p), "");
  for (double tol : {1e-3, 1e-8}) {
    const SolveResult nlgs = solveProblem(p, params(SolverKind::kNlgs, tol, 1000));
    ASSERT_EQ(nlgs.status, SolveStatus::kZeroDiagonal) << nlgs.message;
    const SolveResult r = solveProblem(p, params(SolverKind::kAuto, tol, 1000));
    ASSERT_EQ(r.status, SolveStatus::kConverged) << tol << " " << r.solver << ": " << r.message;
    EXPECT_LE(recomputedResidual(p, r), tol);
    solvers_test::expectPath(r);
    // W is diagonally dominant where it is not zero: at 1e-8 nlgs is predicted, fails, hands
    // over; at 1e-3 a problem this small starts with newton, whose warm-up (nlgs sweeps)
    // cannot start either and whose Newton steps carry it.
    EXPECT_EQ(r.solver.rfind(tol < 1e-3 ? "auto:nlgs->" : "auto:newton", 0), 0u) << r.solver;
    EXPECT_EQ(r.forces[0], 0.0);  // the separating contact carries nothing
  }
}

// maxIt bounds the whole portfolio, not each member: too few iterations for any member
// gives max_iterations with at most maxIt iterations summed over the path.
TEST(Portfolio, MaxItBoundsTheWholePath) {
  const Problem p = boxStack(4, 4, 100.0, 0.5, 0.8);
  const SolveResult r = solveProblem(p, params(SolverKind::kAuto, 1e-8, 400));
  EXPECT_EQ(r.status, SolveStatus::kMaxIterations) << r.solver << ": " << r.message;
  EXPECT_LE(r.iterations, 400);
  EXPECT_GE(r.stages.size(), 2u) << r.solver;  // newton's share ran out and another member took over
  solvers_test::expectPath(r);
  EXPECT_NEAR(recomputedResidual(p, r), r.residual, 1e-12);
}

// time_budget bounds the whole portfolio: with a budget far below what the problem needs
// the solve stops with time_budget and the best iterate, not after each member's budget.
TEST(Portfolio, TimeBudgetBoundsTheWholePath) {
  const Problem p = boxStack(6, 8, 100.0, 0.5, 0.8);
  SolverParams q = params(SolverKind::kAuto, 1e-12, 10000000);
  q.time_budget = 1e-4;
  const SolveResult r = solveProblem(p, q);
  EXPECT_EQ(r.status, SolveStatus::kTimeBudget) << r.solver << ": " << r.message;
  EXPECT_TRUE(r.forces.allFinite());
  solvers_test::expectPath(r);
  EXPECT_NEAR(recomputedResidual(p, r), r.residual, 1e-12);
}

// The warm start feeds the first member: solved again from its own answer, auto stops at once.
TEST(Portfolio, WarmStartFeedsTheFirstMember) {
  const Problem p = boxStack(3, 4, 1.0, 0.5, 0.8);
  SolverParams q = params(SolverKind::kAuto, 1e-8, 5000);
  q.initial_guess = true;
  ContactSolver solver(q);
  const SolveResult first = solver.solve(p);
  ASSERT_TRUE(first.converged) << first.message;
  EXPECT_GT(first.iterations, 0);
  const SolveResult second = solver.solve(p);
  ASSERT_TRUE(second.converged) << second.message;
  EXPECT_EQ(second.iterations, 0);
  EXPECT_EQ(second.solver, "auto");  // the start met the tolerance: no member ran
  EXPECT_TRUE(second.stages.empty());
  EXPECT_LE(recomputedResidual(p, second), 1e-8);
}

// What each feature predicts (docs/ARCHITECTURE.md): the first member of the path.
TEST(Portfolio, FirstMemberFollowsTheFeatures) {
  const Problem stack = boxStack(3, 4, 1.0, 0.5, 0.8);  // coupled normals (4 points per face)
  EXPECT_EQ(afterScout(solveProblem(stack, params(SolverKind::kAuto, 1e-8, 5000))).rfind("auto:newton", 0), 0u);
  expectPlanStartsWith(solveProblem(stack, params(SolverKind::kAuto, 1e-2, 5000)), "auto:apgd");
  // Separate contacts (W block diagonal): Gauss-Seidel is exact in one sweep.
  World w;
  for (int i = 0; i < 3; ++i) {
    w.add(hard::box(1.0, Eigen::Vector3d(1.0, 1.0, 1.0), Eigen::Vector3d(3.0 * i, 0.0, 0.5)));
    w.contact(i, -1, Eigen::Vector3d(3.0 * i, 0.0, 0.0), Eigen::Vector3d::UnitZ(), 0.5);
  }
  for (double tol : {1e-2, 1e-8}) {
    const SolveResult r = solveProblem(w.problem(), params(SolverKind::kAuto, tol, 5000));
    EXPECT_EQ(r.solver, "auto:nlgs") << tol;
    EXPECT_TRUE(r.converged);
  }
  // Torsional friction: only nlgs has the local step, so the path is nlgs alone.
  Problem torsional;
  torsional.W = Eigen::MatrixXd(Eigen::Vector4d(0.1, 0.1, 0.1, 0.5).asDiagonal());
  torsional.d_free = Eigen::Vector4d(-1.0, 0.0, 0.0, -0.05);
  Contact c;
  c.id = 1;
  c.type = ContactType::kTorsional;
  c.rows = 4;
  c.mu = 0.5;
  c.mu_torsional = 0.02;
  torsional.contacts.push_back(c);
  const SolveResult t = solveProblem(torsional, params(SolverKind::kAuto, 1e-10, 1000));
  EXPECT_EQ(t.solver, "auto:nlgs");
  EXPECT_TRUE(t.converged) << t.message;
}

// A wall of balls (radius 0.1) stacked as a triangle, `base` on the ground: each ball above rests
// on the two below it, one contact per pair of touching bodies.
Problem ballTriangle(int base, double mu) {
  World w;
  const double r = 0.1;
  std::vector<std::vector<int>> layers(base);
  for (int k = 0; k < base; ++k) {
    for (int i = 0; i < base - k; ++i) {
      const Eigen::Vector3d com(2.0 * r * i + r * k, 0.0, r + k * r * std::sqrt(3.0));
      const int ball = w.add(hard::box(1.0, Eigen::Vector3d::Constant(2.0 * r), com));
      layers[k].push_back(ball);
      if (k == 0) w.contact(ball, -1, Eigen::Vector3d(com.x(), 0.0, 0.0), Eigen::Vector3d::UnitZ(), mu);
      for (int s = 0; k > 0 && s < 2; ++s) {
        const int below = layers[k - 1][i + s];
        const Eigen::Vector3d n = (com - w.bodies[below].com).normalized();
        w.contact(ball, below, w.bodies[below].com + r * n, n, mu);
      }
    }
  }
  return w.problem();
}

// Down to 1e-4 Gauss-Seidel goes before apgd unless contacts are multi-point (several
// between the same bodies: rows beyond their degrees of freedom), where its rate collapses.
// Both problems have over 200 rows (apgd first before the feature) and Gauss-Seidel needs more
// sweeps than the probe's allowance before apgd, so the path shows the plan; each answer is
// checked against Coulomb's law from the forces. At 1e-3 the stack's load slides, and apgd
// goes behind Gauss-Seidel after the probe (WhereTheLoadSlidesApgdGoesBehindGaussSeidel):
// 784 iterations in all where the path through apgd from the start took 1 057 (nlgs alone
// 1 637, apgd 2 993).
TEST(Portfolio, GaussSeidelFirstAtModerateToleranceUnlessContactsAreMultiPoint) {
  const Problem balls = ballTriangle(10, 0.5);  // 300 rows, one contact per pair of bodies
  const Problem stack = boxStack(18, 4, 1.0, 0.5, 0.8);  // 216 rows, four points per face
  for (double tol : {1e-3, 1e-4}) {
    const SolveResult nlgs = solveProblem(balls, params(SolverKind::kNlgs, tol, 100000));
    ASSERT_TRUE(nlgs.converged) << nlgs.message;
    ASSERT_GT(nlgs.iterations, 50) << tol;  // beyond the probe's allowance before apgd
    const SolveResult r = solveProblem(balls, params(SolverKind::kAuto, tol, 100000));
    ASSERT_TRUE(r.converged) << r.solver << ": " << r.message;
    // The pile's early iterates stick everywhere, so auto tries newton's sticking path once
    // (one Cholesky step); eight contacts slide at the solution, and it sweeps on.
    EXPECT_EQ(r.solver, "auto:nlgs->active-set->nlgs") << tol;
    // The probe's sweeps and nlgs's are one run, but for the over-relaxation trial's (below)
    // and that step.
    EXPECT_LE(r.iterations, nlgs.iterations + 20) << tol;
    EXPECT_LE(recomputedResidual(balls, r), tol);
    SolverParams traced = params(SolverKind::kAuto, tol, 100000);
    traced.displayDebug = true;  // residual histories: the probe's sweeps, then each member's
    const SolveResult s = solveProblem(stack, traced);
    ASSERT_TRUE(s.converged) << s.solver << ": " << s.message;
    EXPECT_LE(recomputedResidual(stack, s), tol);
    if (tol >= 1e-3) {
      EXPECT_LT(s.iterations, solveProblem(stack, params(SolverKind::kNlgs, tol, 100000)).iterations) << s.solver;
      continue;
    }
    // apgd ran from the start after at most the probe's 50 sweeps: its first slice (200
    // iterations) is apgd's own run, residual for residual. An nlgs plan sweeps 100 first.
    traced.solver = SolverKind::kApgd;
    const SolveResult apgd = solveProblem(stack, traced);
    ASSERT_GT(apgd.residual_history.size(), 200u);
    bool apgd_after_probe = false;
    for (std::size_t k = 1; k <= 50 && k + 200 <= s.residual_history.size() && !apgd_after_probe; ++k)
      apgd_after_probe = std::equal(apgd.residual_history.begin(), apgd.residual_history.begin() + 200,
                                    s.residual_history.begin() + static_cast<long>(k));
    EXPECT_TRUE(apgd_after_probe) << s.solver << " at " << tol;
  }
}

// Where about two digits are asked, the probe's rate decides between Gauss-Seidel and a
// planned apgd (multi-point contacts): Gauss-Seidel goes on where that rate reaches the
// tolerance within a slice of its own. Two stacks of the boxes above, four points per face,
// alternate boxes ten and a hundred times heavier: on six boxes Gauss-Seidel needs fewer than
// half apgd's iterations but more than the probe's allowance before apgd (apgd's run from the
// start had cost auto as much as apgd alone), on thirty its sweeps stall and apgd, a dozen
// iterations, still follows the probe. Checked against Coulomb's law from the forces.
TEST(Portfolio, AtTwoDigitsTheProbesRateCanPutGaussSeidelBeforeApgd) {
  const double tol = 1e-2;
  const Problem six = boxStack(6, 4, 10.0, 0.5, 0.8);
  const SolveResult nlgs = solveProblem(six, params(SolverKind::kNlgs, tol, 100000));
  const SolveResult apgd = solveProblem(six, params(SolverKind::kApgd, tol, 100000));
  ASSERT_TRUE(nlgs.converged && apgd.converged);
  ASSERT_GT(nlgs.iterations, 50);  // beyond the probe's allowance before apgd
  ASSERT_LT(2 * nlgs.iterations, apgd.iterations);
  const SolveResult r = solveProblem(six, params(SolverKind::kAuto, tol, 100000));
  ASSERT_TRUE(r.converged) << r.solver << ": " << r.message;
  EXPECT_EQ(r.solver.rfind("auto:nlgs", 0), 0u) << r.solver;
  EXPECT_LT(2 * r.iterations, apgd.iterations) << r.solver;
  EXPECT_LE(recomputedResidual(six, r), tol);
  const Problem thirty = boxStack(30, 4, 100.0, 0.5, 0.8);
  const SolveResult apgd30 = solveProblem(thirty, params(SolverKind::kApgd, tol, 100000));
  const SolveResult nlgs30 = solveProblem(thirty, params(SolverKind::kNlgs, tol, 100000));
  ASSERT_TRUE(apgd30.converged && nlgs30.converged);
  ASSERT_GT(nlgs30.iterations, 10 * apgd30.iterations);
  const SolveResult r30 = solveProblem(thirty, params(SolverKind::kAuto, tol, 100000));
  ASSERT_TRUE(r30.converged) << r30.solver << ": " << r30.message;
  EXPECT_EQ(afterProbe(r30), "auto:apgd");
  EXPECT_LE(r30.iterations, apgd30.iterations + 50);  // at most the probe's allowance on top
  EXPECT_LE(recomputedResidual(thirty, r30), tol);

  // A pyramid's cubes rest on points spread over their faces, no two normal rows nearly
  // parallel, W in blocks: apgd needs about as many iterations as nlgs sweeps, each one
  // product with W, so at two digits it keeps its place whatever the probe's rate says (the
  // stacks above have four close points per face: nearly parallel rows). 55 cubes: on fewer
  // nlgs ends within the probe's own sweeps, before the rule is asked.
  const Problem pyramid = hard::toBlockSparse(cubePyramid(10, 0.8));
  const SolveResult nlgs_p = solveProblem(pyramid, params(SolverKind::kNlgs, tol, 100000));
  const SolveResult apgd_p = solveProblem(pyramid, params(SolverKind::kApgd, tol, 100000));
  ASSERT_TRUE(nlgs_p.converged && apgd_p.converged);
  ASSERT_GT(nlgs_p.iterations, 10);  // beyond the probe's first allowance: the rule is asked
  ASSERT_LE(apgd_p.iterations, 2 * nlgs_p.iterations);
  const SolveResult rp = solveProblem(pyramid, params(SolverKind::kAuto, tol, 100000));
  ASSERT_TRUE(rp.converged) << rp.solver << ": " << rp.message;
  EXPECT_EQ(afterProbe(rp), "auto:apgd") << "nlgs " << nlgs_p.iterations << ", apgd " << apgd_p.iterations;
  EXPECT_LE(recomputedResidual(pyramid, rp), tol);
}

// Below three digits, before newton's apgd scout on the same pyramids: the probe stops at its
// first ten sweeps. There apgd needs no more iterations than nlgs sweeps, so sweeps that go on
// to the tolerance cost more than the scout, and those that stop short are lost (the scout
// starts from the start); before the rule the probe swept up to fifty times first. The scout
// ends the solve, at most ten sweeps after apgd's own iterations. At three digits, where apgd
// goes first without a scout, the same where the pyramid's load sticks (probeAllowance): the
// probe had swept to the tolerance there, 59 and 119 sweeps where apgd takes 27 and 32
// iterations. Residuals recomputed from the forces.
TEST(Portfolio, OnFacesRestingOnFacesThatStickTheProbeStopsAtTenSweepsBeforeApgd) {
  for (int base : {3, 4}) {
    const Problem pyramid = hard::toBlockSparse(cubePyramid(base, 0.8));
    for (double tol : {1e-3, 1e-5, 1e-6}) {
      const SolveResult nlgs = solveProblem(pyramid, params(SolverKind::kNlgs, tol, 100000));
      const SolveResult apgd = solveProblem(pyramid, params(SolverKind::kApgd, tol, 100000));
      ASSERT_TRUE(nlgs.converged && apgd.converged);
      ASSERT_LE(apgd.iterations, nlgs.iterations) << base << " at " << tol;
      const SolveResult r = autoSolvesAlong(pyramid, tol, "auto:apgd");
      EXPECT_EQ(r.solver, "auto:nlgs->apgd");
      EXPECT_LE(r.iterations, apgd.iterations + 10)
          << r.solver << " on " << base << " at " << tol << ": nlgs " << nlgs.iterations << ", apgd "
          << apgd.iterations;
    }
  }
}

// `boxes` boxes stacked, eight points per face, pushed sideways, at 1e-3, where nlgs needs under a
// quarter of apgd's iterations: auto ends on Gauss-Seidel's sweeps alone, within the
// over-relaxation trial of nlgs's own, its answer checked against Coulomb's law.
void expectSweepsAloneOnAPushedStack(int boxes) {
  const double tol = 1e-3;
  const Problem stack = boxStack(boxes, 8, 1.0, 0.5, 0.8);
  const SolveResult nlgs = solveProblem(stack, params(SolverKind::kNlgs, tol, 100000));
  const SolveResult apgd = solveProblem(stack, params(SolverKind::kApgd, tol, 100000));
  ASSERT_TRUE(nlgs.converged && apgd.converged);
  ASSERT_LT(4 * nlgs.iterations, apgd.iterations);
  const SolveResult r = autoSolvesAlong(stack, tol, "auto:nlgs");
  EXPECT_EQ(r.solver, "auto:nlgs");
  EXPECT_LE(r.iterations, nlgs.iterations + 20) << r.solver;  // the over-relaxation trial's at most
}

// The converse at three digits: eight boxes stacked, eight points per face, pushed sideways so
// that all their load slides. apgd, planned first for faces resting on faces, needs more than
// four times nlgs's sweeps there (each update of its shift μ|u_t| restarts its momentum, and on
// a sliding load every shift moves), so after the probe it goes behind Gauss-Seidel, which goes
// on from the probe's iterate: auto had followed apgd, 852 iterations where nlgs takes 180.
// Checked against Coulomb's law from the forces.
TEST(Portfolio, WhereTheLoadSlidesApgdGoesBehindGaussSeidel) { expectSweepsAloneOnAPushedStack(8); }

// At a loose tolerance, where the plan puts apgd first (multi-point contacts) and the probe's
// rate says Gauss-Seidel needs more sweeps than newton's warm-up and two factorizations (but
// at most twice that), newton goes on from the probe's sweeps: six boxes, four points per
// face, at 1e-3 (apgd 581 iterations, newton 28; auto followed apgd's, 601 in all). Its first
// slice is what those sweeps would cost: where newton's steps stall (five boxes, a mass ratio
// of 10: newton alone fails after 580 iterations) apgd takes over after that slice and auto
// does at most about apgd's own work. Where the sweeps' rate is far slower (a mass ratio of
// 100) apgd goes first as before. Residuals recomputed from the forces.
TEST(Portfolio, AtALooseToleranceNewtonGoesBeforeApgdWhereItCostsLessThanTheSweeps) {
  const double tol = 1e-3;
  const Problem six = boxStack(6, 4, 1.0, 0.5, 0.8);
  const SolveResult newton = solveProblem(six, params(SolverKind::kNewton, tol, 100000));
  ASSERT_TRUE(newton.converged);
  ASSERT_LT(4 * newton.iterations, solveProblem(six, params(SolverKind::kApgd, tol, 100000)).iterations);
  const SolveResult r = autoSolvesAlong(six, tol, "auto:newton");
  EXPECT_EQ(afterProbe(r), "auto:newton");
  EXPECT_LE(r.iterations, newton.iterations + 10) << r.solver;

  const Problem stalls = boxStack(5, 4, 10.0, 0.5, 0.8);
  const SolveResult newton5 = solveProblem(stalls, params(SolverKind::kNewton, tol, 100000));
  const SolveResult apgd5 = solveProblem(stalls, params(SolverKind::kApgd, tol, 100000));
  ASSERT_FALSE(newton5.converged);
  ASSERT_TRUE(apgd5.converged);
  const SolveResult s = autoSolvesAlong(stalls, tol, "auto:newton->apgd");
  EXPECT_LE(s.iterations, apgd5.iterations + 100) << s.solver;  // the probe's 50 and newton's slice at most
  autoSolvesAlong(boxStack(5, 4, 100.0, 0.5, 0.8), tol, "auto:apgd");
}

// At three digits too, where the plan puts apgd first (multi-point contacts), the probe's rate
// can put Gauss-Seidel before it: where that rate, measured past the probe's first three sweeps
// (from the start they fall faster than they go on), says Gauss-Seidel reaches the tolerance
// within a slice of its own and for less than newton's modeled cost. Five boxes stacked, eight
// points per face, at 1e-3: nlgs needs a seventh of apgd's iterations, which auto had paid after
// the probe (385 in all). Where the rate is slower (a mass ratio of 100) apgd still goes first
// (AtALooseToleranceNewtonGoesBeforeApgdWhereItCostsLessThanTheSweeps). Checked against Coulomb's
// law from the forces.
TEST(Portfolio, AtThreeDigitsTheProbesLaterRateCanPutGaussSeidelBeforeApgd) { expectSweepsAloneOnAPushedStack(5); }

// Gauss-Seidel's over-relaxation is chosen online: after the probe, ten plain sweeps measure
// their rate and, where at that rate more than ten would still be needed, ten more run at
// Young's ω for that rate; ω stays only if they did better.
// Without it the probe's and the member's sweeps are plain nlgs's own run, sweep for sweep.
// On 20 strongly coupled frictional contacts ω stays: auto sweeps fewer times than plain nlgs,
// and nlgs given a like ω (its sor parameter) confirms that over-relaxation is what saved
// them. On the ball triangle the trial keeps the plain sweeps, and auto pays for the trial
// only. Every answer is checked against Coulomb's law from the forces.
TEST(Portfolio, GaussSeidelOverRelaxesOnlyWhereATrialSaysSo) {
  const double tol = 1e-8;
  const Problem coupled = solvers_test::toBlockSparse(solvers_test::randomFrictionalProblem(20, 2, 1.0, 0.05));
  const SolveResult plain = solveProblem(coupled, params(SolverKind::kNlgs, tol, 100000));
  ASSERT_TRUE(plain.converged) << plain.message;
  SolverParams relaxed = params(SolverKind::kNlgs, tol, 100000);
  relaxed.sor = 1.35;
  const SolveResult sor = solveProblem(coupled, relaxed);
  ASSERT_TRUE(sor.converged) << sor.message;
  EXPECT_LT(sor.iterations, plain.iterations);
  const SolveResult r = solveProblem(coupled, params(SolverKind::kAuto, tol, 100000));
  ASSERT_TRUE(r.converged) << r.solver << ": " << r.message;
  EXPECT_EQ(r.solver, "auto:nlgs");
  EXPECT_LT(r.iterations, plain.iterations) << "nlgs " << plain.iterations << ", with sor 1.35 " << sor.iterations;
  EXPECT_LE(recomputedResidual(coupled, r), tol);
  // A user's own sor is used as given, with no trial: auto's sweeps are nlgs's.
  SolverParams own = params(SolverKind::kAuto, tol, 100000);
  own.sor = 1.35;
  const SolveResult fixed = solveProblem(coupled, own);
  ASSERT_TRUE(fixed.converged) << fixed.message;
  EXPECT_EQ(fixed.solver, "auto:nlgs");
  EXPECT_EQ(fixed.iterations, sor.iterations);
  EXPECT_LE(recomputedResidual(coupled, fixed), tol);

  const Problem balls = ballTriangle(10, 0.5);
  const SolveResult nlgs = solveProblem(balls, params(SolverKind::kNlgs, 1e-4, 100000));
  ASSERT_TRUE(nlgs.converged) << nlgs.message;
  const SolveResult t = solveProblem(balls, params(SolverKind::kAuto, 1e-4, 100000));
  ASSERT_TRUE(t.converged) << t.solver << ": " << t.message;
  EXPECT_EQ(t.solver, "auto:nlgs->active-set->nlgs");  // the failed sticking step (above)
  EXPECT_LE(recomputedResidual(balls, t), 1e-4);
  EXPECT_GT(t.iterations, nlgs.iterations);  // the trial's sweeps at ω were no better
  EXPECT_LE(t.iterations, nlgs.iterations + 20);
}

// Gauss-Seidel converges linearly: at a tight tolerance its remaining sweeps outnumber what
// newton costs from its iterate (its warm-up and two factorizations, n/3 sweeps each), and an
// untried newton then takes over. Two walls of balls: one block-sparse (108 rows), one dense
// (300 rows), where nlgs alone needs 428 and 803 sweeps for 1e-8 and newton ends in a few
// steps. Before the rule auto swept on for as long as nlgs alone. Each answer is checked
// against Coulomb's law from the forces.
TEST(Portfolio, GaussSeidelHandsOverToNewtonWhereItsSweepsWouldCostMore) {
  const double tol = 1e-8;
  for (const Problem& balls : {solvers_test::toBlockSparse(ballTriangle(6, 0.5)), ballTriangle(10, 0.5)}) {
    const SolveResult nlgs = solveProblem(balls, params(SolverKind::kNlgs, tol, 100000));
    ASSERT_TRUE(nlgs.converged) << nlgs.message;
    const SolveResult r = solveProblem(balls, params(SolverKind::kAuto, tol, 100000));
    ASSERT_TRUE(r.converged) << r.solver << ": " << r.message;
    EXPECT_EQ(r.solver.rfind("auto:nlgs", 0), 0u) << r.solver;
    EXPECT_NE(r.solver.find("->newton"), std::string::npos) << r.solver;
    EXPECT_LT(2 * r.iterations, nlgs.iterations) << r.solver;
    EXPECT_LE(recomputedResidual(balls, r), tol);
  }
  // At 1e-4 the sweeps left are fewer than newton's cost: Gauss-Seidel alone.
  const Problem wall = ballTriangle(10, 0.5);
  const SolveResult loose = solveProblem(wall, params(SolverKind::kAuto, 1e-4, 100000));
  ASSERT_TRUE(loose.converged) << loose.message;
  EXPECT_EQ(loose.solver.find("newton"), std::string::npos) << loose.solver;
  EXPECT_LE(recomputedResidual(wall, loose), 1e-4);
}

// Two boxes on the ground and a third across them, four points under each box: the small
// brick pyramid of the scenes (16 contacts, 48 rows against 18 DoF), pushed sideways.
Problem brickPyramid(double push, double mu) {
  World w;
  const Eigen::Vector3d size(1.0, 1.0, 0.5);
  for (int i = 0; i < 2; ++i) w.add(hard::box(1.0, size, Eigen::Vector3d(1.1 * i, 0.0, 0.25)));
  Body top = hard::box(1.0, size, Eigen::Vector3d(0.55, 0.0, 0.75));
  top.v = Eigen::Vector3d(push, 0.0, 0.0);
  const int t = w.add(top);
  for (int i = 0; i < 2; ++i)
    for (const Eigen::Vector3d& p : hard::bottomPoints(w.bodies[i].com, size, 4))
      w.contact(i, -1, p, Eigen::Vector3d::UnitZ(), mu);
  for (const Eigen::Vector3d& p : hard::bottomPoints(w.bodies[t].com, size, 4)) {  // two over each
    w.contact(t, p.x() < 0.55 ? 0 : 1, p, Eigen::Vector3d::UnitZ(), mu);
  }
  return w.problem();
}

// Before newton, multi-point contacts get an apgd scout from the start: on the brick pyramid
// apgd ends in tens of iterations where newton needs its warm-up and several steps, so the
// scout ends the solve; on the heavy box stack it does not (apgd needs thousands), and newton
// then runs as it would have. Answers checked against Coulomb's law from the forces.
TEST(Portfolio, AnApgdScoutGoesBeforeNewtonOnMultiPointContacts) {
  const Problem pyramid = brickPyramid(0.0, 0.8);
  const double tol = 1e-6;
  const SolveResult apgd = solveProblem(pyramid, params(SolverKind::kApgd, tol, 100000));
  ASSERT_TRUE(apgd.converged) << apgd.message;
  ASSERT_LE(apgd.iterations, 100);  // within the scout's allowance
  const SolveResult r = solveProblem(pyramid, params(SolverKind::kAuto, tol, 100000));
  ASSERT_TRUE(r.converged) << r.solver << ": " << r.message;
  EXPECT_EQ(r.solver, "auto:nlgs->apgd");
  EXPECT_LE(recomputedResidual(pyramid, r), tol);
  const Problem stack = boxStack(4, 4, 100.0, 0.5, 0.8);
  autoSolvesAlong(stack, tol, "auto:apgd->newton");
  // The probe before a scout stops within apgd's allowance (50 sweeps), not one sweep per row
  // as before newton alone: the scout's first residuals are apgd's own from zero, found in
  // the history right after the probe's.
  const Problem tall = boxStack(12, 4, 1.0, 0.5, 0.8);  // 144 rows: newton's allowance would be 144
  for (const auto& [p, at] : {std::pair{&pyramid, tol}, {&stack, tol}, {&tall, 1e-5}}) {
    SolverParams traced = params(SolverKind::kAuto, at, 100000);
    traced.displayDebug = true;
    const SolveResult t = solveProblem(*p, traced);
    ASSERT_TRUE(t.converged) << t.solver << ": " << t.message;
    EXPECT_LE(recomputedResidual(*p, t), at);
    traced.solver = SolverKind::kApgd;
    const SolveResult own = solveProblem(*p, traced);
    ASSERT_GE(own.residual_history.size(), 10u);
    std::size_t probe_sweeps = 0;
    for (std::size_t k = 1; k + 10 <= t.residual_history.size() && probe_sweeps == 0; ++k)
      if (std::equal(own.residual_history.begin(), own.residual_history.begin() + 10,
                     t.residual_history.begin() + static_cast<long>(k)))
        probe_sweeps = k;
    EXPECT_GT(probe_sweeps, 0u) << t.solver;
    EXPECT_LE(probe_sweeps, 50u) << t.solver << " " << p->rowCount() << " rows";
  }
}

// newton after the probe: the probe's nlgs sweeps from the start are newton's own warm-up
// (until kNewtonWarmupTolerance or kNewtonWarmupSweeps), which then runs only the rest, and a
// probe that goes on past the warm-up's end hands newton the iterate there, so the Newton
// steps that follow are those newton takes alone. Before, newton swept its whole warm-up again from the
// probe's iterate and took other steps (on a box stack at 1e-8: four that stalled, 1.4x the
// time). Checked on the steps' residuals (the histories' tails), on the forces, and on
// Coulomb's law from the forces.
TEST(Portfolio, NewtonAfterTheProbeTakesItsOwnSteps) {
  struct Case {
    Problem p;
    double tol;
    const char* what;
  };
  const Case cases[] = {
      {solvers_test::randomFrictionalProblem(20, 7, 0.5, 1e-3), 1e-8, "20 coupled contacts, seed 7"},
      {solvers_test::randomFrictionalProblem(20, 8, 0.5, 1e-3), 1e-8, "20 coupled contacts, seed 8"},
      // newton's warm-up ends at 1e-3 after a few sweeps; the probe goes on past it
      {solvers_test::randomFrictionalProblem(20, 5, 0.5, 1e-3), 1e-8, "20 coupled contacts, seed 5"},
      {boxStack(3, 4, 1.0, 0.5, 0.8), 1e-6, "3 boxes (an apgd scout before newton)"},
      {boxStack(6, 4, 1.0, 0.5, 0.8), 1e-6, "6 boxes (an apgd scout before newton)"},
  };
  for (const Case& c : cases) {
    SolverParams traced = params(SolverKind::kNewton, c.tol, 100000);
    traced.displayDebug = true;
    const SolveResult newton = solveProblem(c.p, traced);
    ASSERT_TRUE(newton.converged) << c.what << ": " << newton.message;
    traced.solver = SolverKind::kAuto;
    const SolveResult r = solveProblem(c.p, traced);
    ASSERT_TRUE(r.converged) << c.what << ": " << r.solver << ": " << r.message;
    EXPECT_LE(recomputedResidual(c.p, r), c.tol) << c.what;
    const std::string path = afterScout(r);
    ASSERT_EQ(path, "auto:newton") << c.what << ": " << r.solver;
    ASSERT_GE(newton.residual_history.size(), 2u);
    ASSERT_GE(r.residual_history.size(), 2u);
    for (std::size_t k = 1; k <= 2; ++k) {  // newton's start and one step at least
      const double own = newton.residual_history[newton.residual_history.size() - k];
      const double in_auto = r.residual_history[r.residual_history.size() - k];
      // 1e-3: the round-off of sweeping in the probe's stages instead of one run
      EXPECT_NEAR(in_auto, own, 1e-3 * own) << c.what << ": step " << k << " from the end";
    }
    const double scale = std::max(1.0, newton.forces.cwiseAbs().maxCoeff());
    EXPECT_LE((r.forces - newton.forces).cwiseAbs().maxCoeff(), 1e-6 * scale) << c.what;
  }
}

// Four frictional contacts whose normal rows couple their neighbours (κ = 0.3: above the
// "Gauss-Seidel at any tolerance" bound, so the tight plan starts with newton): each sweep
// of exact local solves contracts ~10×, so the probe's sweeps meet 1e-8 and nothing else
// runs. The answer is checked against the law independently (residual from the forces).
TEST(Portfolio, TheGaussSeidelProbeEndsWeaklyCoupledProblems) {
  Problem p;
  Eigen::MatrixXd W = Eigen::MatrixXd::Identity(12, 12);
  for (int c = 0; c < 4; ++c) {
    p.contacts.push_back(Contact{c, ContactType::kFrictional, 3, 0.5});
    W(3 * c + 1, 3 * c + 2) = W(3 * c + 2, 3 * c + 1) = 0.2;
    if (c > 0) W(3 * c, 3 * (c - 1)) = W(3 * (c - 1), 3 * c) = 0.2;
  }
  p.W = W;
  p.d_free = Eigen::VectorXd(12);
  p.d_free << -1.0, 0.3, -0.2, -0.8, -0.5, 0.1, -1.2, 0.0, 0.4, -0.6, 0.2, 0.2;
  const SolveResult newton = solveProblem(p, params(SolverKind::kNewton, 1e-8, 1000));
  ASSERT_TRUE(newton.converged) << newton.message;
  const SolveResult r = solveProblem(p, params(SolverKind::kAuto, 1e-8, 1000));
  ASSERT_TRUE(r.converged) << r.solver << ": " << r.message;
  EXPECT_EQ(r.solver, "auto:nlgs");
  EXPECT_LE(r.iterations, 10);
  EXPECT_LE(recomputedResidual(p, r), 1e-8);
  EXPECT_LE((r.forces - newton.forces).cwiseAbs().maxCoeff(), 1e-6);  // W is positive definite
}

// Beyond its first ten sweeps the probe goes on stage by stage while the rate of its last
// stage reaches the tolerance well within what the plan's first member would cost (before
// newton, about one sweep per row). 30 coupled contacts (90 rows, a tight tolerance: newton
// is planned) on which Gauss-Seidel converges steadily in 15..30 sweeps end in the probe,
// in at most nlgs's own sweeps from zero (fewer where the probe's over-relaxation window
// paid: one seed, 18 against 19); checked against Coulomb's law and against nlgs.
TEST(Portfolio, TheProbeGoesOnWhileItsRateReachesTheTolerance) {
  for (unsigned seed : {1u, 2u}) {
    const Problem p = solvers_test::randomFrictionalProblem(30, seed, 0.5, 0.2);
    const SolveResult nlgs = solveProblem(p, params(SolverKind::kNlgs, 1e-8, 1000));
    ASSERT_TRUE(nlgs.converged) << nlgs.message;
    ASSERT_GT(nlgs.iterations, 10);  // more than the probe's first ten
    const SolveResult r = solveProblem(p, params(SolverKind::kAuto, 1e-8, 1000));
    ASSERT_TRUE(r.converged) << r.solver << ": " << r.message;
    EXPECT_EQ(r.solver, "auto:nlgs") << seed;
    EXPECT_LE(r.iterations, nlgs.iterations) << seed;
    EXPECT_LE(recomputedResidual(p, r), 1e-8);
    EXPECT_LE((r.forces - nlgs.forces).cwiseAbs().maxCoeff(), 1e-6);
  }
}

// Gauss-Seidel's first sweeps from zero can raise the residual (here 8 equality rows all
// coupled by 100 to one another and a contact: above the start's for a dozen sweeps).
// The probe then sweeps once more from its own iterate and takes it as the best so far; a
// solve that maxIt ends there returns the start, not an iterate worse than it. With room to
// go on, the solve converges.
TEST(Portfolio, AProbeThatRaisesTheResidualNeverReturnsWorseThanTheStart) {
  const int n = 8;
  Problem p;
  Eigen::MatrixXd W = Eigen::MatrixXd::Zero(n + 3, n + 3);
  W.topLeftCorner(n, n).setConstant(100.0);
  W.diagonal().array() += 1.0;
  W(n, n) = 10.0;
  W.block(n, 0, 1, n).setConstant(0.5);  // one island: the contact is coupled to the rows
  W.block(0, n, n, 1).setConstant(0.5);
  p.W = W;
  p.d_free = Eigen::VectorXd::Zero(n + 3);
  for (int i = 0; i < n; ++i) {
    p.contacts.push_back(Contact{i, ContactType::kBilateral, 1, Contact::kMuDefault});
    p.d_free(i) = i % 2 ? -1.0 : 1.0;
  }
  p.contacts.push_back(Contact{n, ContactType::kFrictional, 3, 0.5});  // friction: nlgs probes
  p.d_free(n) = 0.1;  // separating: no force
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(n + 3);
  const double start = naturalMapResidual(p, effectiveMu(p, SolverParams().mu), zero, p.d_free);
  SolverParams nlgs = params(SolverKind::kNlgs, 1e-12, 3);
  nlgs.displayDebug = true;
  const SolveResult sweeps = solveProblem(p, nlgs);
  ASSERT_EQ(sweeps.residual_history.size(), 3u);
  for (double h : sweeps.residual_history) ASSERT_GT(h, start);  // the premise: the sweeps rise
  const SolveResult stopped = solveProblem(p, params(SolverKind::kAuto, 1e-12, 5));
  EXPECT_EQ(stopped.status, SolveStatus::kMaxIterations);
  EXPECT_EQ(stopped.iterations, 5);
  EXPECT_LE(recomputedResidual(p, stopped), start);
  const SolveResult solved = solveProblem(p, params(SolverKind::kAuto, 1e-8, 100000));
  ASSERT_TRUE(solved.converged) << solved.solver << ": " << solved.message;
  EXPECT_LE(recomputedResidual(p, solved), 1e-8);
}

// A frictionless stack (μ = 0: one normal row per contact) has a symmetric, coupled W: a
// convex QP, which newton's active-set path ends in a few Cholesky steps, so auto starts
// there, without the Gauss-Seidel probe (it would only delay them). The same W made
// non-symmetric is no QP: the probe, then Lemke's pivoting.
TEST(Portfolio, SymmetricCoupledLcpStartsWithNewtonOtherwiseLemke) {
  const Problem stack = boxStack(3, 4, 1.0, 0.5, 0.0);
  ASSERT_TRUE(std::holds_alternative<Eigen::MatrixXd>(stack.W));
  const SolveResult r = solveProblem(stack, params(SolverKind::kAuto, 1e-8, 5000));
  ASSERT_TRUE(r.converged) << r.solver << ": " << r.message;
  EXPECT_EQ(r.solver.rfind("auto:newton", 0), 0u) << r.solver;
  EXPECT_LE(recomputedResidual(stack, r), 1e-8);
  // Symmetric but strongly dominant (κ = 0.05 < 0.25): a few pgs sweeps contract it, first.
  Eigen::Matrix3d D;
  D << 4.0, 0.1, -0.1, 0.1, 4.0, 0.1, -0.1, 0.1, 4.0;
  const Problem dominant = frictionlessLcp(D, Eigen::Vector3d(-1.0, 0.5, -2.0));
  const SolveResult d = solveProblem(dominant, params(SolverKind::kAuto, 1e-10, 1000));
  ASSERT_TRUE(d.converged) << d.message;
  EXPECT_EQ(d.solver, "auto:pgs");
  EXPECT_LE(recomputedResidual(dominant, d), 1e-10);
  Problem skewed = stack;
  Eigen::MatrixXd W = toDense(skewed.W);
  W(0, 3) += 0.1 * W(0, 0);  // normal rows 0 and 1 (rows 0 and 3), one side only
  skewed.W = W;
  const SolveResult s = solveProblem(skewed, params(SolverKind::kAuto, 1e-8, 5000));
  EXPECT_EQ(afterProbe(s).rfind("auto:lemke", 0), 0u) << s.solver;
}

// A small symmetric LCP whose plan is newton runs newton's active-set path without the
// portfolio's bookkeeping: the same path and answer. Where that path cannot solve it (an
// indefinite W: its Cholesky and LDLᵀ fail), the portfolio starts as before and its newton
// member's general semismooth Newton carries it.
TEST(Portfolio, ASmallSymmetricLcpRunsNewtonsActiveSetDirectly) {
  // Singular W (rank 1): every z1 + z2 = 1, z >= 0 solves it.
  Eigen::Matrix2d singular;
  singular << 1.0, 1.0, 1.0, 1.0;
  const Problem flat = frictionlessLcp(singular, Eigen::Vector2d(-1.0, -1.0));
  const SolveResult r = autoSolvesAlong(flat, 1e-10, "auto:newton");
  EXPECT_EQ(r.solver, "auto:newton");
  EXPECT_NEAR(r.forces.sum(), 1.0, 1e-10);
  EXPECT_GE(r.forces.minCoeff(), 0.0);
  const SolveResult newton = solveProblem(flat, params(SolverKind::kNewton, 1e-10, 1000));
  EXPECT_EQ(r.forces, newton.forces);
  EXPECT_EQ(r.iterations, newton.iterations);
  // Indefinite (eigenvalues 3 and -1): λ = (1, 0) gives d = (0, 1).
  Eigen::Matrix2d indefinite;
  indefinite << 1.0, 2.0, 2.0, 1.0;
  const Problem saddle = frictionlessLcp(indefinite, Eigen::Vector2d(-1.0, -1.0));
  const SolveResult s = solveProblem(saddle, params(SolverKind::kAuto, 1e-10, 1000));
  ASSERT_TRUE(s.converged) << s.solver << ": " << s.message;
  EXPECT_LE(recomputedResidual(saddle, s), 1e-10) << s.solver;
  // Why the portfolio ran: newton alone leaves the active-set path for its general Newton.
  const SolveResult general = solveProblem(saddle, params(SolverKind::kNewton, 1e-10, 1000));
  EXPECT_EQ(general.message.find("active-set"), std::string::npos) << general.message;
}

// A few contacts at a loose tolerance start with newton, whose warm-up is the probe's sweeps:
// three boxes stacked, one contact per face, the middle one 100 times heavier, pushed
// sideways. Gauss-Seidel's rate collapses on the mass ratio (hundreds of sweeps) and apgd,
// which the features predicted before, crawls (100-160 iterations); the warm-up and a few
// Newton steps finish.
TEST(Portfolio, FewContactsAtALooseToleranceStartWithNewton) {
  World w;
  const Eigen::Vector3d size(1.0, 1.0, 0.5);
  for (int i = 0; i < 3; ++i) {
    Body b = hard::box(i == 1 ? 100.0 : 1.0, size, Eigen::Vector3d(0.0, 0.0, 0.25 + 0.5 * i));
    b.v = Eigen::Vector3d(i == 1 ? 0.5 : -0.5, 0.15, 0.0);
    w.add(b);
  }
  for (int i = 0; i < 3; ++i)
    w.contact(i, i - 1, w.bodies[i].com - Eigen::Vector3d(0.0, 0.0, 0.25), Eigen::Vector3d::UnitZ(), 0.3);
  const Problem p = w.problem();
  for (double tol : {1e-2, 1e-3}) {
    const SolveResult nlgs = solveProblem(p, params(SolverKind::kNlgs, tol, 5000));
    const SolveResult newton = solveProblem(p, params(SolverKind::kNewton, tol, 5000));
    ASSERT_TRUE(nlgs.converged && newton.converged) << tol;
    ASSERT_GT(nlgs.iterations, 4 * newton.iterations) << tol;  // why newton leads here
    const SolveResult r = solveProblem(p, params(SolverKind::kAuto, tol, 5000));
    ASSERT_TRUE(r.converged) << r.solver << ": " << r.message;
    EXPECT_EQ(r.solver, "auto:nlgs->newton") << tol;  // the probe, then newton
    EXPECT_LE(r.iterations, newton.iterations + 3) << tol;
    EXPECT_LE(recomputedResidual(p, r), tol);
  }
}

// A symmetric LCP whose plan is newton's active-set path (κ = 0.6 here, not dominant enough for
// pgs first) is probed by pgs only where two digits are asked and one factorization costs at
// least twenty sweeps (rows / 6 >= 20): a chain of 150 coupled rows, which pgs contracts in a
// few sweeps, then ends in the probe; at 1e-8, or with 60 rows, newton starts at once. Dense
// and block-sparse alike (a block-sparse LCP is presumed symmetric).
TEST(Portfolio, LargeSymmetricLcpAtTwoDigitsIsProbedByGaussSeidel) {
  const auto chain = [](int n, bool sparse) {
    Eigen::MatrixXd W = Eigen::MatrixXd::Identity(n, n);
    Eigen::VectorXd d_free(n);
    for (int i = 0; i < n; ++i) {
      if (i + 1 < n) W(i, i + 1) = W(i + 1, i) = 0.3;
      d_free[i] = -1.0 - 0.5 * std::sin(0.7 * i);
    }
    Problem p = frictionlessLcp(W, d_free);
    if (sparse) {
      BlockSparseMatrix B = BlockSparseMatrix::withBlockSizes(std::vector<int>(n, 1));
      for (int i = 0; i < n; ++i) {
        B.beginRow();
        for (int j = std::max(0, i - 1); j <= std::min(n - 1, i + 1); ++j) B.addBlock(j, W.block(i, j, 1, 1));
      }
      p.W = B;
    }
    return p;
  };
  for (bool sparse : {false, true}) {
    const Problem large = chain(150, sparse);
    const SolveResult loose = solveProblem(large, params(SolverKind::kAuto, 1e-2, 1000));
    ASSERT_TRUE(loose.converged) << loose.solver << ": " << loose.message;
    EXPECT_EQ(loose.solver, "auto:pgs") << sparse;
    EXPECT_LE(loose.iterations, 25) << sparse;  // within one factorization's sweeps
    EXPECT_LE(recomputedResidual(large, loose), 1e-2);
    const SolveResult tight = solveProblem(large, params(SolverKind::kAuto, 1e-8, 1000));
    ASSERT_TRUE(tight.converged) << tight.solver << ": " << tight.message;
    EXPECT_EQ(tight.solver, "auto:newton") << sparse;
    EXPECT_LE(recomputedResidual(large, tight), 1e-8);
    const Problem small = chain(60, sparse);
    const SolveResult s = solveProblem(small, params(SolverKind::kAuto, 1e-2, 1000));
    ASSERT_TRUE(s.converged) << s.solver << ": " << s.message;
    EXPECT_EQ(s.solver, "auto:newton") << sparse;
    EXPECT_LE(recomputedResidual(small, s), 1e-2);
  }
}

// A bimatrix game's LCP (W = [0 A; Bᵀ 0]) has no diagonal: pgs cannot start (zero_diagonal),
// so auto leaves it out of the plan; Lemke, whose covering ray ends here, hands over to newton.
TEST(Portfolio, LcpWithoutDiagonalLeavesPgsOut) {
  Eigen::Matrix4d W;
  W << 0, 0, 1, 3, 0, 0, 2, 1, 1, 3, 0, 0, 2, 1, 0, 0;
  const Problem game = frictionlessLcp(W, -Eigen::Vector4d::Ones());
  ASSERT_EQ(solveProblem(game, params(SolverKind::kPgs, 1e-8, 100)).status, SolveStatus::kZeroDiagonal);
  const SolveResult r = solveProblem(game, params(SolverKind::kAuto, 1e-8, 1000));
  ASSERT_TRUE(r.converged) << r.solver << ": " << r.message;
  EXPECT_EQ(r.solver.find("pgs"), std::string::npos) << r.solver;
  solvers_test::expectPath(r);
  EXPECT_LE(recomputedResidual(game, r), 1e-8);
}

// A non-symmetric W with a positive, dominant diagonal (an H-matrix): projected Gauss-Seidel
// converges there, so auto starts with it; a single contact is its own local solve.
TEST(Portfolio, DominantLcpStartsWithGaussSeidelAndOneContactSkipsTheFeatures) {
  Eigen::Matrix3d W;
  W << 2.0, 0.5, 0.3, -0.2, 1.5, 0.4, 0.6, 0.1, 3.0;
  Problem lcp = frictionlessLcp(W, Eigen::Vector3d(-1.0, 0.5, -2.0));
  const SolveResult r = solveProblem(lcp, params(SolverKind::kAuto, 1e-10, 1000));
  EXPECT_EQ(r.solver.rfind("auto:pgs", 0), 0u) << r.solver;
  ASSERT_TRUE(r.converged) << r.message;
  EXPECT_LE(recomputedResidual(lcp, r), 1e-10);
  // The same W with one side of the dominance lost (row 0: |0.5| + |2.5| > 2): Lemke first.
  W(0, 2) = 2.5;
  lcp.W = Eigen::MatrixXd(W);
  const SolveResult s = solveProblem(lcp, params(SolverKind::kAuto, 1e-10, 1000));
  expectPlanStartsWith(s, "auto:lemke");
  EXPECT_LE(recomputedResidual(lcp, s), 1e-10);

  World w;
  w.add(hard::box(1.0, Eigen::Vector3d(1.0, 1.0, 1.0), Eigen::Vector3d(0.0, 0.0, 0.5)));
  w.contact(0, -1, Eigen::Vector3d(0.0, 0.0, 0.0), Eigen::Vector3d::UnitZ(), 0.5);
  const Problem one = w.problem();
  const SolveResult o = solveProblem(one, params(SolverKind::kAuto, 1e-10, 1000));
  EXPECT_EQ(o.solver, "auto:nlgs");
  ASSERT_TRUE(o.converged) << o.message;
  EXPECT_LE(recomputedResidual(one, o), 1e-10);
}

// One contact alone: Gauss-Seidel's local step is its exact solve, so auto's probe ends the
// solve with nlgs's answer, bit for bit. Where the user's over-relaxation overshoots that
// solve on every sweep the probe does not end it, and the portfolio must still converge.
TEST(Portfolio, OneContactIsGaussSeidelsAnswerAndOverRelaxedStillConverges) {
  World w;
  w.add(hard::box(1.0, Eigen::Vector3d(1.0, 1.0, 1.0), Eigen::Vector3d(0.0, 0.0, 0.5)));
  w.contact(0, -1, Eigen::Vector3d(0.2, 0.1, 0.0), Eigen::Vector3d(0.1, 0.0, 1.0).normalized(), 0.3);
  Problem one = w.problem();
  one.d_free = Eigen::Vector3d(-0.4, 0.3, -0.2);  // pressed and sliding: the cone's edge
  const SolveResult a = solveProblem(one, params(SolverKind::kAuto, 1e-10, 1000));
  const SolveResult g = solveProblem(one, params(SolverKind::kNlgs, 1e-10, 1000));
  EXPECT_EQ(a.solver, "auto:nlgs");
  ASSERT_TRUE(a.converged) << a.message;
  ASSERT_TRUE(g.converged) << g.message;
  EXPECT_EQ(a.iterations, g.iterations);
  EXPECT_EQ(a.forces, g.forces);
  EXPECT_GT(std::abs(a.forces(1)) + std::abs(a.forces(2)), 0.0);  // friction acts
  EXPECT_LE(recomputedResidual(one, a), 1e-10);

  SolverParams over = params(SolverKind::kAuto, 1e-10, 1000);
  over.sor = 1.9;  // each sweep lands 0.9 of the way past the exact local solve
  const SolveResult o = solveProblem(one, over);
  ASSERT_TRUE(o.converged) << o.message;
  EXPECT_GT(o.iterations, 3);  // not ended by the first sweeps
  EXPECT_LE(recomputedResidual(one, o), 1e-10);
}

// A block-sparse LCP W is presumed symmetric (assembled J M⁻¹ Jᵀ) and goes to newton first,
// which tests the symmetry itself: a non-symmetric, coupled one must still be solved.
TEST(Portfolio, NonSymmetricBlockSparseLcpIsStillSolved) {
  Eigen::MatrixXd W(4, 4);
  W << 1.0, 0.9, 0.0, 0.4, -0.6, 1.0, 0.7, 0.0, 0.0, 0.2, 1.0, 0.8, 0.5, 0.0, -0.9, 1.0;
  Problem lcp = frictionlessLcp(W, Eigen::Vector4d(-1.0, -0.5, 0.3, -2.0));
  BlockSparseMatrix B = BlockSparseMatrix::withBlockSizes({1, 1, 1, 1});
  for (int i = 0; i < 4; ++i) {
    B.beginRow();
    for (int j = 0; j < 4; ++j)
      if (W(i, j) != 0.0) B.addBlock(j, W.block(i, j, 1, 1));
  }
  lcp.W = B;
  const SolveResult r = solveProblem(lcp, params(SolverKind::kAuto, 1e-10, 10000));
  ASSERT_TRUE(r.converged) << r.solver << ": " << r.message;
  expectPlanStartsWith(r, "auto:newton");
  EXPECT_LE(recomputedResidual(lcp, r), 1e-10);
  // The same problem dense is compared, so it goes to Lemke (W is not dominant enough for pgs).
  lcp.W = W;
  const SolveResult d = solveProblem(lcp, params(SolverKind::kAuto, 1e-10, 10000));
  ASSERT_TRUE(d.converged) << d.solver << ": " << d.message;
  expectPlanStartsWith(d, "auto:lemke");
  EXPECT_LE(recomputedResidual(lcp, d), 1e-10);
}

// A box pressed by three contacts whose cones cannot balance it (found by a random search):
// with the four-sided pyramid pgs runs out of iterations and Lemke ends on a ray. Both
// failed, auto returns the better iterate by the pyramid residual, the measure of every
// member here (it once judged Lemke's by the disc residual, 9e5, and returned pgs's iterate,
// pyramid residual 1.08, against Lemke's 0.77).
TEST(Portfolio, PyramidMembersAreComparedByThePyramidResidual) {
  World w;
  w.add(hard::box(1.0, Eigen::Vector3d(0.2, 0.2, 0.2), Eigen::Vector3d(0.0, 0.0, 0.1)));
  w.gravity.setZero();
  w.bodies[0].v = Eigen::Vector3d(0.30709956068382738, 0.11168849306717443, -0.89115181605163385);
  w.bodies[0].w = Eigen::Vector3d(-0.99617456573039576, -0.00073698359888996201, 0.18596468404572253);
  // normal, point, μ, gap
  const double contacts[3][8] = {
      {0.86945483772697696, 0.49094067623509086, -0.055004886791881355, -0.099924128922067396,
       0.07467883837190066, 0.019753918700012155, 1.1219173508270313, 0.0012778684042408783},
      {0.42535550060312999, 0.90434064967896943, -0.035223393432208018, 0.026224407782496642,
       -0.079267231144101127, -0.044592862680056793, 0.2998380083695516, -0.00077802933150954991},
      {-0.58837162009196109, -0.61055277152988274, -0.53013597298008364, -0.021770629477739879,
       -0.0056514969218544155, -0.015351727260496151, 0.42918414886735351, -0.021571325763366768}};
  for (const auto& c : contacts)
    w.contact(0, -1, Eigen::Vector3d(c[3], c[4], c[5]), Eigen::Vector3d(c[0], c[1], c[2]), c[6], c[7]);
  const Problem p = w.problem();
  const auto pyramid = [](SolverKind kind) {
    SolverParams q = params(kind, 1e-8, 2000);
    q.friction_model = FrictionModel::kPyramid4;
    return q;
  };
  const SolveResult pgs = solveProblem(p, pyramid(SolverKind::kPgs));
  const SolveResult lemke = solveProblem(p, pyramid(SolverKind::kLemke));
  ASSERT_FALSE(pgs.converged);
  ASSERT_EQ(lemke.status, SolveStatus::kRayTermination);
  ASSERT_LT(lemke.solver_error, 0.9 * pgs.solver_error);  // Lemke's iterate is the better one
  const SolveResult r = solveProblem(p, pyramid(SolverKind::kAuto));
  EXPECT_FALSE(r.converged);
  EXPECT_NE(r.solver.find("lemke"), std::string::npos) << r.solver;
  EXPECT_EQ(r.friction_model, FrictionModel::kPyramid4);
  EXPECT_LE(r.solver_error, lemke.solver_error * (1.0 + 1e-9)) << r.solver;
  EXPECT_TRUE(r.forces.allFinite());
}

// W = -I: no member can solve it (pgs cannot start, Lemke ends on a ray, newton and apgd
// diverge). auto fails honestly and names the last member that failed and its reason.
TEST(Portfolio, WhenEveryMemberFailsTheMessageNamesTheLast) {
  const Problem p = frictionlessLcp(-Eigen::MatrixXd::Identity(2, 2), Eigen::Vector2d(1.0, -1.0));
  const SolveResult r = solveProblem(p, params(SolverKind::kAuto, 1e-8, 10000));
  EXPECT_FALSE(r.converged);
  EXPECT_EQ(r.status, SolveStatus::kNumericalFailure) << r.message;
  const std::string last = r.solver.substr(r.solver.find_last_of(":>") + 1);
  EXPECT_EQ(r.message.rfind("auto: every member failed; last " + last + ": ", 0), 0u) << r.message;
  EXPECT_EQ(r.message.find(last + ": " + last + ": "), std::string::npos) << r.message;  // named once
  EXPECT_TRUE(r.forces.allFinite());
}

TEST(Portfolio, ProxIsANamedSolver) {
  SolverKind kind;
  ASSERT_TRUE(parseSolverName("prox", &kind));
  EXPECT_EQ(kind, SolverKind::kProx);
  EXPECT_STREQ(solverName(SolverKind::kProx), "prox");
  const Problem p = boxStack(3, 4, 1.0, 0.5, 0.8);
  const SolveResult r = solveProblem(p, params(SolverKind::kProx, 1e-10, 5000));
  EXPECT_EQ(r.solver, "prox");
  EXPECT_TRUE(r.stages.empty());
  ASSERT_TRUE(r.converged) << r.message;
  EXPECT_LE(recomputedResidual(p, r), 1e-10);
}

// A caller may solve the same Problem object again after changing W in place (a node reusing
// its buffers): what auto kept from the last solve (Gauss-Seidel blocks, apgd's state) must not
// leak into the next. Checked against the same solves on fresh copies, on a frictional problem
// (the block sweep) and on a block-sparse LCP of one-row contacts (the scalar-row sweep).
TEST(Portfolio, NothingKeptFromTheLastSolveOfAChangedProblem) {
  Problem frictional = boxStack(3, 4, 10.0, 0.5, 0.8);
  Problem lcp = hard::toBlockSparse(frictionlessLcp(
      (Eigen::MatrixXd(3, 3) << 4.0, 0.3, 0.1, 0.3, 4.0, 0.3, 0.1, 0.3, 4.0).finished(), Eigen::Vector3d(-1.0, -0.5, 0.2)));
  for (Problem* p : {&frictional, &lcp}) {
    const SolverParams sp = params(SolverKind::kAuto, 1e-9, 100000);
    const SolveResult before = solveProblem(*p, sp);
    ASSERT_TRUE(before.converged) << before.solver << ": " << before.message;
    // Stiffer contacts: every diagonal block of W changes, the object stays.
    if (auto* dense = std::get_if<Eigen::MatrixXd>(&p->W)) dense->diagonal() *= 3.0;
    else for (double& v : std::get<BlockSparseMatrix>(p->W).values) v *= 3.0;
    const Problem copy = *p;
    const SolveResult again = solveProblem(*p, sp);
    const SolveResult fresh = solveProblem(copy, sp);
    ASSERT_TRUE(again.converged) << again.solver << ": " << again.message;
    EXPECT_EQ(again.solver, fresh.solver);
    EXPECT_EQ(again.forces, fresh.forces);
    EXPECT_LE(recomputedResidual(*p, again), 1e-9);
    EXPECT_GT((again.forces - before.forces).cwiseAbs().maxCoeff(), 1e-6) << "W's change must change the answer";
  }
}

// A kernel's context for p, as ContactSolver builds it: every contact active, no memo.
SolveContext kernelContext(const Problem& p, const SolverParams& sp) {
  SolveContext ctx;
  ctx.problem = &p;
  ctx.params = &sp;
  ctx.offsets = p.rowOffsets();
  ctx.mu = effectiveMu(p, sp.mu);
  ctx.ignored.assign(p.contacts.size(), false);
  return ctx;
}

// Gauss-Seidel called again from exactly the λ its last call ended with, through one memo
// (auto's probe stages and slices), goes on with the d it maintained (KeptD) instead of
// forming W λ again: sweep for sweep the iterates of one long call, bit for bit, its exact
// refresh every 50 sweeps included. From any other λ it forms d afresh (as a call with a new
// memo does, bit for bit). Dense W, block-sparse W and one-row contacts (the scalar-row
// sweep); the converged answer checked against d recomputed from W and d_free.
TEST(Portfolio, GaussSeidelContinuedThroughItsMemoSweepsAsOneCall) {
  const Problem frictional = solvers_test::randomFrictionalProblem(20, 11, 0.5, 1e-6);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::MatrixXd A(12, 14);
  for (int i = 0; i < A.rows(); ++i)
    for (int j = 0; j < A.cols(); ++j) A(i, j) = u(rng);
  const Eigen::MatrixXd spd = A * A.transpose() / 14.0 + 1e-2 * Eigen::MatrixXd::Identity(12, 12);
  const Eigen::VectorXd q = -Eigen::VectorXd::LinSpaced(12, 0.2, 1.0);
  const std::vector<std::pair<std::string, Problem>> problems = {
      {"dense", frictional}, {"block-sparse", solvers_test::toBlockSparse(frictional)},
      {"scalar rows", solvers_test::toBlockSparse(frictionlessLcp(spd, q))}};
  for (const auto& [name, p] : problems) {
    SCOPED_TRACE(name);
    SolverParams long_run;
    long_run.solver = SolverKind::kNlgs;
    long_run.tolerance = 1e-300;  // never met: every call runs its maxIt sweeps
    long_run.maxIt = 56;  // past the refresh at 50, before round-off decides which iterate is best
    const SolveContext one = kernelContext(p, long_run);
    Eigen::VectorXd whole = Eigen::VectorXd::Zero(p.rowCount());
    runNonlinearGaussSeidel(one, whole);

    SolverParams chunk = long_run;
    chunk.maxIt = 8;
    GaussSeidelMemo memo;
    SolveContext chunked = kernelContext(p, chunk);
    chunked.gs_memo = &memo;
    Eigen::VectorXd x = Eigen::VectorXd::Zero(p.rowCount());
    for (int k = 0; k < long_run.maxIt / chunk.maxIt; ++k) {
      runNonlinearGaussSeidel(chunked, x);
      // The call returned its last iterate (not an earlier, better one), so the next starts
      // where the long call goes on: what makes the comparison below sweep for sweep.
      ASSERT_EQ(memo.kept.problem, &p) << "call " << k;
      ASSERT_EQ(memo.kept.lambda, x) << "call " << k;
    }
    EXPECT_EQ(x, whole);

    // Moved off the kept λ: d formed afresh, as with a new memo.
    x[0] += 0.1;
    Eigen::VectorXd fresh = x;
    GaussSeidelMemo new_memo;
    SolveContext unkept = chunked;
    unkept.gs_memo = &new_memo;
    runNonlinearGaussSeidel(chunked, x);
    runNonlinearGaussSeidel(unkept, fresh);
    EXPECT_EQ(x, fresh);

    // To convergence in slices: the residual it reports is that of d recomputed from scratch.
    SolverParams tight = chunk;
    tight.tolerance = 1e-9;
    SolveContext to_tolerance = kernelContext(p, tight);
    to_tolerance.gs_memo = &memo;
    KernelReport r;
    for (int k = 0; k < 1000 && r.status != SolveStatus::kConverged; ++k) r = runNonlinearGaussSeidel(to_tolerance, x);
    ASSERT_EQ(r.status, SolveStatus::kConverged);
    Eigen::VectorXd d;
    multiply(p.W, x, d);
    d += p.d_free;
    EXPECT_NEAR(naturalMapResidual(p, effectiveMu(p, tight.mu), x, d), r.solver_error, 1e-12);
    EXPECT_LE(r.solver_error, 1e-9);
  }
}

// A member on trial (SolveContext::trialPassed, auto's first slice of a member handed a
// stall): past its trial deadline a kernel stops with kTimeBudget only while its best residual
// is not below the one it started from. Here the deadline has passed before the run starts.
// Handed a start residual every iterate beats (∞) each kernel runs exactly as without a
// trial; handed one nothing can beat (0), nlgs, apgd and prox stop at their first check
// (newton reads that value as its start's residual: not asked of it). From λ = 0 at its true
// residual the trial is whatever the kernel's first steps do: nlgs's first sweep raises it here.
TEST(Portfolio, AMemberOnTrialStopsOnlyWhereItHasNotLoweredTheResidual) {
  Problem p = boxStack(4, 4, 100.0, 0.5, 0.8);
  const SolverParams sp = params(SolverKind::kAuto, 1e-10, 5000);
  SolveContext ctx = kernelContext(p, sp);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(p.rowCount());
  using Kernel = KernelReport (*)(const SolveContext&, Eigen::VectorXd&);
  const std::vector<std::pair<const char*, Kernel>> kernels = {
      {"nlgs", runNonlinearGaussSeidel}, {"apgd", runApgd}, {"newton", runNewton}, {"prox", runProxNewton}};
  for (const auto& [name, run] : kernels) {
    SolveContext free = ctx;
    Eigen::VectorXd free_x = zero;
    const KernelReport free_r = run(free, free_x);
    ASSERT_NE(free_r.status, SolveStatus::kTimeBudget) << name;
    ASSERT_GT(free_r.iterations, 1) << name;

    SolveContext trial = ctx;
    trial.has_trial_deadline = true;
    trial.trial_deadline = std::chrono::steady_clock::now() - std::chrono::seconds(1);
    trial.start_residual = std::numeric_limits<double>::infinity();
    Eigen::VectorXd x = zero;
    const KernelReport r = run(trial, x);
    EXPECT_EQ(r.status, free_r.status) << name;
    EXPECT_EQ(r.iterations, free_r.iterations) << name;
    EXPECT_EQ(x, free_x) << name;

    if (std::string(name) == "newton") continue;
    trial.start_residual = 0.0;
    x = zero;
    const KernelReport stopped = run(trial, x);
    EXPECT_EQ(stopped.status, SolveStatus::kTimeBudget) << name;
    EXPECT_LT(stopped.iterations, free_r.iterations) << name;
    EXPECT_TRUE(x.allFinite()) << name;
  }
}

// auto runs apgd in slices; handed back exactly what a slice returned, the next one resumes
// that slice's momentum, step and shift (ApgdMemo), so two slices are one long run. Checked
// against a single run of the same length, and against a restart (which must differ, or the
// check would prove nothing).
TEST(Portfolio, ApgdSlicesResumeAsOneLongRun) {
  Problem p = boxStack(4, 4, 100.0, 0.5, 0.8);
  SolverParams sp = params(SolverKind::kApgd, 1e-14, 80);
  SolveContext ctx = kernelContext(p, sp);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(p.rowCount());

  Eigen::VectorXd whole = zero;  // one run of 80 iterations
  const KernelReport one = runApgd(ctx, whole);
  ASSERT_EQ(one.status, SolveStatus::kMaxIterations) << "the case must not converge in 80 iterations";

  sp.maxIt = 40;
  Eigen::VectorXd restarted = zero;  // two slices without the memo
  runApgd(ctx, restarted);
  runApgd(ctx, restarted);

  ApgdMemo memo;
  ctx.apgd_memo = &memo;
  Eigen::VectorXd sliced = zero;  // two slices with it
  const KernelReport first = runApgd(ctx, sliced);
  EXPECT_EQ(first.iterations, 40);
  const KernelReport second = runApgd(ctx, sliced);
  EXPECT_EQ(second.iterations, 40);

  const double scale = whole.norm();
  ASSERT_GT(scale, 0.0);
  EXPECT_LE((sliced - whole).norm(), 1e-12 * scale) << "the second slice did not resume the first";
  EXPECT_GT((restarted - whole).norm(), 1e-9 * scale) << "a restart changes nothing here: no evidence";
  // The answer is the residual's best over both slices, recomputed from λ alone.
  Eigen::VectorXd d;
  ctx.computeD(sliced, d);
  EXPECT_NEAR(naturalMapResidual(p, ctx.mu, sliced, d, ctx.ignored), second.solver_error,
              1e-12 * std::max(1.0, second.solver_error));
  EXPECT_LE(second.solver_error, first.solver_error);

  // Handed anything else, apgd starts afresh: the memo only resumes its own answer.
  Eigen::VectorXd other = 0.5 * sliced, fresh = 0.5 * sliced;
  runApgd(ctx, other);
  ctx.apgd_memo = nullptr;
  runApgd(ctx, fresh);
  EXPECT_EQ(other, fresh);
}

}  // namespace
}  // namespace lcp_contact_solver::core
