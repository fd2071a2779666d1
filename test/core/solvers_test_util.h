// Problems and checks shared by the core tests (test_solvers*.cpp, test_portfolio.cpp, test_islands.cpp,
// test_shared_problems_solvers.cpp) and scene/test_portfolio_scene.cpp.
#pragma once

#include "lcp_contact_solver/core/contact_solver.h"
#include "lcp_contact_solver/core/kernels/kernels.h"
#include "lcp_contact_solver/core/residual.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <random>
#include <string>

namespace lcp_contact_solver::core {
namespace solvers_test {

inline SolverParams tight(SolverKind kind, double tolerance = 1e-12) {
  SolverParams params;
  params.solver = kind;
  params.tolerance = tolerance;
  params.maxIt = 100000;
  params.initial_guess = false;
  return params;
}

inline Problem oneFrictionalContact(const Eigen::Matrix3d& W, const Eigen::Vector3d& d_free, double mu) {
  Problem p;
  p.contacts.push_back(Contact{7, ContactType::kFrictional, 3, mu});
  p.W = Eigen::MatrixXd(W);
  p.d_free = d_free;
  return p;
}

// W = J Jᵀ / n + εI: symmetric positive definite, contacts pressed, some sliding.
inline Problem randomFrictionalProblem(int contacts, unsigned seed, double mu = 0.5, double eps = 1e-3) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int n = 3 * contacts;
  Eigen::MatrixXd J(n, n + 6);
  for (int i = 0; i < J.rows(); ++i)
    for (int j = 0; j < J.cols(); ++j) J(i, j) = u(rng);
  Problem p;
  for (int c = 0; c < contacts; ++c) p.contacts.push_back(Contact{100 + c, ContactType::kFrictional, 3, mu});
  p.W = Eigen::MatrixXd(J * J.transpose() / n + eps * Eigen::MatrixXd::Identity(n, n));
  p.d_free.resize(n);
  for (int c = 0; c < contacts; ++c) {
    p.d_free[3 * c] = -0.5 - 0.5 * std::abs(u(rng));
    p.d_free[3 * c + 1] = 0.3 * u(rng);
    p.d_free[3 * c + 2] = 0.3 * u(rng);
  }
  return p;
}

// Every contact type at once: a 2-row bilateral joint, frictionless rows, frictional
// contacts with μ > 0 and μ = 0.
inline Problem mixedProblem(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Problem p;
  p.contacts.push_back(Contact{1, ContactType::kBilateral, 2, Contact::kMuDefault});
  p.contacts.push_back(Contact{2, ContactType::kFrictionless, 1, Contact::kMuDefault});
  p.contacts.push_back(Contact{3, ContactType::kFrictional, 3, 0.4});
  p.contacts.push_back(Contact{4, ContactType::kFrictional, 3, 0.0});
  p.contacts.push_back(Contact{5, ContactType::kFrictionless, 1, Contact::kMuDefault});
  p.contacts.push_back(Contact{6, ContactType::kFrictional, 3, 0.8});
  const int n = p.rowCount();
  Eigen::MatrixXd J(n, n + 3);
  for (int i = 0; i < J.rows(); ++i)
    for (int j = 0; j < J.cols(); ++j) J(i, j) = u(rng);
  p.W = Eigen::MatrixXd(J * J.transpose() / n + 0.05 * Eigen::MatrixXd::Identity(n, n));
  p.d_free.resize(n);
  for (int i = 0; i < n; ++i) p.d_free[i] = 0.5 * u(rng);
  const std::vector<int> off = p.rowOffsets();
  for (int c : {1, 2, 3, 5}) p.d_free[off[c]] = -0.5 - 0.5 * std::abs(u(rng));  // pressed normals
  p.d_free[off[4]] = 0.3;                                                       // this one separates
  return p;
}

inline Problem toBlockSparse(const Problem& dense) {
  Problem sparse = dense;
  const Eigen::MatrixXd W = toDense(dense.W);
  std::vector<int> sizes;
  for (const Contact& c : dense.contacts) sizes.push_back(c.rows);
  const std::vector<int> off = dense.rowOffsets();
  BlockSparseMatrix B = BlockSparseMatrix::withBlockSizes(sizes);
  for (std::size_t i = 0; i < sizes.size(); ++i) {
    B.beginRow();
    for (std::size_t j = 0; j < sizes.size(); ++j)
      B.addBlock(static_cast<int>(j), W.block(off[i], off[j], sizes[i], sizes[j]));
  }
  sparse.W = B;
  return sparse;
}

inline void expectFinite(const SolveResult& r) {
  EXPECT_TRUE(r.forces.allFinite());
  EXPECT_TRUE(r.d.allFinite());
  EXPECT_TRUE(std::isfinite(r.residual));
  EXPECT_TRUE(std::isfinite(r.solver_error));
}

// The natural-map residual of `forces`, from W and d_free alone (not from the solver's d).
inline double recomputedResidual(const Problem& p, const Eigen::VectorXd& forces,
                                 double default_mu = SolverParams().mu) {
  Eigen::VectorXd d;
  multiply(p.W, forces, d);
  d += p.d_free;
  return naturalMapResidual(p, effectiveMu(p, default_mu), forces, d);
}

// The reported path and stages agree: "auto:" + the stage names joined by "->".
inline void expectPath(const SolveResult& r) {
  ASSERT_FALSE(r.stages.empty()) << r.solver;  // "auto" alone only when the start was an answer
  std::string path = "auto:";
  double total = 0.0;
  for (std::size_t i = 0; i < r.stages.size(); ++i) {
    path += (i ? "->" : "") + r.stages[i].first;
    EXPECT_GE(r.stages[i].second, 0.0);
    total += r.stages[i].second;
    if (i > 0) {
      EXPECT_NE(r.stages[i].first, r.stages[i - 1].first) << "consecutive slices are one stage";
    }
  }
  EXPECT_EQ(r.solver, path);
  EXPECT_LE(total, r.solve_time + 1e-6);
}

const SolverKind kDiscSolvers[] = {SolverKind::kApgd, SolverKind::kNewton};

}  // namespace solvers_test
}  // namespace lcp_contact_solver::core
