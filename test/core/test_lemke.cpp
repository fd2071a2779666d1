// Lexicographic Lemke (src/core/kernels/lemke.cpp), through the kernel and through ContactSolver.
#include "lcp_contact_solver/core/contact_solver.h"
#include "lcp_contact_solver/core/kernels/kernels.h"
#include "lcp_contact_solver/core/residual.h"

#include <gtest/gtest.h>

#include <Eigen/Core>

#include <chrono>
#include <string>
#include <vector>

namespace lcp_contact_solver::core {
namespace {

// A kernel call set up by hand: owns the problem and parameters the context points to.
struct LemkeRun {
  Problem problem;
  SolverParams params;
  SolveContext ctx;
  Eigen::VectorXd lambda;
  KernelReport report;

  LemkeRun(Problem p, SolverParams sp = SolverParams()) : problem(std::move(p)), params(sp) {
    params.solver = SolverKind::kLemke;
    ctx.problem = &problem;
    ctx.params = &params;
    ctx.offsets = problem.rowOffsets();
    ctx.mu = effectiveMu(problem, params.mu);
    ctx.ignored.assign(problem.contacts.size(), false);
    ctx.regularization = params.regularizationTerm;
    lambda = Eigen::VectorXd::Zero(problem.rowCount());
  }

  const KernelReport& run() {
    report = runLemke(ctx, lambda);
    return report;
  }
};

Eigen::MatrixXd matrix2(double a, double b, double c, double d) {
  Eigen::MatrixXd M(2, 2);
  M << a, b, c, d;
  return M;
}

Eigen::VectorXd vector2(double a, double b) { return Eigen::Vector2d(a, b); }

// w = M z + q of an LCP problem.
Eigen::VectorXd lcpW(const Eigen::MatrixXd& M, const Eigen::VectorXd& q, const Eigen::VectorXd& z) {
  return M * z + q;
}

// Asserts 0 <= z ⟂ w >= 0 to `tol` (absolute).
void expectLcpSolution(const Eigen::MatrixXd& M, const Eigen::VectorXd& q, const Eigen::VectorXd& z,
                       double tol) {
  ASSERT_TRUE(z.allFinite());
  const Eigen::VectorXd w = lcpW(M, q, z);
  for (int i = 0; i < z.size(); ++i) {
    EXPECT_GE(z[i], -tol) << "row " << i;
    EXPECT_GE(w[i], -tol) << "row " << i;
    EXPECT_LE(std::abs(z[i] * w[i]), tol) << "row " << i;
  }
}

// Murty's LCP on which Lemke's method with covering vector e visits 2^n bases (Murty 1978;
// Murty 1988, ch. 6; lcp_exp_murty2.dat is n = 6): M upper triangular with 1 on the
// diagonal and 2 above it, q_i = -(2^(n+1) - 2^i), i = 1..n. (With q = -1 instead, the
// lcp_exp_murty.dat variant, Lemke needs 2 pivots.)
Eigen::MatrixXd murtyMatrix(int n) {
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(n, n);
  for (int i = 0; i < n; ++i) {
    M(i, i) = 1.0;
    for (int j = i + 1; j < n; ++j) M(i, j) = 2.0;
  }
  return M;
}

Eigen::VectorXd murtyVector(int n) {
  Eigen::VectorXd q(n);
  for (int i = 0; i < n; ++i) q[i] = -(std::ldexp(1.0, n + 1) - std::ldexp(1.0, i + 1));
  return q;
}

// ---- kernel -------------------------------------------------------------------------------

TEST(Lemke, TwoCoupledContactsBothClosed) {
  const Eigen::MatrixXd M = matrix2(2, 1, 1, 2);
  const Eigen::VectorXd q = vector2(-5, -6);
  LemkeRun run(makeLcpProblem(M, q));
  const KernelReport& report = run.run();
  ASSERT_EQ(report.status, SolveStatus::kConverged) << report.message;
  EXPECT_NEAR(run.lambda[0], 4.0 / 3.0, 1e-14);
  EXPECT_NEAR(run.lambda[1], 7.0 / 3.0, 1e-14);
  EXPECT_GT(report.iterations, 0);
  EXPECT_LE(report.solver_error, 1e-14);
  EXPECT_TRUE(report.history.empty());  // only with displayDebug
}

TEST(Lemke, TwoCoupledContactsOneOpens) {
  // z = (1/2, 0), w = (0, 7/2).
  const Eigen::MatrixXd M = matrix2(2, 1, 1, 2);
  const Eigen::VectorXd q = vector2(-1, 3);
  LemkeRun run(makeLcpProblem(M, q));
  ASSERT_EQ(run.run().status, SolveStatus::kConverged) << run.report.message;
  EXPECT_NEAR(run.lambda[0], 0.5, 1e-15);
  EXPECT_EQ(run.lambda[1], 0.0);
  EXPECT_LE(run.report.solver_error, 1e-15);
}

TEST(Lemke, NonnegativeQNeedsNoPivot) {
  LemkeRun run(makeLcpProblem(matrix2(2, 1, 1, 2), vector2(0, 3)));
  run.lambda.setConstant(7.0);  // a warm start Lemke cannot use
  ASSERT_EQ(run.run().status, SolveStatus::kConverged);
  EXPECT_EQ(run.report.iterations, 0);
  EXPECT_EQ(run.lambda, Eigen::VectorXd::Zero(2));
  EXPECT_EQ(run.report.solver_error, 0.0);
}

TEST(Lemke, RegularizationIsAddedToTheDiagonal) {
  // W = 0 alone has no unique solution; with r = 0.5, 0.5 z - 1 = 0.
  SolverParams params;
  params.regularizationTerm = 0.5;
  Eigen::MatrixXd W = Eigen::MatrixXd::Zero(1, 1);
  LemkeRun run(makeLcpProblem(W, Eigen::VectorXd::Constant(1, -1.0)), params);
  ASSERT_EQ(run.run().status, SolveStatus::kConverged) << run.report.message;
  EXPECT_NEAR(run.lambda[0], 2.0, 1e-15);
}

Problem bilateralAndUnilateral(double d_bilateral, double d_unilateral) {
  Problem problem;
  problem.contacts.resize(2);
  problem.contacts[0].id = 10;
  problem.contacts[0].type = ContactType::kBilateral;
  problem.contacts[0].rows = 1;
  problem.contacts[1].id = 11;
  problem.contacts[1].type = ContactType::kFrictionless;
  problem.contacts[1].rows = 1;
  problem.W = matrix2(2, 1, 1, 2);
  problem.d_free = vector2(d_bilateral, d_unilateral);
  return problem;
}

TEST(Lemke, BilateralRowPullsAndUnilateralPushes) {
  // d_b = 2 λb + λu + 3 = 0 and d_u = λb + 2 λu - 6 = 0  →  λb = -4 (negative: the split
  // λ = λ⁺ - λ⁻ is needed), λu = 5.
  LemkeRun run(bilateralAndUnilateral(3, -6));
  ASSERT_EQ(run.run().status, SolveStatus::kConverged) << run.report.message;
  EXPECT_NEAR(run.lambda[0], -4.0, 1e-13);
  EXPECT_NEAR(run.lambda[1], 5.0, 1e-13);
  EXPECT_LE(run.report.solver_error, 1e-14);
}

TEST(Lemke, BilateralRowWithOpenUnilateralRow) {
  // λu = 0: λb = -3/2, d_u = -3/2 + 6 = 9/2 > 0.
  LemkeRun run(bilateralAndUnilateral(3, 6));
  ASSERT_EQ(run.run().status, SolveStatus::kConverged) << run.report.message;
  EXPECT_NEAR(run.lambda[0], -1.5, 1e-14);
  EXPECT_EQ(run.lambda[1], 0.0);
}

TEST(Lemke, BilateralRowWithPositiveForce) {
  // d_free_b = -3 → λb = 3/2 with the unilateral row open (d_u = 3/2 + 6).
  LemkeRun run(bilateralAndUnilateral(-3, 6));
  ASSERT_EQ(run.run().status, SolveStatus::kConverged) << run.report.message;
  EXPECT_NEAR(run.lambda[0], 1.5, 1e-14);
  EXPECT_EQ(run.lambda[1], 0.0);
}

TEST(Lemke, MultiRowBilateralCoupledWithContacts) {
  // A 3-row joint and four frictionless contacts on an SPD W: bilateral rows must end at
  // d = 0, the others complementary.
  const int n = 7;
  Eigen::MatrixXd J(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) J(i, j) = std::sin(1.0 + 3.0 * i + 7.0 * j);
  Problem problem;
  problem.contacts.resize(5);
  problem.contacts[0].type = ContactType::kBilateral;
  problem.contacts[0].rows = 3;
  for (int c = 1; c < 5; ++c) {
    problem.contacts[c].id = c;
    problem.contacts[c].type = ContactType::kFrictionless;
    problem.contacts[c].rows = 1;
  }
  problem.W = Eigen::MatrixXd(J * J.transpose() + 0.1 * Eigen::MatrixXd::Identity(n, n));
  problem.d_free.resize(n);
  problem.d_free << 1.0, -2.0, 0.5, -1.0, 2.0, -0.5, -3.0;
  LemkeRun run(problem);
  ASSERT_EQ(run.run().status, SolveStatus::kConverged) << run.report.message;
  Eigen::VectorXd d;
  run.ctx.computeD(run.lambda, d);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(d[i], 0.0, 1e-12);
  for (int i = 3; i < n; ++i) {
    EXPECT_GE(run.lambda[i], 0.0);
    EXPECT_GE(d[i], -1e-12);
    EXPECT_LE(std::abs(run.lambda[i] * d[i]), 1e-12);
  }
  EXPECT_LE(run.report.solver_error, 1e-12);
}

TEST(Lemke, FrictionalContactWithZeroMuIsOneRow) {
  // Two frictional contacts with μ = 0: normal rows as the LCP of the first test, tangents
  // get no force even though W couples them.
  Problem problem;
  problem.contacts.resize(2);
  for (int c = 0; c < 2; ++c) {
    problem.contacts[c].id = c;
    problem.contacts[c].type = ContactType::kFrictional;
    problem.contacts[c].rows = 3;
    problem.contacts[c].mu = 0.0;
  }
  Eigen::MatrixXd W = Eigen::MatrixXd::Identity(6, 6) * 2.0;
  W(0, 3) = W(3, 0) = 1.0;
  W(1, 0) = W(0, 1) = 0.3;  // normal-tangent coupling: tangents still move, force stays 0
  problem.W = W;
  problem.d_free = Eigen::VectorXd::Zero(6);
  problem.d_free[0] = -5.0;
  problem.d_free[3] = -6.0;
  problem.d_free[4] = -1.0;  // a tangential velocity friction would resist, with μ = 0 not
  LemkeRun run(problem);
  ASSERT_EQ(run.run().status, SolveStatus::kConverged) << run.report.message;
  EXPECT_NEAR(run.lambda[0], 4.0 / 3.0, 1e-14);
  EXPECT_NEAR(run.lambda[3], 7.0 / 3.0, 1e-14);
  for (int row : {1, 2, 4, 5}) EXPECT_EQ(run.lambda[row], 0.0) << "row " << row;
  EXPECT_LE(run.report.solver_error, 1e-14);
}

TEST(Lemke, FrictionIsNotApplicable) {
  Problem problem;
  problem.contacts.resize(2);
  problem.contacts[0].type = ContactType::kFrictionless;
  problem.contacts[0].rows = 1;
  problem.contacts[1].type = ContactType::kFrictional;
  problem.contacts[1].rows = 3;
  problem.contacts[1].mu = 0.5;
  problem.W = Eigen::MatrixXd(Eigen::MatrixXd::Identity(4, 4));
  problem.d_free = -Eigen::VectorXd::Ones(4);
  LemkeRun run(problem);
  run.lambda.setConstant(0.25);
  const KernelReport& report = run.run();
  EXPECT_EQ(report.status, SolveStatus::kNotApplicable);
  EXPECT_NE(report.message.find("Lemke solves"), std::string::npos) << report.message;
  EXPECT_NE(report.message.find("friction"), std::string::npos) << report.message;
  EXPECT_EQ(run.lambda, Eigen::VectorXd::Constant(4, 0.25));  // untouched
}

TEST(Lemke, FrictionOfAnIgnoredContactDoesNotCount) {
  Problem problem;
  problem.contacts.resize(2);
  problem.contacts[0].type = ContactType::kFrictionless;
  problem.contacts[0].rows = 1;
  problem.contacts[1].type = ContactType::kFrictional;
  problem.contacts[1].rows = 3;
  problem.contacts[1].mu = 0.5;
  Eigen::MatrixXd W = Eigen::MatrixXd::Identity(4, 4);
  W(0, 1) = W(1, 0) = 0.5;
  problem.W = W;
  problem.d_free = -Eigen::VectorXd::Ones(4);
  LemkeRun run(problem);
  run.ctx.ignored[1] = true;
  ASSERT_EQ(run.run().status, SolveStatus::kConverged) << run.report.message;
  EXPECT_NEAR(run.lambda[0], 1.0, 1e-15);
  for (int row = 1; row < 4; ++row) EXPECT_EQ(run.lambda[row], 0.0);
}

TEST(Lemke, BlockSparseComplianceGivesTheSameAnswer) {
  Problem problem = bilateralAndUnilateral(3, -6);
  BlockSparseMatrix W = BlockSparseMatrix::withBlockSizes({1, 1});
  W.beginRow();
  W.addBlock(0, Eigen::MatrixXd::Constant(1, 1, 2.0));
  W.addBlock(1, Eigen::MatrixXd::Constant(1, 1, 1.0));
  W.beginRow();
  W.addBlock(0, Eigen::MatrixXd::Constant(1, 1, 1.0));
  W.addBlock(1, Eigen::MatrixXd::Constant(1, 1, 2.0));
  problem.W = W;
  LemkeRun run(problem);
  ASSERT_EQ(run.run().status, SolveStatus::kConverged) << run.report.message;
  EXPECT_NEAR(run.lambda[0], -4.0, 1e-13);
  EXPECT_NEAR(run.lambda[1], 5.0, 1e-13);
}

TEST(Lemke, DegenerateLcpsTerminateAndSolve) {
  // Rank-one M = 1 1ᵀ with q = -1: every ratio ties at every step; solutions are the
  // simplex sum z = 1.
  for (int n : {2, 3, 5, 8}) {
    const Eigen::MatrixXd M = Eigen::MatrixXd::Ones(n, n);
    const Eigen::VectorXd q = -Eigen::VectorXd::Ones(n);
    LemkeRun run(makeLcpProblem(M, q));
    ASSERT_EQ(run.run().status, SolveStatus::kConverged) << "n = " << n << ": " << run.report.message;
    EXPECT_NEAR(run.lambda.sum(), 1.0, 1e-14);
    expectLcpSolution(M, q, run.lambda, 1e-14);
  }
  // Zero entries in q and equal negative entries: degenerate from the first pivot on.
  {
    const int n = 6;
    const Eigen::MatrixXd M = Eigen::MatrixXd::Identity(n, n) + Eigen::MatrixXd::Ones(n, n);
    Eigen::VectorXd q(n);
    q << 0, -1, 0, -1, 0, -1;
    LemkeRun run(makeLcpProblem(M, q));
    ASSERT_EQ(run.run().status, SolveStatus::kConverged) << run.report.message;
    expectLcpSolution(M, q, run.lambda, 1e-14);
    EXPECT_NEAR(run.lambda[1], 0.25, 1e-14);  // z = (0, 1/4, 0, 1/4, 0, 1/4)
  }
  // Duplicated contacts: two identical rows, W singular (two contacts on the same point).
  {
    Eigen::MatrixXd M(4, 4);
    M << 2, 2, 1, 0, 2, 2, 1, 0, 1, 1, 3, 1, 0, 0, 1, 2;
    Eigen::VectorXd q(4);
    q << -2, -2, -1, -1;
    LemkeRun run(makeLcpProblem(M, q));
    ASSERT_EQ(run.run().status, SolveStatus::kConverged) << run.report.message;
    expectLcpSolution(M, q, run.lambda, 1e-13);
    EXPECT_LE(run.report.solver_error, 1e-14);
  }
}

TEST(Lemke, MurtyExponentialConvergesWithALargeCap) {
  for (int n = 2; n <= 10; ++n) {
    const Eigen::MatrixXd M = murtyMatrix(n);
    const Eigen::VectorXd q = murtyVector(n);
    SolverParams params;
    params.maxIt = 1 << 12;
    LemkeRun run(makeLcpProblem(M, q), params);
    ASSERT_EQ(run.run().status, SolveStatus::kConverged) << "n = " << n << ": " << run.report.message;
    EXPECT_EQ(run.report.iterations, 1 << n) << "n = " << n;  // Murty: 2^n pivots
    expectLcpSolution(M, q, run.lambda, 1e-9 * q.cwiseAbs().maxCoeff());
    EXPECT_LE(run.report.solver_error, 1e-14);
  }
}

TEST(Lemke, MurtyExponentialHitsThePivotCap) {
  for (int n = 16; n <= 24; n += 4) {
    SolverParams params;
    params.maxIt = 1000;
    LemkeRun run(makeLcpProblem(murtyMatrix(n), murtyVector(n)), params);
    const KernelReport& report = run.run();
    EXPECT_EQ(report.status, SolveStatus::kMaxIterations) << "n = " << n;
    EXPECT_EQ(report.iterations, 1000);
    EXPECT_NE(report.message.find("pivot cap"), std::string::npos) << report.message;
    ASSERT_TRUE(run.lambda.allFinite());
    EXPECT_GE(run.lambda.minCoeff(), 0.0);
    EXPECT_TRUE(std::isfinite(report.solver_error));
  }
}

TEST(Lemke, StopsAtTheDeadline) {
  LemkeRun run(makeLcpProblem(murtyMatrix(20), murtyVector(20)));
  run.params.maxIt = 1 << 22;
  run.ctx.has_deadline = true;
  run.ctx.deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(20);
  const KernelReport& report = run.run();
  EXPECT_EQ(report.status, SolveStatus::kTimeBudget) << report.message;
  EXPECT_GT(report.iterations, 0);
  EXPECT_LT(report.iterations, 1 << 20);  // 2^20 pivots would be needed
  EXPECT_NE(report.message.find("time budget"), std::string::npos) << report.message;
  ASSERT_TRUE(run.lambda.allFinite());
  EXPECT_GE(run.lambda.minCoeff(), 0.0);
}

TEST(Lemke, NoSolutionEndsOnARay) {
  LemkeRun run(makeLcpProblem(-Eigen::MatrixXd::Ones(1, 1), -Eigen::VectorXd::Ones(1)));
  const KernelReport& report = run.run();
  EXPECT_EQ(report.status, SolveStatus::kRayTermination);
  EXPECT_NE(report.message.find("ray"), std::string::npos) << report.message;
  ASSERT_TRUE(run.lambda.allFinite());
  EXPECT_TRUE(std::isfinite(report.solver_error));
}

TEST(Lemke, InfeasibleBilateralRowsEndOnARay) {
  // Two equal joint rows asking for different motions: W λ + d = 0 has no solution.
  Problem problem;
  problem.contacts.resize(1);
  problem.contacts[0].type = ContactType::kBilateral;
  problem.contacts[0].rows = 2;
  problem.W = Eigen::MatrixXd(Eigen::MatrixXd::Ones(2, 2));
  problem.d_free = vector2(1.0, -1.0);
  LemkeRun run(problem);
  EXPECT_EQ(run.run().status, SolveStatus::kRayTermination) << run.report.message;
  EXPECT_TRUE(run.lambda.allFinite());
}

TEST(Lemke, DisplayDebugRecordsOneResidualPerPivot) {
  SolverParams params;
  params.displayDebug = true;
  const Eigen::MatrixXd M = matrix2(2, 1, 1, 2);
  LemkeRun run(makeLcpProblem(M, vector2(-5, -6)), params);
  ASSERT_EQ(run.run().status, SolveStatus::kConverged);
  ASSERT_EQ(static_cast<int>(run.report.history.size()), run.report.iterations);
  EXPECT_LE(run.report.history.back(), 1e-14);
  for (double r : run.report.history) EXPECT_TRUE(std::isfinite(r));
}

TEST(Lemke, HugeEntriesStayFinite) {
  // Entries near overflow: whatever the status, no NaN or infinity comes out.
  Eigen::MatrixXd M(2, 2);
  M << 1e-300, 1e300, 1e300, 1e-300;
  LemkeRun run(makeLcpProblem(M, vector2(-1e300, -1e-300)));
  const KernelReport& report = run.run();
  EXPECT_TRUE(run.lambda.allFinite()) << statusName(report.status);
  EXPECT_TRUE(std::isfinite(report.solver_error));
}

// ---- through ContactSolver -----------------------------------------------------------------

TEST(LemkeContactSolver, SolvesTwoCoupledContacts) {
  SolverParams params;
  params.solver = SolverKind::kLemke;
  ContactSolver solver(params);
  const SolveResult result = solver.solve(makeLcpProblem(matrix2(2, 1, 1, 2), vector2(-5, -6)));
  ASSERT_EQ(result.status, SolveStatus::kConverged) << result.message;
  EXPECT_TRUE(result.converged);
  EXPECT_NEAR(result.forces[0], 4.0 / 3.0, 1e-14);
  EXPECT_NEAR(result.forces[1], 7.0 / 3.0, 1e-14);
  EXPECT_NEAR(result.d[0], 0.0, 1e-14);
  EXPECT_NEAR(result.d[1], 0.0, 1e-14);
  EXPECT_GT(result.iterations, 0);
  EXPECT_LE(result.residual, 1e-14);
  EXPECT_EQ(result.solver, solverName(SolverKind::kLemke));
}

TEST(LemkeContactSolver, BilateralAndUnilateral) {
  SolverParams params;
  params.solver = SolverKind::kLemke;
  const SolveResult result = solveProblem(bilateralAndUnilateral(3, -6), params);
  ASSERT_EQ(result.status, SolveStatus::kConverged) << result.message;
  EXPECT_NEAR(result.forces[0], -4.0, 1e-13);
  EXPECT_NEAR(result.forces[1], 5.0, 1e-13);
  ASSERT_EQ(result.states.size(), 2u);
  EXPECT_EQ(result.states[0], ContactState::kStick);
  EXPECT_EQ(result.states[1], ContactState::kClosed);  // frictionless, pressed
}

TEST(LemkeContactSolver, FrictionIsNotApplicable) {
  Problem problem;
  problem.contacts.resize(1);
  problem.contacts[0].type = ContactType::kFrictional;
  problem.contacts[0].rows = 3;
  problem.W = Eigen::MatrixXd(Eigen::MatrixXd::Identity(3, 3));
  problem.d_free = -Eigen::VectorXd::Ones(3);
  SolverParams params;
  params.solver = SolverKind::kLemke;
  params.mu = 0.6;  // the contact gives none: the default applies
  const SolveResult result = solveProblem(problem, params);
  EXPECT_EQ(result.status, SolveStatus::kNotApplicable);
  EXPECT_FALSE(result.converged);
  EXPECT_NE(result.message.find("friction"), std::string::npos) << result.message;
  EXPECT_TRUE(result.forces.allFinite());
}

TEST(LemkeContactSolver, ZeroDefaultMuMakesFrictionalContactsSolvable) {
  Problem problem;
  problem.contacts.resize(1);
  problem.contacts[0].type = ContactType::kFrictional;
  problem.contacts[0].rows = 3;
  problem.W = Eigen::MatrixXd(Eigen::MatrixXd::Identity(3, 3) * 4.0);
  problem.d_free = Eigen::Vector3d(-2.0, 1.0, -1.0);
  SolverParams params;
  params.solver = SolverKind::kLemke;
  params.mu = 0.0;
  const SolveResult result = solveProblem(problem, params);
  ASSERT_EQ(result.status, SolveStatus::kConverged) << result.message;
  EXPECT_NEAR(result.forces[0], 0.5, 1e-15);
  EXPECT_EQ(result.forces[1], 0.0);
  EXPECT_EQ(result.forces[2], 0.0);
}

TEST(LemkeContactSolver, MurtyPivotCapIsReported) {
  SolverParams params;
  params.solver = SolverKind::kLemke;
  params.maxIt = 1000;
  const SolveResult result = solveProblem(makeLcpProblem(murtyMatrix(16), murtyVector(16)), params);
  EXPECT_EQ(result.status, SolveStatus::kMaxIterations);
  EXPECT_FALSE(result.converged);
  EXPECT_NE(result.message.find("pivot cap"), std::string::npos) << result.message;
  EXPECT_TRUE(result.forces.allFinite());
  EXPECT_TRUE(std::isfinite(result.residual));
}

TEST(LemkeContactSolver, RayTerminationIsReported) {
  SolverParams params;
  params.solver = SolverKind::kLemke;
  // w1 + w2 = -2 for every z: infeasible. M is positive semidefinite with a positive
  // diagonal, so nothing before the kernel refuses it.
  const SolveResult result = solveProblem(makeLcpProblem(matrix2(1, -1, -1, 1), vector2(-1, -1)), params);
  EXPECT_EQ(result.status, SolveStatus::kRayTermination);
  EXPECT_FALSE(result.converged);
  EXPECT_TRUE(result.forces.allFinite());
  EXPECT_TRUE(result.d.allFinite());
}

}  // namespace
}  // namespace lcp_contact_solver::core
