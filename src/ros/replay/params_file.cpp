#include "lcp_contact_solver/ros/replay/params_file.h"

#include "lcp_contact_solver/core/solver_param_table.h"

#include <yaml-cpp/yaml.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <set>

namespace lcp_contact_solver_ros {

namespace {

// The node's own parameters (node_param_table.def), which do not change the forces:
// accepted in a parameter file and ignored offline.
const std::set<std::string>& nodeOnlyParams() {
  static const std::set<std::string> names = {
#define LCS_NODE_DOUBLE(name, member, def, lo, hi, group, doc) #name,
#define LCS_NODE_INT(name, member, def, lo, hi, group, doc) #name,
#define LCS_NODE_BOOL(name, member, def, group, doc) #name,
// dynamic_reconfigure's copies too (rosparam dump of a running node)
#define LCS_NODE_VEC3(name, member, def, lo, hi, group, doc) #name, #name "_x", #name "_y", #name "_z",
#define LCS_NODE_ENUM(name, member, def, group, doc) #name,
#include "lcp_contact_solver/ros/node/node_param_table.def"
#undef LCS_NODE_DOUBLE
#undef LCS_NODE_INT
#undef LCS_NODE_BOOL
#undef LCS_NODE_VEC3
#undef LCS_NODE_ENUM
  };
  return names;
}

}  // namespace

std::string applyReplayOverride(const std::string& assignment, lcs::core::SolverParams* params) {
  const std::string error = lcs::core::applyAssignment(params, assignment);
  return error.empty() ? "" : "override " + error;
}

std::string loadParamsFile(const std::string& path, lcs::core::SolverParams* params) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    return path + ": cannot read the file";
  } catch (const YAML::Exception& e) {
    return path + ": not valid YAML (" + e.what() + ")";
  }
  if (root.IsNull()) return "";
  if (!root.IsMap()) return path + ": expected a map of parameter names to values";
  lcs::core::SolverParams next = *params;
  for (const auto& entry : root) {
    const std::string name = entry.first.Scalar();
    if (nodeOnlyParams().count(name) > 0) continue;
    if (lcs::core::findSolverParam(name) == nullptr) return path + ": unknown parameter '" + name + "'";
    if (!entry.second.IsScalar()) return path + ": parameter " + name + " must be a single value";
    if (const std::string error = lcs::core::setParam(&next, name, entry.second.Scalar()); !error.empty())
      return path + ": " + error;
  }
  if (const std::string error = lcs::core::validateParams(next); !error.empty()) return path + ": " + error;
  *params = next;
  return "";
}

std::string writeParamsFile(const std::string& path, const lcs::core::SolverParams& p) {
  std::ofstream out(path);
  if (!out) return path + ": cannot write (" + std::strerror(errno) + ")";
  out << "# Solver parameters of contact_solver_node (private ~names), as used for the forces of the\n"
         "# bag beside this file. `replay BAG` reads them; see docs/TOOLS.md, \"Replaying recorded "
         "traffic\".\n";
  for (const lcs::core::ParamSpec& spec : lcs::core::solverParamSpecs())
    out << spec.name << ": " << lcs::core::paramText(p, spec.name) << "\n";
  out.close();
  if (!out) return path + ": write failed";
  return "";
}

std::string paramsFileBeside(const std::string& bag_path) {
  std::string base = bag_path;
  if (base.size() > 4 && base.compare(base.size() - 4, 4, ".bag") == 0) base.resize(base.size() - 4);
  return base + ".params.yaml";
}

}  // namespace lcp_contact_solver_ros
