// Compliance W = dt² J M⁻¹ Jᵀ (dense and block-sparse) and d_free.
#include "lcp_contact_solver/core/stabilization.h"
#include "lcp_contact_solver/scene/compliance.h"
#include "lcp_contact_solver/scene/scene_simulator.h"

#include "scene_test_util.h"

#include <gtest/gtest.h>

using namespace lcp_contact_solver;
using namespace lcp_contact_solver::scene;
using namespace scene_test;

namespace {
const std::string kDir = LCS_SCENES_DIR;

// W (both storages) against dt² J M⁻¹ Jᵀ assembled from the full matrices.
void checkCompliance(const Scene& scene, const std::vector<SceneContact>& frames, double dt) {
  ASSERT_FALSE(frames.empty());
  const RigidContactModel model(scene, frames);
  const Eigen::MatrixXd J = model.denseJacobian();
  const Eigen::MatrixXd reference = dt * dt * J * model.denseInverseMass() * J.transpose();
  const Eigen::MatrixXd dense = std::get<Eigen::MatrixXd>(model.compliance(dt, ComplianceStorage::kDense));
  const core::ComplianceMatrix sparse_w = model.compliance(dt, ComplianceStorage::kBlockSparse);
  const core::BlockSparseMatrix& sparse = std::get<core::BlockSparseMatrix>(sparse_w);
  EXPECT_EQ(sparse.validate(), "");
  const double scale = reference.cwiseAbs().maxCoeff();
  EXPECT_LE((dense - reference).cwiseAbs().maxCoeff(), 1e-14 * scale);
  EXPECT_LE((sparse.toDense() - dense).cwiseAbs().maxCoeff(), 1e-14 * scale);
  EXPECT_LE((dense - dense.transpose()).cwiseAbs().maxCoeff(), 1e-14 * scale);

  // Only pairs of contacts sharing a dynamic body have a block.
  for (int i = 0; i < sparse.blockCount(); ++i) {
    for (int k = sparse.row_start[i]; k < sparse.row_start[i + 1]; ++k) {
      const int j = sparse.block_col[k];
      const SceneContact &fi = frames[i], &fj = frames[j];
      auto dyn = [&](int b) { return !scene.bodies[b].is_static; };
      const bool share = (dyn(fi.body_a) && (fi.body_a == fj.body_a || fi.body_a == fj.body_b)) ||
                         (dyn(fi.body_b) && (fi.body_b == fj.body_a || fi.body_b == fj.body_b));
      EXPECT_TRUE(share) << "block (" << i << ", " << j << ") without a shared dynamic body";
    }
  }
  // And every such pair has one.
  int expected_blocks = 0;
  for (std::size_t i = 0; i < frames.size(); ++i)
    for (std::size_t j = 0; j < frames.size(); ++j) {
      const SceneContact &fi = frames[i], &fj = frames[j];
      auto dyn = [&](int b) { return !scene.bodies[b].is_static; };
      const bool share = (dyn(fi.body_a) && (fi.body_a == fj.body_a || fi.body_a == fj.body_b)) ||
                         (dyn(fi.body_b) && (fi.body_b == fj.body_a || fi.body_b == fj.body_b));
      expected_blocks += share ? 1 : 0;
    }
  EXPECT_EQ(static_cast<int>(sparse.block_col.size()), expected_blocks);
}
}  // namespace

TEST(Compliance, GapTermKeepsOnlySpeculativeGaps) {
  EXPECT_DOUBLE_EQ(gapTerm(0.004), 0.004);
  EXPECT_DOUBLE_EQ(gapTerm(-0.004), 0.0);  // penetration: the solver's erp term
  EXPECT_DOUBLE_EQ(gapTerm(0.0), 0.0);
}

TEST(Compliance, SingleSphereOnGroundAnalytic) {
  Scene s;
  s.bodies.push_back(ground());
  const double m = 2.0, r = 0.1, dt = 0.01, gap = 0.003;
  s.bodies.push_back(dynamicBody("ball", sphereShape(r), m, Eigen::Vector3d(0, 0, r + gap)));
  s.bodies[1].linear_velocity = Eigen::Vector3d(0.5, 0, -0.2);
  ContactGenerator gen(s);
  const auto frames = gen.generate();
  ASSERT_EQ(frames.size(), 1u);
  for (ComplianceStorage storage : {ComplianceStorage::kDense, ComplianceStorage::kBlockSparse}) {
    const core::Problem p = buildProblem(s, frames, freeVelocities(s, dt), dt, storage);
    const Eigen::MatrixXd W = core::toDense(p.W);
    ASSERT_EQ(W.rows(), 3);
    // At the bottom point r ∥ n: the normal row sees only the mass.
    EXPECT_NEAR(W(0, 0), dt * dt / m, 1e-15);
    // Tangent rows: 1/m + l²/I with the lever arm l = r + gap/2 (the point is midway
    // between the surfaces); at contact (l = r): 1/m + r²/(2/5 m r²) = 3.5/m.
    const double l = r + 0.5 * gap, I = 0.4 * m * r * r;
    EXPECT_NEAR(W(1, 1), dt * dt * (1.0 / m + l * l / I), 1e-15);
    EXPECT_NEAR(W(2, 2), dt * dt * (1.0 / m + l * l / I), 1e-15);
    EXPECT_NEAR(W(0, 1), 0.0, 1e-18);
    EXPECT_NEAR(W(1, 2), 0.0, 1e-18);
    // d_free: gap + dt v_free·n, tangents dt v_free·t.
    const double vz_free = -0.2 - 9.81 * dt;
    EXPECT_NEAR(p.d_free[0], gap + dt * vz_free, 1e-15);
    EXPECT_NEAR(p.d_free[1], dt * frames[0].tangent1.dot(Eigen::Vector3d(0.5, 0, vz_free)), 1e-15);
    EXPECT_NEAR(p.d_free[2], dt * frames[0].tangent2.dot(Eigen::Vector3d(0.5, 0, vz_free)), 1e-15);
  }
  // Touching (gap 0): W_nn = dt²/m, W_tt = 3.5 dt²/m.
  {
    Scene t = s;
    t.bodies[1].position.z() = r;
    ContactGenerator g(t);
    const auto f = g.generate();
    ASSERT_EQ(f.size(), 1u);
    const Eigen::MatrixXd W =
        core::toDense(buildProblem(t, f, freeVelocities(t, dt), dt, ComplianceStorage::kBlockSparse).W);
    EXPECT_NEAR(W(0, 0), dt * dt / m, 1e-15);
    EXPECT_NEAR(W(1, 1), 3.5 * dt * dt / m, 1e-15);
    EXPECT_NEAR(W(2, 2), 3.5 * dt * dt / m, 1e-15);
  }
  // Penetration: d_free holds the motion only; the contact carries the gap and the scene's
  // erp, and the solver adds erp·gap (the solved problem's d_free).
  s.bodies[1].position.z() = r - gap;
  s.params.erp = 0.2;
  ContactGenerator gen2(s);
  const auto pen = gen2.generate();
  ASSERT_EQ(pen.size(), 1u);
  core::Problem p = buildProblem(s, pen, freeVelocities(s, dt), dt, ComplianceStorage::kDense);
  EXPECT_NEAR(p.d_free[0], dt * (-0.2 - 9.81 * dt), 1e-15);
  EXPECT_NEAR(p.contacts[0].gap, -gap, 1e-12);
  EXPECT_EQ(p.contacts[0].erp, 0.2);
  ASSERT_EQ(core::applyStabilization(core::SolverParams(), &p), "");
  EXPECT_NEAR(p.d_free[0], -0.2 * gap + dt * (-0.2 - 9.81 * dt), 1e-15);
}

TEST(Compliance, DenseEqualsBlockSparseOnScenes) {
  // Settled and in-flight configurations with rotated bodies and shared bodies.
  for (const char* name : {"box_stack", "sphere_pile", "mixed", "incline"}) {
    SCOPED_TRACE(name);
    SceneSimulator sim(loadNamedScene(kDir, name));
    for (int k = 0; k < 30; ++k) sim.step();
    const StepProblem& sp = sim.buildStep();
    checkCompliance(sim.scene(), sp.frames, sp.dt);
    EXPECT_EQ(core::validateProblem(sp.problem), "");
    sim.applyForces(Eigen::VectorXd::Zero(sp.problem.rowCount()));
  }
}

TEST(Compliance, TwoDynamicBodiesShareBlocks) {
  // A tilted box resting on a sphere resting on the ground: contacts of the two pairs share
  // the sphere, the box–sphere contact has both bodies dynamic.
  Scene s;
  s.bodies.push_back(ground());
  s.bodies.push_back(dynamicBody("ball", sphereShape(0.1), 1.0, Eigen::Vector3d(0, 0, 0.1)));
  s.bodies.push_back(dynamicBody("box", boxShape(0.3, 0.3, 0.1), 2.0, Eigen::Vector3d(0.02, 0.01, 0.249)));
  s.bodies[2].orientation =
      Eigen::Quaterniond(Eigen::AngleAxisd(0.05, Eigen::Vector3d(1, 1, 0).normalized()));
  ContactGenerator gen(s);
  const auto frames = gen.generate();
  ASSERT_GE(frames.size(), 2u);
  checkCompliance(s, frames, 0.01);
}

TEST(Compliance, ForcesMoveBodiesAsJTransposeLambda) {
  // v_new = v_free + dt M⁻¹ Jᵀ λ: with λ from the solver the sphere's normal velocity makes
  // d_n = 0 exactly (resting contact), and the applied wrench is n λ_n at the point.
  Scene s;
  s.bodies.push_back(ground());
  s.bodies.push_back(dynamicBody("ball", sphereShape(0.1), 2.0, Eigen::Vector3d(0, 0, 0.1)));
  SceneSimulator sim(s);
  const StepProblem& sp = sim.buildStep();
  ASSERT_EQ(sp.problem.contacts.size(), 1u);
  Eigen::VectorXd lambda(3);
  lambda << 2.0 * 9.81, 0.0, 0.0;
  sim.applyForces(lambda);
  EXPECT_NEAR(sim.body("ball").linear_velocity.norm(), 0.0, 1e-15);
  const auto w = sim.lastContactWrenches();
  EXPECT_NEAR((w[1].head<3>() - Eigen::Vector3d(0, 0, 2.0 * 9.81)).norm(), 0.0, 1e-12);
  EXPECT_NEAR(w[1].tail<3>().norm(), 0.0, 1e-12);
  // Wrong sizes and double calls are refused.
  EXPECT_THROW(sim.applyForces(lambda), SceneError);
  sim.buildStep();
  EXPECT_THROW(sim.buildStep(), SceneError);
  EXPECT_THROW(sim.applyForces(Eigen::VectorXd::Zero(2)), SceneError);
}
