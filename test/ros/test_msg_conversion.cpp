// Unit tests of the ROS layer that need no master: message conversions, parameters,
// markers, pairing and the debug summary.
#include "msg_conversion_test_util.h"

using namespace msg_conversion_test;

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
