// A stream of solves (a simulator's steps, their row count changing by a contact or two) keeps
// the factorizations' n x n storage from one solve to the next (thread_workspace.h,
// kKeptDenseRows). Freed, such an array goes back to the system when it tops the heap, and
// every 4 KB page of it faults again when the next solve writes it: on this VM that cost more
// than the factorization itself. Measured here as the process's minor page faults per solve,
// which no other work in the loop causes; each answer is also checked on its own.
// Whether glibc returns a freed array depends on what the process allocated before: its mmap
// threshold (and with it the trim threshold) grows to the largest block freed. So these tests
// run in a process of their own, in order of growing arrays, each starting as a fresh process
// would for its sizes.
#include "lcp_contact_solver/core/contact_solver.h"

#include <gtest/gtest.h>
#include <sys/resource.h>

#include <random>

namespace lcp_contact_solver::core {
namespace {

long minorFaults() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_minflt;
}

// `contacts` contacts, W = A Aᵀ / rows + 0.1 I (dense, symmetric positive definite), every
// normal pressed in (d_free < 0: most rows active, as in a resting stack).
Problem pressedProblem(int contacts, bool friction, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g;
  const int rows = friction ? 3 * contacts : contacts;
  Eigen::MatrixXd A(rows, rows / 2);
  for (Eigen::Index i = 0; i < A.size(); ++i) A.data()[i] = g(rng);
  Problem p;
  p.W = Eigen::MatrixXd(A * A.transpose() / rows + 0.1 * Eigen::MatrixXd::Identity(rows, rows));
  p.d_free.resize(rows);
  for (int i = 0; i < rows; ++i) p.d_free[i] = (friction && i % 3 != 0) ? 0.1 * g(rng) : -1.0 - std::abs(g(rng));
  for (int i = 0; i < contacts; ++i) {
    Contact c;
    c.id = i;
    c.type = friction ? ContactType::kFrictional : ContactType::kFrictionless;
    c.rows = friction ? 3 : 1;
    c.mu = 0.5;
    p.contacts.push_back(c);
  }
  return p;
}

// ‖min(λ, Wλ + q)‖ of an LCP, computed here from the returned forces.
double lcpResidual(const Problem& p, const Eigen::VectorXd& lambda) {
  const Eigen::VectorXd w = std::get<Eigen::MatrixXd>(p.W) * lambda + p.d_free;
  return lambda.cwiseMin(w).norm();
}

// Solves a and b alternately (after one untimed solve of each) and returns the minor page
// faults per solve; `check` sees every answer.
template <class Check>
double faultsPerSolve(const Problem& a, const Problem& b, const SolverParams& params, Check check) {
  solveProblem(a, params);
  solveProblem(b, params);
  const int solves = 6;
  const long before = minorFaults();
  for (int k = 0; k < solves; ++k) {
    const Problem& p = k % 2 ? b : a;
    const SolveResult r = solveProblem(p, params);
    check(p, r);
  }
  return static_cast<double>(minorFaults() - before) / solves;
}

// One n x n array of doubles, in 4 KB pages.
double pagesOf(int rows) { return rows * static_cast<double>(rows) * 8.0 / 4096.0; }

// In order of growing arrays (above).
TEST(StorageReuse, LemkeStreamDoesNotFaultItsTableauAgain) {
  // 300 and 299 rows: M and B⁻¹, 0.7 MB each.
  const Problem a = pressedProblem(300, false, 5), b = pressedProblem(299, false, 6);
  SolverParams params;
  params.solver = SolverKind::kLemke;
  const double faults = faultsPerSolve(a, b, params, [](const Problem& p, const SolveResult& r) {
    ASSERT_TRUE(r.converged) << r.message;
    EXPECT_LT(lcpResidual(p, r.forces), 1e-9);
    EXPECT_GE(r.forces.minCoeff(), 0.0);
  });
  // Before: ~320 faults per solve.
  EXPECT_LT(faults, 0.05 * pagesOf(300));
}

TEST(StorageReuse, FrictionalStreamDoesNotFaultItsNewtonMatrixAgain) {
  // 600 and 597 rows: the Newton matrix, its LU and W's copy, 2.9 MB each.
  const Problem a = pressedProblem(200, true, 3), b = pressedProblem(199, true, 4);
  for (SolverKind kind : {SolverKind::kNewton, SolverKind::kProx}) {
    SolverParams params;
    params.solver = kind;
    params.tolerance = 1e-8;
    const double faults = faultsPerSolve(a, b, params, [](const Problem&, const SolveResult& r) {
      ASSERT_TRUE(r.converged) << r.message;
      EXPECT_LE(r.residual, 1e-8);
      EXPECT_TRUE(r.forces.allFinite());
    });
    // Before: ~1400 (newton) and ~4100 (prox) faults per solve.
    EXPECT_LT(faults, 0.05 * pagesOf(600)) << solverName(kind);
  }
}

TEST(StorageReuse, SymmetricLcpStreamDoesNotFaultItsFactorizationAgain) {
  // 700 and 699 rows: the active-set path's copies of W and W_AA, up to 4 MB each.
  const Problem a = pressedProblem(700, false, 1), b = pressedProblem(699, false, 2);
  SolverParams params;
  params.solver = SolverKind::kNewton;
  params.tolerance = 1e-9;
  const double faults = faultsPerSolve(a, b, params, [](const Problem& p, const SolveResult& r) {
    ASSERT_TRUE(r.converged) << r.message;
    EXPECT_LT(lcpResidual(p, r.forces), 1e-7);
    EXPECT_GE(r.forces.minCoeff(), 0.0);
  });
  // Before, each solve faulted both arrays in again: ~2000 faults.
  EXPECT_LT(faults, 0.05 * pagesOf(700));
}

}  // namespace
}  // namespace lcp_contact_solver::core
