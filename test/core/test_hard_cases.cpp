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

// A pyramid of boxes at rest, `base` boxes on the ground and each row on the one below,
// offset by half a box: 16 points per face, 8 on each of the two boxes below (rank-deficient).
World boxPyramid(int base, double mu) {
  World world;
  const Eigen::Vector3d size(1.0, 1.0, 0.5);
  std::vector<int> below;
  for (int row = 0; row < base; ++row) {
    std::vector<int> level;
    for (int i = 0; i < base - row; ++i) {
      const Eigen::Vector3d com(i + 0.5 * row, 0.0, 0.25 + 0.5 * row);
      level.push_back(world.add(box(1.0, size, com)));
      for (const Eigen::Vector3d& p : bottomPoints(com, size, 16)) {
        if (row == 0) {
          world.contact(level.back(), -1, p, Eigen::Vector3d::UnitZ(), mu);
          continue;
        }
        const double seam = world.bodies[below[i]].com.x() + 0.5;  // where the two boxes below meet
        if (std::abs(p.x() - seam) < 1e-9) continue;
        world.contact(level.back(), p.x() < seam ? below[i] : below[i + 1], p, Eigen::Vector3d::UnitZ(), mu);
      }
    }
    below = level;
  }
  return world;
}

// apgd warm-started from a few Gauss-Seidel sweeps' forces (a simulator's last step solved
// by another solver, or auto handing over): from such a start on rank-deficient contacts
// its convex problem's residual sat on a plateau above the ratio that moves the De Saxcé
// shift, for 3 900 and 8 000 iterations where apgd from zero needs 51 (apgd.cpp,
// kPlateauIterations); now 280 and 310. Asserted: converged within 1 000 iterations, the
// residual recomputed from the forces, and the ground carrying the pyramid's weight.
TEST(HardCases, ApgdWarmStartedFromGaussSeidelForcesDoesNotStall) {
  const World world = boxPyramid(4, 0.5);
  const Problem p = world.problem();
  double weight = 0.0;
  for (const Body& b : world.bodies) weight += b.mass * kG;
  for (int sweeps : {3, 5}) {
    SolverParams gs = paramsFor(SolverKind::kNlgs, 1e-6, sweeps);
    gs.initial_guess = true;
    ContactSolver solver(gs);
    const SolveResult start = solver.solve(p);
    ASSERT_FALSE(start.converged) << sweeps << " sweeps: the case needs a start short of the tolerance";
    SolverParams apgd = paramsFor(SolverKind::kApgd, 1e-6, 1000);
    apgd.initial_guess = true;
    solver.setParams(apgd);
    const SolveResult r = solver.solve(p);
    const std::string label = "apgd after " + std::to_string(sweeps) + " nlgs sweeps";
    expectHonest(p, apgd, r, label);
    EXPECT_TRUE(r.converged) << label << ": " << r.iterations << " iterations, " << r.message;
    double ground = 0.0;
    for (int b = 0; b < static_cast<int>(world.bodies.size()); ++b) ground += world.normalSum(b, -1, r.forces);
    EXPECT_NEAR(ground, weight, 1e-3 * weight) << label;
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
              // Pivoting on a 1e6 mass ratio sits at the edge of double precision: an honest
              // numerical_failure, or an answer whose residual and force balance are checked
              // above (whether the last pivots survive their rounding depends on the order of
              // the sums in the entering column).
              EXPECT_TRUE(r.status == SolveStatus::kNumericalFailure || r.converged) << label << ": " << r.message;
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

}  // namespace
}  // namespace lcp_contact_solver::core
