// Baumgarte position-error correction and softness (core/stabilization.h): exact answers on
// one or two contacts, both constraint levels, per-contact values over the parameters, both
// storages, and "β = 0 and no softness changes nothing".
#include "lcp_contact_solver/core/contact_solver.h"
#include "lcp_contact_solver/core/stabilization.h"

#include <gtest/gtest.h>

namespace lcp_contact_solver::core {
namespace {

// One frictionless contact: d = w λ + d_free.
Problem oneContact(double w, double d_free, double gap) {
  Problem p = makeLcpProblem(Eigen::MatrixXd::Constant(1, 1, w), Eigen::VectorXd::Constant(1, d_free));
  p.contacts[0].gap = gap;
  return p;
}

SolverParams tight() {
  SolverParams params;
  params.tolerance = 1e-13;
  params.initial_guess = false;
  return params;
}

BlockSparseMatrix toBlockSparse(const Problem& p) {
  const Eigen::MatrixXd W = toDense(p.W);
  const std::vector<int> off = p.rowOffsets();
  std::vector<int> sizes;
  for (const Contact& c : p.contacts) sizes.push_back(c.rows);
  BlockSparseMatrix m = BlockSparseMatrix::withBlockSizes(sizes);
  for (std::size_t i = 0; i < sizes.size(); ++i) {
    m.beginRow();
    for (std::size_t j = 0; j < sizes.size(); ++j) {
      const Eigen::MatrixXd block = W.block(off[i], off[j], sizes[i], sizes[j]);
      if (block.cwiseAbs().maxCoeff() > 0.0) m.addBlock(static_cast<int>(j), block);
    }
  }
  return m;
}

TEST(Stabilization, PositionLevelRemovesTheFractionErpOfAPenetration) {
  // w = 2e-4 m/N, the body resting (d_free = 0) 1 cm deep, β = 0.2: the solve asks for
  // d_n = 0.2 · 0.01 = 2 mm of separation: λ = 0.002 / w.
  SolverParams params = tight();
  params.erp = 0.2;
  const SolveResult r = solveProblem(oneContact(2e-4, 0.0, -0.01), params);
  ASSERT_EQ(r.status, SolveStatus::kConverged) << r.message;
  EXPECT_NEAR(r.forces[0], 0.002 / 2e-4, 1e-9);
  EXPECT_NEAR(r.d[0], 0.0, 1e-15);  // d of the problem as solved: W λ + d_free + β·gap
}

TEST(Stabilization, VelocityLevelDividesByTheStep) {
  SolverParams params = tight();
  params.erp = 0.2;
  params.constraint_level = ConstraintLevel::kVelocity;
  params.time_step = 0.01;
  const SolveResult r = solveProblem(oneContact(0.5, 0.0, -0.01), params);
  ASSERT_EQ(r.status, SolveStatus::kConverged) << r.message;
  EXPECT_NEAR(r.forces[0], (0.2 * 0.01 / 0.01) / 0.5, 1e-12);
  // Without the step the correction cannot be formed: refused, not guessed.
  params.time_step = 0.0;
  const SolveResult refused = solveProblem(oneContact(0.5, 0.0, -0.01), params);
  EXPECT_EQ(refused.status, SolveStatus::kInvalidInput);
  EXPECT_NE(refused.message.find("time_step"), std::string::npos) << refused.message;
}

TEST(Stabilization, SeparatedOrUncorrectedContactsAreUntouched) {
  for (double gap : {0.0, 0.003}) {  // only penetrations are corrected
    SolverParams params = tight();
    params.erp = 0.5;
    const SolveResult r = solveProblem(oneContact(1.0, -0.1, gap), params);
    EXPECT_NEAR(r.forces[0], 0.1, 1e-12) << "gap " << gap;
  }
  // β = 0, no softness: bit-identical to the same problem without any gap.
  Problem plain;
  plain.contacts = {Contact{1, ContactType::kFrictional, 3, 0.5},
                    Contact{2, ContactType::kFrictional, 3, 0.3}};
  Eigen::MatrixXd A = Eigen::MatrixXd::Random(6, 6);
  plain.W = Eigen::MatrixXd(A * A.transpose() + 0.1 * Eigen::MatrixXd::Identity(6, 6));
  plain.d_free = Eigen::VectorXd::Random(6);
  Problem with_gap = plain;
  with_gap.contacts[0].gap = -0.02;
  with_gap.contacts[1].gap = -0.5;
  EXPECT_FALSE(needsStabilization(with_gap, tight()));
  const SolveResult a = solveProblem(plain, tight()), b = solveProblem(with_gap, tight());
  EXPECT_EQ(a.forces, b.forces);
  EXPECT_EQ(a.iterations, b.iterations);
}

TEST(Stabilization, SoftnessMakesASpringOfStiffnessErpOverSoftness) {
  // A load pushing the contact in (d_free < 0 each step) settles where β·gap + s·λ = 0
  // (d_n = 0, body at rest): penetration = s λ / β, i.e. stiffness k = β / s.
  const double w = 1e-4, s = 5e-5, beta = 0.25, load = 100.0;  // N
  SolverParams params = tight();
  params.erp = beta;
  params.softness = s;
  // Equilibrium: the contact force equals the load, and the gap that makes d_n = 0 with
  // the body at rest (W λ = the load's displacement −d_free) is −s·load/β.
  const double gap = -s * load / beta;
  const SolveResult r = solveProblem(oneContact(w, -w * load, gap), params);
  ASSERT_EQ(r.status, SolveStatus::kConverged) << r.message;
  EXPECT_NEAR(r.forces[0], load, 1e-9 * load);
  // Softness alone: λ = -d_free / (w + s).
  params.erp = 0.0;
  const SolveResult soft = solveProblem(oneContact(w, -0.01, -0.02), params);
  EXPECT_NEAR(soft.forces[0], 0.01 / (w + s), 1e-9 * soft.forces[0]);
}

TEST(Stabilization, PerContactValuesOverrideTheParameters) {
  Problem p = makeLcpProblem(Eigen::MatrixXd::Identity(3, 3), Eigen::VectorXd::Zero(3));
  for (Contact& c : p.contacts) c.gap = -0.1;
  p.contacts[1].erp = 0.5;       // its own β
  p.contacts[2].erp = 0.0;       // its own: none
  p.contacts[2].softness = 1.0;  // and soft, with nothing to push
  SolverParams params = tight();
  params.erp = 0.2;  // contact 0 takes the parameter
  const SolveResult r = solveProblem(p, params);
  ASSERT_EQ(r.status, SolveStatus::kConverged) << r.message;
  EXPECT_NEAR(r.forces[0], 0.02, 1e-12);
  EXPECT_NEAR(r.forces[1], 0.05, 1e-12);
  EXPECT_NEAR(r.forces[2], 0.0, 1e-12);
}

TEST(Stabilization, DenseAndBlockSparseAgreeEvenWithoutStoredDiagonalBlocks) {
  Problem p;
  p.contacts = {Contact{1, ContactType::kFrictional, 3, 0.5}, Contact{2, ContactType::kFrictionless, 1, 0.0},
                Contact{3, ContactType::kBilateral, 2, 0.0}};
  Eigen::MatrixXd W = Eigen::MatrixXd::Zero(6, 6);
  W.topLeftCorner(3, 3) << 2, 0.1, 0, 0.1, 2, 0, 0, 0, 2;
  W(3, 3) = 0.0;  // contact 2 has no self-compliance at all: only its softness makes it solvable
  W.bottomRightCorner(2, 2) = Eigen::Matrix2d::Identity();
  p.W = W;
  p.d_free = (Eigen::VectorXd(6) << -0.3, 0.1, 0.0, -0.2, 0.05, -0.05).finished();
  p.contacts[0].gap = -0.1;
  p.contacts[1].gap = -0.1;
  p.contacts[1].softness = 0.5;
  SolverParams params = tight();
  params.erp = 0.3;
  Problem sparse = p;
  sparse.W = toBlockSparse(p);
  ASSERT_EQ(std::get<BlockSparseMatrix>(sparse.W).block_col.size(), 2u);  // no block (1, 1)
  for (SolverKind kind : {SolverKind::kNlgs, SolverKind::kNewton}) {
    params.solver = kind;
    const SolveResult a = solveProblem(p, params), b = solveProblem(sparse, params);
    ASSERT_EQ(a.status, SolveStatus::kConverged) << solverName(kind) << ": " << a.message;
    ASSERT_EQ(b.status, SolveStatus::kConverged) << solverName(kind) << ": " << b.message;
    EXPECT_LE((a.forces - b.forces).lpNorm<Eigen::Infinity>(), 1e-10) << solverName(kind);
    // Contact 2: (0 + 0.5) λ = 0.2 + 0.3 · 0.1.
    EXPECT_NEAR(a.forces[3], (0.2 + 0.03) / 0.5, 1e-10) << solverName(kind);
    // The bilateral rows take no correction.
    EXPECT_NEAR(a.forces[4], -0.05, 1e-10);
  }
}

TEST(Stabilization, InvalidValuesAreRefused) {
  auto refused = [](Problem p, const SolverParams& params, const char* expected) {
    const SolveResult r = solveProblem(p, params);
    EXPECT_EQ(r.status, SolveStatus::kInvalidInput) << expected;
    EXPECT_NE(r.message.find(expected), std::string::npos) << r.message;
    EXPECT_TRUE(r.forces.size() == 0 || r.forces.allFinite());
  };
  Problem p = oneContact(1.0, -0.1, -0.01);
  Problem bad = p;
  bad.contacts[0].erp = 1.5;
  refused(bad, tight(), "outside [0, 1]");
  bad = p;
  bad.contacts[0].softness = -0.2;
  refused(bad, tight(), "negative softness");
  bad = p;
  bad.contacts[0].gap = std::numeric_limits<double>::quiet_NaN();
  refused(bad, tight(), "non-finite gap");
  SolverParams params = tight();
  params.erp = -0.1;
  refused(p, params, "erp must be");
  params = tight();
  params.softness = std::numeric_limits<double>::infinity();
  refused(p, params, "softness must be");
}

}  // namespace
}  // namespace lcp_contact_solver::core
