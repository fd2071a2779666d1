// Hard cases in W itself: zero and near-zero diagonals, non-PSD and non-symmetric W, regularization.
#include "hard_case_util.h"

#include "lcp_contact_solver/core/problem_io.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <map>

namespace lcp_contact_solver::core {
namespace {

using namespace hard;

// ---- zero and near-zero diagonals, non-PSD and non-symmetric W ------------------------------

// A box on 4 frictionless contacts plus one more contact whose W row and column are ε times
// contact 0's (its Jacobian row scaled by ε: W_nn = ε² W_00), ε = 0 (a contact between two
// static bodies: a zero row and column), 1e-8 and 1e-160 (W_nn = 1e-320, denormal), with a
// pressing (q = -1e-3) or separating (q = +1e-3) free motion, with minW = 0 or 1e-12.
// Asserted:
//   - minW = 1e-12 ignores the extra contact (state ignored, force 0) and every solver
//     converges on the rest, Σλ_n = m g;
//   - minW = 0, W_nn = 0: pgs and nlgs refuse with zero_diagonal naming the contact and
//     W_nn (SOFA divides by it and returns NaN); lemke solves the separating case and ends
//     on a ray for the pressing one (infeasible); apgd and newton solve the separating case;
//   - minW = 0, pressing, W_nn = 1e-320: the exact force (|q| / W_nn) overflows a double, so
//     no solver claims convergence; every output stays finite;
//   - minW = 0, W_nn = 1e-16 pressing: pgs, nlgs and newton find the (huge, exact) force.
TEST(HardCases, ZeroAndNearZeroDiagonals) {
  for (double eps : {0.0, 1e-8, 1e-160}) {
    for (double q : {-1e-3, 1e-3}) {
      for (double min_w : {0.0, 1e-12}) {
        const World world = boxOnPlane(4, 0.0);
        Problem p = world.problem();
        const int n = p.rowCount();
        Eigen::MatrixXd W = Eigen::MatrixXd::Zero(n + 1, n + 1);
        W.topLeftCorner(n, n) = std::get<Eigen::MatrixXd>(p.W);
        W.block(n, 0, 1, n) = eps * W.block(0, 0, 1, n);
        W.block(0, n, n, 1) = eps * W.block(0, 0, n, 1);
        W(n, n) = eps * eps * W(0, 0);
        p.W = W;
        p.d_free.conservativeResize(n + 1);
        p.d_free[n] = q;
        p.contacts.push_back(Contact{99, ContactType::kFrictionless, 1, 0.0});
        for (SolverKind kind : allSolvers()) {
          char label[96];
          std::snprintf(label, sizeof(label), "Wnn=%.0e*W00 q=%+.0e minW=%.0e", eps * eps, q, min_w);
          SolverParams params = paramsFor(kind, 1e-8, 2000);
          params.minW = min_w;
          const SolveResult r = solveTwiceChecked(p, params, label);
          const std::string where = std::string(label) + " " + r.solver + ": " + r.message;
          if (min_w > 0.0) {
            ASSERT_TRUE(r.converged) << where;
            EXPECT_EQ(r.states.back(), ContactState::kIgnored) << where;
            EXPECT_EQ(r.forces[n], 0.0) << where;
            EXPECT_NEAR(world.netForce(0, r.forces.head(n)).z(), kG, 1e-6 * kG) << where;
            continue;
          }
          const bool gauss_seidel = kind == SolverKind::kPgs || kind == SolverKind::kNlgs;
          if (eps == 0.0) {
            if (gauss_seidel) {
              EXPECT_EQ(r.status, SolveStatus::kZeroDiagonal) << where;
              EXPECT_NE(r.message.find("id 99"), std::string::npos) << where;
              EXPECT_NE(r.message.find("W_nn"), std::string::npos) << where;
            } else if (q > 0.0) {
              EXPECT_TRUE(r.converged) << where;
            } else {
              EXPECT_FALSE(r.converged) << where;
              if (kind == SolverKind::kLemke) {
                EXPECT_EQ(r.status, SolveStatus::kRayTermination) << where;
              }
            }
          } else if (q > 0.0) {
            EXPECT_TRUE(r.converged) << where;  // the extra contact stays open
            EXPECT_EQ(r.forces[n], 0.0) << where;
          } else if (eps == 1e-160) {
            EXPECT_FALSE(r.converged) << where;
          } else if (gauss_seidel || kind == SolverKind::kNewton) {
            EXPECT_TRUE(r.converged) << where;
          }
        }
      }
    }
  }
}

// W that is not positive semidefinite, or not symmetric. The core does not refuse them
// (validateProblem checks sizes and finiteness only): each solver handles them and says
// what happened, converged only with a true solution. Per case (LCP w = M z + q):
//   indefinite symmetric, positive diagonal: a solution exists; every solver converges
//     (not necessarily to the same one: there are three);
//   negative diagonal: pgs and nlgs refuse (zero_diagonal), lemke ends on a ray, apgd and
//     newton report numerical_failure; nobody converges;
//   non-symmetric P-matrix (unique solution z = 1/3): Gauss-Seidel cycles (max_iterations),
//     lemke, apgd and newton find the solution;
//   non-symmetric positive definite: every solver converges to z = (1, 0);
//   negative definite with an infeasible row: nobody converges.
TEST(HardCases, NonPsdAndNonSymmetricW) {
  struct Case {
    const char* name;
    Eigen::MatrixXd M;
    Eigen::VectorXd q;
    std::map<SolverKind, SolveStatus> expected;  // empty: every solver converges
    Eigen::VectorXd solution;                    // unique solution, if any
  };
  std::vector<Case> cases;
  using S = SolveStatus;
  using K = SolverKind;
  {
    Eigen::MatrixXd M(2, 2);
    M << 1, 2, 2, 1;  // eigenvalues 3, -1
    cases.push_back({"indefinite", M, Eigen::Vector2d(-1, -1), {}, Eigen::VectorXd()});
  }
  {
    Eigen::MatrixXd M(2, 2);
    M << 1, 0, 0, -1;
    cases.push_back({"negative diagonal",
                     M,
                     Eigen::Vector2d(-1, -1),
                     {{K::kPgs, S::kZeroDiagonal},
                      {K::kNlgs, S::kZeroDiagonal},
                      {K::kLemke, S::kRayTermination},
                      {K::kApgd, S::kNumericalFailure},
                      {K::kNewton, S::kNumericalFailure}},
                     Eigen::VectorXd()});
  }
  {
    Eigen::MatrixXd M(3, 3);
    M << 1, 2, 0, 0, 1, 2, 2, 0, 1;
    cases.push_back({"non-symmetric P",
                     M,
                     Eigen::Vector3d(-1, -1, -1),
                     {{K::kPgs, S::kMaxIterations},
                      {K::kNlgs, S::kMaxIterations},
                      {K::kLemke, S::kConverged},
                      {K::kApgd, S::kConverged},
                      {K::kNewton, S::kConverged}},
                     Eigen::Vector3d::Constant(1.0 / 3.0)});
  }
  {
    Eigen::MatrixXd M(2, 2);
    M << 1, -3, 3, 1;
    cases.push_back({"non-symmetric PD", M, Eigen::Vector2d(-1, 1), {}, Eigen::Vector2d(1, 0)});
  }
  {
    Eigen::MatrixXd M(2, 2);
    M << -1, 0, 0, -1;
    cases.push_back({"negative definite",
                     M,
                     Eigen::Vector2d(1, -1),
                     {{K::kPgs, S::kZeroDiagonal},
                      {K::kNlgs, S::kZeroDiagonal},
                      {K::kLemke, S::kRayTermination},
                      {K::kApgd, S::kNumericalFailure},
                      {K::kNewton, S::kNumericalFailure}},
                     Eigen::VectorXd()});
  }
  for (const Case& c : cases) {
    const Problem p = makeLcpProblem(c.M, c.q);
    for (SolverKind kind : allSolvers()) {
      const SolveResult r = solveTwiceChecked(p, paramsFor(kind, 1e-8, 2000), c.name);
      const S expected = c.expected.empty() ? S::kConverged : c.expected.at(kind);
      EXPECT_EQ(r.status, expected) << c.name << " " << r.solver << ": " << r.message;
      if (r.converged) {
        const Eigen::VectorXd w = c.M * r.forces + c.q;  // a true LCP solution
        EXPECT_GE(w.minCoeff(), -1e-8) << c.name << " " << r.solver;
        EXPECT_LE(std::abs(w.dot(r.forces)), 1e-8) << c.name << " " << r.solver;
        if (c.solution.size() > 0) {
          EXPECT_LE((r.forces - c.solution).cwiseAbs().maxCoeff(), 1e-7) << c.name << " " << r.solver;
        }
      }
    }
  }
}

// ---- regularizationTerm on rank-deficient W -------------------------------------------------

// Smallest eigenvalue of the symmetric part of W.
double smallestEigenvalue(const Problem& p) {
  const Eigen::MatrixXd W = toDense(p.W);
  return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(0.5 * (W + W.transpose())).eigenvalues().minCoeff();
}

// Unique: the box with every contact duplicated (8 contacts, rank 3 in the normal rows).
// Without regularization the solvers pick different splits of the same total (all exact:
// residual <= 1e-10); with r = 1e-6 m/N (W_nn = 4e-4 m/N) W + rI is positive definite, the
// solution is unique, and every solver gives it to |Δλ| <= 1e-5 N (forces of ~1.2 N):
// |λ − λ*| <= |e| / λ_min(W + rI) for a residual vector e. The cost is the regularized
// law itself: each contact yields by r λ (here 1.2e-6 m per step).
TEST(HardCases, RegularizationMakesForcesUnique) {
  for (double mu : {0.0, 0.5}) {
    World world = boxOnPlane(4, mu);
    const std::vector<ContactSpec> original = world.contacts;
    for (const ContactSpec& c : original) world.contact(c.a, c.b, c.point, c.normal, c.mu);
    const Problem p = world.problem();
    double spread_plain = 0.0, spread_regularized = 0.0;
    for (double r : {0.0, 1e-6}) {
      std::vector<Eigen::VectorXd> answers;
      for (SolverKind kind : allSolvers()) {
        if (!applies(kind, p)) continue;
        SolverParams params = paramsFor(kind, 1e-10, 20000);
        params.regularizationTerm = r;
        const std::string label =
            "dup mu=" + std::to_string(mu).substr(0, 3) + " r=" + (r > 0 ? "1e-6" : "0");
        const SolveResult res = solveTwiceChecked(p, params, label);
        ASSERT_TRUE(res.converged) << label << " " << res.solver << ": " << res.message;
        answers.push_back(res.forces);
      }
      double spread = 0.0;
      for (const Eigen::VectorXd& a : answers)
        spread = std::max(spread, (a - answers.front()).cwiseAbs().maxCoeff());
      (r == 0.0 ? spread_plain : spread_regularized) = spread;
    }
    std::printf("  mu=%.1f: max |Δλ| between solvers: %.3g N without r, %.3g N with r = 1e-6\n", mu,
                spread_plain, spread_regularized);
    EXPECT_GT(spread_plain, 0.1) << "the unregularized forces were expected to be non-unique";
    EXPECT_LT(spread_regularized, 1e-5);
  }
}

// Smooth in time: the box on 4 frictionless contacts (rank-deficient) under a torque that
// turns slowly (one revolution in 200 steps), solved step after step with warm start.
// With r > 0, W + rI is symmetric positive definite and the LCP's solution is Lipschitz in
// d_free: |λ(t+1) − λ(t)| <= |Δd_free| / λ_min(W + rI). Asserted at every step for pgs
// (warm-started, the node's default path) and lemke, with tolerance 1e-12.
TEST(HardCases, RegularizationMakesForcesSmoothInTime) {
  const double r = 1e-6;
  for (SolverKind kind : {SolverKind::kPgs, SolverKind::kLemke, SolverKind::kNewton}) {
    SolverParams params = paramsFor(kind, 1e-12, 100000);
    params.initial_guess = true;
    params.regularizationTerm = r;
    ContactSolver solver(params);
    Eigen::VectorXd previous_lambda, previous_q;
    double worst_ratio = 0.0;
    for (int step = 0; step < 200; ++step) {
      World world = boxOnPlane(4, 0.0);
      const double angle = 2.0 * M_PI * step / 200.0;
      // A torque of up to 0.3 m g × half the side about a horizontal axis turning in time.
      world.bodies[0].w = world.dt * 0.3 * kG * 0.1 * world.bodies[0].inv_inertia *
                          Eigen::Vector3d(std::cos(angle), std::sin(angle), 0.0);
      const Problem p = world.problem();
      const SolveResult res = solver.solve(p);
      expectHonest(p, params, res, "smooth step " + std::to_string(step));
      ASSERT_TRUE(res.converged) << res.solver << " step " << step << ": " << res.message;
      if (step > 0) {
        const double bound = (p.d_free - previous_q).norm() / (smallestEigenvalue(p) + r);
        const double change = (res.forces - previous_lambda).norm();
        EXPECT_LE(change, bound * (1.0 + 1e-6) + 1e-9) << res.solver << " step " << step;
        worst_ratio = std::max(worst_ratio, change / bound);
      }
      previous_lambda = res.forces;
      previous_q = p.d_free;
    }
    std::printf("  %s: max |Δλ| / (|Δd_free| / λ_min(W + rI)) over 200 steps = %.3g\n", solverName(kind),
                worst_ratio);
  }
}

}  // namespace
}  // namespace lcp_contact_solver::core
