// Cases with a known exact answer, through every solver that applies.
#include "lcp_contact_solver/core/contact_solver.h"
#include "lcp_contact_solver/core/residual.h"

#include <Eigen/LU>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace lcp_contact_solver::core {
namespace {

Problem oneFrictionalContact(const Eigen::Matrix3d& W, const Eigen::Vector3d& d_free, double mu) {
  Problem p;
  p.contacts.push_back(Contact{7, ContactType::kFrictional, 3, mu});
  p.W = Eigen::MatrixXd(W);
  p.d_free = d_free;
  return p;
}

SolverParams tight(SolverKind kind) {
  SolverParams params;
  params.solver = kind;
  params.tolerance = 1e-12;
  params.initial_guess = false;
  return params;
}

TEST(Analytic, RestingContactNormalForceIsMinusDOverW) {
  // A body resting on the ground: the normal force cancels the free penetration.
  Eigen::Matrix3d W = Eigen::Matrix3d::Identity() * 0.5;
  const Problem p = oneFrictionalContact(W, Eigen::Vector3d(-0.2, 0.0, 0.0), 0.6);
  for (SolverKind kind : {SolverKind::kNlgs, SolverKind::kAuto}) {
    const SolveResult r = solveProblem(p, tight(kind));
    ASSERT_EQ(r.status, SolveStatus::kConverged) << r.message;
    EXPECT_NEAR(r.forces[0], 0.2 / 0.5, 1e-12);
    EXPECT_NEAR(r.forces[1], 0.0, 1e-12);
    EXPECT_NEAR(r.forces[2], 0.0, 1e-12);
    EXPECT_NEAR(r.d[0], 0.0, 1e-12);
    EXPECT_EQ(r.states[0], ContactState::kStick);
    EXPECT_LE(r.residual, 1e-12);
  }
}

TEST(Analytic, FrictionlessRestingContactThroughPgsAndLemke) {
  Problem p = makeLcpProblem(Eigen::MatrixXd::Constant(1, 1, 4.0), Eigen::VectorXd::Constant(1, -2.0));
  for (SolverKind kind : {SolverKind::kPgs, SolverKind::kLemke, SolverKind::kAuto}) {
    const SolveResult r = solveProblem(p, tight(kind));
    ASSERT_EQ(r.status, SolveStatus::kConverged) << solverName(kind) << ": " << r.message;
    EXPECT_NEAR(r.forces[0], 0.5, 1e-12);
    EXPECT_EQ(r.states[0], ContactState::kClosed);  // frictionless and pressed: no friction law
  }
}

TEST(Analytic, SlidingContactFrictionOnConeOppositeSlip) {
  // Uncoupled W: the tangential free motion (0.6, -0.8) is too large to stop with
  // μ λ_n, so the contact slides and friction lies on the cone, opposite the slip.
  const double w = 2.0, mu = 0.5;
  const Eigen::Vector3d d_free(-1.0, 0.6, -0.8);
  const Problem p = oneFrictionalContact(Eigen::Matrix3d::Identity() * w, d_free, mu);
  const SolveResult r = solveProblem(p, tight(SolverKind::kNlgs));
  ASSERT_EQ(r.status, SolveStatus::kConverged) << r.message;
  const double lambda_n = 1.0 / w;  // normal decoupled from tangents
  EXPECT_NEAR(r.forces[0], lambda_n, 1e-12);
  const Eigen::Vector2d slip_free(0.6, -0.8);  // |1.0| > what friction can stop: w μ λ_n = 0.5
  ASSERT_GT(slip_free.norm(), w * mu * lambda_n);
  const Eigen::Vector2d expected = -mu * lambda_n * slip_free.normalized();
  EXPECT_NEAR(r.forces[1], expected[0], 1e-12);
  EXPECT_NEAR(r.forces[2], expected[1], 1e-12);
  // The resulting slip velocity points along the free slip, opposite the friction force.
  const Eigen::Vector2d slip(r.d[1], r.d[2]);
  EXPECT_GT(slip.norm(), 0.0);
  EXPECT_NEAR(slip.normalized().dot(expected.normalized()), -1.0, 1e-12);
  EXPECT_EQ(r.states[0], ContactState::kSlip);
}

TEST(Analytic, SlidingWithCoupledAnisotropicBlockStillOpposesSlip) {
  // A full symmetric positive definite block: friction must still oppose the *resulting*
  // slip velocity (Coulomb's maximum dissipation), not just the free one.
  Eigen::Matrix3d W;
  W << 2.0, 0.3, -0.2, 0.3, 1.5, 0.4, -0.2, 0.4, 0.8;
  const Problem p = oneFrictionalContact(W, Eigen::Vector3d(-1.0, 2.0, -1.5), 0.3);
  const SolveResult r = solveProblem(p, tight(SolverKind::kNlgs));
  ASSERT_EQ(r.status, SolveStatus::kConverged) << r.message;
  EXPECT_GT(r.forces[0], 0.0);
  EXPECT_NEAR(r.d[0], 0.0, 1e-12);
  const Eigen::Vector2d force(r.forces[1], r.forces[2]);
  const Eigen::Vector2d slip(r.d[1], r.d[2]);
  EXPECT_NEAR(force.norm(), 0.3 * r.forces[0], 1e-12);
  EXPECT_NEAR(force.normalized().dot(slip.normalized()), -1.0, 1e-10);
  EXPECT_EQ(r.states[0], ContactState::kSlip);
}

TEST(Analytic, OneContactWithAnyBlockIsSolvedExactlyInOneSweep) {
  // With one contact, a Gauss-Seidel sweep is one local solve: if that solve is exact the
  // first sweep lands on the solution, for coupled and for non-symmetric blocks (assembled
  // W often carries round-off asymmetry). Each answer is checked against Coulomb's law.
  std::srand(11);
  int sliding = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Matrix3d J = Eigen::Matrix3d::Random();
    Eigen::Matrix3d W = J * J.transpose() + 0.3 * Eigen::Matrix3d::Identity();
    if (trial % 2 == 1) W += 0.05 * W.norm() * Eigen::Matrix3d::Random();  // non-symmetric
    if (W.determinant() <= 0.0 || W(0, 0) <= 0.0) continue;
    const Eigen::Vector3d d_free(-0.5 - std::abs(Eigen::Vector3d::Random()[0]), Eigen::Vector3d::Random()[1],
                                 Eigen::Vector3d::Random()[2]);
    const double mu = 0.2 + 0.4 * std::abs(Eigen::Vector3d::Random()[0]);
    SolverParams params = tight(SolverKind::kNlgs);
    params.maxIt = 2;  // the second sweep only confirms the first
    const SolveResult r = solveProblem(oneFrictionalContact(W, d_free, mu), params);
    ASSERT_EQ(r.status, SolveStatus::kConverged) << "trial " << trial << ": " << r.message;
    const double scale = d_free.norm();
    ASSERT_GT(r.forces[0], 0.0) << "trial " << trial;
    EXPECT_NEAR(r.d[0], 0.0, 1e-12 * scale) << "trial " << trial;
    const Eigen::Vector2d force(r.forces[1], r.forces[2]);
    const Eigen::Vector2d slip(r.d[1], r.d[2]);
    EXPECT_LE(force.norm(), mu * r.forces[0] * (1 + 1e-12)) << "trial " << trial;
    if (slip.norm() > 1e-10 * scale) {
      ++sliding;
      EXPECT_NEAR(force.norm(), mu * r.forces[0], 1e-12 * scale) << "trial " << trial;
      EXPECT_NEAR(force.normalized().dot(slip.normalized()), -1.0, 1e-10) << "trial " << trial;
    }
  }
  EXPECT_GT(sliding, 40);  // not only sticking contacts
}

TEST(Analytic, SeparatingContactHasZeroForce) {
  const Problem p = oneFrictionalContact(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0.1, 0.5, 0.0), 0.8);
  for (SolverKind kind : {SolverKind::kNlgs, SolverKind::kAuto}) {
    const SolveResult r = solveProblem(p, tight(kind));
    ASSERT_EQ(r.status, SolveStatus::kConverged);
    EXPECT_EQ(r.forces.norm(), 0.0);
    EXPECT_EQ(r.states[0], ContactState::kOpen);
    EXPECT_NEAR(r.d[0], 0.1, 0.0);
  }
}

TEST(Analytic, TwoCoupledContactsMatchLemkeAndGaussSeidel) {
  // w = M z + q with M = [[2,1],[1,2]], q = [-5,-6]: both contacts pressed,
  // z = M⁻¹(-q) = (4/3, 7/3).
  Eigen::MatrixXd M(2, 2);
  M << 2, 1, 1, 2;
  const Problem p = makeLcpProblem(M, Eigen::Vector2d(-5, -6));
  for (SolverKind kind : {SolverKind::kLemke, SolverKind::kPgs}) {
    const SolveResult r = solveProblem(p, tight(kind));
    ASSERT_EQ(r.status, SolveStatus::kConverged) << solverName(kind);
    EXPECT_NEAR(r.forces[0], 4.0 / 3.0, 1e-10);
    EXPECT_NEAR(r.forces[1], 7.0 / 3.0, 1e-10);
  }
  // One contact opens: q = [1, -6] → z = (0, 3), w = (4, 0).
  const Problem open = makeLcpProblem(M, Eigen::Vector2d(1, -6));
  const SolveResult r = solveProblem(open, tight(SolverKind::kLemke));
  ASSERT_EQ(r.status, SolveStatus::kConverged);
  EXPECT_NEAR(r.forces[0], 0.0, 1e-12);
  EXPECT_NEAR(r.forces[1], 3.0, 1e-12);
  EXPECT_NEAR(r.d[0], 4.0, 1e-12);
  EXPECT_EQ(r.states[0], ContactState::kOpen);
}

TEST(Analytic, BilateralRowHoldsWithFreeSign) {
  // A bilateral row pulled apart needs a negative force; a unilateral one would open.
  Problem p;
  p.contacts.push_back(Contact{1, ContactType::kBilateral, 1, Contact::kMuDefault});
  p.W = Eigen::MatrixXd::Constant(1, 1, 2.0);
  p.d_free = Eigen::VectorXd::Constant(1, 0.4);
  const SolveResult r = solveProblem(p, tight(SolverKind::kNlgs));
  ASSERT_EQ(r.status, SolveStatus::kConverged);
  EXPECT_NEAR(r.forces[0], -0.2, 1e-12);
  EXPECT_NEAR(r.d[0], 0.0, 1e-12);
  EXPECT_EQ(r.states[0], ContactState::kStick);
}

TEST(Analytic, ZeroFrictionContactCostsOneRow) {
  // μ = 0 on a frictional contact: tangential forces stay exactly zero, pgs applies.
  const Problem p = oneFrictionalContact(Eigen::Matrix3d::Identity(), Eigen::Vector3d(-1.0, 0.7, 0.2), 0.0);
  const SolveResult r = solveProblem(p, tight(SolverKind::kPgs));
  ASSERT_EQ(r.status, SolveStatus::kConverged) << r.message;
  EXPECT_EQ(r.forces[1], 0.0);
  EXPECT_EQ(r.forces[2], 0.0);
  EXPECT_NEAR(r.forces[0], 1.0, 1e-12);
  EXPECT_EQ(r.states[0], ContactState::kClosed);  // μ = 0: neither stick nor slip
}

TEST(Analytic, PerContactMuOverridesDefault) {
  // Two identical sliding contacts, one with its own μ = 0.1, one using the default 0.6.
  Problem p;
  p.contacts.push_back(Contact{1, ContactType::kFrictional, 3, 0.1});
  p.contacts.push_back(Contact{2, ContactType::kFrictional, 3, Contact::kMuDefault});
  p.W = Eigen::MatrixXd(Eigen::MatrixXd::Identity(6, 6));
  p.d_free.resize(6);
  p.d_free << -1, 5, 0, -1, 5, 0;
  const SolveResult r = solveProblem(p, tight(SolverKind::kNlgs));
  ASSERT_EQ(r.status, SolveStatus::kConverged);
  EXPECT_NEAR(r.forces[1], -0.1, 1e-12);
  EXPECT_NEAR(r.forces[4], -0.6, 1e-12);
}

TEST(Analytic, SparseAndDenseStoragesGiveTheSameForces) {
  Eigen::MatrixXd W(6, 6);
  W << 2.0, 0.1, 0.0, 0.5, 0.0, 0.1, 0.1, 1.0, 0.0, 0.0, 0.2, 0.0, 0.0, 0.0, 1.0, 0.1, 0.0, 0.0, 0.5, 0.0,
      0.1, 2.0, 0.0, 0.0, 0.0, 0.2, 0.0, 0.0, 1.0, 0.1, 0.1, 0.0, 0.0, 0.0, 0.1, 1.0;
  Problem dense;
  dense.contacts = {Contact{1, ContactType::kFrictional, 3, 0.4},
                    Contact{2, ContactType::kFrictional, 3, 0.4}};
  dense.W = W;
  dense.d_free.resize(6);
  dense.d_free << -1.0, 0.3, -0.1, -0.5, 0.9, 0.2;
  Problem sparse = dense;
  BlockSparseMatrix B = BlockSparseMatrix::withBlockSizes({3, 3});
  for (int i = 0; i < 2; ++i) {
    B.beginRow();
    for (int j = 0; j < 2; ++j) B.addBlock(j, W.block(3 * i, 3 * j, 3, 3));
  }
  sparse.W = B;
  ASSERT_EQ(validateProblem(sparse), "");
  const SolveResult a = solveProblem(dense, tight(SolverKind::kNlgs));
  const SolveResult b = solveProblem(sparse, tight(SolverKind::kNlgs));
  ASSERT_EQ(a.status, SolveStatus::kConverged);
  ASSERT_EQ(b.status, SolveStatus::kConverged);
  EXPECT_LE((a.forces - b.forces).norm(), 1e-10);
  EXPECT_LE(a.residual, 1e-12);
}

TEST(Analytic, ConeProjection) {
  double inside[3] = {1.0, 0.1, 0.1};
  projectOntoCone(0.5, inside);
  EXPECT_DOUBLE_EQ(inside[1], 0.1);
  double polar[3] = {-1.0, 0.1, 0.0};
  projectOntoCone(0.5, polar);
  EXPECT_EQ(polar[0], 0.0);
  double outside[3] = {1.0, 2.0, 0.0};
  projectOntoCone(0.5, outside);
  EXPECT_NEAR(outside[1], 0.5 * outside[0], 1e-15);
  EXPECT_NEAR(outside[0], (1.0 + 0.5 * 2.0) / 1.25, 1e-15);
}

TEST(Analytic, ZeroFrictionConeIsTheNormalRay) {
  // μ = 0: the cone is {t = 0, n >= 0}; a point with n < 0 projects to the apex.
  double below[3] = {-2.0, 0.0, 0.0};
  projectOntoCone(0.0, below);
  EXPECT_EQ(below[0], 0.0);
  double sliding[3] = {3.0, 1.0, -1.0};
  projectOntoCone(0.0, sliding);
  EXPECT_EQ(sliding[0], 3.0);
  EXPECT_EQ(sliding[1], 0.0);
  EXPECT_EQ(sliding[2], 0.0);
  // A separating μ = 0 contact with no force is an exact solution (residual 0), in the
  // residual every result reports (a fuzzer found it reported as 1).
  const Problem p =
      oneFrictionalContact(Eigen::Matrix3d::Identity() * 2.0, Eigen::Vector3d(2.0, 0.0, 0.0), 0.0);
  for (SolverKind kind : {SolverKind::kPgs, SolverKind::kNlgs, SolverKind::kAuto}) {
    const SolveResult r = solveProblem(p, tight(kind));
    ASSERT_EQ(r.status, SolveStatus::kConverged) << solverName(kind);
    EXPECT_EQ(r.forces.norm(), 0.0);
    EXPECT_EQ(r.residual, 0.0) << solverName(kind);
  }
}

TEST(Analytic, ResidualOfAHugeProblemIsScaledNotOverflowed) {
  // Two frictionless rows at the scale of 1e300: λ = (0, 5e299) solves it exactly, yet
  // d_2 = 2 λ_2 − 1e300 keeps a rounding error near 1e284, whose square overflows. The
  // residual is relative to |d_free|, so it must read ~1e-16, not DBL_MAX (found by
  // fuzzing: an exact answer reported as "converged with residual DBL_MAX"), and a wrong
  // answer must still read ~1, not 0 (|d_free|² overflowing would divide by inf).
  Problem p;
  p.contacts.push_back(Contact{1, ContactType::kFrictionless, 1, 0.0});
  p.contacts.push_back(Contact{2, ContactType::kFrictionless, 1, 0.0});
  Eigen::Matrix2d W;
  W << 2.0, 1.0, 1.0, 2.0;
  p.W = Eigen::MatrixXd(W);
  p.d_free = Eigen::Vector2d(0.5, -1e300);
  const std::vector<double> mu(2, 0.0);
  const Eigen::VectorXd exact = Eigen::Vector2d(0.0, 5e299);
  const Eigen::VectorXd d_exact = W * exact + p.d_free;
  EXPECT_LT(naturalMapResidual(p, mu, exact, d_exact, {}), 1e-12);
  const Eigen::VectorXd none = Eigen::Vector2d::Zero();
  EXPECT_NEAR(naturalMapResidual(p, mu, none, p.d_free, {}), 1.0, 1e-12);
  for (SolverKind kind : {SolverKind::kNewton, SolverKind::kAuto}) {
    SolverParams params = tight(kind);
    params.tolerance = 1e-10;
    const SolveResult r = solveProblem(p, params);
    EXPECT_EQ(r.status, SolveStatus::kConverged) << solverName(kind);
    EXPECT_LE(r.residual, 1e-10) << solverName(kind);
    EXPECT_NEAR(r.forces[1], 5e299, 1e285) << solverName(kind);
  }
}

TEST(Analytic, ResidualWithFreeMotionsNearDblMaxIsMeasuredToScale) {
  // |d_free| itself overflows (entries of DBL_MAX): the ratio is measured on everything
  // divided by max |d_free_i|, the same number without inf (fuzzing found a penetration of
  // 1 mm read against a norm of 1, while the μ = 0 compaction measured it against DBL_MAX).
  constexpr double kMax = std::numeric_limits<double>::max();
  Problem p;
  p.contacts.push_back(Contact{1, ContactType::kFrictional, 3, 0.5});
  p.contacts.push_back(Contact{2, ContactType::kFrictional, 3, 0.5});
  p.W = Eigen::MatrixXd(Eigen::MatrixXd::Identity(6, 6));
  const std::vector<double> mu(2, 0.5);
  const Eigen::VectorXd none = Eigen::VectorXd::Zero(6);
  p.d_free.resize(6);
  p.d_free << -0.001, 0.0, 0.0, kMax, kMax, kMax;
  EXPECT_LT(naturalMapResidual(p, mu, none, p.d_free, {}), 1e-300);
  // A penetration of DBL_MAX with no force: error DBL_MAX against |d_free| = 2 DBL_MAX.
  p.d_free << -kMax, 0.0, 0.0, kMax, kMax, kMax;
  EXPECT_NEAR(naturalMapResidual(p, mu, none, p.d_free, {}), 0.5, 1e-12);
}

}  // namespace
}  // namespace lcp_contact_solver::core
