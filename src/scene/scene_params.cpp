#include "lcp_contact_solver/scene/scene_params.h"

#include "lcp_contact_solver/core/solver_param_table.h"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

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
  if (name == "dense") { *storage = ComplianceStorage::kDense; return true; }
  if (name == "block_sparse") { *storage = ComplianceStorage::kBlockSparse; return true; }
  if (name == "bodies") { *storage = ComplianceStorage::kBodies; return true; }
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
  auto same = [&](const std::string& x, const std::string& y) { return (x == a && y == b) || (x == b && y == a); };
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
  if (!finite(p.torsional_friction) || p.torsional_friction < 0.0) return "torsional_friction must be >= 0 (m)";
  if (!finite(p.rolling_friction) || p.rolling_friction < 0.0) return "rolling_friction must be >= 0 (m)";
  if (!finite(p.restitution) || p.restitution < 0.0 || p.restitution > 1.0) return "restitution must be in [0, 1]";
  if (!finite(p.restitution_threshold) || p.restitution_threshold < 0.0)
    return "restitution_threshold must be >= 0 (m/s)";
  for (const PairRestitution& r : p.restitution_pairs)
    if (!finite(r.restitution) || r.restitution < 0.0 || r.restitution > 1.0)
      return "restitution_pairs: restitution of [" + r.body_a + ", " + r.body_b + "] must be in [0, 1]";
  if (!finite(p.contact_margin) || p.contact_margin < 0.0) return "contact_margin must be >= 0 (m)";
  if (!finite(p.id_match_tolerance) || p.id_match_tolerance < 0.0) return "id_match_tolerance must be >= 0 (m)";
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
    if (!v.linear.allFinite() || !v.angular.allFinite()) return "initial_velocities." + link + " must be finite";
  if (!finite(p.duration) || p.duration < 0.0) return "duration must be >= 0 (s)";
  if (std::string err = core::validateParams(p.solver); !err.empty()) return "solver: " + err;
  return "";
}

namespace {

class Reader {
 public:
  explicit Reader(std::string source) : source_(std::move(source)) {}

  [[noreturn]] void fail(const std::string& key, const std::string& what) const {
    throw SceneError(source_ + ": " + (key.empty() ? "" : "'" + key + "': ") + what);
  }

  double number(const YAML::Node& n, const std::string& key) const {
    if (!n.IsScalar()) fail(key, "expected a number");
    try {
      return n.as<double>();
    } catch (const YAML::Exception&) {
      fail(key, "expected a number, got '" + n.Scalar() + "'");
    }
  }
  int integer(const YAML::Node& n, const std::string& key) const {
    const double v = number(n, key);
    if (v != std::floor(v) || std::abs(v) > 1e9) fail(key, "expected an integer");
    return static_cast<int>(v);
  }
  bool boolean(const YAML::Node& n, const std::string& key) const {
    if (!n.IsScalar()) fail(key, "expected true or false");
    try {
      return n.as<bool>();
    } catch (const YAML::Exception&) {
      fail(key, "expected true or false, got '" + n.Scalar() + "'");
    }
  }
  std::string string(const YAML::Node& n, const std::string& key) const {
    if (!n.IsScalar()) fail(key, "expected a string");
    return n.Scalar();
  }
  Eigen::Vector3d vec3(const YAML::Node& n, const std::string& key) const {
    if (!n.IsSequence() || n.size() != 3) fail(key, "expected a list of 3 numbers");
    return Eigen::Vector3d(number(n[0], key), number(n[1], key), number(n[2], key));
  }
  void map(const YAML::Node& n, const std::string& key) const {
    if (!n.IsMap()) fail(key, "expected a map");
  }
  void onlyKeys(const YAML::Node& n, const std::string& key, const std::set<std::string>& allowed) const {
    for (const auto& kv : n) {
      const std::string k = kv.first.Scalar();
      if (!allowed.count(k)) {
        std::string list;
        for (const std::string& a : allowed) list += (list.empty() ? "" : ", ") + a;
        fail(key.empty() ? k : key + "." + k, "unknown key (known: " + list + ")");
      }
    }
  }

 private:
  std::string source_;
};

SceneParams parseNode(const YAML::Node& root, const std::string& source) {
  Reader r(source);
  SceneParams p;
  if (!root || root.IsNull()) return p;
  r.map(root, "");
  r.onlyKeys(root, "",
             {"description", "dt", "gravity", "erp", "softness", "mu", "friction_pairs", "disable_collisions",
              "torsional_friction", "rolling_friction", "restitution", "restitution_threshold", "restitution_pairs",
              "contact_margin", "id_match_tolerance", "compliance", "gyroscopic", "ground_plane",
              "joint_origins", "initial_velocities", "solver", "duration"});
  for (const auto& kv : root) {
    const std::string key = kv.first.Scalar();
    const YAML::Node& v = kv.second;
    if (key == "description") {
      p.description = r.string(v, key);
    } else if (key == "dt") {
      p.dt = r.number(v, key);
    } else if (key == "gravity") {
      p.gravity = r.vec3(v, key);
    } else if (key == "erp") {
      p.erp = r.number(v, key);
    } else if (key == "softness") {
      p.softness = r.number(v, key);
    } else if (key == "torsional_friction") {
      p.torsional_friction = r.number(v, key);
    } else if (key == "rolling_friction") {
      p.rolling_friction = r.number(v, key);
    } else if (key == "restitution") {
      p.restitution = r.number(v, key);
    } else if (key == "restitution_threshold") {
      p.restitution_threshold = r.number(v, key);
    } else if (key == "restitution_pairs") {
      if (!v.IsSequence()) r.fail(key, "expected a list of [body_a, body_b, restitution]");
      for (std::size_t i = 0; i < v.size(); ++i) {
        const std::string k = key + "[" + std::to_string(i) + "]";
        if (!v[i].IsSequence() || v[i].size() != 3) r.fail(k, "expected [body_a, body_b, restitution]");
        p.restitution_pairs.push_back({r.string(v[i][0], k), r.string(v[i][1], k), r.number(v[i][2], k)});
      }
    } else if (key == "mu") {
      p.mu = r.number(v, key);
    } else if (key == "contact_margin") {
      p.contact_margin = r.number(v, key);
    } else if (key == "id_match_tolerance") {
      p.id_match_tolerance = r.number(v, key);
    } else if (key == "duration") {
      p.duration = r.number(v, key);
    } else if (key == "gyroscopic") {
      p.gyroscopic = r.boolean(v, key);
    } else if (key == "compliance") {
      if (!parseComplianceStorage(r.string(v, key), &p.compliance))
        r.fail(key, "expected dense, block_sparse or bodies, got '" + v.Scalar() + "'");
    } else if (key == "friction_pairs") {
      if (!v.IsSequence()) r.fail(key, "expected a list of [body_a, body_b, mu(, torsional, rolling)]");
      for (std::size_t i = 0; i < v.size(); ++i) {
        const std::string k = key + "[" + std::to_string(i) + "]";
        if (!v[i].IsSequence() || (v[i].size() != 3 && v[i].size() != 5))
          r.fail(k, "expected [body_a, body_b, mu] or [body_a, body_b, mu, torsional, rolling]");
        PairFriction f{r.string(v[i][0], k), r.string(v[i][1], k), r.number(v[i][2], k)};
        if (v[i].size() == 5) {
          f.torsional = r.number(v[i][3], k);
          f.rolling = r.number(v[i][4], k);
          if (f.torsional < 0.0 || f.rolling < 0.0) r.fail(k, "torsional and rolling must be >= 0 (m)");
        }
        p.friction_pairs.push_back(f);
      }
    } else if (key == "disable_collisions") {
      if (!v.IsSequence()) r.fail(key, "expected a list of [body_a, body_b]");
      for (std::size_t i = 0; i < v.size(); ++i) {
        const std::string k = key + "[" + std::to_string(i) + "]";
        if (!v[i].IsSequence() || v[i].size() != 2) r.fail(k, "expected [body_a, body_b]");
        p.disable_collisions.emplace_back(r.string(v[i][0], k), r.string(v[i][1], k));
      }
    } else if (key == "ground_plane") {
      r.map(v, key);
      r.onlyKeys(v, key, {"enabled", "height", "half_extent", "thickness"});
      p.ground_plane.enabled = true;  // giving the map enables it unless enabled: false
      if (v["enabled"]) p.ground_plane.enabled = r.boolean(v["enabled"], key + ".enabled");
      if (v["height"]) p.ground_plane.height = r.number(v["height"], key + ".height");
      if (v["half_extent"]) p.ground_plane.half_extent = r.number(v["half_extent"], key + ".half_extent");
      if (v["thickness"]) p.ground_plane.thickness = r.number(v["thickness"], key + ".thickness");
    } else if (key == "joint_origins") {
      r.map(v, key);
      for (const auto& j : v) {
        const std::string name = j.first.Scalar();
        const std::string k = key + "." + name;
        r.map(j.second, k);
        r.onlyKeys(j.second, k, {"xyz", "rpy", "rpy_deg"});
        JointOriginOverride o;
        if (j.second["xyz"]) { o.has_xyz = true; o.xyz = r.vec3(j.second["xyz"], k + ".xyz"); }
        if (j.second["rpy"] && j.second["rpy_deg"]) r.fail(k, "give rpy or rpy_deg, not both");
        if (j.second["rpy"]) { o.has_rpy = true; o.rpy = r.vec3(j.second["rpy"], k + ".rpy"); }
        if (j.second["rpy_deg"]) {
          o.has_rpy = true;
          o.rpy = r.vec3(j.second["rpy_deg"], k + ".rpy_deg") * (M_PI / 180.0);
        }
        p.joint_origins[name] = o;
      }
    } else if (key == "initial_velocities") {
      r.map(v, key);
      for (const auto& b : v) {
        const std::string name = b.first.Scalar();
        const std::string k = key + "." + name;
        r.map(b.second, k);
        r.onlyKeys(b.second, k, {"linear", "angular"});
        InitialVelocity iv;
        if (b.second["linear"]) iv.linear = r.vec3(b.second["linear"], k + ".linear");
        if (b.second["angular"]) iv.angular = r.vec3(b.second["angular"], k + ".angular");
        p.initial_velocities[name] = iv;
      }
    } else if (key == "solver") {
      r.map(v, key);
      for (const auto& kv2 : v) {
        // `name` is the solver's name here (the ROS parameter is `solver`).
        const std::string k = kv2.first.Scalar(), param = k == "name" ? "solver" : k;
        if (k == "solver" || core::findSolverParam(param) == nullptr) {
          std::string list = "name";
          for (const core::ParamSpec& spec : core::solverParamSpecs())
            if (spec.name != "solver") list += ", " + spec.name;
          r.fail(key + "." + k, "unknown key (known: " + list + ")");
        }
        if (!kv2.second.IsScalar()) r.fail(key + "." + k, "expected " + core::expectedValue(*core::findSolverParam(param)));
        if (const std::string error = core::setParam(&p.solver, param, kv2.second.Scalar()); !error.empty())
          r.fail(key + "." + k, error);
      }
    }
  }
  if (std::string err = validateSceneParams(p); !err.empty()) throw SceneError(source + ": " + err);
  return p;
}

}  // namespace

SceneParams parseSceneParams(const std::string& yaml_text, const std::string& source) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw SceneError(source + ": YAML syntax error: " + e.what());
  }
  return parseNode(root, source);
}

SceneParams loadSceneParams(const std::string& yaml_path) {
  std::ifstream in(yaml_path);
  if (!in) throw SceneError(yaml_path + ": cannot open the scene parameter file");
  std::stringstream ss;
  ss << in.rdbuf();
  return parseSceneParams(ss.str(), yaml_path);
}

}  // namespace scene
}  // namespace lcp_contact_solver
