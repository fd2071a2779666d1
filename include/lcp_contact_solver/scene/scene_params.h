// Parameters of a scene: the small YAML file beside each URDF under config/scenes/.
//
// Layer rule: the scene layer depends on the core only (no ROS headers). The YAML reader is
// yaml-cpp (Debian libyaml-cpp-dev), used only in the .cpp files.
//
// Every key is optional; unknown keys are an error (a typo must not silently fall back to
// a default). Units are SI. See config/scenes/README.md for an annotated example.
#pragma once

#include "lcp_contact_solver/core/solver_params.h"

#include <Eigen/Core>

#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace lcp_contact_solver {
namespace scene {

// Every fault of a scene file (URDF or YAML) or of a scene's use. The message names the
// file and the link, joint or key at fault.
class SceneError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// How the compliance W is stored in the problem handed to the solver.
enum class ComplianceStorage {
  kDense,        // "dense": Eigen::MatrixXd
  kBlockSparse,  // "block_sparse": one block per pair of contacts sharing a dynamic body
  kBodies,       // "bodies": the body form (dt² M⁻¹ per body and the contacts' Jacobians,
                 // core/body_compliance.h), W not assembled: with build_lcp = false the
                 // solver runs unbuilt (SOFA's build_lcp), otherwise it assembles W once
};
const char* complianceStorageName(ComplianceStorage storage);
bool parseComplianceStorage(const std::string& name, ComplianceStorage* storage);

// Friction between two named bodies (order does not matter). μ = 0 makes the pair's
// contacts frictionless one-row contacts.
// Friction of one body pair. The contact's rows follow what it asks for (MuJoCo's
// condim): mu = 0 → 1 row; mu > 0 → 3; torsional > 0 → 4 (spin); rolling > 0 → 6.
struct PairFriction {
  std::string body_a, body_b;
  double mu = 0.0;
  double torsional = -1.0;  // m; < 0: the scene's torsional_friction
  double rolling = -1.0;    // m; < 0: the scene's rolling_friction
};

// Restitution of one body pair (Newton's coefficient, [0, 1]).
struct PairRestitution {
  std::string body_a, body_b;
  double restitution = 0.0;
};

// What a body pair's contacts are made of.
struct PairContactModel {
  double mu = 0.0, torsional = 0.0, rolling = 0.0, restitution = 0.0;
};

// Replaces the origin of a URDF joint (fixed or floating) before the scene is built;
// e.g. the incline angle: `joint_origins: {tilt: {rpy_deg: [0, 20, 0]}}`.
struct JointOriginOverride {
  bool has_xyz = false, has_rpy = false;
  Eigen::Vector3d xyz = Eigen::Vector3d::Zero();
  Eigen::Vector3d rpy = Eigen::Vector3d::Zero();  // radians (YAML: `rpy` or `rpy_deg`)
};

// Initial velocity of a dynamic body: of its centre of mass, and its angular velocity,
// both in the world frame.
struct InitialVelocity {
  Eigen::Vector3d linear = Eigen::Vector3d::Zero();   // m/s
  Eigen::Vector3d angular = Eigen::Vector3d::Zero();  // rad/s
};

// An optional static ground: a body named "ground_plane" whose top face is the plane
// z = height. It is a large thin box, not an FCL half-space, because FCL's box-box test
// gives up to four contact points per face contact while its box-half-space test gives one
// (a box resting on one point would rock).
struct GroundPlane {
  bool enabled = false;
  double height = 0.0;        // m, z of the top face
  double half_extent = 50.0;  // m, half side length in x and y
  double thickness = 1.0;     // m
};

struct SceneParams {
  std::string description;
  // Fixed time step of the simulator (s). SceneSimulator::step() uses it.
  double dt = 0.01;
  Eigen::Vector3d gravity = Eigen::Vector3d(0.0, 0.0, -9.81);  // m/s²
  // Position-error reduction β: the fraction of a penetration removed per step, [0, 1];
  // 0 leaves penetrations as they are. Each contact carries it with its gap; the solver
  // applies it (core/stabilization.h), in-process and through the node alike.
  double erp = 0.2;
  // Contact softness (CFM) added to each contact's W_nn (m/N, since W = dt² J M⁻¹ Jᵀ):
  // with erp a spring of stiffness erp / softness per contact. 0 = rigid.
  double softness = 0.0;
  // Default friction coefficient of every body pair; `friction_pairs` overrides it.
  double mu = 0.5;
  std::vector<PairFriction> friction_pairs;
  // Torsional and rolling friction of every pair with mu > 0 (m: torque per newton of
  // normal force); 0 = none, so contacts stay 3 rows unless a scene asks for more.
  double torsional_friction = 0.0;
  double rolling_friction = 0.0;
  // Newton restitution: at impact (normal approach faster than restitution_threshold, m/s)
  // the contact asks for a separation speed of restitution × the approach speed.
  double restitution = 0.0;
  double restitution_threshold = 0.1;
  std::vector<PairRestitution> restitution_pairs;
  // Body pairs never tested (SRDF-style disable list): `disable_collisions: [[a, b], ...]`.
  std::vector<std::pair<std::string, std::string>> disable_collisions;
  // Speculative contact distance (m): shape pairs closer than this produce contacts; a
  // contact with gap > 0 gets force only if the bodies would otherwise meet within the step.
  // Should exceed the approach speed × dt (faster approaches penetrate once, then erp).
  double contact_margin = 0.01;
  // A new contact keeps the id of a previous-step contact of the same body pair whose
  // point, in body A's frame, is closer than this (m). Greedy nearest-first, deterministic.
  double id_match_tolerance = 0.01;
  ComplianceStorage compliance = ComplianceStorage::kBlockSparse;
  // Include the gyroscopic torque -ω×Iω in the free motion. Off by default: explicit
  // treatment gains energy for spinning asymmetric bodies; resting scenes do not need it.
  bool gyroscopic = false;
  GroundPlane ground_plane;
  std::map<std::string, JointOriginOverride> joint_origins;
  std::map<std::string, InitialVelocity> initial_velocities;
  // Solver settings of the in-process simulator (SceneSimulator). YAML `solver:` map of
  // the core's parameters (solver_param_table.def), with `name` for `solver`; e.g.
  // `build_lcp: false` with `compliance: bodies`: the unbuilt solve. The ROS simulator node leaves solving to the
  // solver node and ignores them.
  core::SolverParams solver = defaultSceneSolverParams();
  // Suggested simulated time for demos (s); 0 = not given.
  double duration = 0.0;

  static core::SolverParams defaultSceneSolverParams();
  // Friction coefficient of the pair (overrides first, then `mu`).
  double frictionFor(const std::string& a, const std::string& b) const;
  PairContactModel contactModelFor(const std::string& a, const std::string& b) const;
  bool collisionDisabled(const std::string& a, const std::string& b) const;
};

// Reads a scene YAML file. Throws SceneError naming the file and the key on any fault
// (syntax, unknown key, wrong type, out-of-range value).
SceneParams loadSceneParams(const std::string& yaml_path);
// Same, from text; `source` names it in errors.
SceneParams parseSceneParams(const std::string& yaml_text, const std::string& source = "<yaml>");
// Empty string when the values are consistent, otherwise a sentence naming the field.
std::string validateSceneParams(const SceneParams& params);

}  // namespace scene
}  // namespace lcp_contact_solver
