// Results to messages (forces, wrenches, stats) and the solver parameters from ROS.
#include "msg_conversion_test_util.h"

using namespace msg_conversion_test;

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
