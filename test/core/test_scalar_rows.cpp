// Scalar-row storage (core/scalar_rows.h): a block-sparse problem whose contacts all have one
// row is swept as flat scalar rows. Its answers equal those of the other storages: the
// 1×1-block sweep (the same problem beside a decoupled 3-row contact, which keeps the block
// path), sweep for sweep; the dense sweep to 1e-10 where the solution is unique; through
// islands and whatever the thread count. Problems: a frictionless LCP (W = J M⁻¹ Jᵀ + δI of
// random bodies) and a pyramidal-cone LCP (MuJoCo's form: four edge rows n ± μ t_k per
// contact, one-row frictionless contacts).
#include "hard_case_util.h"
#include "lcp_contact_solver/core/contact_solver.h"
#include "lcp_contact_solver/core/kernels/scalar_rows.h"
#include "lcp_contact_solver/core/residual.h"

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include <random>

namespace lcp_contact_solver::core {
namespace {

// `groups` groups of bodies, each body with 6 dof; a contact (or, pyramid, its four edge
// rows) touches one or two bodies of its group, so the groups are islands and rows are
// interleaved across them. W = J M⁻¹ Jᵀ + δ I is symmetric positive definite.
Problem generate(int groups, int contacts_per_group, bool pyramid, unsigned seed, double delta = 1e-4) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0), pos(0.0, 1.0);
  const int bodies_per_group = 3;
  const int nb = groups * bodies_per_group;
  const int per_contact = pyramid ? 4 : 1;
  const int nc = groups * contacts_per_group;
  const int n = nc * per_contact;
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(n, 6 * nb);
  Eigen::VectorXd d_free(n);
  for (int k = 0; k < nc; ++k) {
    const int group = k % groups;  // interleaved
    const int a = group * bodies_per_group + static_cast<int>(pos(rng) * bodies_per_group) % bodies_per_group;
    const int b = group * bodies_per_group + (a - group * bodies_per_group + 1) % bodies_per_group;
    const bool two = pos(rng) < 0.5;
    Eigen::Matrix<double, 3, 6> Ja, Jb;  // normal, tangent 1, tangent 2 rows
    for (int r = 0; r < 3; ++r)
      for (int q = 0; q < 6; ++q) {
        Ja(r, q) = u(rng);
        Jb(r, q) = u(rng);
      }
    const double mu = 0.3 + 0.6 * pos(rng);
    const double gap_velocity = -0.5 + 0.9 * pos(rng);
    for (int e = 0; e < per_contact; ++e) {
      const int row = k * per_contact + e;
      Eigen::Matrix<double, 1, 3> w(1.0, 0.0, 0.0);  // edge row: n ± μ t_k
      if (pyramid) w << 1.0, (e == 0 ? mu : e == 1 ? -mu : 0.0), (e == 2 ? mu : e == 3 ? -mu : 0.0);
      J.block<1, 6>(row, 6 * a) += w * Ja;
      if (two) J.block<1, 6>(row, 6 * b) -= w * Jb;
      d_free[row] = gap_velocity + (pyramid ? 0.2 * u(rng) : 0.0);
    }
  }
  Eigen::VectorXd inverse_mass(6 * nb);
  for (int q = 0; q < 6 * nb; ++q) inverse_mass[q] = 0.5 + pos(rng);
  Eigen::MatrixXd W = J * inverse_mass.asDiagonal() * J.transpose();
  W.diagonal().array() += delta;
  Problem p;
  for (int i = 0; i < n; ++i) {
    Contact c;
    c.id = 1000 + i;
    c.type = ContactType::kFrictionless;
    c.rows = 1;
    p.contacts.push_back(c);
  }
  p.W = W;
  p.d_free = d_free;
  return p;
}

// `p` (block-sparse, one-row contacts) with a 3-row frictional contact appended that W does
// not couple to the others: the 1×1-block sweep runs on it, and the first rows' iterates are
// those of `p` alone.
Problem withDecoupledFrictionalContact(const Problem& p) {
  Problem q = p;
  const Eigen::MatrixXd W = toDense(p.W);
  const int n = static_cast<int>(W.rows());
  Eigen::MatrixXd Wq = Eigen::MatrixXd::Zero(n + 3, n + 3);
  Wq.topLeftCorner(n, n) = W;
  Wq.bottomRightCorner<3, 3>() << 2.0, 0.1, 0.0, 0.1, 1.5, 0.2, 0.0, 0.2, 1.8;
  Contact c;
  c.id = 1;
  c.type = ContactType::kFrictional;
  c.rows = 3;
  c.mu = 0.5;
  q.contacts.push_back(c);
  q.W = Wq;
  q.d_free.conservativeResize(n + 3);
  q.d_free.tail<3>() << -1.0, 0.3, -0.2;
  return hard::toBlockSparse(q);
}

SolverParams params(SolverKind kind, double tolerance, int max_it, bool islands = false, int threads = 1) {
  SolverParams s;
  s.solver = kind;
  s.tolerance = tolerance;
  s.maxIt = max_it;
  s.initial_guess = false;
  s.islands = islands;
  s.threads = threads;
  return s;
}

double maxDiff(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return a.size() == b.size() ? (a - b).cwiseAbs().maxCoeff() : 1e300;
}

TEST(ScalarRows, ChosenForOneRowBlockSparseProblemsOnly) {
  const Problem dense = generate(2, 5, false, 1);
  const Problem sparse = hard::toBlockSparse(dense);
  EXPECT_FALSE(fitsScalarRows(dense));
  EXPECT_TRUE(fitsScalarRows(sparse));
  EXPECT_FALSE(fitsScalarRows(withDecoupledFrictionalContact(sparse)));
  // The stored columns are W's (W symmetric here: Wᵀ = W).
  const ScalarRows columns = scalarColumnsOf(std::get<BlockSparseMatrix>(sparse.W));
  const Eigen::MatrixXd W = toDense(dense.W);
  Eigen::MatrixXd rebuilt = Eigen::MatrixXd::Zero(W.rows(), W.cols());
  for (int j = 0; j < columns.n; ++j)
    for (int s = columns.start[j]; s < columns.start[j + 1]; ++s)
      rebuilt(columns.index[s], j) = columns.value[s];
  EXPECT_EQ(rebuilt, W);
  EXPECT_EQ(columns.entries(), std::get<BlockSparseMatrix>(sparse.W).values.size());
}

TEST(ScalarRows, NonSymmetricWIsStoredByColumns) {
  Problem p = generate(1, 6, false, 2);
  Eigen::MatrixXd W = toDense(p.W);
  W(0, 3) += 0.25;  // W_03 != W_30
  p.W = W;
  const Problem sparse = hard::toBlockSparse(p);
  const ScalarRows columns = scalarColumnsOf(std::get<BlockSparseMatrix>(sparse.W));
  bool found = false;
  for (int s = columns.start[3]; s < columns.start[4]; ++s)
    if (columns.index[s] == 0) {
      EXPECT_EQ(columns.value[s], W(0, 3));
      found = true;
    }
  EXPECT_TRUE(found);
  // Solved to a tight tolerance, it agrees with the dense sweep.
  const SolveResult a = solveProblem(sparse, params(SolverKind::kPgs, 1e-12, 20000));
  const SolveResult b = solveProblem(p, params(SolverKind::kPgs, 1e-12, 20000));
  ASSERT_TRUE(a.converged) << a.message;
  ASSERT_TRUE(b.converged) << b.message;
  EXPECT_LE(maxDiff(a.forces, b.forces), 1e-10);
}

// Sweep for sweep (SOFA's stopping rule with a tolerance out of reach: the last iterate
// after maxIt sweeps), the scalar rows give the 1×1-block sweep's forces.
TEST(ScalarRows, SameIteratesAsTheBlockSweep) {
  for (bool pyramid : {false, true}) {
    for (double sor : {1.0, 1.3}) {
      const Problem p = hard::toBlockSparse(generate(3, 6, pyramid, 3));
      const Problem q = withDecoupledFrictionalContact(p);
      SolverParams s = params(SolverKind::kNlgs, 1e-300, 9);
      s.stopping_rule = StoppingRule::kSofa;
      s.sor = sor;
      const SolveResult scalar = solveProblem(p, s);
      const SolveResult block = solveProblem(q, s);
      ASSERT_EQ(scalar.iterations, 9) << scalar.message;
      ASSERT_EQ(block.iterations, 9);
      const int n = static_cast<int>(p.d_free.size());
      EXPECT_LE(maxDiff(scalar.forces, block.forces.head(n)),
                1e-13 * (1.0 + scalar.forces.cwiseAbs().maxCoeff()))
          << "pyramid " << pyramid << " sor " << sor;
      EXPECT_GT(scalar.forces.cwiseAbs().maxCoeff(), 0.0);
    }
  }
}

// Unique solutions (W positive definite) at a tight tolerance: scalar rows, dense W, the
// block sweep and the symmetric Newton agree to 1e-10, with islands on or off and 1 or 2
// threads; the residual recomputed from W meets the tolerance.
TEST(ScalarRows, SameAnswersAsOtherStoragesOnFrictionlessAndPyramidLcps) {
  for (bool pyramid : {false, true}) {
    const Problem dense = generate(4, pyramid ? 6 : 15, pyramid, 4, pyramid ? 1e-2 : 1e-4);
    const Problem sparse = hard::toBlockSparse(dense);
    const int n = static_cast<int>(dense.d_free.size());
    const SolveResult reference = solveProblem(dense, params(SolverKind::kLemke, 1e-14, 100000));
    ASSERT_LE(reference.residual, 1e-12) << reference.message;
    const SolveResult block =
        solveProblem(withDecoupledFrictionalContact(sparse), params(SolverKind::kNlgs, 1e-13, 200000));
    ASSERT_TRUE(block.converged) << block.message;
    EXPECT_LE(maxDiff(block.forces.head(n), reference.forces), 1e-10);
    for (SolverKind kind : {SolverKind::kPgs, SolverKind::kNlgs, SolverKind::kAuto}) {
      for (bool islands : {false, true}) {
        for (int threads : {1, 2}) {
          const SolveResult r = solveProblem(sparse, params(kind, 1e-13, 200000, islands, threads));
          ASSERT_TRUE(r.converged) << solverName(kind) << ": " << r.message;
          EXPECT_LE(maxDiff(r.forces, reference.forces), 1e-10)
              << solverName(kind) << " pyramid " << pyramid << " islands " << islands << " threads "
              << threads;
          Eigen::VectorXd d;
          multiply(dense.W, r.forces, d);
          d += dense.d_free;
          EXPECT_LE(naturalMapResidual(dense, effectiveMu(dense, 0.0), r.forces, d), 1e-12);
        }
      }
    }
  }
}

// Islands and threads: the same forces bit for bit whatever the thread count, at a loose
// tolerance where each island stops on its own test.
TEST(ScalarRows, IslandResultsIndependentOfThreadCount) {
  const Problem sparse = hard::toBlockSparse(generate(6, 12, false, 5, 1e-2));
  const SolveResult one = solveProblem(sparse, params(SolverKind::kPgs, 1e-6, 10000, true, 1));
  const SolveResult two = solveProblem(sparse, params(SolverKind::kPgs, 1e-6, 10000, true, 2));
  ASSERT_TRUE(one.converged) << one.message;
  EXPECT_EQ(one.forces, two.forces);
  EXPECT_EQ(one.iterations, two.iterations);
}

// Contacts left out by minW stay at zero, as with the block sweep; one-row bilateral rows
// are solved to d = 0.
TEST(ScalarRows, IgnoredAndBilateralRows) {
  Problem dense = generate(2, 8, false, 6);
  Eigen::MatrixXd W = toDense(dense.W);
  W(5, 5) = 1e-9;  // below minW
  for (int k = 0; k < W.rows(); ++k)
    if (k != 5) W(5, k) = W(k, 5) = 0.0;
  dense.W = W;
  dense.contacts[2].type = ContactType::kBilateral;
  const Problem sparse = hard::toBlockSparse(dense);
  SolverParams s = params(SolverKind::kNlgs, 1e-12, 100000);
  s.minW = 1e-6;
  const SolveResult a = solveProblem(sparse, s);
  const SolveResult b = solveProblem(dense, s);
  ASSERT_TRUE(a.converged) << a.message;
  ASSERT_TRUE(b.converged) << b.message;
  EXPECT_EQ(a.forces[5], 0.0);
  EXPECT_EQ(a.states[5], ContactState::kIgnored);
  EXPECT_NEAR(a.d[2], 0.0, 1e-10);
  EXPECT_LE(maxDiff(a.forces, b.forces), 1e-10);
}

// A zero diagonal is reported as the block sweep reports it.
TEST(ScalarRows, ZeroDiagonalIsReported) {
  Problem dense = generate(1, 4, false, 7);
  Eigen::MatrixXd W = toDense(dense.W);
  W.row(1).setZero();
  W.col(1).setZero();
  dense.W = W;
  const SolveResult r = solveProblem(hard::toBlockSparse(dense), params(SolverKind::kPgs, 1e-8, 100));
  EXPECT_EQ(r.status, SolveStatus::kZeroDiagonal);
  EXPECT_NE(r.message.find("W_nn"), std::string::npos) << r.message;
}

}  // namespace
}  // namespace lcp_contact_solver::core
