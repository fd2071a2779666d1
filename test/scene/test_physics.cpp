// Physics validation: closed loop scene → core solver → integration, on the shipped scenes.
#include "lcp_contact_solver/scene/scene_simulator.h"

#include "scene_test_util.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace lcp_contact_solver;
using namespace lcp_contact_solver::scene;
using namespace scene_test;

namespace {

const std::string kDir = LCS_SCENES_DIR;
constexpr double kG = 9.81;

SceneParams tight(SceneParams p) {
  p.solver.solver = core::SolverKind::kNlgs;
  p.solver.tolerance = 1e-10;
  p.solver.maxIt = 20000;
  return p;
}

// The incline scene at angle θ (rad) with friction μ.
Scene incline(double theta, double mu) {
  SceneParams p = tight(loadSceneParams(kDir + "/incline.yaml"));
  p.joint_origins["tilt"].has_rpy = true;
  p.joint_origins["tilt"].rpy = Eigen::Vector3d(0, theta, 0);
  p.mu = mu;
  return loadSceneFromUrdfFile(kDir + "/incline.urdf", p);
}

// Down-slope unit vector of the ramp (its x axis, pitched by θ).
Eigen::Vector3d downSlope(const SceneSimulator& sim) {
  return sim.body("ramp").orientation * Eigen::Vector3d::UnitX();
}

// Along-slope acceleration measured from velocities between t0 and t1.
double slopeAcceleration(SceneSimulator& sim, double t0, double t1) {
  const Eigen::Vector3d s = downSlope(sim);
  sim.run(t0);
  const double v0 = sim.body("box").linear_velocity.dot(s);
  const double time0 = sim.time();
  sim.run(t1 - t0);
  const double v1 = sim.body("box").linear_velocity.dot(s);
  return (v1 - v0) / (sim.time() - time0);
}

}  // namespace

class InclineTest : public ::testing::TestWithParam<double> {};

// Sticks when μ ≥ tan θ (just above the threshold), slides when μ < tan θ (just below),
// with a = g (sin θ − μ cos θ) within 2%.
TEST_P(InclineTest, SticksAboveTanThetaSlidesBelow) {
  const double theta = GetParam() * M_PI / 180.0;
  const double threshold = std::tan(theta);
  {
    SCOPED_TRACE("mu = 1.02 tan(theta): sticks");
    SceneSimulator sim(incline(theta, 1.02 * threshold));
    const Eigen::Vector3d start = sim.body("box").position;
    sim.run(2.0);
    EXPECT_LT((sim.body("box").position - start).norm(), 1e-5);
    EXPECT_LT(sim.body("box").linear_velocity.norm(), 1e-5);
    EXPECT_TRUE(sim.lastStats().converged);
    EXPECT_GT(sim.lastStats().contacts, 0);
  }
  {
    SCOPED_TRACE("mu = tan(theta): sticks (the boundary of the cone)");
    SceneSimulator sim(incline(theta, threshold));
    const Eigen::Vector3d start = sim.body("box").position;
    sim.run(1.0);
    EXPECT_LT((sim.body("box").position - start).norm(), 1e-4);
  }
  for (double factor : {0.98, 0.9, 0.5}) {
    SCOPED_TRACE("mu = " + std::to_string(factor) + " tan(theta): slides");
    const double mu = factor * threshold;
    SceneSimulator sim(incline(theta, mu));
    const double expected = kG * (std::sin(theta) - mu * std::cos(theta));
    const double a = slopeAcceleration(sim, 0.1, 0.6);
    EXPECT_NEAR(a, expected, 0.02 * expected) << "theta " << GetParam() << " deg, mu " << mu;
    EXPECT_TRUE(sim.lastStats().converged);
  }
}

INSTANTIATE_TEST_SUITE_P(Angles, InclineTest, ::testing::Values(20.0, 35.0));

TEST(Physics, RestingSphereNormalForceIsMg) {
  Scene s;
  s.params = tight(s.params);
  s.bodies.push_back(ground());
  const double m = 2.5, r = 0.1;
  // Dropped from 5 cm: it lands, settles, then rests.
  s.bodies.push_back(dynamicBody("ball", sphereShape(r), m, Eigen::Vector3d(0, 0, r + 0.05)));
  SceneSimulator sim(s);
  sim.run(1.0);
  for (int k = 0; k < 100; ++k) {
    sim.step();
    ASSERT_EQ(sim.lastProblem().frames.size(), 1u);
    const double normal_force = sim.lastForces()[0];
    EXPECT_NEAR(normal_force, m * kG, 1e-3 * m * kG);
  }
  EXPECT_NEAR(sim.body("ball").position.z(), r, 1e-6);
}

TEST(Physics, BoxStackRestsWithDriftUnder1mm) {
  SceneSimulator sim(
      loadSceneFromUrdfFile(kDir + "/box_stack.urdf", tight(loadSceneParams(kDir + "/box_stack.yaml"))));
  std::vector<Eigen::Vector3d> start;
  for (int i = 1; i <= 5; ++i) start.push_back(sim.body("box_" + std::to_string(i)).position);
  double drift = 0.0;
  int not_converged = 0;
  const int steps = static_cast<int>(std::lround(10.0 / sim.params().dt));
  for (int k = 0; k < steps; ++k) {
    sim.step();
    not_converged += sim.lastStats().converged ? 0 : 1;
    for (int i = 0; i < 5; ++i)
      drift = std::max(drift, (sim.body("box_" + std::to_string(i + 1)).position - start[i]).norm());
  }
  EXPECT_NEAR(sim.time(), 10.0, 1e-9);
  EXPECT_LT(drift, 1e-3);
  EXPECT_EQ(not_converged, 0);
  EXPECT_EQ(sim.lastStats().contacts, 20);
  RecordProperty("max_drift_m", std::to_string(drift));
  std::printf("box stack: max drift over 10 s = %.3g m\n", drift);
}

TEST(Physics, FrictionlessSceneHasNoTangentialForce) {
  SceneSimulator sim(loadSceneFromUrdfFile(kDir + "/frictionless.urdf",
                                           tight(loadSceneParams(kDir + "/frictionless.yaml"))));
  const Eigen::Vector3d s = downSlope(sim);
  const double theta = std::acos((sim.body("ramp").orientation * Eigen::Vector3d::UnitZ()).z());
  int contacts = 0;
  double v0 = 0, t0 = 0;
  for (int k = 0; k < 80; ++k) {
    if (k == 10) {
      v0 = sim.body("box").linear_velocity.dot(s);
      t0 = sim.time();
    }
    sim.step();
    const StepProblem& sp = sim.lastProblem();
    for (std::size_t i = 0; i < sp.frames.size(); ++i) {
      EXPECT_EQ(sp.problem.contacts[i].type, core::ContactType::kFrictionless);
      EXPECT_EQ(sp.problem.contacts[i].rows, 1);
      ++contacts;
    }
    EXPECT_EQ(sp.problem.rowCount(), static_cast<int>(sp.frames.size()));
    // The contact wrench on each body on the ramp has no component along the slope.
    const auto w = sim.lastContactWrenches();
    for (const char* name : {"box", "ball"}) {
      const int b = sim.scene().bodyIndex(name);
      EXPECT_NEAR(w[b].head<3>().dot(s), 0.0, 1e-9 * (1.0 + w[b].head<3>().norm())) << name;
      EXPECT_NEAR(w[b].head<3>().dot(Eigen::Vector3d::UnitY()), 0.0, 1e-9 * (1.0 + w[b].head<3>().norm()))
          << name;
    }
  }
  EXPECT_GT(contacts, 0);
  // No tangential force: the ball slides without turning, the box accelerates at g sin θ.
  EXPECT_LT(sim.body("ball").angular_velocity.norm(), 1e-9);
  const double a = (sim.body("box").linear_velocity.dot(s) - v0) / (sim.time() - t0);
  EXPECT_NEAR(a, kG * std::sin(theta), 0.02 * kG * std::sin(theta));
}

TEST(Physics, MixedFrictionPerPair) {
  SceneSimulator sim(
      loadSceneFromUrdfFile(kDir + "/mixed.urdf", tight(loadSceneParams(kDir + "/mixed.yaml"))));
  sim.run(0.1);
  // box_grip brakes at μ g (μ = 0.5), box_slick keeps 1 m/s, the ball rides along.
  EXPECT_NEAR(sim.body("box_grip").linear_velocity.x(), 1.0 - 0.5 * kG * sim.time(), 0.02 * 0.5);
  EXPECT_NEAR(sim.body("box_slick").linear_velocity.x(), 1.0, 1e-6);
  sim.run(0.9);
  EXPECT_LT(sim.body("box_grip").linear_velocity.norm(), 1e-6);
  EXPECT_NEAR(sim.body("box_slick").linear_velocity.x(), 1.0, 1e-6);
  EXPECT_NEAR(sim.body("ball").linear_velocity.x(), 1.0, 1e-4);
  // The disabled pair never reached the narrowphase (they are 0.6 m apart anyway).
  EXPECT_EQ(sim.lastStats().generation.skipped_disabled, 0);
}

TEST(Physics, SpherePileSettles) {
  SceneSimulator sim(loadNamedScene(kDir, "sphere_pile"));
  const double e0 = sim.energy();
  sim.run(3.0);
  EXPECT_LT(sim.energy(), e0);
  EXPECT_LT(sim.kineticEnergy(), 1e-3);
  EXPECT_LT(sim.lastStats().max_penetration, 1e-3);
  for (const RigidBody& b : sim.scene().bodies) {
    if (b.is_static) continue;
    EXPECT_LT(std::abs(b.position.x()), 0.3) << b.name;
    EXPECT_LT(std::abs(b.position.y()), 0.3) << b.name;
    EXPECT_GT(b.position.z(), 0.05 - 1e-3) << b.name;
  }
}

TEST(Physics, DenseAndBlockSparseGiveTheSameTrajectory) {
  SceneParams p = tight(loadSceneParams(kDir + "/sphere_pile.yaml"));
  p.compliance = ComplianceStorage::kDense;
  SceneSimulator dense(loadSceneFromUrdfFile(kDir + "/sphere_pile.urdf", p));
  p.compliance = ComplianceStorage::kBlockSparse;
  SceneSimulator sparse(loadSceneFromUrdfFile(kDir + "/sphere_pile.urdf", p));
  for (int k = 0; k < 60; ++k) {
    dense.step();
    sparse.step();
  }
  double diff = 0.0;
  for (int i = 0; i < dense.bodyCount(); ++i)
    diff = std::max(diff, (dense.body(i).position - sparse.body(i).position).norm());
  EXPECT_LT(diff, 1e-6);
}

TEST(Physics, FreeBodyIntegration) {
  // No contacts: semi-implicit Euler under gravity, and rotation about the centre of mass
  // for a link whose COM is offset from its origin.
  Scene s;
  RigidBody b = dynamicBody("flyer", boxShape(0.1, 0.1, 0.1), 1.5, Eigen::Vector3d(0, 0, 10));
  b.com_local = Eigen::Vector3d(0.2, 0, 0);
  b.angular_velocity = Eigen::Vector3d(0, 0, 2.0);
  s.bodies.push_back(b);
  SceneSimulator sim(s);
  const Eigen::Vector3d com0 = sim.body(0).comWorld();
  const double dt = sim.params().dt;
  const int n = 100;
  for (int k = 0; k < n; ++k) {
    const StepStats st = sim.step();
    EXPECT_EQ(st.contacts, 0);
    EXPECT_FALSE(st.solved);
  }
  // v_k = -g k dt, z_k = z_0 - g dt² k(k+1)/2.
  const Eigen::Vector3d com = sim.body(0).comWorld();
  EXPECT_NEAR(com.z(), com0.z() - kG * dt * dt * n * (n + 1) / 2.0, 1e-9);
  EXPECT_NEAR(com.x(), com0.x(), 1e-12);
  EXPECT_NEAR(com.y(), com0.y(), 1e-12);
  // Turned by ω t about z through the COM.
  const double angle = 2.0 * n * dt;
  const Eigen::Vector3d x_axis = sim.body(0).orientation * Eigen::Vector3d::UnitX();
  EXPECT_NEAR(x_axis.x(), std::cos(angle), 1e-12);
  EXPECT_NEAR(x_axis.y(), std::sin(angle), 1e-12);
  EXPECT_NEAR(sim.kineticEnergy(),
              0.5 * 1.5 * std::pow(kG * n * dt, 2) + 0.5 * sim.body(0).inertia_local(2, 2) * 4.0, 1e-9);
  // External wrenches act for one step only.
  sim.addExternalWrench(0, Eigen::Vector3d(3.0, 0, 0), Eigen::Vector3d::Zero());
  sim.step();
  EXPECT_NEAR(sim.body(0).linear_velocity.x(), 3.0 / 1.5 * dt, 1e-15);
  sim.step();
  EXPECT_NEAR(sim.body(0).linear_velocity.x(), 3.0 / 1.5 * dt, 1e-15);
}
