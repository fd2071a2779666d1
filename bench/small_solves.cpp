// Time per warm-started solve of 1-, 3- and 5-contact problems (dense W = J Jᵀ/10 + 0.01 I,
// J random): pgs on the frictionless rows, nlgs with μ = 0.5; best of 3 rounds of 100000
// solves by one ContactSolver (issue #15, "small problems cheap").
//   small_solves
#include <Eigen/Dense>
#include <chrono>
#include <cstdio>
#include <random>
#include "lcp_contact_solver/core/contact_solver.h"
using namespace lcp_contact_solver;
int main() {
  for (int nc : {1, 3, 5}) {
    std::mt19937 rng(nc);
    std::uniform_real_distribution<double> u(-1, 1);
    core::Problem p;
    for (int i = 0; i < nc; ++i) {
      core::Contact c;
      c.id = i;
      c.type = core::ContactType::kFrictional;
      c.rows = 3;
      c.mu = 0.5;
      p.contacts.push_back(c);
    }
    const int n = 3 * nc;
    Eigen::MatrixXd J(n, 6 * nc);
    for (int r = 0; r < n; ++r)
      for (int k = 0; k < J.cols(); ++k) J(r, k) = u(rng);
    Eigen::MatrixXd W = J * J.transpose() * 0.1;
    W.diagonal().array() += 0.01;
    p.W = W;
    p.d_free.resize(n);
    for (int r = 0; r < n; ++r) p.d_free[r] = r % 3 == 0 ? -0.5 : 0.1 * u(rng);
    for (core::SolverKind kind : {core::SolverKind::kPgs, core::SolverKind::kNlgs}) {
      core::SolverParams sp;
      sp.solver = kind;
      sp.tolerance = 1e-6;
      sp.mu = 0.5;
      if (kind == core::SolverKind::kPgs) {
        for (auto& c : p.contacts) {
          c.type = core::ContactType::kFrictionless;
        }
      }
      core::Problem q = p;
      if (kind == core::SolverKind::kPgs) {  // frictionless: 1 row per contact
        for (auto& c : q.contacts) c.rows = 1;
        Eigen::MatrixXd Wn(nc, nc);
        Eigen::VectorXd dn(nc);
        for (int i = 0; i < nc; ++i) {
          dn[i] = p.d_free[3 * i];
          for (int j = 0; j < nc; ++j) Wn(i, j) = W(3 * i, 3 * j);
        }
        q.W = Wn;
        q.d_free = dn;
      }
      core::ContactSolver solver(sp);
      solver.solve(q);
      const int reps = 100000;
      double best = 1e9;
      for (int round = 0; round < 3; ++round) {
        auto t0 = std::chrono::steady_clock::now();
        for (int k = 0; k < reps; ++k) solver.solve(q);
        best = std::min(best,
                        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / reps);
      }
      std::printf("%d contacts %s: %.2f us per warm solve\n", nc, core::solverName(kind), 1e6 * best);
      for (auto& c : p.contacts) c.type = core::ContactType::kFrictional;
    }
  }
}
