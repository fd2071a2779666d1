// Unit tests of the ROS layer that need no master: message conversions, parameters,
// markers, pairing and the debug summary.
#include "lcp_contact_solver/core/body_compliance.h"
#include "lcp_contact_solver/core/contact_solver.h"
#include "lcp_contact_solver/core/residual.h"
#include "lcp_contact_solver/ros/msg_conversion/msg_conversion.h"
#include "lcp_contact_solver/ros/node/cycle_log.h"
#include "lcp_contact_solver/ros/node/cycle_solver.h"
#include "lcp_contact_solver/ros/node/input_queue.h"
#include "lcp_contact_solver/ros/node/markers.h"
#include "lcp_contact_solver/ros/node/solve_rate_status.h"
#include "lcp_contact_solver/ros/node/solver_params_ros.h"
#include "test_scene.h"

#include <gtest/gtest.h>
#include <Eigen/Geometry>
#include <boost/make_shared.hpp>

#include <cmath>
#include <functional>
#include <limits>
#include <set>
#include <thread>

namespace lcs = lcp_contact_solver;
using namespace lcp_contact_solver_ros;
using lcp_contact_solver_test::makeScene;
using lcp_contact_solver_test::Scene;

namespace {

Eigen::Vector3d toEigen(const geometry_msgs::Vector3& v) { return {v.x, v.y, v.z}; }
Eigen::Vector3d toEigen(const geometry_msgs::Point& p) { return {p.x, p.y, p.z}; }

struct Converted {
  lcs::core::Problem problem;
  std::vector<ContactFrame> frames;
  std::string error;
};

Converted convert(const Scene& scene, int max_rows = 0) {
  Converted c;
  c.error = toProblem(scene.contacts, scene.compliance, max_rows, &c.problem, &c.frames);
  return c;
}

const ros::Time kStamp(100, 0);

}  // namespace

// ---- tangents -------------------------------------------------------------------------

TEST(DeriveTangents, RightHandedOrthonormalAndDeterministic) {
  for (const Eigen::Vector3d& raw :
       {Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, -1, 0),
        Eigen::Vector3d(1, 1, 1), Eigen::Vector3d(-0.3, 0.2, 0.9)}) {
    const Eigen::Vector3d n = raw.normalized();
    Eigen::Vector3d t1, t2, again1, again2;
    deriveTangents(n, &t1, &t2);
    deriveTangents(n, &again1, &again2);
    EXPECT_NEAR(t1.norm(), 1.0, 1e-12);
    EXPECT_NEAR(t2.norm(), 1.0, 1e-12);
    EXPECT_NEAR(t1.dot(n), 0.0, 1e-12);
    EXPECT_NEAR(t2.dot(n), 0.0, 1e-12);
    EXPECT_NEAR(t1.dot(t2), 0.0, 1e-12);
    EXPECT_NEAR((n.cross(t1) - t2).norm(), 0.0, 1e-12);
    EXPECT_EQ(t1, again1);
    EXPECT_EQ(t2, again2);
  }
  Eigen::Vector3d t1, t2;
  deriveTangents(Eigen::Vector3d::UnitZ(), &t1, &t2);  // least aligned axis: x
  EXPECT_NEAR((t1 - Eigen::Vector3d::UnitY()).norm(), 0.0, 1e-12);
  EXPECT_NEAR((t2 + Eigen::Vector3d::UnitX()).norm(), 0.0, 1e-12);
}

// ---- contacts and compliance -----------------------------------------------------------

TEST(ToProblem, ReadsContactsInOrder) {
  const Scene scene = makeScene(10, kStamp);
  const Converted c = convert(scene);
  ASSERT_EQ(c.error, "");
  ASSERT_EQ(c.problem.contacts.size(), 4u);
  EXPECT_EQ(c.problem.rowCount(), 9);
  EXPECT_EQ(c.problem.contacts[0].id, 10);
  EXPECT_EQ(c.problem.contacts[0].type, lcs::core::ContactType::kFrictional);
  EXPECT_EQ(c.problem.contacts[0].mu, -1.0);  // MU_DEFAULT reaches the core as "not given"
  EXPECT_EQ(c.problem.contacts[1].mu, 0.2);
  EXPECT_EQ(c.problem.contacts[2].type, lcs::core::ContactType::kFrictionless);
  EXPECT_EQ(c.problem.contacts[2].rows, 1);
  EXPECT_EQ(c.problem.contacts[3].type, lcs::core::ContactType::kBilateral);
  EXPECT_EQ(c.problem.contacts[3].rows, 2);
  Eigen::VectorXd d_free(9);
  d_free << -0.02, 0.01, 0.0, -0.01, -0.02, 0.005, -0.015, 0.01, -0.01;
  EXPECT_EQ(c.problem.d_free, d_free);
  EXPECT_EQ(lcs::core::toDense(c.problem.W), lcp_contact_solver_test::coupledCompliance(9));
}

TEST(ToProblem, FramesNormalizeAndDeriveTangents) {
  const Converted c = convert(makeScene(10, kStamp));
  ASSERT_EQ(c.error, "");
  EXPECT_TRUE(c.frames[0].derived_tangents);
  EXPECT_FALSE(c.frames[1].derived_tangents);
  EXPECT_NEAR((c.frames[1].tangent2 - Eigen::Vector3d(0, 0.8, -0.6)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((c.frames[2].normal - Eigen::Vector3d::UnitZ()).norm(), 0.0, 1e-12);  // (0,0,2) normalized
  EXPECT_NEAR((c.frames[2].position - Eigen::Vector3d(0, 0.2, 0.1)).norm(), 0.0, 1e-12);
}

TEST(ToProblem, BlockSparseEqualsDense) {
  const Converted dense = convert(makeScene(10, kStamp));
  const Converted sparse = convert(makeScene(10, kStamp, true));
  ASSERT_EQ(sparse.error, "");
  ASSERT_TRUE(std::holds_alternative<lcs::core::BlockSparseMatrix>(sparse.problem.W));
  EXPECT_EQ(lcs::core::toDense(sparse.problem.W), lcs::core::toDense(dense.problem.W));
  const lcs::core::SolveResult a = lcs::core::solveProblem(dense.problem, defaultSolverParams());
  const lcs::core::SolveResult b = lcs::core::solveProblem(sparse.problem, defaultSolverParams());
  EXPECT_TRUE(a.converged);
  EXPECT_LT((a.forces - b.forces).norm(), 1e-9);
}

// A message in (row, column) block order is read without sorting; any other order gives the
// same matrix through the sort.
TEST(ToProblem, BlockSparseInAnyBlockOrderIsTheSameMatrix) {
  const Scene scene = makeScene(10, kStamp, true);
  const Converted in_order = convert(scene);
  ASSERT_EQ(in_order.error, "");
  const int sizes[] = {3, 3, 1, 2};
  const lcs::Compliance& W = scene.compliance;
  std::vector<std::size_t> start(W.block_rows.size() + 1, 0);
  for (std::size_t k = 0; k < W.block_rows.size(); ++k)
    start[k + 1] = start[k] + sizes[W.block_rows[k]] * sizes[W.block_cols[k]];
  Scene reversed = scene;
  reversed.compliance.block_rows.clear();
  reversed.compliance.block_cols.clear();
  reversed.compliance.block_data.clear();
  for (std::size_t k = W.block_rows.size(); k-- > 0;) {
    reversed.compliance.block_rows.push_back(W.block_rows[k]);
    reversed.compliance.block_cols.push_back(W.block_cols[k]);
    reversed.compliance.block_data.insert(reversed.compliance.block_data.end(),
                                          W.block_data.begin() + start[k],
                                          W.block_data.begin() + start[k + 1]);
  }
  ASSERT_GT(W.block_rows.size(), 2u);
  const Converted sorted = convert(reversed);
  ASSERT_EQ(sorted.error, "");
  const auto& a = std::get<lcs::core::BlockSparseMatrix>(in_order.problem.W);
  const auto& b = std::get<lcs::core::BlockSparseMatrix>(sorted.problem.W);
  EXPECT_EQ(a.values, b.values);
  EXPECT_EQ(a.block_col, b.block_col);
  EXPECT_EQ(a.row_start, b.row_start);
  EXPECT_EQ(a.value_start, b.value_start);
  EXPECT_EQ(a.validate(), "");
  // A repeated block is found in either order.
  for (const Scene* s : {&scene, static_cast<const Scene*>(&reversed)}) {
    Scene twice = *s;
    twice.compliance.block_rows.push_back(twice.compliance.block_rows.back());
    twice.compliance.block_cols.push_back(twice.compliance.block_cols.back());
    const std::size_t n =
        sizes[twice.compliance.block_rows.back()] * sizes[twice.compliance.block_cols.back()];
    twice.compliance.block_data.insert(twice.compliance.block_data.end(), n, 0.5);
    EXPECT_NE(convert(twice).error.find("is given twice"), std::string::npos) << convert(twice).error;
  }
}

// CycleSolver leaves validation to the core's solve: a non-finite W is still refused, with
// the sentence toProblem gives.
TEST(CycleSolver, ANonFiniteComplianceIsRejectedWithToProblemsSentence) {
  Scene scene = makeScene(10, kStamp, true);
  scene.compliance.block_data[4] = std::numeric_limits<double>::quiet_NaN();
  const Converted checked = convert(scene);
  ASSERT_NE(checked.error, "");
  CycleSolver cycle(defaultSolverParams());
  const CycleOutput out = cycle.solve(scene.contacts, scene.compliance);
  EXPECT_TRUE(out.rejected());
  EXPECT_EQ(out.error, checked.error);
  EXPECT_EQ(out.stats.status_code, lcs::SolverStats::INVALID_INPUT);
  EXPECT_FALSE(out.has_forces);
}

TEST(ToProblem, BlockSparseWithMissingBlocksIsZeroThere) {
  Scene scene = makeScene(10, kStamp, true);
  // Keep only the diagonal blocks.
  lcs::Compliance diagonal;
  diagonal.storage = lcs::Compliance::STORAGE_BLOCK_SPARSE;
  diagonal.rows = 9;
  const int sizes[] = {3, 3, 1, 2};
  std::size_t at = 0;
  for (std::size_t k = 0; k < scene.compliance.block_rows.size(); ++k) {
    const int i = scene.compliance.block_rows[k], j = scene.compliance.block_cols[k];
    const std::size_t n = sizes[i] * sizes[j];
    if (i == j) {
      diagonal.block_rows.push_back(i);
      diagonal.block_cols.push_back(j);
      diagonal.block_data.insert(diagonal.block_data.end(), scene.compliance.block_data.begin() + at,
                                 scene.compliance.block_data.begin() + at + n);
    }
    at += n;
  }
  scene.compliance = diagonal;
  const Converted c = convert(scene);
  ASSERT_EQ(c.error, "");
  const Eigen::MatrixXd W = lcs::core::toDense(c.problem.W),
                        full = lcp_contact_solver_test::coupledCompliance(9);
  EXPECT_EQ(W(0, 3), 0.0);
  EXPECT_EQ(W(6, 6), full(6, 6));
  EXPECT_EQ(W.block(7, 7, 2, 2), full.block(7, 7, 2, 2));
}

struct BadCase {
  const char* what;
  std::function<void(Scene*)> spoil;
  const char* expected;  // part of the error sentence
};

class ToProblemRejects : public ::testing::TestWithParam<BadCase> {};

TEST_P(ToProblemRejects, NamesTheFault) {
  Scene scene = makeScene(10, kStamp, std::string(GetParam().what).find("block") != std::string::npos);
  GetParam().spoil(&scene);
  const Converted c = convert(scene, 30000);
  EXPECT_NE(c.error.find(GetParam().expected), std::string::npos) << "error: '" << c.error << "'";
}

const double kNaN = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();

INSTANTIATE_TEST_SUITE_P(
    Faults, ToProblemRejects,
    ::testing::Values(
        BadCase{"empty", [](Scene* s) { s->contacts.contacts.clear(); }, "empty"},
        BadCase{"nan_dfree", [](Scene* s) { s->contacts.contacts[1].d_free[0] = kNaN; },
                "d_free holds a non-finite"},
        BadCase{"inf_position", [](Scene* s) { s->contacts.contacts[0].position.y = kInf; },
                "contact 0 (id 10) has a non-finite position"},
        BadCase{"nan_normal", [](Scene* s) { s->contacts.contacts[2].normal.x = kNaN; },
                "non-finite direction"},
        BadCase{"zero_normal",
                [](Scene* s) { s->contacts.contacts[2].normal = lcp_contact_solver_test::vec(0, 0, 0); },
                "contact 2 (id 12) has a zero normal"},
        BadCase{"negative_mu", [](Scene* s) { s->contacts.contacts[1].mu = -0.5; }, "negative mu"},
        BadCase{"nan_mu", [](Scene* s) { s->contacts.contacts[1].mu = kNaN; }, "non-finite mu"},
        BadCase{"dfree_size", [](Scene* s) { s->contacts.contacts[0].d_free.pop_back(); },
                "2 d_free values for 3 rows"},
        BadCase{"rows_field", [](Scene* s) { s->contacts.contacts[2].rows = 3; },
                "rows=3 but its type has 1"},
        BadCase{"bilateral_rows", [](Scene* s) { s->contacts.contacts[3].rows = 0; },
                "bilateral with rows=0"},
        BadCase{"unknown_type", [](Scene* s) { s->contacts.contacts[0].type = 7; }, "unknown type 7"},
        BadCase{"duplicate_id", [](Scene* s) { s->contacts.contacts[3].id = 10; },
                "contact 3 (id 10) repeats an id"},
        BadCase{"one_tangent",
                [](Scene* s) { s->contacts.contacts[1].tangent2 = lcp_contact_solver_test::vec(0, 0, 0); },
                "one tangent"},
        BadCase{"skew_tangent",
                [](Scene* s) { s->contacts.contacts[1].tangent1 = lcp_contact_solver_test::vec(1, 0, 1); },
                "not orthogonal"},
        BadCase{"compliance_rows", [](Scene* s) { s->compliance.rows = 8; }, "rows=8, the contacts have 9"},
        BadCase{"dense_size", [](Scene* s) { s->compliance.data.pop_back(); }, "80 values, 9x9 expected"},
        BadCase{"nan_w", [](Scene* s) { s->compliance.data[40] = kNaN; }, "W holds a non-finite value"},
        BadCase{"unknown_storage", [](Scene* s) { s->compliance.storage = 9; }, "unknown storage 9"},
        BadCase{"too_many_rows",
                [](Scene* s) {
                  s->contacts.contacts.resize(20000, s->contacts.contacts[0]);
                  for (int i = 0; i < 20000; ++i) s->contacts.contacts[i].id = i;
                },
                "more than the limit of 30000"},
        BadCase{"block_index", [](Scene* s) { s->compliance.block_cols[0] = 4; }, "beyond the 4 contacts"},
        BadCase{"block_twice", [](Scene* s) { s->compliance.block_cols[1] = s->compliance.block_cols[0]; },
                "is given twice"},
        BadCase{"block_data_size", [](Scene* s) { s->compliance.block_data.push_back(1.0); },
                "block_data values, its blocks need"},
        BadCase{"block_cols_size", [](Scene* s) { s->compliance.block_cols.pop_back(); }, "block_cols"}),
    [](const ::testing::TestParamInfo<BadCase>& info) { return std::string(info.param.what); });

TEST(ToComplianceMsg, RoundTripsBlockSparse) {
  const Converted sparse = convert(makeScene(10, kStamp, true));
  ASSERT_EQ(sparse.error, "");
  Scene again = makeScene(10, kStamp);
  again.compliance = toComplianceMsg(sparse.problem.W);
  const Converted c = convert(again);
  ASSERT_EQ(c.error, "");
  EXPECT_EQ(lcs::core::toDense(c.problem.W), lcs::core::toDense(sparse.problem.W));
}

// ---- the body form (STORAGE_BODIES, build_lcp = false) ----------------------------------

// W = Σ J C Jᵀ of the body-form scene, formed the long way from the message.
Eigen::MatrixXd bodyFormW(const lcs::Compliance& msg) {
  const int nb = static_cast<int>(msg.body_compliance.size() / 36);
  const int rows[] = {3, 3, 1, 2}, offsets[] = {0, 3, 6, 7, 9};
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(9, 6 * nb), C = Eigen::MatrixXd::Zero(6 * nb, 6 * nb);
  for (int b = 0; b < nb; ++b)
    for (int k = 0; k < 36; ++k) C(6 * b + k / 6, 6 * b + k % 6) = msg.body_compliance[36 * b + k];
  std::size_t next = 0;
  for (int i = 0; i < 4; ++i)
    for (int side = 0; side < 2; ++side) {
      const int b = msg.contact_bodies[2 * i + side];
      if (b < 0) continue;
      for (int k = 0; k < 6 * rows[i]; ++k) J(offsets[i] + k / 6, 6 * b + k % 6) += msg.jacobian[next++];
    }
  return J * C * J.transpose();
}

TEST(ToProblem, BodyFormGivesTheBodiesAndNoW) {
  const Scene scene = lcp_contact_solver_test::makeBodyFormScene(10, kStamp);
  const Converted c = convert(scene);
  ASSERT_EQ(c.error, "");
  ASSERT_TRUE(c.problem.bodies);
  EXPECT_EQ(lcs::core::complianceRows(c.problem.W), 0);
  EXPECT_EQ(c.problem.bodies->bodyCount(), 3);
  EXPECT_EQ(c.problem.bodies->contacts[2].body_a, 1);
  EXPECT_EQ(c.problem.bodies->contacts[2].body_b, 0);
  EXPECT_EQ(c.problem.bodies->contacts[0].body_b, -1);
  const Eigen::MatrixXd W = bodyFormW(scene.compliance);
  EXPECT_LT((c.problem.bodies->toDense() - W).cwiseAbs().maxCoeff(), 1e-14 * W.cwiseAbs().maxCoeff());
  // Round trip: the same message back, field by field.
  const lcs::Compliance back = toComplianceMsg(c.problem);
  EXPECT_EQ(back.storage, lcs::Compliance::STORAGE_BODIES);
  EXPECT_EQ(back.rows, 9u);
  EXPECT_EQ(back.body_compliance, scene.compliance.body_compliance);
  EXPECT_EQ(back.contact_bodies, scene.compliance.contact_bodies);
  EXPECT_EQ(back.jacobian, scene.compliance.jacobian);
  EXPECT_TRUE(back.body_diagonal.empty());
  EXPECT_TRUE(back.data.empty());
  // With an extra diagonal too.
  Scene with_diagonal = scene;
  with_diagonal.compliance.body_diagonal.assign(9, 0.25);
  const Converted d = convert(with_diagonal);
  ASSERT_EQ(d.error, "");
  EXPECT_NEAR(d.problem.bodies->toDense()(6, 6), W(6, 6) + 0.25, 1e-12);
  EXPECT_EQ(toComplianceMsg(d.problem).body_diagonal, with_diagonal.compliance.body_diagonal);
}

TEST(ToProblem, BodyFormSolvesUnbuiltToTheBuiltForces) {
  const Scene scene = lcp_contact_solver_test::makeBodyFormScene(10, kStamp);
  const Converted bodies = convert(scene);
  ASSERT_EQ(bodies.error, "");
  Scene dense = scene;
  dense.compliance = toComplianceMsg(bodyFormW(scene.compliance));
  const Converted built = convert(dense);
  ASSERT_EQ(built.error, "");
  lcs::core::SolverParams params = defaultSolverParams();
  params.tolerance = 1e-10;
  params.build_lcp = false;
  const lcs::core::SolveResult u = lcs::core::solveProblem(bodies.problem, params);
  params.build_lcp = true;
  const lcs::core::SolveResult b = lcs::core::solveProblem(built.problem, params);
  ASSERT_TRUE(u.converged) << u.message;
  ASSERT_TRUE(b.converged) << b.message;
  EXPECT_TRUE(u.unbuilt);
  EXPECT_LT((u.forces - b.forces).cwiseAbs().maxCoeff(), 1e-8 * b.forces.cwiseAbs().maxCoeff());
  // The debug line and the heat map read the body form.
  const std::vector<double> mu = lcs::core::effectiveMu(bodies.problem, params.mu);
  EXPECT_NE(cycleSummary(bodies.problem, u, mu).find("4 contacts, 9 rows (bodies, no W)"), std::string::npos);
  DisplayOptions options;
  options.showCellWidth = 0.1;
  options.heatmap_max_rows = 5;  // cuts contact 1's block
  const auto from_bodies = buildMarkers(scene.contacts.header, bodies.frames, bodies.problem, u, mu, options);
  const auto from_w = buildMarkers(dense.contacts.header, built.frames, built.problem, u, mu, options);
  const visualization_msgs::Marker* a = nullptr;
  const visualization_msgs::Marker* w = nullptr;
  for (const auto& m : from_bodies.markers)
    if (m.ns == kNsComplianceHeatmap) a = &m;
  for (const auto& m : from_w.markers)
    if (m.ns == kNsComplianceHeatmap) w = &m;
  ASSERT_NE(a, nullptr);
  ASSERT_NE(w, nullptr);
  ASSERT_EQ(a->colors.size(), 25u);
  for (std::size_t k = 0; k < a->colors.size(); ++k) {
    EXPECT_NEAR(a->colors[k].r, w->colors[k].r, 1e-6) << k;
    EXPECT_NEAR(a->colors[k].g, w->colors[k].g, 1e-6) << k;
    EXPECT_NEAR(a->colors[k].b, w->colors[k].b, 1e-6) << k;
  }
}

TEST(ToProblem, MalformedBodyFormsAreRefusedBeforeAllocating) {
  struct Case {
    const char* what;
    std::function<void(lcs::Compliance*)> spoil;
    const char* expected;
  };
  const std::vector<Case> cases = {
      {"compliance_size", [](lcs::Compliance* c) { c->body_compliance.pop_back(); },
       "107 body_compliance values, not 36"},
      {"contact_bodies", [](lcs::Compliance* c) { c->contact_bodies.push_back(0); },
       "9 contact_bodies, 8 expected"},
      {"body_range", [](lcs::Compliance* c) { c->contact_bodies[4] = 3; },
       "contact 2 names body_a 3, outside -1..2"},
      {"body_negative", [](lcs::Compliance* c) { c->contact_bodies[7] = -2; }, "contact 3 names body_b -2"},
      {"huge_body_index", [](lcs::Compliance* c) { c->contact_bodies[0] = 2147483647; }, "outside -1..2"},
      {"jacobian_size", [](lcs::Compliance* c) { c->jacobian.pop_back(); },
       "71 jacobian values, its contacts need 72"},
      {"static_side_counts", [](lcs::Compliance* c) { c->contact_bodies[1] = 1; }, "its contacts need 90"},
      {"diagonal_size", [](lcs::Compliance* c) { c->body_diagonal.assign(8, 0.0); },
       "8 body_diagonal values, 9 rows"},
      {"nan_jacobian", [](lcs::Compliance* c) { c->jacobian[20] = kNaN; }, "non-finite Jacobian"},
      {"inf_compliance", [](lcs::Compliance* c) { c->body_compliance[40] = kInf; },
       "body 1 has a non-finite compliance"},
      {"nan_diagonal",
       [](lcs::Compliance* c) {
         c->body_diagonal.assign(9, 0.0);
         c->body_diagonal[3] = kNaN;
       },
       "diagonal holds a non-finite"},
      {"rows", [](lcs::Compliance* c) { c->rows = 10; }, "rows=10, the contacts have 9"},
  };
  for (const Case& bad : cases) {
    Scene scene = lcp_contact_solver_test::makeBodyFormScene(10, kStamp);
    bad.spoil(&scene.compliance);
    const Converted c = convert(scene);
    EXPECT_NE(c.error.find(bad.expected), std::string::npos) << bad.what << ": '" << c.error << "'";
  }
}

// ---- forces and stats -----------------------------------------------------------------

TEST(ToConstraintForcesMsg, ForcesFollowTheContactFrames) {
  const Scene scene = makeScene(10, kStamp);
  const Converted c = convert(scene);
  ASSERT_EQ(c.error, "");
  const lcs::core::SolveResult result = lcs::core::solveProblem(c.problem, defaultSolverParams());
  ASSERT_TRUE(result.converged);
  const lcs::ConstraintForces msg = toConstraintForcesMsg(scene.contacts, c.frames, c.problem, result);
  EXPECT_EQ(msg.header.stamp, kStamp);
  ASSERT_EQ(msg.forces.size(), 4u);
  const std::vector<int> offsets = c.problem.rowOffsets();
  for (std::size_t i = 0; i < 4; ++i) {
    const lcs::ContactForce& f = msg.forces[i];
    const ContactFrame& frame = c.frames[i];
    ASSERT_EQ(f.lambda.size(), static_cast<std::size_t>(c.problem.contacts[i].rows));
    for (std::size_t k = 0; k < f.lambda.size(); ++k) EXPECT_EQ(f.lambda[k], result.forces[offsets[i] + k]);
    EXPECT_EQ(f.state, static_cast<std::uint8_t>(result.states[i]));
    const Eigen::Vector3d expected =
        f.normal_force * frame.normal + f.tangent1_force * frame.tangent1 + f.tangent2_force * frame.tangent2;
    EXPECT_NEAR((toEigen(f.force) - expected).norm(), 0.0, 1e-15);
    EXPECT_NEAR((toEigen(f.tangent1) - frame.tangent1).norm(), 0.0, 1e-15);  // derived ones published back
  }
  EXPECT_EQ(msg.forces[2].tangent1_force, 0.0);                      // frictionless
  EXPECT_EQ(msg.forces[3].tangent1_force, msg.forces[3].lambda[1]);  // bilateral second row along t1
  EXPECT_TRUE(allFinite(msg));
}

TEST(SumBodyPairWrenches, SumsForceAndTorquePerPair) {
  const Scene scene = makeScene(10, kStamp);
  const Converted c = convert(scene);
  const lcs::core::SolveResult result = lcs::core::solveProblem(c.problem, defaultSolverParams());
  const lcs::ConstraintForces msg = toConstraintForcesMsg(scene.contacts, c.frames, c.problem, result);
  ASSERT_EQ(msg.wrenches.size(), 3u);  // (box, ground), (ball, box), (arm, box) in order
  EXPECT_EQ(msg.wrenches[0].body_a, "box");
  EXPECT_EQ(msg.wrenches[0].body_b, "ground");
  EXPECT_EQ(msg.wrenches[2].body_a, "arm");
  const Eigen::Vector3d f0 = toEigen(msg.forces[0].force), f1 = toEigen(msg.forces[1].force);
  EXPECT_NEAR((toEigen(msg.wrenches[0].wrench.force) - (f0 + f1)).norm(), 0.0, 1e-15);
  const Eigen::Vector3d torque =
      toEigen(msg.forces[0].position).cross(f0) + toEigen(msg.forces[1].position).cross(f1);
  EXPECT_NEAR((toEigen(msg.wrenches[0].wrench.torque) - torque).norm(), 0.0, 1e-15);
}

// Pairs interleaved (a simulator need not list a pair's contacts together): one wrench per
// pair in order of first appearance, each the sum of its own contacts only.
TEST(SumBodyPairWrenches, InterleavedPairsAreSummedApart) {
  auto force = [](const std::string& a, const std::string& b, double fx, double px) {
    lcs::ContactForce f;
    f.body_a = a;
    f.body_b = b;
    f.force.x = fx;
    f.position.y = px;
    return f;
  };
  const std::vector<lcs::ContactForce> forces = {
      force("a", "b", 1, 0),  force("c", "d", 10, 1),    force("a", "b", 2, 2),    force("b", "a", 100, 0),
      force("c", "d", 20, 0), force("a", "bc", 1000, 0), force("ab", "c", 5000, 0)};
  const std::vector<lcs::BodyPairWrench> w = sumBodyPairWrenches(forces);
  ASSERT_EQ(w.size(), 5u);
  const std::pair<std::string, std::string> names[] = {
      {"a", "b"}, {"c", "d"}, {"b", "a"}, {"a", "bc"}, {"ab", "c"}};
  const double sums[] = {3, 30, 100, 1000, 5000};
  for (int k = 0; k < 5; ++k) {
    EXPECT_EQ(w[k].body_a, names[k].first);
    EXPECT_EQ(w[k].body_b, names[k].second);
    EXPECT_EQ(w[k].wrench.force.x, sums[k]) << k;
  }
  // Torque p × f: (0, y, 0) × (x, 0, 0) = (0, 0, -x y).
  EXPECT_EQ(w[0].wrench.torque.z, -(1 * 0.0 + 2 * 2.0));
  EXPECT_EQ(w[1].wrench.torque.z, -(10 * 1.0));
}

// A rolling contact (6 rows): its spin and rolling rows come back as a torque on body_a,
// which the pair's wrench adds to p × f.
TEST(ToConstraintForcesMsg, TorsionalAndRollingRowsAreATorque) {
  Scene scene;
  scene.contacts.header.stamp = kStamp;
  lcs::ContactPoint c = lcp_contact_solver_test::contact(5, "ball", "ground", lcs::ContactPoint::ROLLING,
                                                         {-1.0, 0.0, 0.0, -0.05, 0.3, 0.4}, 0.5);
  c.position = lcp_contact_solver_test::point(1.0, 2.0, 0.0);
  c.normal = lcp_contact_solver_test::vec(0, 0, 1);
  c.mu_torsional = 0.02;
  c.mu_rolling = 0.01;
  scene.contacts.contacts.push_back(c);
  scene.compliance.header = scene.contacts.header;
  scene.compliance.storage = lcs::Compliance::STORAGE_DENSE;
  scene.compliance.rows = 6;
  const Eigen::MatrixXd W = Eigen::MatrixXd::Identity(6, 6);
  scene.compliance.data.assign(W.data(), W.data() + 36);
  const Converted conv = convert(scene);
  ASSERT_EQ(conv.error, "");
  ASSERT_EQ(conv.problem.contacts[0].type, lcs::core::ContactType::kRolling);
  EXPECT_EQ(conv.problem.contacts[0].mu_rolling, 0.01);
  lcs::core::SolverParams params = defaultSolverParams();
  params.tolerance = 1e-12;
  const lcs::core::SolveResult result = lcs::core::solveProblem(conv.problem, params);
  ASSERT_TRUE(result.converged) << result.message;
  const lcs::ConstraintForces msg = toConstraintForcesMsg(scene.contacts, conv.frames, conv.problem, result);
  const ContactFrame& frame = conv.frames[0];
  const Eigen::Vector3d torque =
      frame.normal * result.forces[3] + frame.tangent1 * result.forces[4] + frame.tangent2 * result.forces[5];
  EXPECT_GT(torque.norm(), 0.0);
  EXPECT_NEAR((toEigen(msg.forces[0].torque) - torque).norm(), 0.0, 1e-15);
  EXPECT_NEAR(result.forces[3], 0.02, 1e-10);  // spin: 0.05 would stick, bound 0.02 · λ_n = 0.02
  ASSERT_EQ(msg.wrenches.size(), 1u);
  const Eigen::Vector3d expected =
      toEigen(msg.forces[0].position).cross(toEigen(msg.forces[0].force)) + torque;
  EXPECT_NEAR((toEigen(msg.wrenches[0].wrench.torque) - expected).norm(), 0.0, 1e-15);
}

TEST(StatsMsg, CarriesTheResult) {
  const Scene scene = makeScene(10, kStamp);
  const Converted c = convert(scene);
  const lcs::core::SolveResult result = lcs::core::solveProblem(c.problem, defaultSolverParams());
  const lcs::SolverStats stats = toStatsMsg(scene.contacts.header, c.problem, result);
  EXPECT_TRUE(stats.success);
  EXPECT_EQ(stats.status, "converged");
  EXPECT_EQ(stats.status_code, lcs::SolverStats::CONVERGED);
  EXPECT_EQ(stats.solver, result.solver);  // auto's path, e.g. "auto:nlgs" (#14)
  EXPECT_EQ(stats.solver.rfind("auto:", 0), 0u);
  EXPECT_EQ(stats.iterations, result.iterations);
  EXPECT_EQ(stats.residual, result.residual);
  EXPECT_EQ(stats.num_contacts, 4);
  EXPECT_EQ(stats.num_rows, 9);
  EXPECT_TRUE(allFinite(stats));

  const lcs::SolverStats rejected =
      rejectedStatsMsg(scene.contacts.header, lcs::SolverStats::NO_COMPLIANCE, "nothing came");
  EXPECT_FALSE(rejected.success);
  EXPECT_EQ(rejected.status, "no_compliance");
  EXPECT_EQ(statusCodeName(lcs::SolverStats::INVALID_INPUT), "invalid_input");
  EXPECT_EQ(statusCodeName(lcs::SolverStats::MAX_ITERATIONS), "max_iterations");
}

TEST(AllFinite, CatchesANonFiniteForce) {
  lcs::ConstraintForces msg;
  msg.forces.resize(1);
  EXPECT_TRUE(allFinite(msg));
  msg.forces[0].lambda = {1.0, kNaN};
  EXPECT_FALSE(allFinite(msg));
}

// ---- parameters -----------------------------------------------------------------------

TEST(SolverParamsRos, DefaultsAreSofas) {
  const NodeSettings s;
  EXPECT_EQ(s.solver.tolerance, 0.001);
  EXPECT_EQ(s.solver.maxIt, 1000);
  EXPECT_EQ(s.solver.mu, 0.6);
  EXPECT_TRUE(s.solver.initial_guess);
  EXPECT_TRUE(s.solver.build_lcp);
  EXPECT_EQ(s.solver.regularizationTerm, 0.0);
  EXPECT_EQ(s.solver.minW, 0.0);
  EXPECT_EQ(s.solver.maxF, 0.0);
  EXPECT_FALSE(s.solver.computeConstraintForces);
  EXPECT_FALSE(s.solver.displayDebug);
  EXPECT_EQ(s.display.showCellWidth, 0.0);
  EXPECT_EQ(s.solver.max_rows, 30000);
  EXPECT_EQ(validateSettings(s), "");
}

TEST(SolverParamsRos, OverridesParseAndNameTheirFaults) {
  lcs::core::SolverParams p = defaultSolverParams();
  EXPECT_EQ(applyOverride("maxIt=50", &p), "");
  EXPECT_EQ(p.maxIt, 50);
  EXPECT_EQ(applyOverride("mu=0.25", &p), "");
  EXPECT_EQ(p.mu, 0.25);
  EXPECT_EQ(applyOverride("solver=lemke", &p), "");
  EXPECT_EQ(p.solver, lcs::core::SolverKind::kLemke);
  EXPECT_EQ(applyOverride("build_lcp=false", &p), "");
  EXPECT_FALSE(p.build_lcp);
  EXPECT_NE(applyOverride("maxIt=abc", &p).find("maxIt"), std::string::npos);
  EXPECT_NE(applyOverride("maxIt=5.5", &p).find("an integer"), std::string::npos);
  EXPECT_NE(applyOverride("speed=3", &p).find("'speed' is not a solver parameter"), std::string::npos);
  EXPECT_NE(applyOverride("tolerance", &p).find("name=value"), std::string::npos);
  EXPECT_NE(applyOverride("solver=fast", &p).find("one of auto, pgs, nlgs, lemke"), std::string::npos);
  EXPECT_EQ(p.maxIt, 50);  // failed overrides change nothing
}

TEST(SolverParamsRos, OverridesTrimSpacesAroundNameAndValue) {
  lcs::core::SolverParams p = defaultSolverParams();
  EXPECT_EQ(applyOverride("tolerance = 1e-3", &p), "");  // as written in a YAML list
  EXPECT_EQ(p.tolerance, 1e-3);
  EXPECT_EQ(applyOverride("  maxIt=\t42 ", &p), "");
  EXPECT_EQ(p.maxIt, 42);
  EXPECT_EQ(applyOverride("solver = newton", &p), "");
  EXPECT_EQ(p.solver, lcs::core::SolverKind::kNewton);
  EXPECT_EQ(applyOverride("islands=false", &p), "");
  EXPECT_FALSE(p.islands);
  EXPECT_EQ(applyOverride("threads=1", &p), "");
  EXPECT_EQ(p.threads, 1);
  EXPECT_NE(applyOverride(" = 3", &p).find("'' is not a solver parameter"), std::string::npos);
  EXPECT_NE(applyOverride("maxIt = ", &p).find("an integer"), std::string::npos);
}

TEST(SolverParamsRos, ConfigRoundTripAndRejection) {
  NodeSettings s;
  s.solver.maxIt = 77;
  s.solver.solver = lcs::core::SolverKind::kPgs;
  s.display.showTranslation = {{1.0, 2.0, 3.0}};
  s.pairing_window = 0.7;  // startup-only: kept by fromConfig
  lcp_contact_solver::ContactSolverConfig config = toConfig(s);
  EXPECT_EQ(config.maxIt, 77);
  EXPECT_EQ(config.solver, "pgs");
  EXPECT_EQ(config.showTranslation_y, 2.0);
  config.mu = 0.1;
  NodeSettings t;
  t.pairing_window = 0.7;
  ASSERT_EQ(fromConfig(config, &t), "");
  EXPECT_EQ(t.solver.maxIt, 77);
  EXPECT_EQ(t.solver.mu, 0.1);
  EXPECT_EQ(t.display.showTranslation[2], 3.0);
  EXPECT_EQ(t.pairing_window, 0.7);

  config.tolerance = -1.0;
  EXPECT_NE(fromConfig(config, &t).find("tolerance"), std::string::npos);
  EXPECT_EQ(t.solver.tolerance, 0.001);  // unchanged
  config.tolerance = 0.01;
  config.solver = "fast";
  EXPECT_NE(fromConfig(config, &t).find("solver"), std::string::npos);
  config.solver = "auto";
  config.force_arrow_scale = 0.0;
  EXPECT_NE(fromConfig(config, &t).find("force_arrow_scale"), std::string::npos);
}

// ---- markers --------------------------------------------------------------------------

class Markers : public ::testing::Test {
 protected:
  void SetUp() override {
    scene_ = makeScene(10, kStamp);
    c_ = convert(scene_);
    ASSERT_EQ(c_.error, "");
    result_ = lcs::core::solveProblem(c_.problem, defaultSolverParams());
    mu_ = lcs::core::effectiveMu(c_.problem, 0.6);
  }

  std::set<std::string> namespaces(const visualization_msgs::MarkerArray& markers) const {
    std::set<std::string> ns;
    for (const auto& m : markers.markers) ns.insert(m.ns);
    return ns;
  }

  const visualization_msgs::Marker* find(const visualization_msgs::MarkerArray& markers,
                                         const std::string& ns) const {
    for (const auto& m : markers.markers)
      if (m.ns == ns) return &m;
    return nullptr;
  }

  Scene scene_;
  Converted c_;
  lcs::core::SolveResult result_;
  std::vector<double> mu_;
};

TEST_F(Markers, BuiltOnlyWithSubscribers) {
  EXPECT_FALSE(shouldBuildMarkers(0));
  EXPECT_TRUE(shouldBuildMarkers(1));
}

TEST_F(Markers, StableNamespacesAndNoHeatmapByDefault) {
  const DisplayOptions options;  // showCellWidth 0: SOFA's default, no heat map
  const auto markers = buildMarkers(scene_.contacts.header, c_.frames, c_.problem, result_, mu_, options);
  EXPECT_EQ(namespaces(markers),
            (std::set<std::string>{kNsContactPoints, kNsNormals, kNsForces, kNsFrictionCones}));
  for (const auto& m : markers.markers) {
    EXPECT_EQ(m.header.frame_id, "world");
    EXPECT_EQ(m.lifetime.toSec(), 0.5);
    if (m.ns != kNsForces) {
      EXPECT_EQ(m.id, 0);
    }
  }
  const auto* points = find(markers, kNsContactPoints);
  ASSERT_NE(points, nullptr);
  ASSERT_EQ(points->points.size(), 4u);
  EXPECT_EQ(points->colors[0], stateColor(result_.states[0]));
  // Two frictional contacts with μ > 0, 12 triangles each.
  EXPECT_EQ(find(markers, kNsFrictionCones)->points.size(), 2u * 12u * 3u);
}

TEST_F(Markers, ColoursTellStatesAndForcesApart) {
  const auto markers =
      buildMarkers(scene_.contacts.header, c_.frames, c_.problem, result_, mu_, DisplayOptions());
  std::vector<std_msgs::ColorRGBA> colours;
  for (int s = 0; s < lcs::core::kContactStateCount; ++s)
    colours.push_back(stateColor(static_cast<lcs::core::ContactState>(s)));
  bool arrows = false;
  for (const auto& m : markers.markers) {
    if (m.ns != kNsForces) continue;
    arrows = true;
    for (const auto& state : colours) EXPECT_NE(m.color, state) << "a force arrow has a state's colour";
    EXPECT_GE(m.scale.x, 0.1 * DisplayOptions().cone_height);  // readable shaft
  }
  ASSERT_TRUE(arrows);
  for (std::size_t a = 0; a < colours.size(); ++a)
    for (std::size_t b = a + 1; b < colours.size(); ++b) EXPECT_NE(colours[a], colours[b]) << a << " " << b;
}

TEST_F(Markers, ForceArrowsScaleWithTheParameter) {
  DisplayOptions options;
  options.force_arrow_scale = 0.5;
  const auto markers = buildMarkers(scene_.contacts.header, c_.frames, c_.problem, result_, mu_, options);
  const lcs::ConstraintForces forces = toConstraintForcesMsg(scene_.contacts, c_.frames, c_.problem, result_);
  for (const auto& m : markers.markers) {
    if (m.ns != kNsForces) continue;
    ASSERT_EQ(m.points.size(), 2u);
    const Eigen::Vector3d arrow = toEigen(m.points[1]) - toEigen(m.points[0]);
    EXPECT_NEAR((arrow - 0.5 * toEigen(forces.forces[m.id].force)).norm(), 0.0, 1e-12);
  }
}

TEST_F(Markers, HeatmapsAtShowTranslationWithCellWidth) {
  DisplayOptions options;
  options.showCellWidth = 0.1;
  options.showTranslation = {{1.0, 2.0, 3.0}};
  options.heatmap_max_rows = 5;
  const auto markers = buildMarkers(scene_.contacts.header, c_.frames, c_.problem, result_, mu_, options);
  const auto* w = find(markers, kNsComplianceHeatmap);
  const auto* lambda = find(markers, kNsLambdaHeatmap);
  ASSERT_NE(w, nullptr);
  ASSERT_NE(lambda, nullptr);
  EXPECT_EQ(w->points.size(), 25u);  // the leading 5 x 5 rows only
  EXPECT_EQ(lambda->points.size(), 5u);
  EXPECT_NEAR((toEigen(w->points[0]) - Eigen::Vector3d(1.0, 2.0, 3.0)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((toEigen(w->points[6]) - Eigen::Vector3d(1.1, 1.9, 3.0)).norm(), 0.0, 1e-12);  // row 1, col 1
  EXPECT_NEAR((toEigen(lambda->points[0]) - Eigen::Vector3d(1.6, 2.0, 3.0)).norm(), 0.0, 1e-12);
  EXPECT_NEAR(w->scale.x, 0.095, 1e-12);

  options.show_w_heatmap = false;
  const auto hidden = buildMarkers(scene_.contacts.header, c_.frames, c_.problem, result_, mu_, options);
  EXPECT_EQ(find(hidden, kNsComplianceHeatmap), nullptr);
}

TEST(HeatColor, DivergesAroundZero) {
  EXPECT_EQ(heatColor(0.0, 1.0).g, 1.0f);  // white
  EXPECT_EQ(heatColor(1.0, 1.0).r, 1.0f);
  EXPECT_EQ(heatColor(1.0, 1.0).b, 0.0f);  // red
  EXPECT_EQ(heatColor(-2.0, 1.0).b, 1.0f);
  EXPECT_EQ(heatColor(-2.0, 1.0).r, 0.0f);  // clamped blue
  EXPECT_EQ(heatColor(5.0, 0.0).g, 1.0f);   // no scale: white
}

// ---- pairing and debug summary --------------------------------------------------------

namespace {

lcs::ContactArray::ConstPtr arrayAt(double t) {
  auto a = boost::make_shared<lcs::ContactArray>();
  a->header.stamp = ros::Time(t);
  return a;
}

lcs::Compliance::ConstPtr complianceAt(double t) {
  auto c = boost::make_shared<lcs::Compliance>();
  c->header.stamp = ros::Time(t);
  return c;
}

// Every array received is in exactly one outcome.
void expectAccounted(const InputCounts& c) {
  EXPECT_EQ(c.arrays_received, c.taken + c.unpaired + c.dropped + c.waiting());
}

}  // namespace

TEST(InputQueue, PairsByStampInEitherOrderAndReportsOnlyArraysWaitingPastTheWindow) {
  InputQueue queue(OverloadPolicy::kQueue, 10);
  const ros::Time now(10, 0);
  // Stamps increase on each topic (going back would mean a restart).
  queue.addContacts(arrayAt(1), now);
  queue.addContacts(arrayAt(2), now);
  queue.addCompliance(complianceAt(2), now);  // array first
  queue.addCompliance(complianceAt(3), now);  // compliance first: its array comes next
  queue.addContacts(arrayAt(3), now);
  EXPECT_TRUE(queue.takeExpired(ros::Time(10, 400000000), 0.5).empty());
  const auto expired = queue.takeExpired(ros::Time(10, 600000000), 0.5);
  ASSERT_EQ(expired.size(), 1u);
  EXPECT_EQ(expired[0].header.stamp, ros::Time(1));
  EXPECT_FALSE(expired[0].behind);
  std::vector<UnsolvedInput> dropped;
  InputPair pair;
  ASSERT_TRUE(queue.take(std::chrono::milliseconds(0), &pair, &dropped));
  EXPECT_EQ(pair.contacts->header.stamp, ros::Time(2));
  EXPECT_EQ(pair.compliance->header.stamp, ros::Time(2));
  ASSERT_TRUE(queue.take(std::chrono::milliseconds(0), &pair, &dropped));
  EXPECT_EQ(pair.contacts->header.stamp, ros::Time(3));
  EXPECT_FALSE(queue.take(std::chrono::milliseconds(0), &pair, &dropped));
  EXPECT_TRUE(dropped.empty());
  const InputCounts c = queue.counts();
  EXPECT_EQ(c.arrays_received, 3u);
  EXPECT_EQ(c.taken, 2u);
  EXPECT_EQ(c.unpaired, 1u);
  EXPECT_EQ(c.waiting(), 0u);
  expectAccounted(c);
}

TEST(InputQueue, DropOldestSolvesTheNewestAndCountsTheRestAsBehind) {
  InputQueue queue(OverloadPolicy::kDropOldest, 10);
  for (int k = 1; k <= 5; ++k) {
    queue.addContacts(arrayAt(k), ros::Time(100));
    queue.addCompliance(complianceAt(k), ros::Time(100));
  }
  std::vector<UnsolvedInput> dropped;
  InputPair pair;
  ASSERT_TRUE(queue.take(std::chrono::milliseconds(0), &pair, &dropped));
  EXPECT_EQ(pair.contacts->header.stamp, ros::Time(5));
  ASSERT_EQ(dropped.size(), 4u);
  for (const UnsolvedInput& d : dropped) {
    EXPECT_TRUE(d.behind);
    EXPECT_NE(d.reason.find("drop_oldest"), std::string::npos);
  }
  const InputCounts c = queue.counts();
  EXPECT_EQ(c.dropped, 4u);
  EXPECT_EQ(c.unpaired, 0u);  // the node's backlog is never blamed on the simulator
  expectAccounted(c);
}

TEST(InputQueue, QueuePolicyKeepsOrderAndDropsTheOldestPastItsCapacity) {
  InputQueue queue(OverloadPolicy::kQueue, 3);
  for (int k = 1; k <= 5; ++k) {
    queue.addCompliance(complianceAt(k), ros::Time(100));  // compliance first this time
    queue.addContacts(arrayAt(k), ros::Time(100));
  }
  std::vector<UnsolvedInput> dropped;
  InputPair pair;
  std::vector<double> solved;
  while (queue.take(std::chrono::milliseconds(0), &pair, &dropped))
    solved.push_back(pair.contacts->header.stamp.toSec());
  EXPECT_EQ(solved, (std::vector<double>{3, 4, 5}));
  ASSERT_EQ(dropped.size(), 2u);
  EXPECT_EQ(dropped[0].header.stamp, ros::Time(1));
  EXPECT_TRUE(dropped[0].behind);
  expectAccounted(queue.counts());
  EXPECT_EQ(queue.counts().waiting(), 0u);
}

TEST(InputQueue, RepeatedStampAndLoneCompliancesAreAccounted) {
  InputQueue queue(OverloadPolicy::kQueue, 10);
  queue.addContacts(arrayAt(1), ros::Time(100));
  queue.addContacts(arrayAt(1), ros::Time(100));  // a restarted simulator reuses the stamp
  queue.addCompliance(complianceAt(7), ros::Time(100));
  std::vector<UnsolvedInput> dropped;
  InputPair pair;
  EXPECT_FALSE(queue.take(std::chrono::milliseconds(0), &pair, &dropped));
  ASSERT_EQ(dropped.size(), 1u);
  EXPECT_FALSE(dropped[0].behind);
  EXPECT_NE(dropped[0].reason.find("same stamp"), std::string::npos);
  queue.addCompliance(complianceAt(1), ros::Time(100));
  ASSERT_TRUE(queue.take(std::chrono::milliseconds(0), &pair, &dropped));
  EXPECT_TRUE(queue.takeExpired(ros::Time(200), 0.5).empty());  // the lone compliance goes quietly
  const InputCounts c = queue.counts();
  EXPECT_EQ(c.compliances_unpaired, 1u);
  EXPECT_EQ(c.arrays_received, 2u);
  expectAccounted(c);
}

TEST(InputQueue, StopWakesAWaitingTake) {
  InputQueue queue(OverloadPolicy::kQueue, 10);
  std::thread stopper([&queue] {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    queue.stop();
  });
  std::vector<UnsolvedInput> dropped;
  InputPair pair;
  EXPECT_FALSE(queue.take(std::chrono::seconds(30), &pair, &dropped));
  stopper.join();
}

TEST(CycleLog, NamesTheWorstContact) {
  const Scene scene = makeScene(10, kStamp);
  const Converted c = convert(scene);
  lcs::core::SolverParams params = defaultSolverParams();
  params.maxIt = 1;  // far from converged: some contact has a clear error
  const lcs::core::SolveResult result = lcs::core::solveProblem(c.problem, params);
  const std::vector<double> mu = lcs::core::effectiveMu(c.problem, params.mu);
  double worst_error = 0.0;
  const int worst = worstContact(c.problem, result, mu, &worst_error);
  ASSERT_GE(worst, 0);
  // The per-contact errors add up (squared) to the core's unnormalised residual.
  const double total = result.residual * c.problem.d_free.norm();
  EXPECT_LE(worst_error, total + 1e-12);
  EXPECT_GE(worst_error * std::sqrt(4.0), total - 1e-12);
  const std::string line = cycleSummary(c.problem, result, mu);
  EXPECT_NE(line.find("4 contacts, 9 rows (dense W)"), std::string::npos) << line;
  EXPECT_NE(line.find("worst contact " + std::to_string(worst)), std::string::npos) << line;
}

namespace {

std::string summaryOf(lcp_contact_solver_ros::SolveRateStatus& task, std::uint8_t* level) {
  diagnostic_updater::DiagnosticStatusWrapper status;
  task.run(status);
  *level = status.level;
  return status.message;
}

}  // namespace

TEST(SolveRateStatus, IdleIsWaitingNotAnError) {
  lcp_contact_solver_ros::SolveRateStatus task(0.0, 1e12);  // no bound a real rate can cross
  std::uint8_t level = 255;
  EXPECT_NE(summaryOf(task, &level).find("waiting for contacts"), std::string::npos);
  EXPECT_EQ(level, diagnostic_msgs::DiagnosticStatus::OK);
  task.contactsReceived();
  task.solved();
  summaryOf(task, &level);
  EXPECT_EQ(level, diagnostic_msgs::DiagnosticStatus::OK);
  const std::string idle_again = summaryOf(task, &level);  // nothing new since
  EXPECT_NE(idle_again.find("last received"), std::string::npos) << idle_again;
  EXPECT_EQ(level, diagnostic_msgs::DiagnosticStatus::OK);
}

TEST(SolveRateStatus, WarnsWhenContactsComeButSolvingIsTooSlow) {
  lcp_contact_solver_ros::SolveRateStatus task(1e9, 2e9);  // no machine solves this fast
  task.contactsReceived();
  std::uint8_t level = 0;
  EXPECT_NE(summaryOf(task, &level).find("below"), std::string::npos);
  EXPECT_EQ(level, diagnostic_msgs::DiagnosticStatus::WARN);
}
