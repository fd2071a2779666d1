// Per-pair contact effects, each against its analytic law (issue #8):
//   - torsional friction: a ball spinning about the vertical on the ground decelerates at
//     α = μ_tor m g / I and stops (sliding friction alone exerts no torque about n);
//   - rolling friction: a ball rolling without slipping decelerates at
//     a = μ_roll g / (r (1 + I / (m r²))) and stops; without it, it keeps rolling;
//   - restitution: a ball dropped on the ground leaves it at e times its impact speed;
//   - each pair costs the rows it asks for (1, 3, 4 or 6).
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
constexpr double kR = 0.1;     // m
constexpr double kMass = 1.0;  // kg
constexpr double kInertia = 0.4 * kMass * kR * kR;

Scene ballOnGround(double torsional, double rolling, double dt) {
  Scene s;
  s.name = "ball_on_ground";
  s.params.dt = dt;
  s.params.erp = 0.2;
  s.params.solver.solver = core::SolverKind::kNlgs;
  s.params.solver.tolerance = 1e-12;
  s.params.solver.maxIt = 5000;
  s.params.friction_pairs.push_back({"ball", "ground", 0.5, torsional, rolling});
  s.bodies.push_back(ground());
  s.bodies.push_back(dynamicBody("ball", sphereShape(kR), kMass, Eigen::Vector3d(0, 0, kR)));
  return s;
}

}  // namespace

TEST(TorsionalFriction, SpinningBallDeceleratesByTheTorsionalLaw) {
  const double mu_tor = 0.01, w0 = 10.0, dt = 0.005;
  SceneSimulator sim(ballOnGround(mu_tor, 0.0, dt));
  sim.setBodyVelocity(sim.scene().requireBody("ball"), Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, w0));
  const double alpha = mu_tor * kMass * kG / kInertia;  // 24.5 rad/s²
  sim.run(0.2);
  ASSERT_EQ(sim.lastProblem().problem.contacts.size(), 1u);
  EXPECT_EQ(sim.lastProblem().problem.contacts[0].type, core::ContactType::kTorsional);
  EXPECT_EQ(sim.lastProblem().problem.rowCount(), 4);
  EXPECT_NEAR(sim.body("ball").angular_velocity.z(), w0 - alpha * sim.time(), 0.01 * w0);
  sim.run(0.4);  // stops at w0 / α = 0.41 s, and does not turn back
  EXPECT_LT(std::abs(sim.body("ball").angular_velocity.z()), 1e-6);
  EXPECT_LT(sim.body("ball").linear_velocity.norm(), 1e-6);
}

TEST(TorsionalFriction, WithoutItASpinningBallKeepsSpinning) {
  SceneSimulator sim(ballOnGround(0.0, 0.0, 0.005));
  sim.setBodyVelocity(sim.scene().requireBody("ball"), Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, 10.0));
  sim.run(0.5);
  EXPECT_EQ(sim.lastProblem().problem.rowCount(), 3);  // no spin row was paid for
  EXPECT_NEAR(sim.body("ball").angular_velocity.z(), 10.0, 1e-9);
}

TEST(RollingFriction, RollingBallDeceleratesByTheRollingLawAndStops) {
  const double mu_roll = 0.005, v0 = 1.0, dt = 0.005;
  SceneSimulator sim(ballOnGround(0.0, mu_roll, dt));
  sim.setBodyVelocity(sim.scene().requireBody("ball"), Eigen::Vector3d(v0, 0, 0),
                      Eigen::Vector3d(0, v0 / kR, 0));
  const double a = mu_roll * kG / (kR * (1.0 + kInertia / (kMass * kR * kR)));  // 0.350 m/s²
  sim.run(1.0);
  EXPECT_EQ(sim.lastProblem().problem.contacts[0].type, core::ContactType::kRolling);
  EXPECT_NEAR(sim.body("ball").linear_velocity.x(), v0 - a * sim.time(), 0.01 * v0);
  // Still rolling without slipping: v = ω r.
  EXPECT_NEAR(sim.body("ball").linear_velocity.x(), sim.body("ball").angular_velocity.y() * kR, 1e-6);
  sim.run(2.5);  // stops at v0 / a = 2.85 s
  EXPECT_LT(sim.body("ball").linear_velocity.norm(), 1e-6);
  EXPECT_LT(sim.body("ball").angular_velocity.norm(), 1e-5);
  EXPECT_NEAR(sim.body("ball").position.x(), v0 * v0 / (2 * a), 0.01 * v0 * v0 / (2 * a));
}

TEST(RollingFriction, WithoutItABallKeepsRolling) {
  SceneSimulator sim(ballOnGround(0.0, 0.0, 0.005));
  sim.setBodyVelocity(sim.scene().requireBody("ball"), Eigen::Vector3d(1.0, 0, 0),
                      Eigen::Vector3d(0, 10.0, 0));
  sim.run(1.0);
  EXPECT_NEAR(sim.body("ball").linear_velocity.x(), 1.0, 1e-6);
}

TEST(Restitution, BallLeavesTheGroundAtETimesItsImpactSpeed) {
  for (double e : {0.0, 0.5, 0.8}) {
    SCOPED_TRACE("e = " + std::to_string(e));
    Scene s = ballOnGround(0.0, 0.0, 0.001);
    s.params.restitution = e;
    s.bodies[1].position.z() = kR + 1.0;  // bottom 1 m above the ground
    SceneSimulator sim(std::move(s));
    double impact_speed = 0.0, rebound_speed = 0.0, apex = 0.0;
    bool bounced = false;
    while (sim.time() < 1.5) {
      const double vz = sim.body("ball").linear_velocity.z();
      if (!bounced) impact_speed = std::max(impact_speed, -vz);
      sim.step();
      if (sim.lastStats().impacts > 0) bounced = true;
      if (bounced) {
        rebound_speed = std::max(rebound_speed, sim.body("ball").linear_velocity.z());
        apex = std::max(apex, sim.body("ball").position.z() - kR);
      }
    }
    ASSERT_TRUE(bounced || e == 0.0);
    EXPECT_NEAR(impact_speed, std::sqrt(2 * kG * 1.0), 0.01 * impact_speed);
    EXPECT_NEAR(rebound_speed, e * impact_speed, 0.01 * impact_speed);
    // The apex follows e² h (the bounce may start up to one step's travel early: 4 mm).
    EXPECT_NEAR(apex, e * e * 1.0, 0.005 + 0.01 * e * e);
  }
}

TEST(ContactRows, EachPairPaysForTheRowsItAsksFor) {
  // Four balls on the ground, one per model: frictionless, sliding, torsional, rolling.
  Scene s;
  s.name = "condims";
  s.params.friction_pairs = {{"b1", "ground", 0.0},
                             {"b3", "ground", 0.5},
                             {"b4", "ground", 0.5, 0.01, 0.0},
                             {"b6", "ground", 0.5, 0.01, 0.002}};
  s.bodies.push_back(ground());
  const char* names[4] = {"b1", "b3", "b4", "b6"};
  for (int i = 0; i < 4; ++i)
    s.bodies.push_back(dynamicBody(names[i], sphereShape(kR), kMass, Eigen::Vector3d(0.5 * i, 0, kR)));
  SceneSimulator sim(std::move(s));
  sim.step();
  const core::Problem& p = sim.lastProblem().problem;
  ASSERT_EQ(p.contacts.size(), 4u);
  std::map<std::string, int> rows;
  for (std::size_t c = 0; c < p.contacts.size(); ++c) {
    const SceneContact& f = sim.lastProblem().frames[c];
    rows[f.body_a_name == "ground" ? f.body_b_name : f.body_a_name] = p.contacts[c].rows;
  }
  EXPECT_EQ(rows["b1"], 1);
  EXPECT_EQ(rows["b3"], 3);
  EXPECT_EQ(rows["b4"], 4);
  EXPECT_EQ(rows["b6"], 6);
  EXPECT_EQ(p.rowCount(), 14);
  EXPECT_TRUE(sim.lastSolve().converged) << sim.lastSolve().message;
}
