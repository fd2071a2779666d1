// Problems of growing size taken from the scene library (the "scenes" family of the
// benchmark). Two generators, each using the body sizes, masses and parameters of a shipped
// scene (config/scenes/<name>.yaml is loaded, only the body count changes):
//
//   box_pyramid_B<k>: a brick pyramid of 0.2 m, 1 kg cubes (box_stack.urdf's bodies) with
//     k bricks at the base, each upper brick resting on two (running bond); FCL gives four
//     points per face contact, so about 4 k^2 contacts, rank-deficient like BoxesStack.
//   sphere_pile_<n>: n balls of r = 0.05 m, 0.2 kg (sphere_pile.urdf's) dropped as a loose
//     lattice into a square bin of static walls sized to the pile; a few hundred contacts
//     per hundred balls once settled.
//
// The scene is stepped in-process (SceneSimulator::step, nlgs at 1e-6, at most 2000 sweeps,
// only to move the bodies) for `steps` steps so contacts are those of a resting or settling
// pile, and the problem of the next step is taken (buildStep), W block-sparse as the scene
// builds it.
#pragma once

#include "lcp_contact_solver/core/problem.h"
#include "lcp_contact_solver/scene/scene.h"

#include <string>
#include <vector>

namespace lcs_bench {

struct SceneProblem {
  std::string name;   // e.g. "box_pyramid_B5"
  std::string scene;  // the shipped scene whose parameters it uses
  int bodies = 0;
  int steps = 0;  // simulated steps before the problem was taken
  lcp_contact_solver::core::Problem problem;
  // The same step with the compliance in body form (Problem::bodies, no W; the unbuilt solve,
  // bench/unbuilt_scaling.cpp).
  lcp_contact_solver::core::Problem body_form;
};

// Box pyramids with the given base widths, then sphere piles with the given ball counts.
// Throws scene::SceneError when a shipped scene cannot be read.
std::vector<SceneProblem> makeSceneProblems(const std::string& scenes_dir,
                                            const std::vector<int>& pyramid_bases,
                                            const std::vector<int>& pile_balls, int steps);

// The scene behind one of those problems before its first step: family "box_pyramid" (size =
// bricks at the base) or "sphere_pile" (size = balls), parameters from the shipped scene,
// in-process solver nlgs at 1e-6. Throws std::invalid_argument for another family.
lcp_contact_solver::scene::Scene makeBenchScene(const std::string& scenes_dir, const std::string& family,
                                                int size);

}  // namespace lcs_bench
