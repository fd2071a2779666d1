// Scene loading: URDF conventions, errors that name the link, YAML parameters.
#include "lcp_contact_solver/scene/scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

using namespace lcp_contact_solver;
using namespace lcp_contact_solver::scene;

namespace {

const std::string kDir = LCS_SCENES_DIR;

std::string freeBox(const std::string& name, const std::string& inertial, const std::string& geometry,
                    const std::string& joint_type = "floating", const std::string& parent = "world") {
  return "<link name='" + name + "'>" + inertial + "<collision><geometry>" + geometry +
         "</geometry></collision></link>"
         "<joint name='" +
         name + "_joint' type='" + joint_type + "'><parent link='" + parent + "'/><child link='" + name +
         "'/><origin xyz='0 0 1'/></joint>";
}

const std::string kInertial =
    "<inertial><mass value='2'/><inertia ixx='0.1' ixy='0' ixz='0' iyy='0.1' iyz='0' izz='0.1'/></inertial>";
const std::string kBox = "<box size='0.2 0.2 0.2'/>";

std::string robot(const std::string& body) {
  return "<?xml version='1.0'?><robot name='t'><link name='world'/>" + body + "</robot>";
}

// Expects a SceneError whose message contains every fragment.
void expectError(const std::string& urdf, const std::vector<std::string>& fragments,
                 const SceneParams& params = SceneParams()) {
  try {
    loadSceneFromUrdfString(urdf, params, "test.urdf");
    FAIL() << "no error for " << urdf;
  } catch (const SceneError& e) {
    for (const std::string& f : fragments)
      EXPECT_NE(std::string(e.what()).find(f), std::string::npos) << "'" << f << "' not in: " << e.what();
  }
}

}  // namespace

TEST(SceneLoading, FloatingLinkIsDynamicRootAndFixedAreStatic) {
  const std::string urdf =
      robot(freeBox("crate", kInertial, kBox) +
            "<link name='shelf'><collision><geometry><box size='1 1 0.1'/></geometry></collision></link>"
            "<joint name='shelf_joint' type='fixed'><parent link='world'/><child link='shelf'/>"
            "<origin xyz='0 0 0.5' rpy='0 0 1.5707963267948966'/></joint>");
  const Scene s = loadSceneFromUrdfString(urdf, SceneParams());
  ASSERT_EQ(s.bodies.size(), 3u);
  const RigidBody& world = s.bodies[s.requireBody("world")];
  const RigidBody& crate = s.bodies[s.requireBody("crate")];
  const RigidBody& shelf = s.bodies[s.requireBody("shelf")];
  EXPECT_TRUE(world.is_static);
  EXPECT_FALSE(world.hasCollision());
  EXPECT_FALSE(crate.is_static);
  EXPECT_DOUBLE_EQ(crate.mass, 2.0);
  EXPECT_NEAR(crate.position.z(), 1.0, 1e-15);
  EXPECT_TRUE(shelf.is_static);
  EXPECT_NEAR(shelf.position.z(), 0.5, 1e-15);
  EXPECT_NEAR((shelf.orientation * Eigen::Vector3d::UnitX() - Eigen::Vector3d::UnitY()).norm(), 0.0, 1e-12);
  EXPECT_EQ(s.dynamicBodyCount(), 1);
}

TEST(SceneLoading, ErrorsNameTheLink) {
  // Missing inertial on a free body.
  expectError(robot(freeBox("crate", "", kBox)), {"test.urdf", "link 'crate'", "no <inertial>"});
  // Zero mass.
  expectError(robot(freeBox("crate",
                            "<inertial><mass value='0'/><inertia ixx='0.1' ixy='0' ixz='0' iyy='0.1' iyz='0' "
                            "izz='0.1'/></inertial>",
                            kBox)),
              {"link 'crate'", "mass"});
  // Inertia not positive definite.
  expectError(robot(freeBox("crate",
                            "<inertial><mass value='1'/><inertia ixx='0' ixy='0' ixz='0' iyy='0.1' iyz='0' "
                            "izz='0.1'/></inertial>",
                            kBox)),
              {"link 'crate'", "positive definite"});
  // Unsupported geometry.
  expectError(robot(freeBox("teapot", kInertial, "<mesh filename='package://x/teapot.stl'/>")),
              {"link 'teapot'", "mesh"});
  // Unsupported joint type.
  expectError(robot("<link name='arm'/><joint name='elbow' type='continuous'><parent link='world'/>"
                    "<child link='arm'/><axis xyz='0 0 1'/></joint>"),
              {"link 'arm'", "continuous", "'elbow'"});
  // Fixed joint to a dynamic link.
  expectError(robot(freeBox("crate", kInertial, kBox) + "<link name='lid'><collision><geometry>" + kBox +
                    "</geometry></collision></link>"
                    "<joint name='lid_joint' type='fixed'><parent link='crate'/><child link='lid'/></joint>"),
              {"link 'lid'", "dynamic link 'crate'"});
  // Not XML at all.
  expectError("<robot", {"test.urdf", "not a valid URDF"});
}

TEST(SceneLoading, ParamsAreCheckedAgainstTheBodies) {
  SceneParams p;
  p.friction_pairs.push_back({"crate", "ghost", 0.1});
  expectError(robot(freeBox("crate", kInertial, kBox)), {"friction_pairs", "'ghost'"}, p);
  p = SceneParams();
  p.joint_origins["nope"] = JointOriginOverride();
  expectError(robot(freeBox("crate", kInertial, kBox)), {"joint_origins", "'nope'"}, p);
  p = SceneParams();
  p.initial_velocities["world"] = InitialVelocity();
  expectError(robot(freeBox("crate", kInertial, kBox)), {"initial_velocities", "'world'", "static"}, p);
}

TEST(SceneLoading, YamlParameters) {
  const SceneParams p = parseSceneParams(
      "dt: 0.005\nmu: 0.25\nerp: 0.3\ncompliance: dense\n"
      "friction_pairs: [[a, b, 0.0]]\ndisable_collisions: [[a, c]]\n"
      "joint_origins: {tilt: {rpy_deg: [0, 30, 0], xyz: [1, 2, 3]}}\n"
      "initial_velocities: {a: {linear: [1, 0, 0]}}\n"
      "ground_plane: {height: -0.5}\nsolver: {name: nlgs, tolerance: 1.0e-10, maxIt: 100}\n",
      "inline.yaml");
  EXPECT_DOUBLE_EQ(p.dt, 0.005);
  EXPECT_DOUBLE_EQ(p.frictionFor("b", "a"), 0.0);
  EXPECT_DOUBLE_EQ(p.frictionFor("a", "c"), 0.25);
  EXPECT_TRUE(p.collisionDisabled("c", "a"));
  EXPECT_FALSE(p.collisionDisabled("a", "b"));
  EXPECT_EQ(p.compliance, ComplianceStorage::kDense);
  EXPECT_NEAR(p.joint_origins.at("tilt").rpy.y(), M_PI / 6, 1e-15);
  EXPECT_TRUE(p.joint_origins.at("tilt").has_xyz);
  EXPECT_TRUE(p.ground_plane.enabled);
  EXPECT_DOUBLE_EQ(p.ground_plane.height, -0.5);
  EXPECT_EQ(p.solver.solver, core::SolverKind::kNlgs);
  EXPECT_EQ(p.solver.maxIt, 100);

  auto expectYamlError = [](const std::string& text, const std::string& fragment) {
    try {
      parseSceneParams(text, "bad.yaml");
      FAIL() << "no error for " << text;
    } catch (const SceneError& e) {
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("bad.yaml"), std::string::npos) << e.what();
    }
  };
  expectYamlError("mu: -1\n", "mu");
  expectYamlError("muu: 0.3\n", "'muu'");
  expectYamlError("dt: fast\n", "'dt'");
  expectYamlError("compliance: sparse\n", "compliance");
  expectYamlError("friction_pairs: [[a, b]]\n", "friction_pairs[0]");
  expectYamlError("solver: {name: magic}\n", "solver.name");
  expectYamlError("solver: {maxIt: 5.5}\n", "'solver.maxIt': maxIt='5.5' must be an integer");
  expectYamlError("solver: {speed: 3}\n", "'solver.speed': unknown key");
  expectYamlError("solver: {solver: pgs}\n", "'solver.solver': unknown key");  // `name` here
  expectYamlError("solver: {sor: 2}\n", "solver: sor must be");                // validateParams
  expectYamlError("mu: [\n", "syntax");
}

// The solver: map takes every parameter of the core's table (solver_param_table.def).
TEST(SceneLoading, SolverMapTakesEveryTableParameter) {
  const SceneParams p = parseSceneParams(
      "solver: {name: pgs, sor: 1.2, friction_model: pyramid4, islands: false, threads: 1, max_rows: 900,\n"
      "         initial_guess: no, stopping_rule: sofa, time_budget: 0.5}\n",
      "inline.yaml");
  EXPECT_EQ(p.solver.solver, core::SolverKind::kPgs);
  EXPECT_EQ(p.solver.sor, 1.2);
  EXPECT_EQ(p.solver.friction_model, core::FrictionModel::kPyramid4);
  EXPECT_FALSE(p.solver.islands);
  EXPECT_EQ(p.solver.threads, 1);
  EXPECT_EQ(p.solver.max_rows, 900);
  EXPECT_FALSE(p.solver.initial_guess);
  EXPECT_EQ(p.solver.stopping_rule, core::StoppingRule::kSofa);
  EXPECT_EQ(p.solver.time_budget, 0.5);
  EXPECT_EQ(p.solver.tolerance,
            SceneParams::defaultSceneSolverParams().tolerance);  // not given: the scene default
}

TEST(SceneLoading, ShippedScenesLoad) {
  for (const char* name : {"box_stack", "incline", "sphere_pile", "frictionless", "mixed"}) {
    SCOPED_TRACE(name);
    const Scene s = loadNamedScene(kDir, name);
    EXPECT_GT(s.dynamicBodyCount(), 0);
    EXPECT_GE(s.bodyIndex("ground_plane"), 0);
  }
  const Scene stack = loadNamedScene(kDir, "box_stack");
  EXPECT_EQ(stack.dynamicBodyCount(), 5);
  // The incline's angle comes from the YAML and places the box on the ramp surface.
  const Scene incline = loadNamedScene(kDir, "incline");
  const RigidBody& ramp = incline.bodies[incline.requireBody("ramp")];
  const RigidBody& box = incline.bodies[incline.requireBody("box")];
  const Eigen::Vector3d n = ramp.orientation * Eigen::Vector3d::UnitZ();
  EXPECT_NEAR(std::acos(n.z()), 20.0 * M_PI / 180.0, 1e-12);
  EXPECT_NEAR(n.dot(box.position - ramp.position), 0.05, 1e-12);  // half the box height
}
