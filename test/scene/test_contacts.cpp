// Contact generation: geometry of the contacts, normal convention for every shape pair,
// speculative contacts, persistent ids, and which pairs reach the narrowphase.
#include "lcp_contact_solver/scene/contact_generator.h"
#include "lcp_contact_solver/scene/scene_simulator.h"

#include "scene_test_util.h"

#include <gtest/gtest.h>

#include <set>

using namespace lcp_contact_solver;
using namespace lcp_contact_solver::scene;
using namespace scene_test;

namespace {
const std::string kDir = LCS_SCENES_DIR;
}

TEST(Contacts, SphereOnPlaneIsExact) {
  Scene s;
  s.bodies.push_back(ground());
  const double r = 0.1, depth = 0.002;
  s.bodies.push_back(dynamicBody("ball", sphereShape(r), 1.0, Eigen::Vector3d(0.3, -0.2, r - depth)));
  ContactGenerator gen(s);
  const std::vector<SceneContact> c = gen.generate();
  ASSERT_EQ(c.size(), 1u);
  const SceneContact& f = c[0];
  EXPECT_EQ(f.body_a_name, "ball");  // A is the dynamic body
  EXPECT_EQ(f.body_b_name, "ground");
  EXPECT_NEAR((f.normal - Eigen::Vector3d::UnitZ()).norm(), 0.0, 1e-12);  // from B (ground) into A
  EXPECT_NEAR(f.depth, depth, 1e-12);
  // Midway between the surfaces: the sphere's lowest point is at -depth, the plane at 0.
  EXPECT_NEAR((f.position - Eigen::Vector3d(0.3, -0.2, -0.5 * depth)).norm(), 0.0, 1e-12);
  EXPECT_NEAR(f.tangent1.dot(f.normal), 0.0, 1e-15);
  EXPECT_NEAR(f.tangent2.dot(f.normal), 0.0, 1e-15);
  EXPECT_NEAR((f.tangent1.cross(f.tangent2) - f.normal).norm(), 0.0, 1e-15);  // right-handed (t1, t2, n)
  EXPECT_NEAR((f.tangent1 - Eigen::Vector3d::UnitY()).norm(), 0.0, 1e-15);    // n × x
  EXPECT_EQ(f.type, core::ContactType::kFrictional);
  EXPECT_EQ(f.rows, 3);
  EXPECT_DOUBLE_EQ(f.mu, s.params.mu);
  EXPECT_EQ(f.id, makeContactId(1, 0, 0));
}

TEST(Contacts, SpeculativeWithinMarginOnly) {
  Scene s;
  s.params.contact_margin = 0.01;
  s.bodies.push_back(ground());
  s.bodies.push_back(dynamicBody("ball", sphereShape(0.1), 1.0, Eigen::Vector3d(0, 0, 0.1 + 0.004)));
  {
    ContactGenerator gen(s);
    const auto c = gen.generate();
    ASSERT_EQ(c.size(), 1u);
    EXPECT_NEAR(c[0].gap(), 0.004, 1e-12);
    EXPECT_NEAR(c[0].position.z(), 0.002, 1e-12);
  }
  s.bodies[1].position.z() = 0.1 + 0.011;
  ContactGenerator gen(s);
  EXPECT_TRUE(gen.generate().empty());
}

TEST(Contacts, BoxOnGroundHasFourCorners) {
  Scene s;
  s.bodies.push_back(ground());
  s.bodies.push_back(dynamicBody("box", boxShape(0.4, 0.2, 0.1), 1.0, Eigen::Vector3d(1, 2, 0.05)));
  ContactGenerator gen(s);
  const auto c = gen.generate();
  ASSERT_EQ(c.size(), 4u);
  std::set<std::pair<int, int>> corners;
  for (const SceneContact& f : c) {
    EXPECT_NEAR((f.normal - Eigen::Vector3d::UnitZ()).norm(), 0.0, 1e-12);
    EXPECT_NEAR(f.depth, 0.0, 1e-12);
    EXPECT_NEAR(f.position.z(), 0.0, 1e-12);
    corners.emplace(f.position.x() > 1 ? 1 : -1, f.position.y() > 2 ? 1 : -1);
    EXPECT_NEAR(std::abs(f.position.x() - 1), 0.2, 1e-12);
    EXPECT_NEAR(std::abs(f.position.y() - 2), 0.1, 1e-12);
  }
  EXPECT_EQ(corners.size(), 4u);
}

// For every supported shape pair, in both index orders, the normal points from B into A
// and the depth is the overlap along it.
TEST(Contacts, NormalConventionForEveryShapePair) {
  const std::vector<std::pair<std::string, CollisionShape>> shapes = {
      {"box", boxShape(0.2, 0.2, 0.2)}, {"sphere", sphereShape(0.1)}, {"cylinder", cylinderShape(0.1, 0.2)}};
  const double overlap = 0.003;
  for (const auto& [name_lo, lo] : shapes) {
    for (const auto& [name_hi, hi] : shapes) {
      for (bool lower_is_top : {false, true}) {
        SCOPED_TRACE(name_lo + " / " + name_hi + (lower_is_top ? " (lower index on top)" : ""));
        // Both extend 0.1 along z from their centres; stack them with the given overlap.
        Scene s;
        const Eigen::Vector3d bottom(0, 0, 0), top(0, 0, 0.2 - overlap);
        s.bodies.push_back(dynamicBody("lo", lo, 1.0, lower_is_top ? top : bottom));
        s.bodies.push_back(dynamicBody("hi", hi, 1.0, lower_is_top ? bottom : top));
        ContactGenerator gen(s);
        const auto c = gen.generate();
        ASSERT_FALSE(c.empty());
        for (const SceneContact& f : c) {
          EXPECT_EQ(f.body_a, 0);  // both dynamic: A is the lower index
          const Eigen::Vector3d expected(0, 0, lower_is_top ? 1.0 : -1.0);
          EXPECT_NEAR((f.normal - expected).norm(), 0.0, 1e-4);
          EXPECT_NEAR(f.depth, overlap, 1e-4);
        }
      }
    }
  }
}

TEST(Contacts, IdsPersistAcrossSteps) {
  SceneParams params = loadSceneParams(kDir + "/box_stack.yaml");
  SceneSimulator sim(loadSceneFromUrdfFile(kDir + "/box_stack.urdf", params));
  sim.step();
  const std::vector<SceneContact> first = sim.lastProblem().frames;
  ASSERT_EQ(first.size(), 20u);  // 5 face contacts × 4 corners
  std::set<std::int64_t> ids;
  for (const SceneContact& f : first) ids.insert(f.id);
  EXPECT_EQ(ids.size(), first.size()) << "ids are unique";
  for (int k = 0; k < 50; ++k) sim.step();
  const std::vector<SceneContact>& later = sim.lastProblem().frames;
  ASSERT_EQ(later.size(), first.size());
  for (std::size_t i = 0; i < first.size(); ++i) {
    EXPECT_EQ(later[i].id, first[i].id);
    EXPECT_NEAR((later[i].position - first[i].position).norm(), 0.0, 1e-3);
  }
  EXPECT_EQ(sim.lastStats().generation.new_ids, 0);
  // A second simulator of the same scene produces the same ids: deterministic.
  SceneSimulator again(loadSceneFromUrdfFile(kDir + "/box_stack.urdf", params));
  again.step();
  for (std::size_t i = 0; i < first.size(); ++i) EXPECT_EQ(again.lastProblem().frames[i].id, first[i].id);
}

TEST(Contacts, DisabledPairsAreNotTested) {
  // Two overlapping boxes on the ground.
  Scene s;
  s.bodies.push_back(ground());
  s.bodies.push_back(dynamicBody("a", boxShape(0.2, 0.2, 0.2), 1.0, Eigen::Vector3d(0, 0, 0.1)));
  s.bodies.push_back(dynamicBody("b", boxShape(0.2, 0.2, 0.2), 1.0, Eigen::Vector3d(0.15, 0, 0.1)));
  s.bodies.push_back(ground("slab"));  // a second static body overlapping the ground: never tested
  {
    ContactGenerator gen(s);
    const auto c = gen.generate();
    // a–ground, b–ground, a–slab, b–slab, a–b
    EXPECT_EQ(gen.lastStats().narrowphase_tests, 5);
    EXPECT_EQ(gen.narrowphaseTests(), 5);
    bool ab = false;
    for (const SceneContact& f : c) ab |= (f.body_a_name == "a" && f.body_b_name == "b");
    EXPECT_TRUE(ab);
  }
  s.params.disable_collisions.emplace_back("b", "a");
  s.params.disable_collisions.emplace_back("a", "slab");
  s.params.disable_collisions.emplace_back("b", "slab");
  ContactGenerator gen(s);
  for (int k = 0; k < 3; ++k) {
    const auto c = gen.generate();
    EXPECT_EQ(gen.lastStats().narrowphase_tests, 2);
    EXPECT_EQ(gen.lastStats().skipped_disabled, 3);
    for (const SceneContact& f : c) EXPECT_EQ(f.body_b_name, "ground");
  }
  EXPECT_EQ(gen.narrowphaseTests(), 6);
  gen.resetCounters();
  EXPECT_EQ(gen.narrowphaseTests(), 0);
}

TEST(Contacts, LinksWithoutCollisionAndStaticPairsAreSkipped) {
  // The sphere pile: 4 static walls + ground (static-static pairs overlap at the corners)
  // and the world link without geometry.
  SceneSimulator sim(loadNamedScene(kDir, "sphere_pile"));
  const StepProblem& sp = sim.buildStep();
  for (const SceneContact& f : sp.frames) {
    EXPECT_FALSE(sim.body(f.body_a).is_static && sim.body(f.body_b).is_static);
    EXPECT_NE(f.body_a_name, "world");
    EXPECT_NE(f.body_b_name, "world");
  }
  // Only pairs with a ball reach the narrowphase: at most each ball against the ground and
  // four walls, plus ball–ball pairs whose boxes overlap (none at the start).
  EXPECT_LE(sim.contactGenerator().lastStats().narrowphase_tests, 13 * 5);
  sim.applyForces(Eigen::VectorXd::Zero(sp.problem.rowCount()));
}

TEST(Contacts, PerPairFrictionAndFrictionlessRows) {
  SceneSimulator sim(loadNamedScene(kDir, "mixed"));
  const StepProblem& sp = sim.buildStep();
  int slick = 0, grip = 0, ball = 0;
  for (std::size_t i = 0; i < sp.frames.size(); ++i) {
    const SceneContact& f = sp.frames[i];
    const core::Contact& c = sp.problem.contacts[i];
    EXPECT_EQ(c.id, f.id);
    EXPECT_EQ(c.type, f.type);
    EXPECT_EQ(c.rows, f.rows);
    if (f.body_a_name == "box_slick" && f.body_b_name == "ground_plane") {
      ++slick;
      EXPECT_EQ(c.type, core::ContactType::kFrictionless);
      EXPECT_EQ(c.rows, 1);
      EXPECT_EQ(c.mu, 0.0);
    } else if (f.body_a_name == "box_grip") {
      ++grip;
      EXPECT_EQ(c.type, core::ContactType::kFrictional);
      EXPECT_EQ(c.rows, 3);
      EXPECT_DOUBLE_EQ(c.mu, 0.5);
    } else {
      ++ball;
      EXPECT_EQ(c.type, core::ContactType::kFrictional);
    }
  }
  EXPECT_EQ(slick, 4);
  EXPECT_EQ(grip, 4);
  EXPECT_EQ(ball, 1);
  EXPECT_EQ(sp.problem.rowCount(), 4 * 1 + 4 * 3 + 3);
  sim.applyForces(Eigen::VectorXd::Zero(sp.problem.rowCount()));
}
