// The unbuilt Gauss-Seidel against the built solve on the same problems (unbuilt_test_util.h).
#include "unbuilt_test_util.h"

namespace lcp_contact_solver::core {
namespace {

using namespace unbuilt_test;

// ---- the unbuilt solve against the built one -------------------------------------------------

TEST(Unbuilt, FrictionalAndFrictionlessGiveTheBuiltForces) {
  for (unsigned seed : {11u, 12u, 13u, 14u}) {
    SCOPED_TRACE(seed);
    const RandomScene s = randomScene(10, 14, seed);
    expectSameAsBuilt(s.problem, tight());
  }
}

TEST(Unbuilt, BilateralContactsGiveTheBuiltForces) {
  Mix mix;
  mix.bilateral = 0.4;
  mix.frictionless = 0.2;
  for (unsigned seed : {21u, 22u}) {
    SCOPED_TRACE(seed);
    const RandomScene s = randomScene(10, 12, seed, mix);
    expectSameAsBuilt(s.problem, tight());
  }
}

TEST(Unbuilt, TorsionalAndRollingContactsGiveTheBuiltForces) {
  // 4-row (spin) and 6-row (spin + rolling) contacts: angular rows J = ±[0, ωᵀ].
  RandomScene s = randomScene(8, 10, 17);
  std::mt19937 rng(18);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (std::size_t i = 0; i < s.problem.contacts.size(); ++i) {
    Contact& c = s.problem.contacts[i];
    ContactJacobian& j = s.bodies.contacts[i];
    if (c.type != ContactType::kFrictional) continue;
    c.type = i % 2 ? ContactType::kTorsional : ContactType::kRolling;
    c.rows = rowsForType(c.type);
    c.mu_torsional = 0.01;
    c.mu_rolling = 0.005;
    const int old_rows = j.rows;
    j.rows = c.rows;
    for (JacobianBlock* J : {&j.jacobian_a, &j.jacobian_b}) {
      if (J->rows() == 0) continue;
      const double sign = J == &j.jacobian_a ? 1.0 : -1.0;
      const JacobianBlock linear = *J;
      J->setZero(c.rows, 6);
      J->topRows(old_rows) = linear;
      for (int k = 3; k < c.rows; ++k) J->row(k).tail<3>() = sign * linear.row(k - 3).head<3>();
    }
  }
  s.problem.d_free.resize(s.bodies.rowCount());
  int row = 0;
  for (const Contact& c : s.problem.contacts) {
    for (int k = 0; k < c.rows; ++k)
      s.problem.d_free[row + k] = k == 0 ? -1e-3 * (1.2 + u(rng)) : 3e-4 * u(rng);
    row += c.rows;
  }
  s.problem.bodies = std::make_shared<const BodyCompliance>(s.bodies);
  ASSERT_EQ(validateProblem(s.problem), "");
  expectSameAsBuilt(s.problem, tight());
}

TEST(Unbuilt, FrictionlessProblemsRunPgsUnbuilt) {
  Mix mix;
  mix.frictionless = 1.0;
  const RandomScene s = randomScene(8, 20, 31, mix);
  for (SolverKind kind : {SolverKind::kPgs, SolverKind::kAuto}) {
    const SolveResult r = solveProblem(s.problem, unbuilt(tight(kind)));
    EXPECT_EQ(r.solver, kind == SolverKind::kAuto ? "auto:pgs" : "pgs");
    EXPECT_TRUE(r.unbuilt);
    // Built, auto may start elsewhere (Lemke on a coupled LCP); its unbuilt path is pgs.
    expectSameAsBuilt(s.problem, tight(SolverKind::kPgs));
  }
}

TEST(Unbuilt, AutoStaysGaussSeidelAtTightTolerances) {
  // Unbuilt, auto starts with Gauss-Seidel (W is not formed unless a fallback needs it);
  // built block-sparse with a moderate normal coupling (κ < 2) it starts with nlgs as well
  // (the rate watch may then let apgd try: built, W exists).
  const RandomScene s = randomScene(10, 14, 41);
  const SolveResult u = solveProblem(s.problem, unbuilt(tight(SolverKind::kAuto)));
  EXPECT_EQ(u.solver, "auto:nlgs");
  EXPECT_TRUE(u.unbuilt);
  EXPECT_EQ(u.status, SolveStatus::kConverged) << u.message;
  EXPECT_NE(u.message.find("unbuilt solve on the body form (10 bodies)"), std::string::npos) << u.message;
  const SolveResult b = solveProblem(builtSparse(s.problem), tight(SolverKind::kAuto));
  EXPECT_EQ(b.solver.rfind("auto:nlgs", 0), 0u) << b.solver;
  EXPECT_EQ(b.status, SolveStatus::kConverged) << b.message;
  EXPECT_LT(relDiff(u.forces, b.forces), 1e-7);
}

TEST(Unbuilt, SameSweepsBeforeConvergence) {
  // maxIt = 3: not converged, and still the same iterate: it is the same iteration.
  const RandomScene s = randomScene(10, 14, 51);
  SolverParams params = tight();
  params.maxIt = 3;
  expectSameAsBuilt(s.problem, params, 1e-10, false);
  EXPECT_EQ(solveProblem(s.problem, unbuilt(params)).iterations, 3);
}

TEST(Unbuilt, WarmStartMinWMaxFRegularizationSorAndSofaRule) {
  const RandomScene s = randomScene(10, 16, 61);
  {
    SCOPED_TRACE("regularization");
    SolverParams params = tight();
    params.regularizationTerm = 1e-6;
    expectSameAsBuilt(s.problem, params);
  }
  {
    SCOPED_TRACE("sor");
    SolverParams params = tight();
    params.sor = 1.3;
    expectSameAsBuilt(s.problem, params);
  }
  {
    SCOPED_TRACE("sofa stopping rule");
    SolverParams params = tight();
    params.stopping_rule = StoppingRule::kSofa;
    params.tolerance = 1e-14;
    expectSameAsBuilt(s.problem, params, 1e-8, false);
  }
  {
    SCOPED_TRACE("minW");
    // Between the smallest and the largest W_nn: some contacts are ignored.
    const Eigen::MatrixXd W = s.bodies.toDense();
    const std::vector<int> off = s.problem.rowOffsets();
    std::vector<double> wnn;
    for (std::size_t i = 0; i < s.problem.contacts.size(); ++i) wnn.push_back(W(off[i], off[i]));
    std::sort(wnn.begin(), wnn.end());
    SolverParams params = tight();
    params.minW = 0.5 * (wnn[2] + wnn[3]);
    const SolveResult u = solveProblem(s.problem, unbuilt(params));
    EXPECT_EQ(std::count(u.states.begin(), u.states.end(), ContactState::kIgnored), 3);
    expectSameAsBuilt(s.problem, params);
  }
  {
    SCOPED_TRACE("maxF");
    const SolveResult free = solveProblem(s.problem, unbuilt(tight()));
    double largest = 0.0;
    const std::vector<int> off = s.problem.rowOffsets();
    for (std::size_t i = 0; i < s.problem.contacts.size(); ++i)
      largest = std::max(largest, free.forces.segment(off[i], s.problem.contacts[i].rows).norm());
    SolverParams params = tight();
    params.maxF = 0.7 * largest;
    const SolveResult u = solveProblem(s.problem, unbuilt(params));
    EXPECT_GE(u.resolves, 1);
    expectSameAsBuilt(s.problem, params);
  }
  {
    SCOPED_TRACE("warm start over three solves");
    SolverParams params = tight();
    params.initial_guess = true;
    params.maxIt = 40;  // warm start visible in the forces when the sweeps are capped
    ContactSolver unbuilt_solver(unbuilt(params)), built_solver(params);
    Problem u_problem = s.problem;
    Problem b_problem = builtSparse(s.problem);
    for (int step = 0; step < 3; ++step) {
      const SolveResult u = unbuilt_solver.solve(u_problem);
      const SolveResult b = built_solver.solve(b_problem);
      EXPECT_TRUE(u.unbuilt);
      EXPECT_EQ(u.iterations, b.iterations) << "step " << step;
      EXPECT_LT(relDiff(u.forces, b.forces), 1e-9) << "step " << step;
      u_problem.d_free *= 0.9;
      b_problem.d_free *= 0.9;
    }
    EXPECT_EQ(unbuilt_solver.warmStartSize(), s.problem.contacts.size());
  }
}

TEST(Unbuilt, SoftnessAndErpJoinTheBodyForm) {
  RandomScene s = randomScene(10, 14, 71);
  Problem p = s.problem;
  for (std::size_t i = 0; i < p.contacts.size(); ++i) {
    p.contacts[i].gap = i % 3 == 0 ? -0.002 : 0.0;
    p.contacts[i].erp = 0.2;
    p.contacts[i].softness = i % 2 == 0 ? 1e-6 : 0.0;
  }
  expectSameAsBuilt(p, tight());
  // The input's body form is shared and must stay as given.
  EXPECT_EQ(p.bodies->diagonal.size(), 0);
}

TEST(Unbuilt, ZeroSelfComplianceIsAZeroDiagonalUnlessMinW) {
  // A contact between two static bodies has W_cc = 0: Gauss-Seidel refuses it, built or not.
  RandomScene s = randomScene(4, 5, 81);
  BodyCompliance b = s.bodies;
  b.contacts[2].body_a = -1;
  b.contacts[2].body_b = -1;
  Problem p = s.problem;
  p.bodies = std::make_shared<const BodyCompliance>(b);
  const SolveResult u = solveProblem(p, unbuilt(tight()));
  EXPECT_EQ(u.status, SolveStatus::kZeroDiagonal);
  EXPECT_NE(u.message.find("contact 2"), std::string::npos) << u.message;
  SolverParams params = tight();
  params.minW = 1e-300;
  expectSameAsBuilt(p, params);
  EXPECT_EQ(solveProblem(p, unbuilt(params)).states[2], ContactState::kIgnored);
}

TEST(Unbuilt, OtherSolversAssembleWAndSaySo) {
  Mix mix;
  mix.frictionless = 1.0;
  const RandomScene s = randomScene(6, 10, 91, mix);
  for (SolverKind kind : {SolverKind::kLemke, SolverKind::kNewton, SolverKind::kApgd}) {
    const SolveResult u = solveProblem(s.problem, unbuilt(tight(kind)));
    const SolveResult b = solveProblem(builtSparse(s.problem), tight(kind));
    EXPECT_FALSE(u.unbuilt) << solverName(kind);
    EXPECT_NE(u.message.find(std::string("build_lcp=false: ") + solverName(kind) +
                             " needs the assembled W; assembled it from the body form"),
              std::string::npos)
        << u.message;
    EXPECT_EQ(u.status, b.status) << solverName(kind);
    EXPECT_EQ(u.forces, b.forces) << solverName(kind) << ": the very same assembled problem";
  }
  // build_lcp = true on a body form: assembled, no note.
  const SolveResult built = solveProblem(s.problem, tight(SolverKind::kPgs));
  EXPECT_FALSE(built.unbuilt);
  EXPECT_EQ(built.message, "");
  // build_lcp = false without a body form: the built solve, with SOFA's note.
  const SolveResult no_bodies = solveProblem(builtDense(s.problem), unbuilt(tight(SolverKind::kPgs)));
  EXPECT_FALSE(no_bodies.unbuilt);
  EXPECT_NE(no_bodies.message.find("needs the body form"), std::string::npos);
}

TEST(Unbuilt, TimeBudgetAndMaxIterationsAreHonest) {
  const RandomScene s = randomScene(40, 80, 101);
  SolverParams params = tight();
  params.tolerance = 1e-300;  // never reached
  params.maxIt = 5;
  const SolveResult capped = solveProblem(s.problem, unbuilt(params));
  EXPECT_EQ(capped.status, SolveStatus::kMaxIterations);
  EXPECT_EQ(capped.iterations, 5);
  EXPECT_TRUE(capped.forces.allFinite());
  params.maxIt = 100000000;
  params.time_budget = 0.02;
  const SolveResult budget = solveProblem(s.problem, unbuilt(params));
  EXPECT_EQ(budget.status, SolveStatus::kTimeBudget) << budget.message;
  EXPECT_LT(budget.solve_time, 1.0);
  // The residual is the true one of the returned forces (computed through W λ).
  Problem built = builtDense(s.problem);
  Eigen::VectorXd d = toDense(built.W) * budget.forces + built.d_free;
  EXPECT_LT((d - budget.d).norm(), 1e-12 * (1.0 + d.norm()));
}

TEST(Unbuilt, DisplayDebugHistoryMatches) {
  const RandomScene s = randomScene(10, 14, 111);
  SolverParams params = tight();
  params.displayDebug = true;
  params.maxIt = 20;
  const SolveResult u = solveProblem(s.problem, unbuilt(params));
  const SolveResult b = solveProblem(builtDense(s.problem), params);
  ASSERT_EQ(u.residual_history.size(), b.residual_history.size());
  for (std::size_t k = 0; k < u.residual_history.size(); ++k)
    EXPECT_NEAR(u.residual_history[k], b.residual_history[k], 1e-9 * (b.residual_history[k] + 1e-300));
}

}  // namespace
}  // namespace lcp_contact_solver::core
