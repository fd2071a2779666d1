// The simulator's message conversions: a SceneSimulator step survives the trip through
// ContactArray + Compliance and the solver node's own reader (toProblem) unchanged, and
// forces come back by contact id.
#include "lcp_contact_solver/core/contact_solver.h"
#include "lcp_contact_solver/ros/msg_conversion/msg_conversion.h"
#include "lcp_contact_solver/ros/msg_conversion/scene_msg_conversion.h"
#include "lcp_contact_solver/scene/scene.h"
#include "lcp_contact_solver/scene/scene_simulator.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

namespace lcs = lcp_contact_solver;
namespace scene = lcp_contact_solver::scene;
namespace ros_layer = lcp_contact_solver_ros;

namespace {

Eigen::MatrixXd dense(const lcs::core::ComplianceMatrix& W) {
  if (const auto* d = std::get_if<Eigen::MatrixXd>(&W)) return *d;
  return std::get<lcs::core::BlockSparseMatrix>(W).toDense();
}

std_msgs::Header header(double t) {
  std_msgs::Header h;
  h.stamp = ros::Time(t);
  h.frame_id = "world";
  return h;
}

// A few steps into a scene, so contacts exist and carry warm ids.
scene::SceneSimulator* settled(const std::string& name, int steps) {
  auto* sim = new scene::SceneSimulator(scene::loadNamedScene(LCS_SCENES_DIR, name));
  for (int k = 0; k < steps; ++k) sim->step();
  return sim;
}

void expectRoundTrip(const std::string& name) {
  std::unique_ptr<scene::SceneSimulator> sim(settled(name, 5));
  const scene::StepProblem& sp = sim->buildStep();
  ASSERT_FALSE(sp.problem.contacts.empty()) << name;
  const lcs::ContactArray contacts = ros_layer::toContactArrayMsg(sp, header(0.05));
  const lcs::Compliance compliance = ros_layer::toComplianceMsg(sp, header(0.05));
  EXPECT_EQ(contacts.header.stamp, compliance.header.stamp);
  ASSERT_EQ(contacts.contacts.size(), sp.frames.size());

  lcs::core::Problem back;
  std::vector<ros_layer::ContactFrame> frames;
  ASSERT_EQ(ros_layer::toProblem(contacts, compliance, 0, &back, &frames), "") << name;
  ASSERT_EQ(back.contacts.size(), sp.problem.contacts.size());
  for (std::size_t i = 0; i < back.contacts.size(); ++i) {
    const lcs::core::Contact& a = sp.problem.contacts[i];
    const lcs::core::Contact& b = back.contacts[i];
    EXPECT_EQ(b.id, a.id);
    EXPECT_EQ(b.type, a.type);
    EXPECT_EQ(b.rows, a.rows);
    EXPECT_EQ(b.mu, a.mu) << "μ is explicit, never MU_DEFAULT";
    EXPECT_FALSE(frames[i].derived_tangents) << "the tangents are published";
    EXPECT_LT((frames[i].tangent1 - sp.frames[i].tangent1).norm(), 1e-12);
    EXPECT_LT((frames[i].tangent2 - sp.frames[i].tangent2).norm(), 1e-12);
    EXPECT_EQ(contacts.contacts[i].body_a, sp.frames[i].body_a_name);
    EXPECT_EQ(contacts.contacts[i].body_b, sp.frames[i].body_b_name);
  }
  EXPECT_EQ(back.d_free, sp.problem.d_free);
  EXPECT_EQ(back.W.index(), sp.problem.W.index()) << "same storage";
  EXPECT_EQ(dense(back.W), dense(sp.problem.W));

  // The node's solve of the received problem equals the in-process solve.
  lcs::core::ContactSolver direct(sim->params().solver), through(sim->params().solver);
  const lcs::core::SolveResult a = direct.solve(sp.problem);
  const lcs::core::SolveResult b = through.solve(back);
  ASSERT_EQ(a.forces.size(), b.forces.size());
  EXPECT_LE((a.forces - b.forces).lpNorm<Eigen::Infinity>(),
            1e-12 * (1.0 + a.forces.lpNorm<Eigen::Infinity>()));

  // Forces back by id, in any order.
  lcs::ConstraintForces msg = ros_layer::toConstraintForcesMsg(contacts, frames, back, b);
  std::reverse(msg.forces.begin(), msg.forces.end());
  Eigen::VectorXd lambda;
  ASSERT_EQ(ros_layer::toStepForces(msg, sp.problem, &lambda), "");
  EXPECT_EQ(lambda, b.forces);
  sim->applyForces(lambda);
}

// `compliance: bodies`: the step's body form goes out as STORAGE_BODIES, comes back equal,
// and the node's unbuilt solve of it is the in-process one.
TEST(SceneMsgConversion, BodyFormRoundTripsAndSolvesUnbuilt) {
  scene::Scene s = scene::loadNamedScene(LCS_SCENES_DIR, "box_stack");
  s.params.compliance = scene::ComplianceStorage::kBodies;
  s.params.solver.build_lcp = false;
  scene::SceneSimulator sim(s);
  for (int k = 0; k < 5; ++k) sim.step();
  const scene::StepProblem& sp = sim.buildStep();
  ASSERT_FALSE(sp.problem.contacts.empty());
  ASSERT_TRUE(sp.problem.bodies);
  const lcs::ContactArray contacts = ros_layer::toContactArrayMsg(sp, header(0.05));
  const lcs::Compliance compliance = ros_layer::toComplianceMsg(sp, header(0.05));
  EXPECT_EQ(compliance.storage, lcs::Compliance::STORAGE_BODIES);
  EXPECT_EQ(compliance.header.stamp, contacts.header.stamp);
  EXPECT_TRUE(compliance.data.empty());
  EXPECT_TRUE(compliance.block_data.empty());
  lcs::core::Problem back;
  std::vector<ros_layer::ContactFrame> frames;
  ASSERT_EQ(ros_layer::toProblem(contacts, compliance, 0, &back, &frames), "");
  ASSERT_TRUE(back.bodies);
  EXPECT_EQ(back.bodies->toDense(), sp.problem.bodies->toDense());
  EXPECT_EQ(back.d_free, sp.problem.d_free);
  lcs::core::ContactSolver direct(sim.params().solver), through(sim.params().solver);
  const lcs::core::SolveResult a = direct.solve(sp.problem);
  const lcs::core::SolveResult b = through.solve(back);
  EXPECT_TRUE(a.unbuilt);
  EXPECT_TRUE(b.unbuilt);
  EXPECT_EQ(a.forces, b.forces) << "the same body form, bit for bit";
  sim.applyForces(a.forces);
}

TEST(SceneMsgConversion, RoundTripBoxStack) { expectRoundTrip("box_stack"); }
TEST(SceneMsgConversion, RoundTripMixedFrictionlessPairs) { expectRoundTrip("mixed"); }
TEST(SceneMsgConversion, RoundTripSpherePile) { expectRoundTrip("sphere_pile"); }

TEST(SceneMsgConversion, ForcesThatDoNotFitAreRefused) {
  std::unique_ptr<scene::SceneSimulator> sim(settled("box_stack", 3));
  const scene::StepProblem& sp = sim->buildStep();
  const lcs::ContactArray contacts = ros_layer::toContactArrayMsg(sp, header(0.03));
  lcs::ConstraintForces good;
  for (const lcs::ContactPoint& c : contacts.contacts) {
    lcs::ContactForce f;
    f.id = c.id;
    f.lambda.assign(c.d_free.size(), 1.0);
    good.forces.push_back(f);
  }
  Eigen::VectorXd lambda;
  ASSERT_EQ(ros_layer::toStepForces(good, sp.problem, &lambda), "");
  EXPECT_EQ(lambda, Eigen::VectorXd::Ones(sp.problem.rowCount()));

  auto refused = [&](lcs::ConstraintForces bad, const std::string& words) {
    Eigen::VectorXd out;
    const std::string error = ros_layer::toStepForces(bad, sp.problem, &out);
    EXPECT_NE(error.find(words), std::string::npos) << "'" << error << "' should say '" << words << "'";
    EXPECT_EQ(out, Eigen::VectorXd::Zero(sp.problem.rowCount())) << "λ is zero on a fault";
  };
  lcs::ConstraintForces unknown = good;
  unknown.forces[0].id = 12345;
  refused(unknown, "not in the step");
  lcs::ConstraintForces twice = good;
  twice.forces[1].id = twice.forces[0].id;
  refused(twice, "twice");
  lcs::ConstraintForces missing = good;
  missing.forces.pop_back();
  refused(missing, "nothing for contact id");
  lcs::ConstraintForces rows = good;
  rows.forces[0].lambda.push_back(0.0);
  refused(rows, "rows for contact id");
  lcs::ConstraintForces nan = good;
  nan.forces[2].lambda[0] = std::numeric_limits<double>::quiet_NaN();
  refused(nan, "not finite");
  sim->applyForces(lambda);
}

TEST(SceneMsgConversion, PosesAndMarkers) {
  scene::SceneSimulator sim(scene::loadNamedScene(LCS_SCENES_DIR, "mixed"));
  const scene::RigidBody& ball = sim.body("ball");
  const geometry_msgs::TransformStamped t = ros_layer::toTransformMsg(ball, header(0.0));
  EXPECT_EQ(t.header.frame_id, "world");
  EXPECT_EQ(t.child_frame_id, "ball");
  EXPECT_DOUBLE_EQ(t.transform.translation.z, ball.position.z());
  EXPECT_DOUBLE_EQ(t.transform.rotation.w, ball.orientation.normalized().w());

  const visualization_msgs::MarkerArray markers = ros_layer::bodyMarkers(sim.scene(), header(0.0));
  std::size_t shapes = 0;
  for (const scene::RigidBody& b : sim.scene().bodies) shapes += b.shapes.size();
  ASSERT_EQ(markers.markers.size(), shapes);
  for (const visualization_msgs::Marker& m : markers.markers) {
    EXPECT_EQ(m.header.frame_id, "world");
    EXPECT_GT(m.scale.x, 0.0);
    EXPECT_GT(m.color.a, 0.0f);
    if (m.ns == "ball") {
      EXPECT_EQ(m.type, visualization_msgs::Marker::SPHERE);
      EXPECT_DOUBLE_EQ(m.pose.position.z, ball.position.z());
    }
  }
}

}  // namespace
