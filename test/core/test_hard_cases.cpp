// Hard cases (issue "hard cases stay numerically stable"): rank-deficient and duplicated
// contacts, extreme mass ratios and scales, extreme μ, zero and near-zero diagonals,
// non-PSD and non-symmetric W, regularization, Murty's LCP, the degenerate shared LCPs,
// and maxF. Every case runs every solver that applies and asserts, per result
// (hard_case_util.h: expectHonest, solveTwiceChecked):
//   - every output finite;
//   - the status is honest: converged only with residual <= tolerance; otherwise a named
//     failure with a message, and the best iterate with its true residual;
//   - forces bounded by a physical bound stated in the test;
//   - the residual reached where the method applies (stated per case);
//   - the same input gives bit-identical output.
#include "hard_case_util.h"

#include "lcp_contact_solver/core/problem_io.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <map>

namespace lcp_contact_solver::core {
namespace {

using namespace hard;

// A box (0.2 m cube, 1 kg unless given) resting on the static ground with k contacts.
World boxOnPlane(int k, double mu, double mass = 1.0, double side = 0.2) {
  World world;
  const Eigen::Vector3d size(side, side, side);
  const Eigen::Vector3d com(0.0, 0.0, 0.5 * side);
  world.add(box(mass, size, com));
  for (const Eigen::Vector3d& p : bottomPoints(com, size, k))
    world.contact(0, -1, p, Eigen::Vector3d::UnitZ(), mu);
  return world;
}

// Solvers that apply to a problem: pgs and lemke need μ = 0 (disc model) everywhere.
bool applies(SolverKind kind, const Problem& p, double default_mu = 0.6) {
  if (kind != SolverKind::kPgs && kind != SolverKind::kLemke) return true;
  for (const Contact& c : p.contacts)
    if (c.type == ContactType::kFrictional && (c.mu < 0.0 ? default_mu : c.mu) > 0.0) return false;
  return true;
}

// ---- redundant contacts ---------------------------------------------------------------------

// A box on a plane with 4, 8 and 16 contacts: W (12..48 rows) has rank 3 in the normal rows
// (the box's z, roll and pitch), so the forces are not unique but their sum is: Σλ_n = m g.
// Friction-capable solvers (nlgs, apgd, newton) reach 1e-8; pgs and lemke are
// not_applicable with μ > 0 and are run on the μ = 0 variant, where they reach it too.
TEST(HardCases, BoxOnPlaneRedundantContacts) {
  for (int k : {4, 8, 16}) {
    for (double mu : {0.0, 0.5}) {
      for (bool sparse : {false, true}) {
        const World world = boxOnPlane(k, mu);
        Problem p = world.problem();
        if (sparse) p = toBlockSparse(p);
        const double weight = kG * world.bodies[0].mass;
        for (SolverKind kind : allSolvers()) {
          const std::string label = "box k=" + std::to_string(k) + " mu=" + std::to_string(mu).substr(0, 3) +
                                    (sparse ? " sparse" : " dense");
          const SolverParams params = paramsFor(kind, 1e-8, 5000);
          const SolveResult r = solveTwiceChecked(p, params, label);
          if (!applies(kind, p)) {
            EXPECT_EQ(r.status, SolveStatus::kNotApplicable) << label;
            EXPECT_EQ(r.forces.cwiseAbs().maxCoeff(), 0.0) << label;
            continue;
          }
          ASSERT_EQ(r.status, SolveStatus::kConverged) << label << " " << r.solver << ": " << r.message;
          // Bound: the forces carry the weight, no more (Σλ_n = m g to the tolerance), and
          // at rest there is no friction to speak of.
          const Eigen::Vector3d f = world.netForce(0, r.forces);
          EXPECT_NEAR(f.z(), weight, 1e-5 * weight) << label << " " << r.solver;
          EXPECT_LE(f.head<2>().norm(), 1e-5 * weight) << label << " " << r.solver;
          EXPECT_LE(energyGain(p, 0.0, r.forces), 1e-9 * weight * world.dt * world.dt * kG) << label;
        }
      }
    }
  }
}

// Every contact of a box duplicated (same point, normal and body, another id): W has two
// identical rows per duplicate. The solution is the undoubled one's, split any way.
TEST(HardCases, DuplicatedContacts) {
  for (double mu : {0.0, 0.5}) {
    World world = boxOnPlane(4, mu);
    const std::vector<ContactSpec> original = world.contacts;
    for (const ContactSpec& c : original) world.contact(c.a, c.b, c.point, c.normal, c.mu);
    const Problem p = world.problem();
    const double weight = kG;
    for (SolverKind kind : allSolvers()) {
      const std::string label = "duplicated mu=" + std::to_string(mu).substr(0, 3);
      const SolveResult r = solveTwiceChecked(p, paramsFor(kind, 1e-8, 5000), label);
      if (!applies(kind, p)) {
        EXPECT_EQ(r.status, SolveStatus::kNotApplicable);
        continue;
      }
      ASSERT_EQ(r.status, SolveStatus::kConverged) << label << " " << r.solver << ": " << r.message;
      EXPECT_NEAR(world.netForce(0, r.forces).z(), weight, 1e-5 * weight) << label << " " << r.solver;
    }
  }
}

// One contact repeated with the opposite normal: the body is pinched between two planes
// through the same point. W = [[w, -w], [-w, w]] on the normal rows, singular.
//   consistent: d_free = (-a, +b) with b >= a, solvable (λ1 − λ2 = a / w, any split);
//   contradictory: d_free = (-a, -a), both planes penetrated, the LCP is infeasible.
// Asserted: consistent → pgs, lemke, nlgs, apgd, newton converge; contradictory → no
// solver claims convergence: lemke ends on a ray (ray_termination), the iterative ones stop
// at maxIt (max_iterations) or report numerical_failure, every force finite.
TEST(HardCases, ContactRepeatedWithOppositeNormals) {
  for (bool contradictory : {false, true}) {
    for (double mu : {0.0, 0.5}) {
      World world;
      world.add(box(1.0, Eigen::Vector3d(0.2, 0.2, 0.2), Eigen::Vector3d(0, 0, 0.1)));
      world.gravity.setZero();
      world.bodies[0].v = Eigen::Vector3d(0.0, 0.0, -0.1);  // moving down into the lower plane
      const Eigen::Vector3d p0(0.0, 0.0, 0.0);
      world.contact(0, -1, p0, Eigen::Vector3d::UnitZ(), mu, 0.0);
      world.contact(0, -1, p0, -Eigen::Vector3d::UnitZ(), mu, contradictory ? -0.01 : 0.01);
      const Problem p = world.problem();
      for (SolverKind kind : allSolvers()) {
        const std::string label = std::string(contradictory ? "opposite infeasible" : "opposite feasible") +
                                  " mu=" + std::to_string(mu).substr(0, 3);
        const SolveResult r = solveTwiceChecked(p, paramsFor(kind, 1e-8, 2000), label);
        if (!applies(kind, p)) {
          EXPECT_EQ(r.status, SolveStatus::kNotApplicable);
          continue;
        }
        if (!contradictory) {
          EXPECT_EQ(r.status, SolveStatus::kConverged) << label << " " << r.solver << ": " << r.message;
          // Stops the body at the lower plane: λ1 − λ2 = m |v| / dt = 10 N.
          EXPECT_NEAR(world.netForce(0, r.forces).z(), 10.0, 1e-6) << label << " " << r.solver;
        } else {
          EXPECT_FALSE(r.converged) << label << " " << r.solver;
          if (kind == SolverKind::kLemke) {
            EXPECT_EQ(r.status, SolveStatus::kRayTermination) << label;
          }
        }
      }
    }
  }
}

// ---- mass ratios and scales -----------------------------------------------------------------

// Two boxes stacked on the ground, 4 contacts per interface (24 rows, rank-deficient),
// masses m_bottom and m_top with a ratio of 1e3 or 1e6 either way. Exact: Σλ_n(ground) =
// (m_b + m_t) g, Σλ_n(interface) = m_t g.
World twoBoxStack(double m_bottom, double m_top, double mu) {
  World world;
  const Eigen::Vector3d size(0.2, 0.2, 0.2);
  const Eigen::Vector3d c0(0, 0, 0.1), c1(0, 0, 0.3);
  const int b0 = world.add(box(m_bottom, size, c0));
  const int b1 = world.add(box(m_top, size, c1));
  for (const Eigen::Vector3d& p : bottomPoints(c0, size, 4))
    world.contact(b0, -1, p, Eigen::Vector3d::UnitZ(), mu);
  for (const Eigen::Vector3d& p : bottomPoints(c1, size, 4))
    world.contact(b1, b0, p, Eigen::Vector3d::UnitZ(), mu);
  return world;
}

// Asserted, tolerance 1e-8, maxIt 20000:
//   - newton converges in every case, with both sums within 1e-6 of the weights;
//   - heavy bottom (light on heavy): pgs, nlgs, lemke converge; apgd at 1:1e3 (at 1:1e6
//     its residual stalls near 2e-7: max_iterations);
//   - heavy top at 1:1e3: pgs, lemke, apgd converge (nlgs with μ > 0 may stop at maxIt);
//   - heavy top at 1:1e6: Gauss-Seidel (pgs, nlgs) and apgd stop at maxIt, lemke reports
//     numerical_failure (its basis misses the tolerance by round-off): honest failures;
//   - every result that gives forces (converged or max_iterations) keeps each interface's
//     normal sum within [0, 1.01 × the weight it carries];
//   - a converged result has both sums within 1e-6 of the weights.
TEST(HardCases, MassRatios) {
  for (double ratio : {1e3, 1e6}) {
    for (bool heavy_on_top : {true, false}) {
      for (double mu : {0.0, 0.5}) {
        const double m_top = heavy_on_top ? ratio : 1.0, m_bottom = heavy_on_top ? 1.0 : ratio;
        const World world = twoBoxStack(m_bottom, m_top, mu);
        const Problem p = world.problem();
        const double w_ground = (m_top + m_bottom) * kG, w_top = m_top * kG;
        for (SolverKind kind : allSolvers()) {
          char label[96];
          std::snprintf(label, sizeof(label), "%s 1:%.0e mu=%.1f",
                        heavy_on_top ? "heavy/light" : "light/heavy", ratio, mu);
          const SolveResult r = solveTwiceChecked(p, paramsFor(kind, 1e-8, 20000), label);
          if (!applies(kind, p)) {
            EXPECT_EQ(r.status, SolveStatus::kNotApplicable) << label;
            continue;
          }
          const double ground = world.normalSum(0, -1, r.forces), top = world.normalSum(1, 0, r.forces);
          if (r.status == SolveStatus::kConverged || r.status == SolveStatus::kMaxIterations) {
            EXPECT_GE(ground, 0.0) << label << " " << r.solver;
            EXPECT_LE(ground, 1.01 * w_ground) << label << " " << r.solver;
            EXPECT_GE(top, 0.0) << label << " " << r.solver;
            EXPECT_LE(top, 1.01 * w_top) << label << " " << r.solver;
          }
          if (r.converged) {
            EXPECT_NEAR(ground, w_ground, 1e-6 * w_ground) << label << " " << r.solver;
            EXPECT_NEAR(top, w_top, 1e-6 * w_top) << label << " " << r.solver;
          }
          const bool must_converge =
              kind == SolverKind::kNewton || (!heavy_on_top && kind != SolverKind::kApgd) ||
              (ratio == 1e3 &&
               (kind == SolverKind::kPgs || kind == SolverKind::kLemke || kind == SolverKind::kApgd));
          if (must_converge) {
            EXPECT_TRUE(r.converged) << label << " " << r.solver << ": " << r.message;
          }
          if (heavy_on_top && ratio == 1e6) {
            if (kind == SolverKind::kLemke) {
              EXPECT_EQ(r.status, SolveStatus::kNumericalFailure) << label << ": " << r.message;
            } else if (kind != SolverKind::kNewton) {
              EXPECT_EQ(r.status, SolveStatus::kMaxIterations) << label << " " << r.solver;
            }
          }
        }
      }
    }
  }
}

// One box sliding (0.1 side lengths per second) on 4 contacts at lengths 1e-6..1e3 m and
// masses 1e-6..1e6 kg: W spans dt²/m = 1e-10..1e2 m/N and forces m g = 1e-5..1e7 N. The
// solvers' measures are relative, so every applicable solver must converge (1e-8), with
// Σλ_n = m g (1e-6 frictionless; 1e-4 with friction, whose tipping moment makes the
// rank-deficient problem's normal sum depend slightly on the solution picked) and the
// friction force opposite the slide: μ m g while it slides, m v / dt when that stops it
// within the step (small boxes).
TEST(HardCases, TinyAndHugeScales) {
  for (double side : {1e-6, 1e-3, 1.0, 1e3}) {
    for (double mass : {1e-6, 1.0, 1e6}) {
      for (double mu : {0.0, 0.5}) {
        World world = boxOnPlane(4, mu, mass, side);
        world.bodies[0].v = Eigen::Vector3d(0.1 * side, 0.0, 0.0);
        const Problem p = world.problem();
        const double weight = mass * kG;
        for (SolverKind kind : allSolvers()) {
          char label[96];
          std::snprintf(label, sizeof(label), "L=%.0e m=%.0e mu=%.1f", side, mass, mu);
          const SolveResult r = solveTwiceChecked(p, paramsFor(kind, 1e-8, 5000), label, false);
          if (!applies(kind, p)) {
            EXPECT_EQ(r.status, SolveStatus::kNotApplicable) << label;
            continue;
          }
          ASSERT_TRUE(r.converged) << label << " " << r.solver << ": " << r.message;
          const Eigen::Vector3d f = world.netForce(0, r.forces);
          EXPECT_NEAR(f.z(), weight, (mu == 0.0 ? 1e-6 : 1e-4) * weight) << label << " " << r.solver;
          // Friction: μ Σλ_n while sliding, or what stops the slide within the step.
          const double stopping = mass * world.bodies[0].v.x() / world.dt;
          EXPECT_NEAR(f.x(), -std::min(mu * f.z(), stopping), 1e-4 * weight) << label << " " << r.solver;
          EXPECT_NEAR(f.y(), 0.0, 1e-5 * weight) << label << " " << r.solver;
          EXPECT_LE(energyGain(p, 0.0, r.forces), 1e-6 * weight * world.dt * world.dt * kG)
              << label << " " << r.solver;
        }
      }
    }
  }
}

// ---- friction coefficients ------------------------------------------------------------------

// A box sliding at 1 m/s on 4 contacts with μ = 0, 1e-9, 1, 2, 10, and with mixed μ
// (0, 1e-9, 1, 10) in one problem. At μ >= 2 the friction tips the box onto its front
// edge. Bounds: each force in its cone (expectHonest); the friction cannot reverse the
// slide within the step, |ΣF_x| <= m v / dt, and opposes it; the contacts never add
// kinetic energy (energyGain <= 0). Asserted: nlgs and newton converge (1e-8) for every μ;
// apgd converges up to μ = 2 and may stop at maxIt for μ = 10 (its gradient steps crawl
// along the steep cone); pgs and lemke run the μ = 0 case and are not_applicable otherwise.
TEST(HardCases, FrictionCoefficients) {
  const std::vector<std::vector<double>> mus = {{0.0}, {1e-9}, {1.0}, {2.0}, {10.0}, {0.0, 1e-9, 1.0, 10.0}};
  for (const std::vector<double>& mu : mus) {
    World world = boxOnPlane(4, 0.5);
    for (std::size_t i = 0; i < world.contacts.size(); ++i) {
      world.contacts[i].mu = mu[i % mu.size()];
      world.contacts[i].type = ContactType::kFrictional;  // μ = 0 as a frictional contact
    }
    const double v = 1.0, m = world.bodies[0].mass;
    world.bodies[0].v = Eigen::Vector3d(v, 0.0, 0.0);
    const Problem p = world.problem();
    const double max_mu = *std::max_element(mu.begin(), mu.end());
    for (SolverKind kind : allSolvers()) {
      std::string label = "mu=";
      for (double x : mu) label += (label.size() > 3 ? "," : "") + std::to_string(x).substr(0, 5);
      const SolveResult r = solveTwiceChecked(p, paramsFor(kind, 1e-8, 5000), label);
      if (!applies(kind, p)) {
        EXPECT_EQ(r.status, SolveStatus::kNotApplicable) << label;
        continue;
      }
      if (kind != SolverKind::kApgd || max_mu <= 2.0) {
        ASSERT_TRUE(r.converged) << label << " " << r.solver << ": " << r.message;
      }
      const Eigen::Vector3d f = world.netForce(0, r.forces);
      EXPECT_LE(f.x(), 1e-12) << label << " " << r.solver;
      EXPECT_LE(-f.x(), m * v / world.dt) << label << " " << r.solver;
      if (max_mu == 0.0) {
        EXPECT_EQ(f.x(), 0.0) << label << " " << r.solver;
      }
      if (max_mu == 1e-9) {
        EXPECT_NEAR(f.x(), -1e-9 * f.z(), 1e-6 * 1e-9 * f.z()) << label << " " << r.solver;
      }
      if (r.converged) {
        EXPECT_LE(energyGain(p, 0.0, r.forces), 1e-9 * m * kG * world.dt * world.dt)
            << label << " " << r.solver;
      }
    }
  }
}

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

// ---- Murty's exponential LCP and the shared degenerate LCPs ---------------------------------

Eigen::MatrixXd murtyMatrix(int n) {
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(n, n);
  for (int i = 0; i < n; ++i) {
    M(i, i) = 1.0;
    for (int j = i + 1; j < n; ++j) M(i, j) = 2.0;
  }
  return M;
}

Eigen::VectorXd murtyVector(int n) {
  Eigen::VectorXd q(n);
  for (int i = 0; i < n; ++i) q[i] = -(std::ldexp(1.0, n + 1) - std::ldexp(1.0, i + 1));
  return q;
}

// Murty's LCP (Lemke visits 2^n bases) at n = 16..24 through ContactSolver: lemke stops at
// its pivot cap (maxIt = 1000) and says so (max_iterations, "pivot cap"), with finite,
// nonnegative forces and their true residual. Gauss-Seidel solves the triangular M in n
// sweeps and newton in a few steps; apgd assumes a symmetric W and may stop at maxIt.
// Unique solution (P-matrix): z = (0, ..., 0, 2^(n+1) - 2^n).
TEST(HardCases, MurtyThroughEverySolver) {
  for (int n = 16; n <= 24; n += 4) {
    const Problem p = makeLcpProblem(murtyMatrix(n), murtyVector(n));
    Eigen::VectorXd solution = Eigen::VectorXd::Zero(n);
    solution[n - 1] = std::ldexp(1.0, n + 1) - std::ldexp(1.0, n);
    for (SolverKind kind : allSolvers()) {
      const std::string label = "murty n=" + std::to_string(n);
      const SolveResult r = solveTwiceChecked(p, paramsFor(kind, 1e-8, 1000), label);
      if (kind == SolverKind::kLemke) {
        EXPECT_EQ(r.status, SolveStatus::kMaxIterations) << label;
        EXPECT_EQ(r.iterations, 1000) << label;
        EXPECT_NE(r.message.find("pivot cap"), std::string::npos) << r.message;
        EXPECT_GE(r.forces.minCoeff(), 0.0) << label;
      } else if (kind != SolverKind::kApgd) {
        ASSERT_TRUE(r.converged) << label << " " << r.solver << ": " << r.message;
      }
      if (r.converged) {
        EXPECT_LE((r.forces - solution).cwiseAbs().maxCoeff(), 1e-6 * solution.norm())
            << label << " " << r.solver;
      }
    }
  }
}

// Every LCP in ../shared/problems/lcp (degenerate, zero diagonals, non-symmetric, Murty)
// through every solver: finite, honest, bit-identical; some solver solves each one, except
// the infeasible Pang_isolated_sol_perturbed, which nobody may report solved. (Lemke's own
// outcome per file is asserted in test_lemke_shared.cpp.)
TEST(HardCases, SharedLcpsThroughEverySolver) {
  namespace fs = std::filesystem;
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(std::string(LCS_PROBLEMS_DIR) + "/lcp"))
    if (entry.path().extension() == ".dat") files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  ASSERT_EQ(files.size(), 20u);
  for (const fs::path& file : files) {
    const Problem p = readSiconosDat(file.string());
    int converged = 0;
    for (SolverKind kind : allSolvers()) {
      const SolveResult r = solveTwiceChecked(p, paramsFor(kind, 1e-8, 2000), file.filename().string());
      converged += r.converged ? 1 : 0;
    }
    // Pang_isolated_sol_perturbed is infeasible (w1 = -z2 - z3 - 1e-4 < 0 for all z >= 0).
    if (file.filename() == "lcp_Pang_isolated_sol_perturbed.dat") {
      EXPECT_EQ(converged, 0) << file.filename() << ": an infeasible LCP was reported solved";
    } else {
      EXPECT_GE(converged, 1) << file.filename() << ": no solver found a solution";
    }
  }
}

// The frictional reference problems of ../shared/problems/fc3d up to 400 rows (Rover*,
// FC3D_Example1, Confeti, NESpheres, OneObject, BoxesStack1: the last two rank-deficient)
// through every solver at 1e-6, 2000 iterations: finite, honest, bit-identical; pgs and
// lemke are not_applicable (friction); newton solves every one of them.
TEST(HardCases, SharedFc3dThroughEverySolver) {
  namespace fs = std::filesystem;
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(std::string(LCS_PROBLEMS_DIR) + "/fc3d"))
    if (entry.path().extension() == ".dat") files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  int tried = 0;
  for (const fs::path& file : files) {
    const Problem p = readSiconosDat(file.string());
    if (p.rowCount() > 400) continue;
    ++tried;
    for (SolverKind kind : allSolvers()) {
      const SolveResult r =
          solveTwiceChecked(p, paramsFor(kind, 1e-6, 2000), file.filename().string(), false);
      if (!applies(kind, p)) {
        EXPECT_EQ(r.status, SolveStatus::kNotApplicable) << file.filename();
      }
      if (kind == SolverKind::kNewton) {
        EXPECT_TRUE(r.converged) << file.filename() << ": " << r.message;
      }
    }
  }
  EXPECT_GE(tried, 15);
}

// ---- maxF -----------------------------------------------------------------------------------

// A box whose centre of mass sits over one corner region carries most of its weight on
// that corner. maxF below that corner's force drops it; the rest is solved again (and
// again, while another contact exceeds maxF). Asserted for every applicable solver: at
// least one drop (resolves >= 1), the dropped contacts are ignored with zero force, every
// remaining force is <= maxF, the result converged, and it equals a fresh solve of the
// problem without the dropped contacts (the re-solve is consistent, unlike SOFA's).
TEST(HardCases, MaxFDropsAndResolves) {
  for (double mu : {0.0, 0.5}) {
    World world;
    const Eigen::Vector3d size(0.2, 0.2, 0.2);
    world.add(box(10.0, size, Eigen::Vector3d(0.06, 0.06, 0.1)));
    for (const Eigen::Vector3d& pt : bottomPoints(Eigen::Vector3d(0, 0, 0.1), size, 4))
      world.contact(0, -1, pt, Eigen::Vector3d::UnitZ(), mu);
    const Problem p = world.problem();
    for (SolverKind kind : allSolvers()) {
      if (!applies(kind, p)) continue;
      SolverParams params = paramsFor(kind, 1e-9, 20000);
      params.regularizationTerm = 1e-6;  // 4 contacts on 3 freedoms: make the forces unique
      const SolveResult full = solveProblem(p, params);
      ASSERT_TRUE(full.converged) << full.solver << ": " << full.message;
      const double max_force = full.forces.cwiseAbs().maxCoeff();
      params.maxF = 0.8 * max_force;
      const std::string label = "maxF mu=" + std::to_string(mu).substr(0, 3);
      const SolveResult r = solveTwiceChecked(p, params, label);
      ASSERT_TRUE(r.converged) << label << " " << r.solver << ": " << r.message;
      EXPECT_GE(r.resolves, 1) << label;
      Problem rest = p;
      rest.contacts.clear();
      std::vector<int> keep_rows;
      const std::vector<int> off = p.rowOffsets();
      for (std::size_t i = 0; i < p.contacts.size(); ++i) {
        const double norm = r.forces.segment(off[i], p.contacts[i].rows).norm();
        if (r.states[i] == ContactState::kIgnored) {
          EXPECT_EQ(norm, 0.0) << label;
          continue;
        }
        EXPECT_LE(norm, params.maxF) << label << " contact " << i;
        rest.contacts.push_back(p.contacts[i]);
        for (int k = 0; k < p.contacts[i].rows; ++k) keep_rows.push_back(off[i] + k);
      }
      ASSERT_LT(rest.contacts.size(), p.contacts.size()) << label;
      const Eigen::MatrixXd W = toDense(p.W);
      Eigen::MatrixXd Wr(keep_rows.size(), keep_rows.size());
      Eigen::VectorXd qr(keep_rows.size()), expected_rows(keep_rows.size());
      for (std::size_t a = 0; a < keep_rows.size(); ++a) {
        qr[a] = p.d_free[keep_rows[a]];
        expected_rows[a] = r.forces[keep_rows[a]];
        for (std::size_t b = 0; b < keep_rows.size(); ++b) Wr(a, b) = W(keep_rows[a], keep_rows[b]);
      }
      rest.W = Wr;
      rest.d_free = qr;
      SolverParams fresh = params;
      fresh.maxF = 0.0;
      const SolveResult again = solveProblem(rest, fresh);
      ASSERT_TRUE(again.converged) << again.message;
      EXPECT_LE((again.forces - expected_rows).cwiseAbs().maxCoeff(), 1e-6 * max_force)
          << label << " " << r.solver;
    }
  }
}

// ---- regressions of faults the hard cases found ---------------------------------------------

// The natural map of a row, λ − max(0, λ − d), cancels to exactly 0 in floating point when
// |d| is below λ's rounding (λ = 2.45e6 N, d = 2e-10 m: the heavy-on-light stack), which
// made a solver report "residual 0" for an error of 2e-7. residual.cpp now computes it as
// min(λ, d) (frictionless) and as the modified velocity itself inside the cone.
TEST(HardCases, ResidualDoesNotCancelOnLargeForces) {
  for (ContactType type : {ContactType::kFrictionless, ContactType::kFrictional}) {
    Problem p;
    const int rows = type == ContactType::kFrictional ? 3 : 1;
    p.contacts.push_back(Contact{1, type, rows, 0.5});
    p.W = Eigen::MatrixXd(Eigen::MatrixXd::Identity(rows, rows));
    p.d_free = Eigen::VectorXd::Zero(rows);
    p.d_free[0] = -1e-3;
    Eigen::VectorXd lambda = Eigen::VectorXd::Zero(rows), d = Eigen::VectorXd::Zero(rows);
    lambda[0] = 2.45e6;
    d[0] = 2e-10;  // the contact still closes at 2e-10 m per step
    const double r = naturalMapResidual(p, {0.5}, lambda, d);
    EXPECT_NEAR(r, 2e-10 / 1e-3, 1e-12) << (type == ContactType::kFrictional ? "frictional" : "frictionless");
  }
}

// Lemke's dense tableau is 3 × 8 n² bytes: a large problem (or a hostile message with
// solver=lemke and max_rows = 30000, 21 GB) must be refused, not end in an allocation
// failure. 5000 frictionless rows (block-sparse diagonal W, so the test itself is cheap),
// and a pyramid4 problem of 1000 frictional contacts (6000 LCP variables).
TEST(HardCases, LemkeRefusesProblemsTooLargeForItsTableau) {
  for (bool pyramid : {false, true}) {
    const int contacts = pyramid ? 1000 : 5000;
    Problem p;
    std::vector<int> sizes;
    for (int i = 0; i < contacts; ++i) {
      p.contacts.push_back(pyramid ? Contact{i, ContactType::kFrictional, 3, 0.5}
                                   : Contact{i, ContactType::kFrictionless, 1, 0.0});
      sizes.push_back(p.contacts.back().rows);
    }
    BlockSparseMatrix W = BlockSparseMatrix::withBlockSizes(sizes);
    for (int i = 0; i < contacts; ++i) {
      W.beginRow();
      W.addBlock(i, Eigen::MatrixXd::Identity(sizes[i], sizes[i]));
    }
    p.W = W;
    p.d_free = -Eigen::VectorXd::Ones(p.rowCount());
    SolverParams params = paramsFor(SolverKind::kLemke, 1e-8, 100000);
    if (pyramid) params.friction_model = FrictionModel::kPyramid4;
    // W is diagonal: by island (the default) every contact is its own small tableau.
    const SolveResult split = solveProblem(p, params);
    EXPECT_EQ(split.status, SolveStatus::kConverged) << split.message;
    params.islands = false;  // one tableau for the whole problem
    const SolveResult r =
        solveTwiceChecked(p, params, pyramid ? "lemke pyramid4 6000 vars" : "lemke 5000 rows");
    EXPECT_EQ(r.status, SolveStatus::kNotApplicable) << r.message;
    EXPECT_NE(r.message.find("limited to 4096"), std::string::npos) << r.message;
    EXPECT_LT(r.solve_time, 1.0);
  }
}

}  // namespace
}  // namespace lcp_contact_solver::core
