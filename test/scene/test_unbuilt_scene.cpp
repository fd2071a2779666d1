// The scene's body form (`compliance: bodies`, RigidContactModel::bodyCompliance) and the
// in-process simulator running the unbuilt solve (solver.build_lcp = false): the body form
// is the same W, and the unbuilt closed loop reproduces the built one (block-sparse W) on
// the shipped box stack and sphere pile, step by step.
#include "lcp_contact_solver/core/body_compliance.h"
#include "lcp_contact_solver/scene/compliance.h"
#include "lcp_contact_solver/scene/scene_simulator.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace lcp_contact_solver;
using namespace lcp_contact_solver::scene;

namespace {

const std::string kDir = LCS_SCENES_DIR;

SceneParams params(const std::string& name, ComplianceStorage storage, bool build_lcp) {
  SceneParams p = loadSceneParams(kDir + "/" + name + ".yaml");
  p.compliance = storage;
  p.solver.solver = core::SolverKind::kNlgs;
  p.solver.tolerance = 1e-10;
  p.solver.maxIt = 20000;
  p.solver.build_lcp = build_lcp;
  return p;
}

SceneSimulator simulator(const std::string& name, ComplianceStorage storage, bool build_lcp) {
  return SceneSimulator(loadSceneFromUrdfFile(kDir + "/" + name + ".urdf", params(name, storage, build_lcp)));
}

double relDiff(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  if (a.size() != b.size()) return std::numeric_limits<double>::infinity();
  if (a.size() == 0) return 0.0;
  const double scale = std::max({a.cwiseAbs().maxCoeff(), b.cwiseAbs().maxCoeff(), 1e-300});
  return (a - b).cwiseAbs().maxCoeff() / scale;
}

}  // namespace

TEST(UnbuiltScene, YamlSelectsTheBodyFormAndTheUnbuiltSolve) {
  const SceneParams p =
      parseSceneParams("compliance: bodies\nsolver: {name: nlgs, build_lcp: false}\n", "inline.yaml");
  EXPECT_EQ(p.compliance, ComplianceStorage::kBodies);
  EXPECT_FALSE(p.solver.build_lcp);
  EXPECT_STREQ(complianceStorageName(ComplianceStorage::kBodies), "bodies");
  try {
    parseSceneParams("compliance: body\n", "inline.yaml");
    FAIL() << "an unknown storage was accepted";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("dense, block_sparse or bodies"), std::string::npos) << e.what();
  }
}

TEST(UnbuiltScene, BodyFormIsTheAssembledW) {
  for (const char* name : {"box_stack", "sphere_pile", "mixed"}) {
    SCOPED_TRACE(name);
    SceneSimulator sim = simulator(name, ComplianceStorage::kBodies, false);
    for (int k = 0; k < 40; ++k) sim.step();  // let things touch
    const StepProblem& sp = sim.buildStep();
    ASSERT_FALSE(sp.problem.contacts.empty());
    ASSERT_TRUE(sp.problem.bodies);
    EXPECT_EQ(core::complianceRows(sp.problem.W), 0) << "no W beside the body form";
    EXPECT_EQ(core::validateProblem(sp.problem), "");
    const RigidContactModel model(sim.scene(), sp.frames);
    const Eigen::MatrixXd W = std::get<Eigen::MatrixXd>(model.compliance(sp.dt, ComplianceStorage::kDense));
    const Eigen::MatrixXd from_bodies = sp.problem.bodies->toDense();
    EXPECT_LE((from_bodies - W).cwiseAbs().maxCoeff(), 1e-14 * W.cwiseAbs().maxCoeff());
    // Same block pattern as the scene's block-sparse W.
    const core::BlockSparseMatrix sparse =
        std::get<core::BlockSparseMatrix>(model.compliance(sp.dt, ComplianceStorage::kBlockSparse));
    const core::BlockSparseMatrix assembled = sp.problem.bodies->assemble();
    EXPECT_EQ(assembled.block_col, sparse.block_col);
    EXPECT_EQ(assembled.row_start, sparse.row_start);
    // The body form grows with bodies + rows, W with the pairs.
    EXPECT_EQ(sp.problem.bodies->bodyCount(), sim.bodyCount());
    sim.applyForces(Eigen::VectorXd::Zero(sp.problem.rowCount()));
  }
}

TEST(UnbuiltScene, ClosedLoopMatchesTheBuiltSolve) {
  for (const char* name : {"box_stack", "sphere_pile", "mixed"}) {
    SCOPED_TRACE(name);
    SceneSimulator unbuilt = simulator(name, ComplianceStorage::kBodies, false);
    SceneSimulator built = simulator(name, ComplianceStorage::kBlockSparse, true);
    SceneSimulator assembled = simulator(name, ComplianceStorage::kBodies, true);  // build_lcp: W once
    int solved = 0, steps = 0;
    for (int k = 0; k < 120; ++k, ++steps) {
      unbuilt.step();
      built.step();
      assembled.step();
      ASSERT_EQ(unbuilt.lastForces().size(), built.lastForces().size()) << "step " << k;
      if (unbuilt.lastStats().solved) {
        ++solved;
        ASSERT_TRUE(unbuilt.lastSolve().unbuilt) << "step " << k;
        EXPECT_FALSE(assembled.lastSolve().unbuilt);
        EXPECT_FALSE(built.lastSolve().unbuilt);
        EXPECT_EQ(unbuilt.lastSolve().status, built.lastSolve().status) << "step " << k;
        EXPECT_LE(unbuilt.lastSolve().residual, 1e-10) << "step " << k << ": " << unbuilt.lastSolve().message;
        EXPECT_LT(relDiff(unbuilt.lastForces(), built.lastForces()), 1e-8) << "step " << k;
        EXPECT_LT(relDiff(assembled.lastForces(), built.lastForces()), 1e-8) << "step " << k;
      }
    }
    EXPECT_GT(solved, steps / 2);
    double diff = 0.0;
    for (int i = 0; i < unbuilt.bodyCount(); ++i)
      diff = std::max(diff, (unbuilt.body(i).position - built.body(i).position).norm());
    EXPECT_LT(diff, 1e-9);
  }
}
