// The pyramid friction models: boxed pgs and Lemke on the Stewart-Trinkle LCP.
#include "solvers_test_util.h"

namespace lcp_contact_solver::core {
namespace {

using namespace solvers_test;

// ---- pyramid friction ---------------------------------------------------------------------

// A box on an incline of slope s = tan α in tangent direction θ: per unit of compliance the
// free motion presses the normal by 1 and drives the tangent by s (cos θ, sin θ).
Problem incline(double slope, double theta, double mu) {
  return oneFrictionalContact(Eigen::Matrix3d::Identity(),
                              Eigen::Vector3d(-1.0, slope * std::cos(theta), slope * std::sin(theta)), mu);
}

SolverParams pyramidParams(SolverKind kind, FrictionModel model) {
  SolverParams params = tight(kind);
  params.friction_model = model;
  return params;
}

void expectSticks(const SolveResult& r, double slope, double theta) {
  ASSERT_EQ(r.status, SolveStatus::kConverged) << r.message;
  EXPECT_NEAR(r.d[1], 0.0, 1e-12);
  EXPECT_NEAR(r.d[2], 0.0, 1e-12);
  EXPECT_NEAR(r.forces[1], -slope * std::cos(theta), 1e-12);
  EXPECT_NEAR(r.forces[2], -slope * std::sin(theta), 1e-12);
}

TEST(Pyramid, BoxOnInclineSticksUpToThePyramidThreshold) {
  const double mu = 0.5;
  const double pi = std::acos(-1.0);
  struct Case {
    FrictionModel model;
    double theta;      // slope direction in the tangent plane
    double threshold;  // slope (tan α) at which it starts to slide
  };
  const Case cases[] = {
      {FrictionModel::kPyramid4, 0.0, mu},  // along a facet normal
      {FrictionModel::kPyramid4, 0.5 * pi, mu},
      {FrictionModel::kPyramid4, 0.25 * pi, mu * std::sqrt(2.0)},  // toward a corner
      {FrictionModel::kPyramid8, 0.0, mu},
      {FrictionModel::kPyramid8, 0.25 * pi, mu},                          // facet normal at 45°
      {FrictionModel::kPyramid8, 0.125 * pi, mu / std::cos(0.125 * pi)},  // toward a corner
  };
  for (const Case& c : cases) {
    for (SolverKind kind : {SolverKind::kPgs, SolverKind::kLemke}) {
      const std::string what = std::string(frictionModelName(c.model)) + " " + solverName(kind) + " theta " +
                               std::to_string(c.theta);
      // Just below the threshold: sticks (no tangential velocity).
      const double below = 0.999 * c.threshold;
      const SolveResult stick = solveProblem(incline(below, c.theta, mu), pyramidParams(kind, c.model));
      SCOPED_TRACE(what);
      expectSticks(stick, below, c.theta);
      EXPECT_EQ(stick.friction_model, c.model);
      // Just above: slides, the friction force on the polygon's boundary at the threshold.
      const double above = 1.001 * c.threshold;
      const SolveResult slide = solveProblem(incline(above, c.theta, mu), pyramidParams(kind, c.model));
      ASSERT_EQ(slide.status, SolveStatus::kConverged) << slide.message;
      EXPECT_GT(std::hypot(slide.d[1], slide.d[2]), 1e-4);
      EXPECT_NEAR(slide.forces[0], 1.0, 1e-12);
      EXPECT_NEAR(slide.forces[1], -c.threshold * std::cos(c.theta), 1e-9);
      EXPECT_NEAR(slide.forces[2], -c.threshold * std::sin(c.theta), 1e-9);
      EXPECT_LE(slide.solver_error, 1e-12);  // the pyramid problem is solved ...
      if (c.threshold > mu * (1.0 + 1e-9)) {
        EXPECT_GT(slide.residual, 1e-3);  // ... the disc is not, by design
        EXPECT_GT(stick.residual, 1e-3);  // (it sticks where the disc would slide)
      }
      // "converged" names the law it holds for, and what the disc residual means then.
      const std::string law = std::string("converged on the ") + frictionModelName(c.model) + " friction law";
      EXPECT_NE(slide.message.find(law), std::string::npos) << slide.message;
      EXPECT_NE(slide.message.find("distance to Coulomb's disc"), std::string::npos) << slide.message;
    }
  }
  // The disc slides at μ in every direction.
  const SolveResult disc = solveProblem(incline(1.001 * mu, 0.25 * pi, mu), tight(SolverKind::kNlgs));
  EXPECT_GT(std::hypot(disc.d[1], disc.d[2]), 1e-4);
  EXPECT_EQ(disc.friction_model, FrictionModel::kCoulombDisc);
}

TEST(Pyramid, LemkeAndBoxedPgsAgree) {
  for (FrictionModel model : {FrictionModel::kPyramid4, FrictionModel::kPyramid8}) {
    for (unsigned seed : {41u, 42u, 43u}) {
      const Problem p = seed == 43u ? mixedProblem(seed) : randomFrictionalProblem(5, seed, 0.6, 0.05);
      const SolveResult lemke = solveProblem(p, pyramidParams(SolverKind::kLemke, model));
      const SolveResult pgs = solveProblem(p, pyramidParams(SolverKind::kPgs, model));
      SCOPED_TRACE(std::string(frictionModelName(model)) + " seed " + std::to_string(seed));
      ASSERT_EQ(lemke.status, SolveStatus::kConverged) << lemke.message;
      ASSERT_EQ(pgs.status, SolveStatus::kConverged) << pgs.message;
      EXPECT_EQ(lemke.friction_model, model);
      EXPECT_EQ(pgs.friction_model, model);
      EXPECT_EQ(lemke.solver, "lemke");
      EXPECT_EQ(pgs.solver, "pgs");
      EXPECT_LE(lemke.solver_error, 1e-12);
      EXPECT_LE(pgs.solver_error, 1e-12);
      EXPECT_LE((lemke.forces - pgs.forces).norm(), 1e-8 * lemke.forces.norm());
      EXPECT_NE(lemke.message.find(frictionModelName(model)), std::string::npos);
      expectFinite(lemke);
    }
  }
}

TEST(Pyramid, SolutionIsInsideThePolygonWithMaximumDissipation) {
  const Problem p = randomFrictionalProblem(6, 51, 0.7, 0.05);
  const SolveResult r = solveProblem(p, pyramidParams(SolverKind::kPgs, FrictionModel::kPyramid4));
  ASSERT_EQ(r.status, SolveStatus::kConverged);
  for (int c = 0; c < 6; ++c) {
    const double bound = 0.7 * r.forces[3 * c];
    EXPECT_LE(std::abs(r.forces[3 * c + 1]), bound * (1 + 1e-12) + 1e-15);
    EXPECT_LE(std::abs(r.forces[3 * c + 2]), bound * (1 + 1e-12) + 1e-15);
    // Box: each tangent either sticks (velocity 0) or sits on its bound opposing the velocity.
    for (int k = 1; k <= 2; ++k) {
      const double v = r.d[3 * c + k], f = r.forces[3 * c + k];
      if (std::abs(v) > 1e-9) {
        EXPECT_NEAR(f, -std::copysign(bound, v), 1e-9);
      }
    }
  }
}

TEST(Pyramid, RelaxedBoxedPgsConvergesToTheSameAnswer) {
  const Problem p = randomFrictionalProblem(5, 61, 0.5, 0.05);
  const SolveResult reference = solveProblem(p, pyramidParams(SolverKind::kPgs, FrictionModel::kPyramid8));
  for (double omega : {0.8, 1.4}) {
    SolverParams params = pyramidParams(SolverKind::kPgs, FrictionModel::kPyramid8);
    params.sor = omega;
    const SolveResult r = solveProblem(p, params);
    ASSERT_EQ(r.status, SolveStatus::kConverged);
    EXPECT_LE((r.forces - reference.forces).norm(), 1e-9 * reference.forces.norm());
  }
}

TEST(Pyramid, ModelSelection) {
  const Problem p = randomFrictionalProblem(3, 71);
  // Lemke with the disc: still not applicable.
  const SolveResult refused = solveProblem(p, tight(SolverKind::kLemke));
  EXPECT_EQ(refused.status, SolveStatus::kNotApplicable);
  // auto with a pyramid: boxed pgs.
  const SolveResult automatic = solveProblem(p, pyramidParams(SolverKind::kAuto, FrictionModel::kPyramid4));
  EXPECT_EQ(automatic.solver, "auto:pgs");
  EXPECT_EQ(automatic.friction_model, FrictionModel::kPyramid4);
  EXPECT_EQ(automatic.status, SolveStatus::kConverged);
  // The disc solvers ignore a pyramid and say so.
  for (SolverKind kind : {SolverKind::kNlgs, SolverKind::kApgd, SolverKind::kNewton}) {
    const SolveResult r = solveProblem(p, pyramidParams(kind, FrictionModel::kPyramid8));
    EXPECT_EQ(r.friction_model, FrictionModel::kCoulombDisc) << solverName(kind);
    EXPECT_NE(r.message.find("Coulomb disc"), std::string::npos) << r.message;
  }
  // No friction: the pyramid changes nothing.
  Eigen::MatrixXd M(2, 2);
  M << 2, 1, 1, 2;
  const Problem lcp = makeLcpProblem(M, Eigen::Vector2d(-5, -6));
  for (SolverKind kind : {SolverKind::kPgs, SolverKind::kLemke}) {
    const SolveResult r = solveProblem(lcp, pyramidParams(kind, FrictionModel::kPyramid4));
    ASSERT_EQ(r.status, SolveStatus::kConverged);
    EXPECT_EQ(r.friction_model, FrictionModel::kCoulombDisc);
    EXPECT_NEAR(r.forces[0], 4.0 / 3.0, 1e-10);
  }
}

}  // namespace
}  // namespace lcp_contact_solver::core
