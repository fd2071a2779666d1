#include "lcp_contact_solver/scene/scene_params.h"

#include "lcp_contact_solver/core/solver_param_table.h"

#include <cmath>

namespace lcp_contact_solver {
namespace scene {

const char* complianceStorageName(ComplianceStorage storage) {
  switch (storage) {
    case ComplianceStorage::kDense: return "dense";
    case ComplianceStorage::kBlockSparse: return "block_sparse";
    case ComplianceStorage::kBodies: return "bodies";
  }
  return "?";
}

bool parseComplianceStorage(const std::string& name, ComplianceStorage* storage) {
  if (name == "dense") {
    *storage = ComplianceStorage::kDense;
    return true;
  }
  if (name == "block_sparse") {
    *storage = ComplianceStorage::kBlockSparse;
    return true;
  }
  if (name == "bodies") {
    *storage = ComplianceStorage::kBodies;
    return true;
  }
  return false;
}

core::SolverParams SceneParams::defaultSceneSolverParams() {
  core::SolverParams p;
  // Closed-loop physics wants a converged answer every step; warm starting by contact id
  // makes a tight tolerance cheap for resting contacts.
  p.solver = core::SolverKind::kAuto;
  p.tolerance = 1e-9;
  p.maxIt = 5000;
  p.initial_guess = true;
  return p;
}

double SceneParams::frictionFor(const std::string& a, const std::string& b) const {
  for (const PairFriction& f : friction_pairs)
    if ((f.body_a == a && f.body_b == b) || (f.body_a == b && f.body_b == a)) return f.mu;
  return mu;
}

PairContactModel SceneParams::contactModelFor(const std::string& a, const std::string& b) const {
  auto same = [&](const std::string& x, const std::string& y) {
    return (x == a && y == b) || (x == b && y == a);
  };
  PairContactModel m;
  m.mu = mu;
  m.torsional = torsional_friction;
  m.rolling = rolling_friction;
  m.restitution = restitution;
  for (const PairFriction& f : friction_pairs) {
    if (!same(f.body_a, f.body_b)) continue;
    m.mu = f.mu;
    if (f.torsional >= 0.0) m.torsional = f.torsional;
    if (f.rolling >= 0.0) m.rolling = f.rolling;
  }
  for (const PairRestitution& r : restitution_pairs)
    if (same(r.body_a, r.body_b)) m.restitution = r.restitution;
  return m;
}

bool SceneParams::collisionDisabled(const std::string& a, const std::string& b) const {
  for (const auto& d : disable_collisions)
    if ((d.first == a && d.second == b) || (d.first == b && d.second == a)) return true;
  return false;
}

std::string validateSceneParams(const SceneParams& p) {
  auto finite = [](double v) { return std::isfinite(v); };
  if (!finite(p.dt) || p.dt <= 0.0) return "dt must be > 0 (s)";
  if (!p.gravity.allFinite()) return "gravity must be finite";
  if (!finite(p.erp) || p.erp < 0.0 || p.erp > 1.0) return "erp must be in [0, 1]";
  if (!finite(p.softness) || p.softness < 0.0) return "softness must be >= 0 (m/N)";
  if (!finite(p.mu) || p.mu < 0.0) return "mu must be >= 0";
  for (const PairFriction& f : p.friction_pairs) {
    if (!finite(f.mu) || f.mu < 0.0)
      return "friction_pairs: mu of [" + f.body_a + ", " + f.body_b + "] must be >= 0";
    if (!finite(f.torsional) || !finite(f.rolling))
      return "friction_pairs: torsional and rolling of [" + f.body_a + ", " + f.body_b + "] must be finite";
  }
  if (!finite(p.torsional_friction) || p.torsional_friction < 0.0)
    return "torsional_friction must be >= 0 (m)";
  if (!finite(p.rolling_friction) || p.rolling_friction < 0.0) return "rolling_friction must be >= 0 (m)";
  if (!finite(p.restitution) || p.restitution < 0.0 || p.restitution > 1.0)
    return "restitution must be in [0, 1]";
  if (!finite(p.restitution_threshold) || p.restitution_threshold < 0.0)
    return "restitution_threshold must be >= 0 (m/s)";
  for (const PairRestitution& r : p.restitution_pairs)
    if (!finite(r.restitution) || r.restitution < 0.0 || r.restitution > 1.0)
      return "restitution_pairs: restitution of [" + r.body_a + ", " + r.body_b + "] must be in [0, 1]";
  if (!finite(p.contact_margin) || p.contact_margin < 0.0) return "contact_margin must be >= 0 (m)";
  if (!finite(p.id_match_tolerance) || p.id_match_tolerance < 0.0)
    return "id_match_tolerance must be >= 0 (m)";
  if (p.ground_plane.enabled) {
    if (!finite(p.ground_plane.height)) return "ground_plane.height must be finite";
    if (!finite(p.ground_plane.half_extent) || p.ground_plane.half_extent <= 0.0)
      return "ground_plane.half_extent must be > 0";
    if (!finite(p.ground_plane.thickness) || p.ground_plane.thickness <= 0.0)
      return "ground_plane.thickness must be > 0";
  }
  for (const auto& [joint, o] : p.joint_origins)
    if (!o.xyz.allFinite() || !o.rpy.allFinite()) return "joint_origins." + joint + " must be finite";
  for (const auto& [link, v] : p.initial_velocities)
    if (!v.linear.allFinite() || !v.angular.allFinite())
      return "initial_velocities." + link + " must be finite";
  if (!finite(p.duration) || p.duration < 0.0) return "duration must be >= 0 (s)";
  if (std::string err = core::validateParams(p.solver); !err.empty()) return "solver: " + err;
  return "";
}

}  // namespace scene
}  // namespace lcp_contact_solver
