// Runs against a live contact_solver (node, or with --nodelet a nodelet loaded in this
// process): publishes known problems and checks what comes back against a direct core
// solve of the same problem.
#include "contact_solver_node_test_util.h"

namespace {

TEST_F(ContactSolverNodeTest, DefaultParametersAreSofas) {
  lcp_contact_solver_ros::NodeSettings loaded;
  ASSERT_EQ(lcp_contact_solver_ros::loadSettings(ros::NodeHandle(kSolver), &loaded), "");
  const lcp_contact_solver_ros::NodeSettings defaults;
  EXPECT_EQ(loaded.solver.tolerance, defaults.solver.tolerance);
  EXPECT_EQ(loaded.solver.maxIt, defaults.solver.maxIt);
  EXPECT_EQ(loaded.solver.mu, defaults.solver.mu);
  EXPECT_EQ(loaded.solver.initial_guess, defaults.solver.initial_guess);
  EXPECT_EQ(loaded.solver.computeConstraintForces, defaults.solver.computeConstraintForces);
  EXPECT_EQ(loaded.display.showCellWidth, defaults.display.showCellWidth);
  EXPECT_EQ(loaded.solver.max_rows, defaults.solver.max_rows);
}

TEST_F(ContactSolverNodeTest, PublishedForcesEqualTheCores) {
  Inbox<lcs::ConstraintForces> forces(nh_, "constraint_forces");
  ASSERT_TRUE(waitFor([&] { return forces.connected(); }));
  for (bool block_sparse : {false, true}) {
    const Scene scene = makeScene(freshIds(), freshStamp(), block_sparse);
    const lcs::SolverStats* stats = solve(scene);
    ASSERT_NE(stats, nullptr);
    ASSERT_TRUE(forces.wait(scene.contacts.header.stamp));
    lcs::core::Problem problem;
    const lcs::core::SolveResult expected = directSolve(scene, &problem);
    ASSERT_TRUE(expected.converged);
    expectForcesEqual(*forces.get(scene.contacts.header.stamp), problem, expected);
    EXPECT_TRUE(stats->success);
    EXPECT_TRUE(stats->converged);
    EXPECT_TRUE(stats->forces_published);  // somebody subscribes
    EXPECT_EQ(stats->iterations, expected.iterations);
    EXPECT_NEAR(stats->residual, expected.residual, 1e-12);
    EXPECT_EQ(stats->num_rows, 9);
  }
}

TEST_F(ContactSolverNodeTest, ServiceReturnsTheSameForces) {
  const Scene scene = makeScene(freshIds(), freshStamp(), true);
  lcs::SolveContacts srv;
  srv.request.contacts = scene.contacts;
  srv.request.compliance = scene.compliance;
  ASSERT_TRUE(ros::service::call(kSolver + "/solve_contacts", srv));
  EXPECT_TRUE(srv.response.success) << srv.response.message;
  EXPECT_EQ(srv.response.message, "converged");
  lcs::core::Problem problem;
  const lcs::core::SolveResult expected = directSolve(scene, &problem);
  expectForcesEqual(srv.response.forces, problem, expected);
  EXPECT_EQ(srv.response.stats.iterations, expected.iterations);

  srv.request.param_overrides = {"maxIt=1"};
  ASSERT_TRUE(ros::service::call(kSolver + "/solve_contacts", srv));
  EXPECT_TRUE(srv.response.success);
  EXPECT_EQ(srv.response.stats.iterations, 1);
  EXPECT_EQ(srv.response.stats.status, "max_iterations");

  srv.request.param_overrides = {"maxIt=lots"};
  ASSERT_TRUE(ros::service::call(kSolver + "/solve_contacts", srv));
  EXPECT_FALSE(srv.response.success);
  EXPECT_NE(srv.response.message.find("maxIt"), std::string::npos) << srv.response.message;

  srv.request.param_overrides.clear();
  srv.request.contacts.contacts[2].mu = -0.4;
  ASSERT_TRUE(ros::service::call(kSolver + "/solve_contacts", srv));
  EXPECT_FALSE(srv.response.success);
  EXPECT_NE(srv.response.message.find("negative mu"), std::string::npos) << srv.response.message;
  EXPECT_TRUE(srv.response.forces.forces.empty());
}

// Baumgarte β and softness: per solve as overrides (the node's ~erp/~softness for contacts
// with USE_DEFAULT), per contact in the message; the same forces as the core with those.
TEST_F(ContactSolverNodeTest, ServiceAppliesErpAndSoftnessPerSolveAndPerContact) {
  Scene scene = makeScene(freshIds(), freshStamp(), true);
  for (lcs::ContactPoint& c : scene.contacts.contacts) {
    c.gap = -0.02;
    c.erp = lcs::ContactPoint::USE_DEFAULT;
    c.softness = lcs::ContactPoint::USE_DEFAULT;
  }
  scene.contacts.contacts[1].erp = 0.5;       // its own β
  scene.contacts.contacts[2].softness = 0.3;  // its own softness
  lcs::SolveContacts srv;
  srv.request.contacts = scene.contacts;
  srv.request.compliance = scene.compliance;
  srv.request.param_overrides = {"erp=0.2", "softness=0.05", "tolerance=1e-10"};
  ASSERT_TRUE(ros::service::call(kSolver + "/solve_contacts", srv));
  ASSERT_TRUE(srv.response.success) << srv.response.message;
  lcs::core::Problem problem;
  std::vector<lcp_contact_solver_ros::ContactFrame> frames;
  ASSERT_EQ(lcp_contact_solver_ros::toProblem(scene.contacts, scene.compliance, 0, &problem, &frames), "");
  EXPECT_EQ(problem.contacts[1].erp, 0.5);
  EXPECT_EQ(problem.contacts[0].gap, -0.02);
  lcs::core::SolverParams params = lcp_contact_solver_ros::defaultSolverParams();
  params.erp = 0.2;
  params.softness = 0.05;
  params.tolerance = 1e-10;
  const lcs::core::SolveResult expected = lcs::core::solveProblem(problem, params);
  ASSERT_TRUE(expected.converged) << expected.message;
  expectForcesEqual(srv.response.forces, problem, expected);
  // The node's defaults (erp 0, softness 0) give the uncorrected forces: different ones.
  srv.request.param_overrides = {"tolerance=1e-10"};
  ASSERT_TRUE(ros::service::call(kSolver + "/solve_contacts", srv));
  ASSERT_TRUE(srv.response.success) << srv.response.message;
  params.erp = 0.0;
  params.softness = 0.0;
  const lcs::core::SolveResult plain = lcs::core::solveProblem(problem, params);
  expectForcesEqual(srv.response.forces, problem, plain);
  EXPECT_GT((plain.forces - expected.forces).norm(), 1e-3);
  // Velocity level without a step: refused, naming the parameter.
  srv.request.param_overrides = {"erp=0.2", "constraint_level=velocity"};
  ASSERT_TRUE(ros::service::call(kSolver + "/solve_contacts", srv));
  EXPECT_FALSE(srv.response.success);
  EXPECT_NE(srv.response.message.find("time_step"), std::string::npos) << srv.response.message;
}

// The body form of the compliance (STORAGE_BODIES): build_lcp=false runs the unbuilt
// Gauss-Seidel and gives the forces of the built solve on the assembled W; build_lcp=true
// (the node's default) assembles W; the topics take the body form too.
TEST_F(ContactSolverNodeTest, BodyFormSolvesUnbuiltWithBuildLcpFalse) {
  const Scene scene = lcp_contact_solver_test::makeBodyFormScene(freshIds(), freshStamp());
  lcs::core::Problem problem;
  std::vector<lcp_contact_solver_ros::ContactFrame> frames;
  ASSERT_EQ(lcp_contact_solver_ros::toProblem(scene.contacts, scene.compliance, 0, &problem, &frames), "");
  ASSERT_TRUE(problem.bodies);
  lcs::core::Problem assembled = problem;  // the built problem: the same W, assembled and dense
  assembled.bodies.reset();
  assembled.W = problem.bodies->toDense();
  lcs::core::SolverParams params = lcp_contact_solver_ros::defaultSolverParams();
  params.tolerance = 1e-10;
  const lcs::core::SolveResult built = lcs::core::solveProblem(assembled, params);
  ASSERT_TRUE(built.converged) << built.message;

  lcs::SolveContacts srv;
  srv.request.contacts = scene.contacts;
  srv.request.compliance = scene.compliance;
  srv.request.param_overrides = {"build_lcp=false", "tolerance=1e-10"};
  ASSERT_TRUE(ros::service::call(kSolver + "/solve_contacts", srv));
  ASSERT_TRUE(srv.response.success) << srv.response.message;
  EXPECT_TRUE(srv.response.stats.converged);
  EXPECT_NE(srv.response.message.find("unbuilt solve on the body form (3 bodies)"), std::string::npos)
      << srv.response.message;
  ASSERT_EQ(srv.response.forces.forces.size(), problem.contacts.size());
  const std::vector<int> offsets = problem.rowOffsets();
  const double scale = built.forces.cwiseAbs().maxCoeff();
  for (std::size_t i = 0; i < problem.contacts.size(); ++i) {
    EXPECT_EQ(srv.response.forces.forces[i].state, static_cast<std::uint8_t>(built.states[i])) << i;
    for (int k = 0; k < problem.contacts[i].rows; ++k)
      EXPECT_NEAR(srv.response.forces.forces[i].lambda[k], built.forces[offsets[i] + k], 1e-8 * scale)
          << i << ", " << k;
  }

  // build_lcp=true: W assembled once, the same forces, no unbuilt note.
  srv.request.param_overrides = {"build_lcp=true", "tolerance=1e-10"};
  ASSERT_TRUE(ros::service::call(kSolver + "/solve_contacts", srv));
  ASSERT_TRUE(srv.response.success) << srv.response.message;
  EXPECT_EQ(srv.response.message.find("unbuilt"), std::string::npos) << srv.response.message;
  for (std::size_t i = 0; i < problem.contacts.size(); ++i)
    for (int k = 0; k < problem.contacts[i].rows; ++k)
      EXPECT_NEAR(srv.response.forces.forces[i].lambda[k], built.forces[offsets[i] + k], 1e-8 * scale);

  // Other solvers assemble W and say so.
  srv.request.param_overrides = {"build_lcp=false", "solver=newton", "tolerance=1e-10"};
  ASSERT_TRUE(ros::service::call(kSolver + "/solve_contacts", srv));
  ASSERT_TRUE(srv.response.success) << srv.response.message;
  EXPECT_NE(srv.response.message.find("newton needs the assembled W"), std::string::npos)
      << srv.response.message;

  // A malformed body form is refused with its sentence.
  srv.request.compliance.contact_bodies[4] = 7;
  srv.request.param_overrides = {"build_lcp=false"};
  ASSERT_TRUE(ros::service::call(kSolver + "/solve_contacts", srv));
  EXPECT_FALSE(srv.response.success);
  EXPECT_NE(srv.response.message.find("names body_a 7"), std::string::npos) << srv.response.message;

  // The topics: paired and solved like any compliance (the node's build_lcp: assembled).
  const lcs::SolverStats* stats = solve(scene);
  ASSERT_NE(stats, nullptr);
  EXPECT_TRUE(stats->success) << stats->message;
  EXPECT_EQ(stats->num_rows, 9);
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_contact_solver_node");
  for (int i = 1; i < argc; ++i) g_nodelet = g_nodelet || std::strcmp(argv[i], "--nodelet") == 0;
  ros::NodeHandle nh;
  // With --nodelet the solver runs in this process, as in a simulator's nodelet manager.
  std::unique_ptr<nodelet::Loader> loader;
  if (g_nodelet) {
    loader = std::make_unique<nodelet::Loader>(false);
    if (!loader->load("/" + kSolver, "lcp_contact_solver/ContactSolverNodelet", {}, {})) {
      ADD_FAILURE() << "could not load the nodelet";
      return 1;
    }
  }
  const int result = RUN_ALL_TESTS();
  loader.reset();
  return result;
}
