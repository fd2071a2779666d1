// Baumgarte correction and softness in closed loop (scene → core solver → integration),
// the analytic checks of issue #9:
//   - a box 1 cm into the ground recovers to < 0.1 mm within 25 steps for β = 0.2, without
//     leaving the ground or gaining energy; with β = 0 the penetration stays;
//   - a resting stack with softness s settles at the static deflection load / k per contact,
//     k = β / s (position level, W = dt² J M⁻¹ Jᵀ), within 1 %.
#include "lcp_contact_solver/scene/scene_simulator.h"

#include "scene_test_util.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>

using namespace lcp_contact_solver;
using namespace lcp_contact_solver::scene;
using namespace scene_test;

namespace {

constexpr double kG = 9.81;
constexpr double kDt = 0.01;

SceneParams params(double erp, double softness) {
  SceneParams p;
  p.dt = kDt;
  p.erp = erp;
  p.softness = softness;
  p.mu = 0.5;
  p.solver.solver = core::SolverKind::kNlgs;
  p.solver.tolerance = 1e-11;
  p.solver.maxIt = 20000;
  p.solver.initial_guess = true;
  return p;
}

// A 0.2 m cube of 1 kg with its bottom `penetration` below z = 0.
Scene boxInGround(double penetration, double erp) {
  Scene s;
  s.name = "box_in_ground";
  s.params = params(erp, 0.0);
  s.bodies.push_back(ground());
  s.bodies.push_back(
      dynamicBody("box", boxShape(0.2, 0.2, 0.2), 1.0, Eigen::Vector3d(0, 0, 0.1 - penetration)));
  return s;
}

double penetration(const SceneSimulator& sim) { return 0.1 - sim.body("box").position.z(); }

}  // namespace

TEST(Baumgarte, OneCentimetrePenetrationRecoversWithoutBouncing) {
  const double beta = 0.2, p0 = 0.01;
  SceneSimulator sim(boxInGround(p0, beta));
  // Each step removes the fraction β of what is left: p_k = p0 (1 − β)^k, below 0.1 mm
  // after ceil(ln(0.01) / ln(0.8)) = 21 steps; the test allows 25.
  int recovered_at = -1;
  double max_height = -1.0, max_up_speed = 0.0;
  for (int k = 1; k <= 300; ++k) {
    sim.step();
    ASSERT_TRUE(sim.lastSolve().converged) << "step " << k << ": " << sim.lastSolve().message;
    if (recovered_at < 0 && penetration(sim) < 1e-4) recovered_at = k;
    max_height = std::max(max_height, -penetration(sim));
    max_up_speed = std::max(max_up_speed, sim.body("box").linear_velocity.z());
  }
  RecordProperty("recovered_at_step", recovered_at);
  EXPECT_GT(recovered_at, 0) << "still " << penetration(sim) << " m deep";
  EXPECT_LE(recovered_at, 25);
  // Does not bounce out: the bottom never rises above the ground (10 µm), the push-out is
  // never faster than the first step's β p0 / dt, and the box ends at rest on the ground.
  EXPECT_LE(max_height, 1e-5);
  EXPECT_LE(max_up_speed, beta * p0 / kDt + 1e-9);
  EXPECT_LT(sim.body("box").linear_velocity.norm(), 1e-6);
  EXPECT_NEAR(penetration(sim), 0.0, 1e-6);
  EXPECT_LT(sim.body("box").angular_velocity.norm(), 1e-6);
  // No energy gain beyond lifting the box by p0 (the correction's work): kinetic ~ 0.
  EXPECT_LT(sim.kineticEnergy(), 1e-10);
}

TEST(Baumgarte, ZeroErpLeavesThePenetration) {
  SceneSimulator sim(boxInGround(0.01, 0.0));
  for (int k = 0; k < 200; ++k) {
    sim.step();
    ASSERT_TRUE(sim.lastSolve().converged) << sim.lastSolve().message;
  }
  EXPECT_NEAR(penetration(sim), 0.01, 1e-6);
  EXPECT_LT(sim.body("box").linear_velocity.norm(), 1e-6);
}

// Three boxes, each narrower than the one below so every interface has the upper box's
// four bottom corners as contacts (an even split by symmetry). Interface i carries the
// weight above it, L_i = g Σ m_above; each of its 4 contacts L_i / 4, and settles at
// penetration (L_i / 4) / k with k = β / s.
TEST(Softness, RestingStackHasTheAnalyticStaticDeflection) {
  const double beta = 0.2, softness = 2e-5;  // m/N: k = 1e4 N/m per contact
  const double k = beta / softness;
  Scene s;
  s.name = "soft_stack";
  s.params = params(beta, softness);
  s.bodies.push_back(ground());
  const double sizes[3] = {0.5, 0.35, 0.2}, masses[3] = {3.0, 2.0, 1.0};
  for (int i = 0; i < 3; ++i)
    s.bodies.push_back(dynamicBody("box" + std::to_string(i), boxShape(sizes[i], sizes[i], 0.2), masses[i],
                                   Eigen::Vector3d(0, 0, 0.1 + 0.2 * i)));
  SceneSimulator sim(std::move(s));
  for (int step = 0; step < 600; ++step) {
    sim.step();
    ASSERT_TRUE(sim.lastSolve().converged) << "step " << step << ": " << sim.lastSolve().message;
  }
  // Penetration per interface from the contacts of the last step, against the analytic.
  std::map<std::string, std::vector<double>> depths;  // "lower/upper" → depths
  const StepProblem& sp = sim.lastProblem();
  for (const SceneContact& f : sp.frames)
    depths[std::min(f.body_a_name, f.body_b_name) + "/" + std::max(f.body_a_name, f.body_b_name)].push_back(
        f.depth);
  const char* below[3] = {"box0/ground", "box0/box1", "box1/box2"};
  double load = 0.0;
  for (int i = 2; i >= 0; --i) {
    load += masses[i] * kG;
    SCOPED_TRACE(below[i]);
    const std::vector<double>& d = depths[below[i]];
    ASSERT_EQ(d.size(), 4u) << "contacts under box" << i;
    const double expected = (load / 4.0) / k;
    for (double depth : d) EXPECT_NEAR(depth, expected, 0.01 * expected);
  }
  // And the top box sits lower by the sum of the three deflections.
  const double drop = 0.1 + 0.4 - sim.body("box2").position.z();
  const double expected_drop = (6.0 + 3.0 + 1.0) * kG / 4.0 / k;
  EXPECT_NEAR(drop, expected_drop, 0.01 * expected_drop);
  EXPECT_LT(sim.kineticEnergy(), 1e-10);
}
