// The scene YAML (config/scenes/<name>.yaml) read into SceneParams: one reader for the keys of
// one value (a table of fields) and one per key with structure; unknown keys and wrong types
// are refused with the key's path.
#include "lcp_contact_solver/core/solver_param_table.h"
#include "lcp_contact_solver/scene/scene_params.h"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <variant>

namespace lcp_contact_solver {
namespace scene {
namespace {

// Where the value of a key of one value goes.
using PlainField = std::variant<double*, bool*, std::string*, Eigen::Vector3d*>;

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
  // Each item of the list `n` (else "expected a list of <what>"), with its key "key[i]".
  template <typename F>
  void forEachItem(const YAML::Node& n, const std::string& key, const std::string& what, F&& f) const {
    if (!n.IsSequence()) fail(key, "expected a list of " + what);
    for (std::size_t i = 0; i < n.size(); ++i) f(n[i], key + "[" + std::to_string(i) + "]");
  }
  // Each entry of the map `n`: its name, its value (a map of `allowed` keys only) and its key
  // "key.name".
  template <typename F>
  void forEachEntry(const YAML::Node& n, const std::string& key, const std::set<std::string>& allowed,
                    F&& f) const {
    map(n, key);
    for (const auto& entry : n) {
      const std::string name = entry.first.Scalar();
      const std::string k = key + "." + name;
      map(entry.second, k);
      onlyKeys(entry.second, k, allowed);
      f(name, entry.second, k);
    }
  }
  // A key of one value into its field, read as the field's type.
  void read(const YAML::Node& n, const std::string& key, const PlainField& field) const {
    switch (field.index()) {
      case 0: *std::get<double*>(field) = number(n, key); break;
      case 1: *std::get<bool*>(field) = boolean(n, key); break;
      case 2: *std::get<std::string*>(field) = string(n, key); break;
      default: *std::get<Eigen::Vector3d*>(field) = vec3(n, key); break;
    }
  }

 private:
  std::string source_;
};

// The keys of one value each.
std::map<std::string, PlainField> plainFields(SceneParams* p) {
  return {{"description", &p->description},
          {"dt", &p->dt},
          {"gravity", &p->gravity},
          {"erp", &p->erp},
          {"softness", &p->softness},
          {"mu", &p->mu},
          {"torsional_friction", &p->torsional_friction},
          {"rolling_friction", &p->rolling_friction},
          {"restitution", &p->restitution},
          {"restitution_threshold", &p->restitution_threshold},
          {"contact_margin", &p->contact_margin},
          {"id_match_tolerance", &p->id_match_tolerance},
          {"duration", &p->duration},
          {"gyroscopic", &p->gyroscopic}};
}

// ---- the keys with structure: one reader each -------------------------------------------

void readCompliance(const Reader& r, const YAML::Node& v, const std::string& key, SceneParams* p) {
  if (!parseComplianceStorage(r.string(v, key), &p->compliance))
    r.fail(key, "expected dense, block_sparse or bodies, got '" + v.Scalar() + "'");
}

void readRestitutionPairs(const Reader& r, const YAML::Node& v, const std::string& key, SceneParams* p) {
  r.forEachItem(v, key, "[body_a, body_b, restitution]", [&](const YAML::Node& item, const std::string& k) {
    if (!item.IsSequence() || item.size() != 3) r.fail(k, "expected [body_a, body_b, restitution]");
    p->restitution_pairs.push_back({r.string(item[0], k), r.string(item[1], k), r.number(item[2], k)});
  });
}

void readFrictionPairs(const Reader& r, const YAML::Node& v, const std::string& key, SceneParams* p) {
  r.forEachItem(v, key, "[body_a, body_b, mu(, torsional, rolling)]",
                [&](const YAML::Node& item, const std::string& k) {
                  if (!item.IsSequence() || (item.size() != 3 && item.size() != 5))
                    r.fail(k, "expected [body_a, body_b, mu] or [body_a, body_b, mu, torsional, rolling]");
                  PairFriction f{r.string(item[0], k), r.string(item[1], k), r.number(item[2], k)};
                  if (item.size() == 5) {
                    f.torsional = r.number(item[3], k);
                    f.rolling = r.number(item[4], k);
                    if (f.torsional < 0.0 || f.rolling < 0.0)
                      r.fail(k, "torsional and rolling must be >= 0 (m)");
                  }
                  p->friction_pairs.push_back(f);
                });
}

void readDisableCollisions(const Reader& r, const YAML::Node& v, const std::string& key, SceneParams* p) {
  r.forEachItem(v, key, "[body_a, body_b]", [&](const YAML::Node& item, const std::string& k) {
    if (!item.IsSequence() || item.size() != 2) r.fail(k, "expected [body_a, body_b]");
    p->disable_collisions.emplace_back(r.string(item[0], k), r.string(item[1], k));
  });
}

void readGroundPlane(const Reader& r, const YAML::Node& v, const std::string& key, SceneParams* p) {
  r.map(v, key);
  r.onlyKeys(v, key, {"enabled", "height", "half_extent", "thickness"});
  p->ground_plane.enabled = true;  // giving the map enables it unless enabled: false
  if (v["enabled"]) p->ground_plane.enabled = r.boolean(v["enabled"], key + ".enabled");
  if (v["height"]) p->ground_plane.height = r.number(v["height"], key + ".height");
  if (v["half_extent"]) p->ground_plane.half_extent = r.number(v["half_extent"], key + ".half_extent");
  if (v["thickness"]) p->ground_plane.thickness = r.number(v["thickness"], key + ".thickness");
}

void readJointOrigins(const Reader& r, const YAML::Node& v, const std::string& key, SceneParams* p) {
  r.forEachEntry(v, key, {"xyz", "rpy", "rpy_deg"},
                 [&](const std::string& name, const YAML::Node& j, const std::string& k) {
                   JointOriginOverride o;
                   if (j["xyz"]) {
                     o.has_xyz = true;
                     o.xyz = r.vec3(j["xyz"], k + ".xyz");
                   }
                   if (j["rpy"] && j["rpy_deg"]) r.fail(k, "give rpy or rpy_deg, not both");
                   if (j["rpy"]) {
                     o.has_rpy = true;
                     o.rpy = r.vec3(j["rpy"], k + ".rpy");
                   }
                   if (j["rpy_deg"]) {
                     o.has_rpy = true;
                     o.rpy = r.vec3(j["rpy_deg"], k + ".rpy_deg") * (M_PI / 180.0);
                   }
                   p->joint_origins[name] = o;
                 });
}

void readInitialVelocities(const Reader& r, const YAML::Node& v, const std::string& key, SceneParams* p) {
  r.forEachEntry(v, key, {"linear", "angular"},
                 [&](const std::string& name, const YAML::Node& b, const std::string& k) {
                   InitialVelocity iv;
                   if (b["linear"]) iv.linear = r.vec3(b["linear"], k + ".linear");
                   if (b["angular"]) iv.angular = r.vec3(b["angular"], k + ".angular");
                   p->initial_velocities[name] = iv;
                 });
}

void readSolver(const Reader& r, const YAML::Node& v, const std::string& key, SceneParams* p) {
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
    if (!kv2.second.IsScalar())
      r.fail(key + "." + k, "expected " + core::expectedValue(*core::findSolverParam(param)));
    if (const std::string error = core::setParam(&p->solver, param, kv2.second.Scalar()); !error.empty())
      r.fail(key + "." + k, error);
  }
}

using SectionReader = void (*)(const Reader&, const YAML::Node&, const std::string&, SceneParams*);
const std::map<std::string, SectionReader> kSections = {{"compliance", readCompliance},
                                                        {"restitution_pairs", readRestitutionPairs},
                                                        {"friction_pairs", readFrictionPairs},
                                                        {"disable_collisions", readDisableCollisions},
                                                        {"ground_plane", readGroundPlane},
                                                        {"joint_origins", readJointOrigins},
                                                        {"initial_velocities", readInitialVelocities},
                                                        {"solver", readSolver}};

SceneParams parseNode(const YAML::Node& root, const std::string& source) {
  Reader r(source);
  SceneParams p;
  if (!root || root.IsNull()) return p;
  const std::map<std::string, PlainField> fields = plainFields(&p);
  std::set<std::string> known;
  for (const auto& field : fields) known.insert(field.first);
  for (const auto& section : kSections) known.insert(section.first);
  r.map(root, "");
  r.onlyKeys(root, "", known);
  for (const auto& kv : root) {
    const std::string key = kv.first.Scalar();
    if (const auto field = fields.find(key); field != fields.end())
      r.read(kv.second, key, field->second);
    else
      kSections.at(key)(r, kv.second, key, &p);
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
