// The scenes of the effects-cost benchmark: the variants derived from one problem of 6-row
// contacts, the ball pile of the generation measurement, and the scene YAMLs with torsional
// and rolling friction set.
#include "effects_cost.h"

#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace lcs_bench::effects_cost {

namespace {

// Body pair of a scene contact id: id = (A << 40) | (B << 16) | slot.
std::int64_t pairOf(std::int64_t id) { return id >> 16; }

// "Half of the body pairs": every other pair in order of first appearance.
std::vector<bool> halfThePairs(const lcs::core::Problem& p) {
  std::map<std::int64_t, int> index;
  std::vector<bool> pick(p.contacts.size());
  for (std::size_t i = 0; i < p.contacts.size(); ++i) {
    auto it = index.emplace(pairOf(p.contacts[i].id), static_cast<int>(index.size())).first;
    pick[i] = it->second % 2 == 1;
  }
  return pick;
}

}  // namespace

std::vector<Variant> variantsOf(const lcs::core::Problem& p6, double mu_tor, double mu_roll) {
  using T = lcs::core::ContactType;
  const ContactModel frictional{T::kFrictional, 3, 0.5, 0.0, 0.0};
  const ContactModel frictional0{T::kFrictional, 3, 0.0, 0.0, 0.0};
  const ContactModel frictionless{T::kFrictionless, 1, 0.0, 0.0, 0.0};
  const ContactModel torsional{T::kTorsional, 4, 0.5, mu_tor, 0.0};
  const ContactModel rolling{T::kRolling, 6, 0.5, mu_tor, mu_roll};
  const std::vector<bool> half = halfThePairs(p6);
  std::vector<ContactModel> mixed1, mixed3;
  for (bool h : half) {
    mixed1.push_back(h ? frictionless : frictional);
    mixed3.push_back(h ? frictional0 : frictional);
  }
  return {
      {"mu0.5", lcs_bench::deriveUniform(p6, frictional)},
      {"mu0_3row", lcs_bench::deriveUniform(p6, frictional0)},
      {"frictionless", lcs_bench::deriveUniform(p6, frictionless)},
      {"mixed_1row", lcs_bench::deriveProblem(p6, mixed1)},
      {"mixed_3row", lcs_bench::deriveProblem(p6, mixed3)},
      {"torsional", lcs_bench::deriveUniform(p6, torsional)},
      {"rolling", lcs_bench::deriveUniform(p6, rolling)},
  };
}

// n balls of r = 0.05 m, 0.2 kg in a square bin of static walls, as a loose lattice (the
// geometry of bench/scene_problems.cpp's sphere piles, written here because that generator
// does not hand out its simulator).
std::string pileUrdf(int n) {
  const double r = 0.05, pitch = 0.104;
  int side = 2;
  while (side * side * side < n) ++side;
  const double inner = side * pitch + 0.01, wall = 0.05, height = 0.3 + 0.11 * (n / (side * side) + 1);
  std::ostringstream u;
  u.precision(17);
  u << "<?xml version=\"1.0\"?>\n<robot name=\"pile\">\n  <link name=\"world\"/>\n";
  auto wallBox = [&](const std::string& name, double sx, double sy, double x, double y) {
    u << "  <link name=\"" << name << "\"><collision><geometry><box size=\"" << sx << " " << sy << " "
      << height << "\"/></geometry></collision></link>\n  <joint name=\"" << name
      << "_joint\" type=\"fixed\"><parent link=\"world\"/><child link=\"" << name << "\"/><origin xyz=\"" << x
      << " " << y << " " << 0.5 * height << "\"/></joint>\n";
  };
  const double h = 0.5 * (inner + wall);
  wallBox("wall_north", inner + 2 * wall, wall, 0, h);
  wallBox("wall_south", inner + 2 * wall, wall, 0, -h);
  wallBox("wall_east", wall, inner, h, 0);
  wallBox("wall_west", wall, inner, -h, 0);
  int k = 0;
  for (int layer = 0; k < n; ++layer) {
    const int per_row = layer % 2 == 0 ? side : side - 1;
    const double shift = layer % 2 == 0 ? 0.0 : 0.5 * pitch;
    for (int i = 0; i < per_row && k < n; ++i)
      for (int j = 0; j < per_row && k < n; ++j) {
        const double x = (i - 0.5 * (side - 1)) * pitch + shift + 0.003 * std::sin(1.7 * k);
        const double y = (j - 0.5 * (side - 1)) * pitch + shift + 0.003 * std::cos(2.3 * k);
        const double z = r + 0.002 + layer * 0.09;
        const std::string name = "ball_" + std::to_string(++k);
        u << "  <link name=\"" << name
          << "\"><inertial><mass value=\"0.2\"/><inertia ixx=\"0.0002\" ixy=\"0\" "
          << "ixz=\"0\" iyy=\"0.0002\" iyz=\"0\" izz=\"0.0002\"/></inertial><collision><geometry><sphere "
          << "radius=\"0.05\"/></geometry></collision></link>\n  <joint name=\"" << name
          << "_joint\" type=\"floating\"><parent link=\"world\"/><child link=\"" << name
          << "\"/><origin xyz=\"" << x << " " << y << " " << z << "\"/></joint>\n";
      }
  }
  u << "</robot>\n";
  return u.str();
}

// (ii) every ball-ball pair disabled: n(n-1)/2 of the n(n-1)/2 + 5n candidate pairs.
sc::Scene withBallPairsDisabled(const sc::Scene& settled) {
  std::vector<std::string> balls;
  for (const sc::RigidBody& b : settled.bodies)
    if (!b.is_static) balls.push_back(b.name);
  sc::Scene disabled = settled;
  for (std::size_t i = 0; i < balls.size(); ++i)
    for (std::size_t j = i + 1; j < balls.size(); ++j)
      disabled.params.disable_collisions.emplace_back(balls[i], balls[j]);
  return disabled;
}

// (iii) mixed: half of the touching ball-ball pairs frictionless via friction_pairs.
sc::Scene withHalfTouchingFrictionless(const sc::Scene& settled) {
  sc::Scene mixed = settled;
  sc::ContactGenerator gen(settled);
  std::set<std::pair<int, int>> touching;
  for (const sc::SceneContact& f : gen.generate())
    if (!settled.bodies[f.body_a].is_static && !settled.bodies[f.body_b].is_static)
      touching.emplace(f.body_a, f.body_b);
  int k = 0;
  for (const auto& [a, b] : touching)
    if (k++ % 2 == 0)
      mixed.params.friction_pairs.push_back({settled.bodies[a].name, settled.bodies[b].name, 0.0});
  return mixed;
}

// Copies the two scene YAMLs the generators read into a temporary folder with torsional and
// rolling friction set, so every contact of the generated problems has 6 rows.
std::string rollingScenesDir(double torsional, double rolling) {
  char tmpl[] = "/tmp/effects_cost_scenes_XXXXXX";
  if (!mkdtemp(tmpl)) throw std::runtime_error("cannot create a temporary folder");
  const std::string dir = tmpl;
  for (const char* name : {"box_stack.yaml", "sphere_pile.yaml"}) {
    std::ifstream in(std::string(LCS_SCENES_DIR) + "/" + name);
    std::stringstream text;
    text << in.rdbuf();
    if (text.str().find("torsional_friction") != std::string::npos ||
        text.str().find("rolling_friction") != std::string::npos)
      throw std::runtime_error(std::string(name) + " already sets torsional/rolling friction");
    std::ofstream out(dir + "/" + name);
    out << text.str() << "\ntorsional_friction: " << torsional << "\nrolling_friction: " << rolling << "\n";
  }
  return dir;
}

}  // namespace lcs_bench::effects_cost
