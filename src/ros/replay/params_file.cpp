#include "lcp_contact_solver/ros/replay/params_file.h"

#include "lcp_contact_solver/ros/replay/text.h"
#include "lcp_contact_solver/ros/solver_params_ros.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <set>
#include <vector>

namespace lcp_contact_solver_ros {

namespace {

std::string lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return std::tolower(c); });
  return text;
}

// The node's parameters that do not change the forces: accepted in a parameter file and
// ignored offline.
const std::set<std::string>& nodeOnlyParams() {
  static const std::set<std::string> names = {
      "computeConstraintForces", "showCellWidth", "showTranslation", "showTranslation_x", "showTranslation_y",
      "showTranslation_z",  // the last three: dynamic_reconfigure's copies (rosparam dump of a running node)
      "pairing_window", "queue_size", "overload",
      "force_arrow_scale", "show_w_heatmap", "heatmap_max_rows", "cone_height", "marker_lifetime",
      "diagnostics_min_rate", "diagnostics_max_rate"};
  return names;
}

bool isSolverParam(const std::string& name) {
  if (name == "initial_guess") return true;
  const std::vector<std::string> names = overridableNames();
  return std::find(names.begin(), names.end(), name) != names.end();
}

// YAML 1.1 booleans (what rosparam accepts) as the override parser's true/false.
std::string scalarText(const std::string& name, const std::string& value) {
  static const std::set<std::string> bools = {"initial_guess", "build_lcp", "displayDebug"};
  if (bools.count(name) == 0) return value;
  const std::string v = lower(value);
  if (v == "true" || v == "yes" || v == "on") return "true";
  if (v == "false" || v == "no" || v == "off") return "false";
  return value;
}

}  // namespace

std::string applyReplayOverride(const std::string& assignment, lcs::SolverParams* params) {
  const std::size_t eq = assignment.find('=');
  if (eq != std::string::npos && assignment.compare(0, eq, "initial_guess") == 0) {
    const std::string value = assignment.substr(eq + 1);
    if (value == "true" || value == "1") {
      params->initial_guess = true;
    } else if (value == "false" || value == "0") {
      params->initial_guess = false;
    } else {
      return "override initial_guess='" + value + "' must be true or false";
    }
    return "";
  }
  return applyOverride(assignment, params);
}

std::string loadParamsFile(const std::string& path, lcs::SolverParams* params) {
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
  lcs::SolverParams next = *params;
  for (const auto& entry : root) {
    const std::string name = entry.first.Scalar();
    if (nodeOnlyParams().count(name) > 0) continue;
    if (!isSolverParam(name)) return path + ": unknown parameter '" + name + "'";
    if (!entry.second.IsScalar()) return path + ": parameter " + name + " must be a single value";
    const std::string error = applyReplayOverride(name + "=" + scalarText(name, entry.second.Scalar()), &next);
    if (!error.empty()) return path + ": " + error;
  }
  if (const std::string error = lcs::validateParams(next); !error.empty()) return path + ": " + error;
  *params = next;
  return "";
}

std::string writeParamsFile(const std::string& path, const lcs::SolverParams& p) {
  std::ofstream out(path);
  if (!out) return path + ": cannot write (" + std::strerror(errno) + ")";
  auto flag = [](bool b) { return b ? "true" : "false"; };
  out << "# Solver parameters of contact_solver_node (private ~names), as used for the forces of the\n"
         "# bag beside this file. `replay BAG` reads them; see the README, \"Replaying recorded traffic\".\n"
      << "tolerance: " << exactNumber(p.tolerance) << "\n"
      << "maxIt: " << p.maxIt << "\n"
      << "mu: " << exactNumber(p.mu) << "\n"
      << "initial_guess: " << flag(p.initial_guess) << "\n"
      << "build_lcp: " << flag(p.build_lcp) << "\n"
      << "regularizationTerm: " << exactNumber(p.regularizationTerm) << "\n"
      << "minW: " << exactNumber(p.minW) << "\n"
      << "maxF: " << exactNumber(p.maxF) << "\n"
      << "displayDebug: " << flag(p.displayDebug) << "\n"
      << "solver: " << lcs::solverName(p.solver) << "\n"
      << "stopping_rule: " << lcs::stoppingRuleName(p.stopping_rule) << "\n"
      << "friction_model: " << lcs::frictionModelName(p.friction_model) << "\n"
      << "sor: " << exactNumber(p.sor) << "\n"
      << "time_budget: " << exactNumber(p.time_budget) << "\n"
      << "max_rows: " << p.max_rows << "\n";
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
