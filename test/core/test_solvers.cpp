// The solvers added beside pgs/nlgs/lemke: over-relaxation of the Gauss-Seidel solvers,
// apgd, newton, the pyramid friction models (boxed pgs, Lemke on the Stewart-Trinkle LCP)
// and the per-solve time budget.
#include "solvers_test_util.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include <thread>

namespace lcp_contact_solver::core {
namespace {

using namespace solvers_test;

// ---- names and parameters ---------------------------------------------------------------

TEST(Solvers, NamesRoundTrip) {
  for (const std::string& name : solverNames()) {
    SolverKind kind;
    ASSERT_TRUE(parseSolverName(name, &kind)) << name;
    EXPECT_EQ(solverName(kind), name);
  }
  SolverKind kind;
  EXPECT_TRUE(parseSolverName("apgd", &kind));
  EXPECT_EQ(kind, SolverKind::kApgd);
  EXPECT_TRUE(parseSolverName("newton", &kind));
  EXPECT_EQ(kind, SolverKind::kNewton);
  for (const std::string name : {"disc", "pyramid4", "pyramid8"}) {
    FrictionModel model;
    ASSERT_TRUE(parseFrictionModel(name, &model)) << name;
    EXPECT_EQ(frictionModelName(model), name);
  }
  FrictionModel model = FrictionModel::kPyramid8;
  EXPECT_FALSE(parseFrictionModel("pyramid6", &model));
  EXPECT_EQ(model, FrictionModel::kPyramid8);
  EXPECT_EQ(frictionModelNames().size(), 3u);
}

TEST(Solvers, TimeBudgetStatusIsAppended) {
  // Existing statuses keep their numbers (messages and logs carry them).
  EXPECT_EQ(static_cast<int>(SolveStatus::kInvalidInput), 6);
  EXPECT_EQ(static_cast<int>(SolveStatus::kTimeBudget), 7);
  EXPECT_STREQ(statusName(SolveStatus::kTimeBudget), "time_budget");
}

TEST(Solvers, NewParametersAreValidated) {
  SolverParams p;
  EXPECT_EQ(p.sor, 1.0);
  EXPECT_EQ(p.time_budget, 0.0);
  EXPECT_EQ(p.friction_model, FrictionModel::kCoulombDisc);
  for (double bad : {0.0, 2.0, -0.5, 2.5, std::nan("")}) {
    p.sor = bad;
    EXPECT_NE(validateParams(p), "") << bad;
  }
  p.sor = 1.9;
  EXPECT_EQ(validateParams(p), "");
  p.sor = 0.1;
  EXPECT_EQ(validateParams(p), "");
  for (double bad : {-1.0, std::nan(""), std::numeric_limits<double>::infinity()}) {
    p.time_budget = bad;
    EXPECT_NE(validateParams(p), "") << bad;
  }
  p.time_budget = 0.5;
  EXPECT_EQ(validateParams(p), "");
  p.friction_model = static_cast<FrictionModel>(42);
  EXPECT_NE(validateParams(p), "");
  const SolveResult r = solveProblem(randomFrictionalProblem(2, 1), p);
  EXPECT_EQ(r.status, SolveStatus::kInvalidInput);
}

// ---- over-relaxation --------------------------------------------------------------------

// k sweeps of (relaxed) projected Gauss-Seidel written out for a frictionless LCP.
Eigen::VectorXd handPsor(const Eigen::MatrixXd& M, const Eigen::VectorXd& q, double omega, int sweeps) {
  Eigen::VectorXd z = Eigen::VectorXd::Zero(q.size());
  for (int s = 0; s < sweeps; ++s)
    for (int i = 0; i < q.size(); ++i) {
      const double w = M.row(i).dot(z) + q[i];
      const double local = std::max(0.0, z[i] - w / M(i, i));
      z[i] = std::max(0.0, z[i] + omega * (local - z[i]));
    }
  return z;
}

TEST(Sor, PgsSweepsAreTheRelaxedStep) {
  Eigen::MatrixXd M(3, 3);
  M << 4, 1, 0.5, 1, 3, 0.2, 0.5, 0.2, 2;
  const Eigen::VectorXd q = Eigen::Vector3d(-1, -2, 0.5);
  const Problem p = makeLcpProblem(M, q);
  for (double omega : {1.0, 0.7, 1.5}) {
    for (int sweeps : {1, 2, 5}) {
      SolverParams params = tight(SolverKind::kPgs, 1e-300);
      params.maxIt = sweeps;
      params.sor = omega;
      const SolveResult r = solveProblem(p, params);
      EXPECT_EQ(r.iterations, sweeps);
      EXPECT_LE((r.forces - handPsor(M, q, omega, sweeps)).norm(), 1e-14) << omega << " " << sweeps;
    }
  }
}

TEST(Sor, OmegaOneIsPlainGaussSeidel) {
  const Problem p = randomFrictionalProblem(6, 3);
  SolverParams plain = tight(SolverKind::kNlgs, 1e-10);
  SolverParams one = plain;
  one.sor = 1.0;
  const SolveResult a = solveProblem(p, plain);
  const SolveResult b = solveProblem(p, one);
  EXPECT_EQ(a.iterations, b.iterations);
  EXPECT_TRUE(a.forces == b.forces);
}

// Over-relaxation is not guaranteed to converge with friction (ω = 1.7 fails on one of
// these), so the frictional cases use moderate ω; the frictionless LCP (PSOR, symmetric
// positive definite) converges for every ω in (0, 2).
TEST(Sor, RelaxedSolversConvergeToTheSameAnswer) {
  for (unsigned seed : {1u, 2u, 3u}) {
    for (const Problem& p : {randomFrictionalProblem(6, seed), mixedProblem(seed)}) {
      for (SolverKind kind : {SolverKind::kNlgs}) {
        const SolveResult reference = solveProblem(p, tight(kind, 1e-12));
        ASSERT_EQ(reference.status, SolveStatus::kConverged);
        for (double omega : {0.6, 1.3}) {
          SolverParams params = tight(kind, 1e-12);
          params.sor = omega;
          const SolveResult r = solveProblem(p, params);
          ASSERT_EQ(r.status, SolveStatus::kConverged) << "seed " << seed << " omega " << omega;
          EXPECT_LE(r.residual, 1e-12);
          EXPECT_LE((r.forces - reference.forces).norm(), 1e-8 * reference.forces.norm()) << omega;
          // Admissible: every normal force >= 0, every friction force inside its cone.
          for (std::size_t c = 0; c < p.contacts.size(); ++c) {
            const int off = p.rowOffsets()[c];
            if (p.contacts[c].type == ContactType::kBilateral) continue;
            EXPECT_GE(r.forces[off], 0.0);
          }
        }
      }
    }
  }
  // Frictionless: PSOR on the LCP.
  Eigen::MatrixXd J = Eigen::MatrixXd::Random(8, 10);
  const Problem lcp = makeLcpProblem(J * J.transpose() + 0.1 * Eigen::MatrixXd::Identity(8, 8),
                                     -Eigen::VectorXd::LinSpaced(8, -0.5, 1.0));
  const SolveResult reference = solveProblem(lcp, tight(SolverKind::kPgs));
  for (double omega : {0.5, 1.2, 1.8}) {
    SolverParams params = tight(SolverKind::kPgs);
    params.sor = omega;
    const SolveResult r = solveProblem(lcp, params);
    ASSERT_EQ(r.status, SolveStatus::kConverged);
    EXPECT_LE((r.forces - reference.forces).norm(), 1e-9 * (1.0 + reference.forces.norm()));
  }
}

// ---- time budget --------------------------------------------------------------------------

// Rank-deficient and large enough that no solver finishes at an unreachable tolerance.
Problem largeProblem() {
  std::mt19937 rng(99);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int contacts = 150, n = 3 * contacts;
  Eigen::MatrixXd J(n, 120);
  for (int i = 0; i < J.rows(); ++i)
    for (int j = 0; j < J.cols(); ++j) J(i, j) = u(rng);
  Problem p;
  for (int c = 0; c < contacts; ++c) p.contacts.push_back(Contact{c, ContactType::kFrictional, 3, 0.6});
  p.W = Eigen::MatrixXd(J * J.transpose() / 120.0);
  p.d_free.resize(n);
  for (int c = 0; c < contacts; ++c) p.d_free.segment<3>(3 * c) << -1.0 - std::abs(u(rng)), u(rng), u(rng);
  return p;
}

TEST(TimeBudget, EveryIterativeSolverStopsWithItsBestIterate) {
  const Problem p = largeProblem();
  struct Run {
    SolverKind kind;
    FrictionModel model;
  };
  for (const Run& run :
       {Run{SolverKind::kNlgs, FrictionModel::kCoulombDisc},
        Run{SolverKind::kApgd, FrictionModel::kCoulombDisc},
        Run{SolverKind::kNewton, FrictionModel::kCoulombDisc},
        Run{SolverKind::kPgs, FrictionModel::kPyramid4}, Run{SolverKind::kLemke, FrictionModel::kPyramid8}}) {
    SolverParams params = tight(run.kind, 1e-300);
    params.maxIt = 100000000;
    params.time_budget = 1e-3;
    params.friction_model = run.model;
    const auto start = std::chrono::steady_clock::now();
    const SolveResult r = solveProblem(p, params);
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    SCOPED_TRACE(solverName(run.kind));
    EXPECT_EQ(r.status, SolveStatus::kTimeBudget) << r.message;
    EXPECT_STREQ(statusName(r.status), "time_budget");
    EXPECT_FALSE(r.converged);
    EXPECT_LT(r.iterations, params.maxIt);
    EXPECT_FALSE(r.message.empty());
    expectFinite(r);
    EXPECT_LT(elapsed, 20.0);  // loose: only that it did not run to maxIt
  }
  // Frictionless Lemke on the normal rows alone.
  Problem lcp = p;
  for (Contact& c : lcp.contacts) c.mu = 0.0;
  SolverParams params = tight(SolverKind::kLemke, 1e-12);
  params.time_budget = 1e-6;
  const SolveResult r = solveProblem(lcp, params);
  EXPECT_EQ(r.status, SolveStatus::kTimeBudget) << r.message;
  expectFinite(r);
}

TEST(TimeBudget, ZeroMeansNoBudget) {
  const Problem p = randomFrictionalProblem(4, 81);
  SolverParams params = tight(SolverKind::kNlgs, 1e-10);
  params.time_budget = 0.0;
  EXPECT_EQ(solveProblem(p, params).status, SolveStatus::kConverged);
  params.time_budget = 60.0;  // ample
  EXPECT_EQ(solveProblem(p, params).status, SolveStatus::kConverged);
}

// ---- newton's linear solves -------------------------------------------------------------

// A monotone, non-symmetric LCP (M = skew-symmetric + a PSD diagonal that is zero on every
// other row) with a known solution: nlgs cannot start on a zero diagonal and the symmetric
// active-set path does not apply, so every iteration is a Newton step of the general path,
// whose (J + εI) Δ = -Φ is solved by plain loops up to 32 rows and by Eigen's LU above. A
// wrong solve (a permutation applied out of order, say) leaves the line search without a
// descent direction and the solve crawls on damped steps to maxIt.
Problem monotoneSkewLcp(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j) {
      M(i, j) = u(rng);
      M(j, i) = -M(i, j);
    }
  for (int i = 0; i < n; i += 2) M(i, i) = 1.0 + std::abs(u(rng));
  Eigen::VectorXd lambda(n), w(n);
  for (int i = 0; i < n; ++i) {
    const bool active = i % 3 != 0;
    lambda(i) = active ? 0.5 + std::abs(u(rng)) : 0.0;
    w(i) = active ? 0.0 : 0.5 + std::abs(u(rng));
  }
  return makeLcpProblem(M, w - M * lambda);
}

TEST(Newton, StepsSolveTheLinearisationOnSmallAndLargeSystems) {
  for (int n : {5, 8, 24, 32, 33, 48}) {
    SCOPED_TRACE(n);
    const Problem p = monotoneSkewLcp(n, 300u + static_cast<unsigned>(n));
    SolverParams params = tight(SolverKind::kNewton, 1e-12);
    params.maxIt = 60;
    const SolveResult r = solveProblem(p, params);
    EXPECT_EQ(r.status, SolveStatus::kConverged) << r.message;
    EXPECT_LE(r.residual, 1e-12);
    expectFinite(r);
  }
}

// newton's active-set paths factor W_AA by choleskyInPlace: the column form up to
// kColumnCholeskyRows rows, Eigen's blocked LLᵀ above. On either side of that size L Lᵀ gives
// back the matrix (the upper half untouched), and a matrix that is not positive definite (one
// eigenvalue pushed below zero; a zero row) is refused by both forms, as Eigen's LLT refuses it.
TEST(Cholesky, BothFormsFactorWhatEigensLltFactorsAndRefuseWhatItRefuses) {
  std::mt19937 rng(5);
  std::normal_distribution<double> g;
  for (int n : {1, 2, 7, 52, kColumnCholeskyRows, kColumnCholeskyRows + 1, 150}) {
    SCOPED_TRACE(n);
    Eigen::MatrixXd J(n, n);
    for (int i = 0; i < J.size(); ++i) J.data()[i] = g(rng);
    const Eigen::MatrixXd W = J * J.transpose() / n + 1e-3 * Eigen::MatrixXd::Identity(n, n);
    for (bool column_form : {false, true}) {
      Eigen::MatrixXd A = W;
      A.triangularView<Eigen::StrictlyUpper>().setConstant(7.0);  // not read, not written
      ASSERT_TRUE(column_form ? columnCholeskyInPlace(A) : choleskyInPlace(A));
      const Eigen::MatrixXd L = A.triangularView<Eigen::Lower>();
      EXPECT_LE((L * L.transpose() - W).norm(), 1e-12 * W.norm());
      EXPECT_TRUE((A.triangularView<Eigen::StrictlyUpper>().toDenseMatrix().array() ==
                   Eigen::MatrixXd(Eigen::MatrixXd::Constant(n, n, 7.0).triangularView<Eigen::StrictlyUpper>()).array())
                      .all());
    }
    if (n < 2) continue;
    // Indefinite: W minus twice its smallest eigenvalue's share along that eigenvector.
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(W);
    const Eigen::VectorXd v = eig.eigenvectors().col(0);
    const Eigen::MatrixXd indefinite = W - (eig.eigenvalues()[0] + 1e-2) * 2.0 * v * v.transpose();
    Eigen::MatrixXd singular = W;
    singular.row(n / 2).setZero();
    singular.col(n / 2).setZero();
    for (const Eigen::MatrixXd* bad : std::initializer_list<const Eigen::MatrixXd*>{&indefinite, &singular}) {
      ASSERT_NE(Eigen::LLT<Eigen::MatrixXd>(*bad).info(), Eigen::Success);
      Eigen::MatrixXd A = *bad, B = *bad;
      EXPECT_FALSE(choleskyInPlace(A));
      EXPECT_FALSE(columnCholeskyInPlace(B));
    }
  }
}

// A block-tridiagonal W (each contact coupled to its two neighbours: at most 3 of a block
// row's blocks stored, below the quarter that would make newton gather it dense) with every
// normal pressed and large tangential free velocities, so that contacts slide and newton takes
// its Newton steps on the sparse LU. The pattern depends on `contacts` only, the values on
// `seed`.
Problem slidingChainProblem(int contacts, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int n = 3 * contacts;
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(n, n);
  for (int c = 0; c < contacts; ++c)
    for (int r = 0; r < 3; ++r)
      for (int k = 0; k < 3; ++k) {
        J(3 * c + r, 3 * c + k) = u(rng);
        if (c + 1 < contacts) J(3 * c + r, 3 * (c + 1) + k) = u(rng);
      }
  Problem dense;
  for (int c = 0; c < contacts; ++c) dense.contacts.push_back(Contact{200 + c, ContactType::kFrictional, 3, 0.3});
  dense.W = Eigen::MatrixXd(J * J.transpose() + 1e-3 * Eigen::MatrixXd::Identity(n, n));
  dense.d_free.resize(n);
  for (int c = 0; c < contacts; ++c) {
    dense.d_free[3 * c] = -0.5 - 0.5 * std::abs(u(rng));
    dense.d_free[3 * c + 1] = 2.0 * u(rng);
    dense.d_free[3 * c + 2] = 2.0 * u(rng);
  }
  // Only the blocks J Jᵀ can fill: the diagonal and the two next to it.
  Problem sparse = dense;
  const std::vector<int> sizes(contacts, 3);
  BlockSparseMatrix B = BlockSparseMatrix::withBlockSizes(sizes);
  for (int i = 0; i < contacts; ++i) {
    B.beginRow();
    for (int j = std::max(0, i - 1); j <= std::min(contacts - 1, i + 1); ++j)
      B.addBlock(j, std::get<Eigen::MatrixXd>(dense.W).block(3 * i, 3 * j, 3, 3));
  }
  sparse.W = B;
  return sparse;
}

// newton and prox keep the sparse LU's pattern and ordering for the next solve on the same
// block pattern (newton.cpp, SparseSystem::matches). A solve after one on other values of
// that pattern must factor its own values: its answer is the one a fresh thread (no kept
// system) returns, and meets the tolerance recomputed from W and d_free.
TEST(Newton, SparsePatternKeptFromTheLastSolveFactorsTheNewValues) {
  const Problem first = slidingChainProblem(20, 11u);
  const Problem second = slidingChainProblem(20, 12u);
  ASSERT_EQ(std::get<BlockSparseMatrix>(first.W).block_col, std::get<BlockSparseMatrix>(second.W).block_col);
  for (SolverKind kind : {SolverKind::kNewton, SolverKind::kProx}) {
    SCOPED_TRACE(solverName(kind));
    const SolverParams params = tight(kind, 1e-10);
    SolveResult alone;
    std::thread([&] { alone = solveProblem(second, params); }).join();
    const SolveResult before = solveProblem(first, params);
    const SolveResult after = solveProblem(second, params);
    ASSERT_EQ(alone.status, SolveStatus::kConverged) << alone.message;
    EXPECT_EQ(before.status, SolveStatus::kConverged) << before.message;
    EXPECT_EQ(after.status, SolveStatus::kConverged) << after.message;
    EXPECT_EQ(after.iterations, alone.iterations);
    EXPECT_TRUE(after.forces.isApprox(alone.forces, 1e-12));
    EXPECT_LE(recomputedResidual(second, after.forces), 1e-10);
    EXPECT_GT((after.forces - before.forces).norm(), 1e-3);  // the two problems' answers differ
  }
}

}  // namespace
}  // namespace lcp_contact_solver::core
