// One test per SOFA LCPConstraintSolver field the core honours; each fails if the field's
// meaning is lost. (computeConstraintForces, showCellWidth and showTranslation act in the
// ROS layer and are tested there.)
#include "solvers_test_util.h"

#include "lcp_contact_solver/core/contact_solver.h"

#include <gtest/gtest.h>

namespace lcp_contact_solver::core {
namespace {

using solvers_test::randomFrictionalProblem;

SolverParams withSolver(SolverKind kind) {
  SolverParams params;
  params.solver = kind;
  params.initial_guess = false;
  return params;
}

TEST(SofaParams, DefaultsAreSofas) {
  const SolverParams p;
  EXPECT_EQ(p.tolerance, 1e-3);
  EXPECT_EQ(p.maxIt, 1000);
  EXPECT_EQ(p.mu, 0.6);
  EXPECT_TRUE(p.initial_guess);
  EXPECT_TRUE(p.build_lcp);
  EXPECT_EQ(p.regularizationTerm, 0.0);
  EXPECT_EQ(p.minW, 0.0);
  EXPECT_EQ(p.maxF, 0.0);
  EXPECT_FALSE(p.computeConstraintForces);
  EXPECT_FALSE(p.displayDebug);
}

TEST(SofaParams, ToleranceIsTheResidualReached) {
  const Problem p = randomFrictionalProblem(8, 1);
  int previous_iterations = 0;
  for (double tol : {1e-2, 1e-4, 1e-6, 1e-8}) {
    SolverParams params = withSolver(SolverKind::kNlgs);
    params.tolerance = tol;
    params.maxIt = 100000;
    const SolveResult r = solveProblem(p, params);
    ASSERT_EQ(r.status, SolveStatus::kConverged) << tol;
    EXPECT_LE(r.residual, tol);
    EXPECT_GE(r.iterations, previous_iterations);
    previous_iterations = r.iterations;
  }
}

TEST(SofaParams, MaxItCapsSweeps) {
  const Problem p = randomFrictionalProblem(8, 2);
  SolverParams params = withSolver(SolverKind::kNlgs);
  params.tolerance = 1e-14;
  params.maxIt = 3;
  const SolveResult r = solveProblem(p, params);
  EXPECT_EQ(r.status, SolveStatus::kMaxIterations);
  EXPECT_FALSE(r.converged);
  EXPECT_EQ(r.iterations, 3);
  EXPECT_TRUE(r.forces.allFinite());
  EXPECT_GT(r.residual, 1e-14);
}

TEST(SofaParams, MuIsTheDefaultForContactsWithoutOne) {
  Problem p;
  p.contacts.push_back(Contact{1, ContactType::kFrictional, 3, Contact::kMuDefault});
  p.W = Eigen::MatrixXd(Eigen::MatrixXd::Identity(3, 3));
  p.d_free = Eigen::Vector3d(-1.0, 10.0, 0.0);
  for (double mu : {0.2, 0.9}) {
    SolverParams params = withSolver(SolverKind::kNlgs);
    params.mu = mu;
    params.tolerance = 1e-12;
    const SolveResult r = solveProblem(p, params);
    ASSERT_EQ(r.status, SolveStatus::kConverged);
    EXPECT_NEAR(r.forces[1], -mu * r.forces[0], 1e-12);
  }
}

TEST(SofaParams, InitialGuessReducesIterationsOnResolve) {
  const Problem p = randomFrictionalProblem(10, 3);
  SolverParams params = withSolver(SolverKind::kNlgs);
  params.tolerance = 1e-8;
  params.maxIt = 100000;
  params.initial_guess = true;
  ContactSolver warm(params);
  const SolveResult first = warm.solve(p);
  const SolveResult second = warm.solve(p);
  ASSERT_EQ(first.status, SolveStatus::kConverged);
  ASSERT_EQ(second.status, SolveStatus::kConverged);
  EXPECT_LT(second.iterations, first.iterations);
  EXPECT_LE(second.iterations, 1);

  params.initial_guess = false;
  ContactSolver cold(params);
  cold.solve(p);
  EXPECT_EQ(cold.solve(p).iterations, first.iterations);
}

TEST(SofaParams, InitialGuessIsKeyedByContactId) {
  const Problem p = randomFrictionalProblem(4, 4);
  SolverParams params = withSolver(SolverKind::kNlgs);
  params.tolerance = 1e-10;
  params.initial_guess = true;
  ContactSolver solver(params);
  const SolveResult first = solver.solve(p);
  // Same contacts with new ids: nothing to warm start from.
  Problem renamed = p;
  for (auto& c : renamed.contacts) c.id += 1000;
  EXPECT_EQ(solver.solve(renamed).iterations, first.iterations);
}

TEST(SofaParams, BuildLcpFalseSolvesTheSameProblemAndSaysHow) {
  const Problem p = randomFrictionalProblem(5, 5);
  SolverParams params = withSolver(SolverKind::kNlgs);
  const SolveResult built = solveProblem(p, params);
  params.build_lcp = false;
  const SolveResult unbuilt = solveProblem(p, params);
  EXPECT_EQ((built.forces - unbuilt.forces).norm(), 0.0);
  EXPECT_NE(unbuilt.message.find("build_lcp=false"), std::string::npos);
}

TEST(SofaParams, RegularizationAddsToTheDiagonal) {
  Problem p = makeLcpProblem(Eigen::MatrixXd::Constant(1, 1, 0.5), Eigen::VectorXd::Constant(1, -0.2));
  SolverParams params = withSolver(SolverKind::kPgs);
  params.tolerance = 1e-12;
  params.regularizationTerm = 0.5;
  const SolveResult r = solveProblem(p, params);
  ASSERT_EQ(r.status, SolveStatus::kConverged);
  EXPECT_NEAR(r.forces[0], 0.2 / (0.5 + 0.5), 1e-12);
  // It also makes a singular W solvable: a zero diagonal becomes r.
  Problem singular = makeLcpProblem(Eigen::MatrixXd::Zero(1, 1), Eigen::VectorXd::Constant(1, -1.0));
  EXPECT_EQ(solveProblem(singular, withSolver(SolverKind::kPgs)).status, SolveStatus::kZeroDiagonal);
  params.regularizationTerm = 0.25;
  const SolveResult reg = solveProblem(singular, params);
  EXPECT_EQ(reg.status, SolveStatus::kConverged);
  EXPECT_NEAR(reg.forces[0], 4.0, 1e-12);
}

TEST(SofaParams, MinWIgnoresContactsWithTinySelfCompliance) {
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(2, 2);
  M(0, 0) = 1.0;
  M(1, 1) = 1e-9;  // a nearly rigid constraint
  const Problem p = makeLcpProblem(M, Eigen::Vector2d(-1.0, -1.0));
  SolverParams params = withSolver(SolverKind::kPgs);
  params.minW = 1e-6;
  params.tolerance = 1e-12;
  const SolveResult r = solveProblem(p, params);
  ASSERT_EQ(r.status, SolveStatus::kConverged) << r.message;
  EXPECT_EQ(r.states[1], ContactState::kIgnored);
  EXPECT_EQ(r.forces[1], 0.0);
  EXPECT_NEAR(r.forces[0], 1.0, 1e-12);
  params.minW = 0.0;  // without it the stiff contact takes its (huge) force
  const SolveResult all = solveProblem(p, params);
  EXPECT_NEAR(all.forces[1], 1e9, 1e-3);
}

TEST(SofaParams, ZeroDiagonalWithoutMinWIsAnExplicitFailure) {
  Eigen::MatrixXd M(2, 2);
  M << 0, 1, -1, 2;
  const Problem p = makeLcpProblem(M, Eigen::Vector2d(-1, -1));
  const SolveResult r = solveProblem(p, withSolver(SolverKind::kPgs));
  EXPECT_EQ(r.status, SolveStatus::kZeroDiagonal);
  EXPECT_FALSE(r.converged);
  EXPECT_TRUE(r.forces.allFinite());
  EXPECT_TRUE(r.d.allFinite());
  EXPECT_NE(r.message.find("W_nn"), std::string::npos);
}

TEST(SofaParams, MaxFDropsTheContactAndResolvesTheRest) {
  // Two coupled contacts; the second needs a large force. Dropping it must change the
  // first one's force to what it is alone (SOFA keeps the stale coupled value).
  Eigen::MatrixXd M(2, 2);
  M << 1.0, 0.5, 0.5, 1.0;
  const Problem p = makeLcpProblem(M, Eigen::Vector2d(-1.0, -10.0));
  SolverParams params = withSolver(SolverKind::kPgs);
  params.tolerance = 1e-12;
  const SolveResult full = solveProblem(p, params);
  ASSERT_GT(full.forces[1], 5.0);
  EXPECT_NEAR(full.forces[0], 0.0, 1e-12);  // pushed open by its neighbour

  params.maxF = 5.0;
  const SolveResult r = solveProblem(p, params);
  ASSERT_EQ(r.status, SolveStatus::kConverged);
  EXPECT_EQ(r.states[1], ContactState::kIgnored);
  EXPECT_EQ(r.forces[1], 0.0);
  EXPECT_NEAR(r.forces[0], 1.0, 1e-12);  // alone: λ = 1 / 1
  EXPECT_EQ(r.resolves, 1);
  EXPECT_LE(r.residual, 1e-12);
}

TEST(SofaParams, DisplayDebugRecordsTheResidualHistory) {
  const Problem p = randomFrictionalProblem(5, 6);
  SolverParams params = withSolver(SolverKind::kNlgs);
  EXPECT_TRUE(solveProblem(p, params).residual_history.empty());
  params.displayDebug = true;
  const SolveResult r = solveProblem(p, params);
  ASSERT_EQ(static_cast<int>(r.residual_history.size()), r.iterations);
  EXPECT_LE(r.residual_history.back(), params.tolerance);
}

TEST(SofaParams, SofaStoppingRuleStopsOnTheSweepChange) {
  const Problem p = randomFrictionalProblem(8, 7);
  SolverParams params = withSolver(SolverKind::kNlgs);
  params.stopping_rule = StoppingRule::kSofa;
  params.tolerance = 1e-6;
  params.maxIt = 100000;
  const SolveResult r = solveProblem(p, params);
  ASSERT_EQ(r.status, SolveStatus::kConverged);
  EXPECT_LT(r.solver_error, 1e-6);
  EXPECT_GT(r.residual, 0.0);  // the solver-independent residual is still reported
}

TEST(SofaParams, InvalidParametersAreRefused) {
  SolverParams params;
  params.tolerance = -1.0;
  ContactSolver solver;
  EXPECT_NE(solver.setParams(params), "");
  EXPECT_EQ(solver.params().tolerance, 1e-3);
  params = SolverParams();
  params.mu = std::nan("");
  EXPECT_NE(validateParams(params), "");
  EXPECT_EQ(solveProblem(randomFrictionalProblem(1, 8), params).status, SolveStatus::kInvalidInput);
}

}  // namespace
}  // namespace lcp_contact_solver::core
