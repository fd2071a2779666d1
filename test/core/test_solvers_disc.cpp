// apgd and newton (the disc friction model) on analytic, mixed, random and hard problems.
#include "solvers_test_util.h"

namespace lcp_contact_solver::core {
namespace {

using namespace solvers_test;

// ---- apgd and newton on the analytic cases -----------------------------------------------

TEST(DiscSolvers, RestingContact) {
  const Problem p = oneFrictionalContact(Eigen::Matrix3d::Identity() * 0.5, Eigen::Vector3d(-0.2, 0, 0), 0.6);
  for (SolverKind kind : kDiscSolvers) {
    const SolveResult r = solveProblem(p, tight(kind));
    ASSERT_EQ(r.status, SolveStatus::kConverged) << solverName(kind) << ": " << r.message;
    EXPECT_EQ(r.solver, solverName(kind));
    EXPECT_NEAR(r.forces[0], 0.4, 1e-12);
    EXPECT_NEAR(r.forces[1], 0.0, 1e-12);
    EXPECT_NEAR(r.forces[2], 0.0, 1e-12);
    EXPECT_EQ(r.states[0], ContactState::kStick);
  }
}

TEST(DiscSolvers, SlidingOnTheConeOppositeSlip) {
  const double w = 2.0, mu = 0.5;
  const Problem p =
      oneFrictionalContact(Eigen::Matrix3d::Identity() * w, Eigen::Vector3d(-1.0, 0.6, -0.8), mu);
  const Eigen::Vector2d expected = -mu * 0.5 * Eigen::Vector2d(0.6, -0.8).normalized();
  for (SolverKind kind : kDiscSolvers) {
    const SolveResult r = solveProblem(p, tight(kind));
    ASSERT_EQ(r.status, SolveStatus::kConverged) << solverName(kind) << ": " << r.message;
    EXPECT_NEAR(r.forces[0], 0.5, 1e-11) << solverName(kind);
    EXPECT_NEAR(r.forces[1], expected[0], 1e-11);
    EXPECT_NEAR(r.forces[2], expected[1], 1e-11);
    EXPECT_NEAR(Eigen::Vector2d(r.d[1], r.d[2]).normalized().dot(expected.normalized()), -1.0, 1e-10);
    EXPECT_EQ(r.states[0], ContactState::kSlip);
  }
}

TEST(DiscSolvers, CoupledAnisotropicBlockStillOpposesSlip) {
  Eigen::Matrix3d W;
  W << 2.0, 0.3, -0.2, 0.3, 1.5, 0.4, -0.2, 0.4, 0.8;
  const Problem p = oneFrictionalContact(W, Eigen::Vector3d(-1.0, 2.0, -1.5), 0.3);
  const SolveResult nlgs = solveProblem(p, tight(SolverKind::kNlgs));
  for (SolverKind kind : kDiscSolvers) {
    const SolveResult r = solveProblem(p, tight(kind));
    ASSERT_EQ(r.status, SolveStatus::kConverged) << solverName(kind) << ": " << r.message;
    EXPECT_NEAR(r.d[0], 0.0, 1e-11);
    const Eigen::Vector2d force(r.forces[1], r.forces[2]);
    const Eigen::Vector2d slip(r.d[1], r.d[2]);
    EXPECT_NEAR(force.norm(), 0.3 * r.forces[0], 1e-11);
    EXPECT_NEAR(force.normalized().dot(slip.normalized()), -1.0, 1e-10);
    EXPECT_LE((r.forces - nlgs.forces).norm(), 1e-10);
  }
}

TEST(DiscSolvers, SeparatingContactHasZeroForce) {
  const Problem p = oneFrictionalContact(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0.1, 0.5, 0.0), 0.8);
  for (SolverKind kind : kDiscSolvers) {
    const SolveResult r = solveProblem(p, tight(kind));
    ASSERT_EQ(r.status, SolveStatus::kConverged) << solverName(kind);
    EXPECT_LE(r.forces.norm(), 1e-14);
    EXPECT_EQ(r.states[0], ContactState::kOpen);
  }
}

TEST(DiscSolvers, BilateralRowHoldsWithFreeSign) {
  Problem p;
  p.contacts.push_back(Contact{1, ContactType::kBilateral, 1, Contact::kMuDefault});
  p.W = Eigen::MatrixXd::Constant(1, 1, 2.0);
  p.d_free = Eigen::VectorXd::Constant(1, 0.4);
  for (SolverKind kind : kDiscSolvers) {
    const SolveResult r = solveProblem(p, tight(kind));
    ASSERT_EQ(r.status, SolveStatus::kConverged) << solverName(kind);
    EXPECT_NEAR(r.forces[0], -0.2, 1e-12);
    EXPECT_NEAR(r.d[0], 0.0, 1e-12);
  }
}

TEST(DiscSolvers, ZeroFrictionIsNormalOnly) {
  const Problem p = oneFrictionalContact(Eigen::Matrix3d::Identity(), Eigen::Vector3d(-1.0, 0.7, 0.2), 0.0);
  for (SolverKind kind : kDiscSolvers) {
    const SolveResult r = solveProblem(p, tight(kind));
    ASSERT_EQ(r.status, SolveStatus::kConverged) << solverName(kind);
    EXPECT_EQ(r.forces[1], 0.0);
    EXPECT_EQ(r.forces[2], 0.0);
    EXPECT_NEAR(r.forces[0], 1.0, 1e-12);
  }
}

TEST(DiscSolvers, FrictionlessLcpMatchesLemke) {
  Eigen::MatrixXd M(2, 2);
  M << 2, 1, 1, 2;
  const Problem p = makeLcpProblem(M, Eigen::Vector2d(1, -6));
  for (SolverKind kind : kDiscSolvers) {
    const SolveResult r = solveProblem(p, tight(kind));
    ASSERT_EQ(r.status, SolveStatus::kConverged) << solverName(kind);
    EXPECT_NEAR(r.forces[0], 0.0, 1e-12);
    EXPECT_NEAR(r.forces[1], 3.0, 1e-12);
  }
}

TEST(DiscSolvers, MixedContactTypesMatchNlgs) {
  for (unsigned seed : {4u, 5u, 6u}) {
    const Problem p = mixedProblem(seed);
    const SolveResult reference = solveProblem(p, tight(SolverKind::kNlgs));
    ASSERT_EQ(reference.status, SolveStatus::kConverged);
    for (SolverKind kind : kDiscSolvers) {
      const SolveResult r = solveProblem(p, tight(kind, 1e-11));
      ASSERT_EQ(r.status, SolveStatus::kConverged)
          << solverName(kind) << " seed " << seed << ": " << r.message;
      EXPECT_LE((r.forces - reference.forces).norm(), 1e-8 * reference.forces.norm()) << solverName(kind);
      EXPECT_EQ(r.forces[p.rowOffsets()[3] + 1], 0.0);  // μ = 0 tangents stay exactly zero
    }
  }
}

TEST(DiscSolvers, RandomWellPosedProblemsMatchNlgs) {
  for (unsigned seed = 10; seed < 16; ++seed) {
    const Problem p = randomFrictionalProblem(5 + seed % 4, seed, seed % 2 ? 0.3 : 0.8);
    const SolveResult reference = solveProblem(p, tight(SolverKind::kNlgs));
    ASSERT_EQ(reference.status, SolveStatus::kConverged) << seed;
    for (SolverKind kind : kDiscSolvers) {
      const SolveResult r = solveProblem(p, tight(kind, 1e-11));
      ASSERT_EQ(r.status, SolveStatus::kConverged)
          << solverName(kind) << " seed " << seed << ": " << r.message;
      EXPECT_LE(r.residual, 1e-11);
      EXPECT_LE((r.forces - reference.forces).norm(), 1e-7 * reference.forces.norm())
          << solverName(kind) << " seed " << seed;
    }
  }
}

TEST(DiscSolvers, BlockSparseStorageGivesTheSameForces) {
  const Problem dense = mixedProblem(9);
  const Problem sparse = toBlockSparse(dense);
  ASSERT_EQ(validateProblem(sparse), "");
  for (SolverKind kind : kDiscSolvers) {
    const SolveResult a = solveProblem(dense, tight(kind, 1e-11));
    const SolveResult b = solveProblem(sparse, tight(kind, 1e-11));
    ASSERT_EQ(a.status, SolveStatus::kConverged) << solverName(kind);
    ASSERT_EQ(b.status, SolveStatus::kConverged) << solverName(kind);
    EXPECT_LE((a.forces - b.forces).norm(), 1e-8 * a.forces.norm()) << solverName(kind);
  }
}

TEST(DiscSolvers, RegularizationMinWAndWarmStartStillApply) {
  const Problem p = randomFrictionalProblem(4, 21);
  for (SolverKind kind : kDiscSolvers) {
    SolverParams params = tight(kind, 1e-10);
    params.regularizationTerm = 0.01;
    const SolveResult r = solveProblem(p, params);
    ASSERT_EQ(r.status, SolveStatus::kConverged) << solverName(kind);
    SolverParams nlgs = params;
    nlgs.solver = SolverKind::kNlgs;
    EXPECT_LE((r.forces - solveProblem(p, nlgs).forces).norm(), 1e-7 * r.forces.norm());
    // Warm start from the answer: done at once.
    ContactSolver solver(params);
    solver.setParams([&] {
      SolverParams w = params;
      w.initial_guess = true;
      return w;
    }());
    const SolveResult first = solver.solve(p);
    const SolveResult second = solver.solve(p);
    ASSERT_EQ(second.status, SolveStatus::kConverged);
    EXPECT_LE(second.iterations, std::max(1, first.iterations / 2)) << solverName(kind);
  }
}

TEST(DiscSolvers, RankDeficientStackNewtonReachesTenDigits) {
  // Four contacts on one body with 3 degrees of freedom: 12 rows, W of rank 3.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::MatrixXd J(12, 3);
  for (int i = 0; i < 12; ++i)
    for (int j = 0; j < 3; ++j) J(i, j) = u(rng);
  Problem p;
  for (int c = 0; c < 4; ++c) p.contacts.push_back(Contact{c, ContactType::kFrictional, 3, 0.5});
  p.W = Eigen::MatrixXd(J * J.transpose());
  // Consistent pressing: d_free = -W λ* + u* with a known admissible λ*, zero velocity.
  Eigen::VectorXd lambda_star(12);
  for (int c = 0; c < 4; ++c) lambda_star.segment<3>(3 * c) << 1.0 + c, 0.1 * c, -0.05 * c;
  p.d_free = -toDense(p.W) * lambda_star;
  const SolveResult r = solveProblem(p, tight(SolverKind::kNewton, 1e-10));
  ASSERT_EQ(r.status, SolveStatus::kConverged) << r.message;
  EXPECT_LE(r.residual, 1e-10);
}

// Asked for a tolerance below round-off, newton and prox reach their floor and say so
// (numerical_failure, the best iterate) instead of spending all of maxIt there.
TEST(DiscSolvers, AnUnreachableToleranceEndsAtTheFloorNotAtMaxIt) {
  const Problem p = randomFrictionalProblem(8, 31, 0.9, 1e-6);
  for (SolverKind kind : {SolverKind::kNewton, SolverKind::kProx}) {
    SolverParams params = tight(kind, 1e-300);
    params.maxIt = 2000000;
    const SolveResult r = solveProblem(p, params);
    expectFinite(r);
    EXPECT_EQ(r.status, SolveStatus::kNumericalFailure) << solverName(kind) << ": " << r.message;
    EXPECT_LT(r.iterations, params.maxIt / 4) << solverName(kind);
    EXPECT_LE(r.residual, 1e-12) << solverName(kind);
  }
}

TEST(DiscSolvers, HonestFailureKeepsTheBestIterate) {
  const Problem p = randomFrictionalProblem(8, 31, 0.9, 1e-6);
  for (SolverKind kind : kDiscSolvers) {
    SolverParams params = tight(kind, 1e-300);
    params.maxIt = 3;
    const SolveResult r = solveProblem(p, params);
    expectFinite(r);
    EXPECT_EQ(r.status, SolveStatus::kMaxIterations) << solverName(kind);
    EXPECT_FALSE(r.converged);
    EXPECT_LE(r.iterations, 3);
    EXPECT_FALSE(r.message.empty());
    EXPECT_LT(r.residual, naturalMapResidual(p, effectiveMu(p, 0.6), Eigen::VectorXd::Zero(24), p.d_free));
  }
}

}  // namespace
}  // namespace lcp_contact_solver::core
