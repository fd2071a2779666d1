#include "scene_problems.h"

#include "lcp_contact_solver/scene/scene.h"
#include "lcp_contact_solver/scene/scene_params.h"
#include "lcp_contact_solver/scene/scene_simulator.h"

#include <cmath>
#include <memory>
#include <sstream>
#include <stdexcept>

namespace lcs_bench {
namespace {

namespace lcs = lcp_contact_solver;
namespace sc = lcp_contact_solver::scene;

void floatingBody(std::ostringstream& u, const std::string& name, double mass, double inertia,
                  const std::string& geometry, double x, double y, double z) {
  u << "  <link name=\"" << name << "\">\n"
    << "    <inertial><mass value=\"" << mass << "\"/><inertia ixx=\"" << inertia
    << "\" ixy=\"0\" ixz=\"0\" iyy=\"" << inertia << "\" iyz=\"0\" izz=\"" << inertia << "\"/></inertial>\n"
    << "    <collision><geometry>" << geometry << "</geometry></collision>\n"
    << "  </link>\n"
    << "  <joint name=\"" << name << "_joint\" type=\"floating\"><parent link=\"world\"/><child link=\""
    << name << "\"/><origin xyz=\"" << x << " " << y << " " << z << "\"/></joint>\n";
}

void staticBox(std::ostringstream& u, const std::string& name, double sx, double sy, double sz, double x,
               double y, double z) {
  u << "  <link name=\"" << name << "\"><collision><geometry><box size=\"" << sx << " " << sy << " " << sz
    << "\"/></geometry></collision></link>\n"
    << "  <joint name=\"" << name << "_joint\" type=\"fixed\"><parent link=\"world\"/><child link=\"" << name
    << "\"/><origin xyz=\"" << x << " " << y << " " << z << "\"/></joint>\n";
}

// Brick pyramid in the x-z plane: layer l (from 0 at the ground) has base - l cubes of side
// s = 0.2 m with 0.02 m gaps (more than the contact margin, so no side contacts), shifted by
// half a pitch per layer so every upper brick rests on two.
std::string pyramidUrdf(int base) {
  const double s = 0.2, gap = 0.02, pitch = s + gap;
  std::ostringstream u;
  u.precision(17);
  u << "<?xml version=\"1.0\"?>\n<robot name=\"box_pyramid\">\n  <link name=\"world\"/>\n";
  int k = 0;
  for (int layer = 0; layer < base; ++layer) {
    const int count = base - layer;
    for (int i = 0; i < count; ++i) {
      const double x = (i - 0.5 * (count - 1)) * pitch;
      const double z = 0.5 * s + layer * s;
      floatingBody(u, "box_" + std::to_string(++k), 1.0, 0.00666666667, "<box size=\"0.2 0.2 0.2\"/>", x, 0.0,
                   z);
    }
  }
  u << "</robot>\n";
  return u.str();
}

// n balls of r = 0.05 m as a loose lattice (pitch 0.104 m, alternate layers shifted by half a
// pitch) above the floor of a square bin of static walls that holds `side` balls per row.
std::string pileUrdf(int n, int* side_out) {
  const double r = 0.05, pitch = 0.104;
  int side = 2;
  while (side * side * side < n) ++side;  // about `side` layers: a deep pile
  *side_out = side;
  const double inner = side * pitch + 0.01;  // bin inner width
  const double wall = 0.05, height = 0.3 + 0.11 * (n / (side * side) + 1);
  std::ostringstream u;
  u.precision(17);
  u << "<?xml version=\"1.0\"?>\n<robot name=\"sphere_pile\">\n  <link name=\"world\"/>\n";
  const double h = 0.5 * (inner + wall);
  staticBox(u, "wall_north", inner + 2 * wall, wall, height, 0, h, 0.5 * height);
  staticBox(u, "wall_south", inner + 2 * wall, wall, height, 0, -h, 0.5 * height);
  staticBox(u, "wall_east", wall, inner, height, h, 0, 0.5 * height);
  staticBox(u, "wall_west", wall, inner, height, -h, 0, 0.5 * height);
  int k = 0;
  for (int layer = 0; k < n; ++layer) {
    const int per_row = layer % 2 == 0 ? side : side - 1;
    const double shift = layer % 2 == 0 ? 0.0 : 0.5 * pitch;
    for (int i = 0; i < per_row && k < n; ++i)
      for (int j = 0; j < per_row && k < n; ++j) {
        // a small deterministic jitter so the lattice does not stay perfectly symmetric
        const double jx = 0.003 * std::sin(1.7 * k), jy = 0.003 * std::cos(2.3 * k);
        const double x = (i - 0.5 * (side - 1)) * pitch + shift + jx;
        const double y = (j - 0.5 * (side - 1)) * pitch + shift + jy;
        const double z = r + 0.002 + layer * 0.09;
        floatingBody(u, "ball_" + std::to_string(++k), 0.2, 0.0002, "<sphere radius=\"0.05\"/>", x, y, z);
      }
  }
  u << "</robot>\n";
  return u.str();
}

SceneProblem runAndTake(const std::string& name, const std::string& scene_name, sc::Scene scene, int steps) {
  SceneProblem out;
  out.name = name;
  out.scene = scene_name;
  out.bodies = scene.dynamicBodyCount();
  out.steps = steps;
  sc::SceneSimulator sim(std::move(scene));
  for (int i = 0; i < steps; ++i) sim.step();
  const sc::StepProblem& step = sim.buildStep();
  out.problem = step.problem;
  out.problem.name = name;
  out.body_form = out.problem;
  out.body_form.W = Eigen::MatrixXd();
  out.body_form.bodies = std::make_shared<const lcs::core::BodyCompliance>(
      sc::RigidContactModel(sim.scene(), step.frames).bodyCompliance(step.dt));
  return out;
}

sc::SceneParams generationParams(const std::string& yaml) {
  sc::SceneParams params = sc::loadSceneParams(yaml);
  // Only to move the bodies to realistic contact states; the benchmark solves the taken
  // problem from scratch with every solver.
  params.solver.solver = lcs::core::SolverKind::kNlgs;
  params.solver.tolerance = 1e-6;
  params.solver.maxIt = 2000;
  params.compliance = sc::ComplianceStorage::kBlockSparse;
  return params;
}

}  // namespace

sc::Scene makeBenchScene(const std::string& scenes_dir, const std::string& family, int size) {
  if (family == "box_pyramid")
    return sc::loadSceneFromUrdfString(pyramidUrdf(size), generationParams(scenes_dir + "/box_stack.yaml"),
                                       "box_pyramid");
  if (family == "sphere_pile") {
    int side = 0;
    return sc::loadSceneFromUrdfString(pileUrdf(size, &side),
                                       generationParams(scenes_dir + "/sphere_pile.yaml"), "sphere_pile");
  }
  throw std::invalid_argument("unknown scene family '" + family + "' (box_pyramid or sphere_pile)");
}

std::vector<SceneProblem> makeSceneProblems(const std::string& scenes_dir,
                                            const std::vector<int>& pyramid_bases,
                                            const std::vector<int>& pile_balls, int steps) {
  std::vector<SceneProblem> out;
  for (int base : pyramid_bases)
    out.push_back(runAndTake("box_pyramid_B" + std::to_string(base), "box_stack",
                             makeBenchScene(scenes_dir, "box_pyramid", base), steps));
  for (int n : pile_balls)
    out.push_back(runAndTake("sphere_pile_" + std::to_string(n), "sphere_pile",
                             makeBenchScene(scenes_dir, "sphere_pile", n), steps));
  return out;
}

}  // namespace lcs_bench
