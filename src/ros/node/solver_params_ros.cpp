#include "lcp_contact_solver/ros/node/solver_params_ros.h"

#include "lcp_contact_solver/core/solver_param_table.h"

#include <boost/any.hpp>

#include <cmath>
#include <cstdlib>

namespace lcp_contact_solver_ros {

namespace {

template <typename T>
const char* typeName();
template <>
const char* typeName<double>() {
  return "a number";
}
template <>
const char* typeName<int>() {
  return "an integer";
}
template <>
const char* typeName<bool>() {
  return "true or false";
}
template <>
const char* typeName<std::string>() {
  return "a string";
}
template <>
const char* typeName<std::vector<double>>() {
  return "a list of numbers";
}

// Reads `name` if present; a present value of the wrong type is an error, not a default.
template <typename T>
std::string readParam(const ros::NodeHandle& pnh, const std::string& name, T* value) {
  if (!pnh.hasParam(name)) return "";
  if (!pnh.getParam(name, *value)) return "parameter " + pnh.resolveName(name) + " must be " + typeName<T>();
  return "";
}

std::string readVec3(const ros::NodeHandle& pnh, const std::string& name, std::array<double, 3>* xyz) {
  std::vector<double> values(xyz->begin(), xyz->end());
  std::string error = readParam(pnh, name, &values);
  if (error.empty() && values.size() != 3) error = "parameter " + name + " must hold 3 numbers [x, y, z]";
  if (error.empty()) std::copy(values.begin(), values.end(), xyz->begin());
  return error;
}

std::string readEnum(const ros::NodeHandle& pnh, const std::string& name, OverloadPolicy* policy) {
  std::string text = overloadPolicyName(*policy);
  std::string error = readParam(pnh, name, &text);
  if (error.empty() && !parseOverloadPolicy(text, policy))
    error = "parameter " + name + ": unknown policy '" + text + "' (one of drop_oldest, queue)";
  return error;
}

// Every parameter of the table present in `pnh`, read with its own type and set through
// the table's parser (numbers as their exact text, so nothing is rounded).
std::string readSolverParams(const ros::NodeHandle& pnh, lcs::core::SolverParams* p) {
  for (const lcs::core::ParamSpec& spec : lcs::core::solverParamSpecs()) {
    if (!pnh.hasParam(spec.name)) continue;
    std::string text;
    bool read = false;
    switch (spec.type) {
      case lcs::core::ParamType::kDouble: {
        double v = 0.0;
        read = pnh.getParam(spec.name, v);
        text = lcs::core::exactDoubleText(v);
        break;
      }
      case lcs::core::ParamType::kInt: {
        int v = 0;
        read = pnh.getParam(spec.name, v);
        text = std::to_string(v);
        break;
      }
      case lcs::core::ParamType::kBool: {
        bool v = false;
        read = pnh.getParam(spec.name, v);
        text = v ? "true" : "false";
        break;
      }
      case lcs::core::ParamType::kEnum: read = pnh.getParam(spec.name, text); break;
    }
    if (!read)
      return "parameter " + pnh.resolveName(spec.name) + " must be " + lcs::core::expectedValue(spec);
    if (const std::string why = lcs::core::setParam(p, spec.name, text); !why.empty())
      return "parameter " + pnh.resolveName(spec.name) + ": " + why;
  }
  return "";
}

bool positive(double v) { return std::isfinite(v) && v > 0.0; }

std::string validateDisplay(const DisplayOptions& d) {
  if (!positive(d.force_arrow_scale)) return "force_arrow_scale must be a finite number > 0";
  if (!std::isfinite(d.showCellWidth)) return "showCellWidth must be finite (<= 0 hides the heat map)";
  for (double v : d.showTranslation)
    if (!std::isfinite(v)) return "showTranslation must hold finite numbers";
  if (d.heatmap_max_rows < 1) return "heatmap_max_rows must be >= 1";
  if (!positive(d.cone_height)) return "cone_height must be a finite number > 0";
  if (!positive(d.marker_lifetime)) return "marker_lifetime must be a finite number > 0";
  return "";
}

}  // namespace

lcs::core::SolverParams defaultSolverParams() {
  lcs::core::SolverParams params;  // SOFA's defaults, then the node's own (node_param_defaults.def)
#define LCS_NODE_DEFAULT(name, value) lcs::core::setParam(&params, #name, value);
#include "lcp_contact_solver/ros/node/node_param_defaults.def"
#undef LCS_NODE_DEFAULT
  return params;
}

// The node's own parameters (node_param_table.def), each with its type.
std::string readNodeParams(const ros::NodeHandle& pnh, NodeSettings* s) {
  for (const std::string& error : {
#define LCS_NODE_DOUBLE(name, member, def, lo, hi, group, doc) readParam(pnh, #name, &s->member),
#define LCS_NODE_INT(name, member, def, lo, hi, group, doc) readParam(pnh, #name, &s->member),
#define LCS_NODE_BOOL(name, member, def, group, doc) readParam(pnh, #name, &s->member),
#define LCS_NODE_VEC3(name, member, def, lo, hi, group, doc) readVec3(pnh, #name, &s->member),
#define LCS_NODE_ENUM(name, member, def, group, doc) readEnum(pnh, #name, &s->member),
#include "lcp_contact_solver/ros/node/node_param_table.def"
#undef LCS_NODE_DOUBLE
#undef LCS_NODE_INT
#undef LCS_NODE_BOOL
#undef LCS_NODE_VEC3
#undef LCS_NODE_ENUM
       }) {
    if (!error.empty()) return error;
  }
  return "";
}

std::string loadSettings(const ros::NodeHandle& pnh, NodeSettings* s) {
  for (const std::string& error : {readSolverParams(pnh, &s->solver), readNodeParams(pnh, s)})
    if (!error.empty()) return error;
  return validateSettings(*s);
}

std::string validateSettings(const NodeSettings& s) {
  std::string error = lcs::core::validateParams(s.solver);
  if (error.empty()) error = validateDisplay(s.display);
  if (!error.empty()) return error;
  if (!positive(s.pairing_window)) return "pairing_window must be a finite number > 0 (s)";
  if (s.queue_size < 1) return "queue_size must be >= 1";
  if (!std::isfinite(s.diagnostics_min_rate) || s.diagnostics_min_rate < 0.0)
    return "diagnostics_min_rate must be a finite number >= 0";
  if (!std::isfinite(s.diagnostics_max_rate) || s.diagnostics_max_rate < s.diagnostics_min_rate)
    return "diagnostics_max_rate must be finite and >= diagnostics_min_rate";
  return "";
}

std::string applyOverride(const std::string& assignment, lcs::core::SolverParams* params) {
  const std::string error = lcs::core::applyAssignment(params, assignment, lcs::core::kParamOverride);
  return error.empty() ? "" : "override " + error;
}

std::vector<std::string> overridableNames() {
  std::vector<std::string> names;
  for (const lcs::core::ParamSpec& spec : lcs::core::solverParamSpecs())
    if (spec.access & lcs::core::kParamOverride) names.push_back(spec.name);
  return names;
}

namespace {

using Config = lcp_contact_solver::ContactSolverConfig;

template <typename T>
void setField(Config* config, const Config::AbstractParamDescription& description, const T& value) {
  if (const auto* typed = dynamic_cast<const Config::ParamDescription<T>*>(&description))
    config->*(typed->field) = value;
}

// A config field's value as the table's text.
std::string fieldText(const Config& config, const Config::AbstractParamDescription& description) {
  boost::any value;
  description.getValue(config, value);
  if (const double* v = boost::any_cast<double>(&value)) return lcs::core::exactDoubleText(*v);
  if (const int* v = boost::any_cast<int>(&value)) return std::to_string(*v);
  if (const bool* v = boost::any_cast<bool>(&value)) return *v ? "true" : "false";
  if (const std::string* v = boost::any_cast<std::string>(&value)) return *v;
  return "";
}

}  // namespace

// The node table's groups: SOFA and NODE are in the dynamic_reconfigure config, STARTUP not.
#define LCS_IN_CONFIG_SOFA(...) __VA_ARGS__
#define LCS_IN_CONFIG_NODE(...) __VA_ARGS__
#define LCS_IN_CONFIG_STARTUP(...)

// The solver table's parameters go by name through the generated descriptions, the node
// table's reconfigurable ones by their config fields.
lcp_contact_solver::ContactSolverConfig toConfig(const NodeSettings& s) {
  Config c = Config::__getDefault__();
  for (const auto& description : Config::__getParamDescriptions__()) {
    const lcs::core::ParamSpec* spec = lcs::core::findSolverParam(description->name);
    if (spec == nullptr) continue;
    const std::string text = lcs::core::paramText(s.solver, spec->name);
    switch (spec->type) {
      case lcs::core::ParamType::kDouble:
        setField(&c, *description, std::strtod(text.c_str(), nullptr));
        break;
      case lcs::core::ParamType::kInt: setField(&c, *description, std::stoi(text)); break;
      case lcs::core::ParamType::kBool: setField(&c, *description, text == "true"); break;
      case lcs::core::ParamType::kEnum: setField(&c, *description, text); break;
    }
  }
  // The node's reconfigurable ones (node_param_table.def).
#define LCS_NODE_DOUBLE(name, member, def, lo, hi, group, doc) LCS_IN_CONFIG_##group(c.name = s.member;)
#define LCS_NODE_INT(name, member, def, lo, hi, group, doc) LCS_IN_CONFIG_##group(c.name = s.member;)
#define LCS_NODE_BOOL(name, member, def, group, doc) LCS_IN_CONFIG_##group(c.name = s.member;)
#define LCS_NODE_VEC3(name, member, def, lo, hi, group, doc) \
  LCS_IN_CONFIG_##group(c.name##_x = s.member[0], c.name##_y = s.member[1], c.name##_z = s.member[2];)
#define LCS_NODE_ENUM(name, member, def, group, doc)
#include "lcp_contact_solver/ros/node/node_param_table.def"
#undef LCS_NODE_DOUBLE
#undef LCS_NODE_INT
#undef LCS_NODE_BOOL
#undef LCS_NODE_VEC3
#undef LCS_NODE_ENUM
  return c;
}

std::string fromConfig(const lcp_contact_solver::ContactSolverConfig& c, NodeSettings* s) {
  NodeSettings next = *s;
  for (const auto& description : Config::__getParamDescriptions__()) {
    if (lcs::core::findSolverParam(description->name) == nullptr) continue;
    if (const std::string error =
            lcs::core::setParam(&next.solver, description->name, fieldText(c, *description));
        !error.empty())
      return error;
  }
#define LCS_NODE_DOUBLE(name, member, def, lo, hi, group, doc) LCS_IN_CONFIG_##group(next.member = c.name;)
#define LCS_NODE_INT(name, member, def, lo, hi, group, doc) LCS_IN_CONFIG_##group(next.member = c.name;)
#define LCS_NODE_BOOL(name, member, def, group, doc) LCS_IN_CONFIG_##group(next.member = c.name;)
#define LCS_NODE_VEC3(name, member, def, lo, hi, group, doc) \
  LCS_IN_CONFIG_##group(next.member = {{c.name##_x, c.name##_y, c.name##_z}};)
#define LCS_NODE_ENUM(name, member, def, group, doc)
#include "lcp_contact_solver/ros/node/node_param_table.def"
#undef LCS_NODE_DOUBLE
#undef LCS_NODE_INT
#undef LCS_NODE_BOOL
#undef LCS_NODE_VEC3
#undef LCS_NODE_ENUM
  const std::string error = validateSettings(next);
  if (error.empty()) *s = next;
  return error;
}

}  // namespace lcp_contact_solver_ros
