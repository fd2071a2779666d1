#include "lcp_contact_solver/ros/solver_params_ros.h"

#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <functional>

namespace lcp_contact_solver_ros {

namespace {

template <typename T>
const char* typeName();
template <>
const char* typeName<double>() { return "a number"; }
template <>
const char* typeName<int>() { return "an integer"; }
template <>
const char* typeName<bool>() { return "true or false"; }
template <>
const char* typeName<std::string>() { return "a string"; }
template <>
const char* typeName<std::vector<double>>() { return "a list of numbers"; }

// Reads `name` if present; a present value of the wrong type is an error, not a default.
template <typename T>
std::string readParam(const ros::NodeHandle& pnh, const std::string& name, T* value) {
  if (!pnh.hasParam(name)) return "";
  if (!pnh.getParam(name, *value))
    return "parameter " + pnh.resolveName(name) + " must be " + typeName<T>();
  return "";
}

std::string joined(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& name : names) out += (out.empty() ? "" : ", ") + name;
  return out;
}

const std::string& solverChoices() {
  static const std::string choices = joined(lcs::solverNames());
  return choices;
}

const std::string& frictionModelChoices() {
  static const std::string choices = joined(lcs::frictionModelNames());
  return choices;
}

const char* kStoppingRuleChoices = "residual, sofa";
const char* kConstraintLevelChoices = "position, velocity";

std::string readConstraintLevel(const ros::NodeHandle& pnh, lcs::SolverParams* params) {
  std::string name = lcs::constraintLevelName(params->constraint_level);
  std::string error = readParam(pnh, "constraint_level", &name);
  if (error.empty() && !lcs::parseConstraintLevel(name, &params->constraint_level))
    error = "parameter constraint_level: unknown level '" + name + "' (one of " + kConstraintLevelChoices + ")";
  return error;
}

std::string readSolverKind(const ros::NodeHandle& pnh, lcs::SolverParams* params) {
  std::string name = lcs::solverName(params->solver);
  std::string error = readParam(pnh, "solver", &name);
  if (error.empty() && !lcs::parseSolverName(name, &params->solver))
    error = "parameter solver: unknown solver '" + name + "' (one of " + solverChoices() + ")";
  return error;
}

std::string readStoppingRule(const ros::NodeHandle& pnh, lcs::SolverParams* params) {
  std::string name = lcs::stoppingRuleName(params->stopping_rule);
  std::string error = readParam(pnh, "stopping_rule", &name);
  if (error.empty() && !lcs::parseStoppingRule(name, &params->stopping_rule))
    error = "parameter stopping_rule: unknown rule '" + name + "' (one of " + kStoppingRuleChoices + ")";
  return error;
}

std::string readFrictionModel(const ros::NodeHandle& pnh, lcs::SolverParams* params) {
  std::string name = lcs::frictionModelName(params->friction_model);
  std::string error = readParam(pnh, "friction_model", &name);
  if (error.empty() && !lcs::parseFrictionModel(name, &params->friction_model))
    error = "parameter friction_model: unknown model '" + name + "' (one of " + frictionModelChoices() + ")";
  return error;
}

std::string readTranslation(const ros::NodeHandle& pnh, std::array<double, 3>* translation) {
  std::vector<double> xyz(translation->begin(), translation->end());
  std::string error = readParam(pnh, "showTranslation", &xyz);
  if (error.empty() && xyz.size() != 3) error = "parameter showTranslation must hold 3 numbers [x, y, z]";
  if (error.empty()) std::copy(xyz.begin(), xyz.end(), translation->begin());
  return error;
}

std::string readSolverParams(const ros::NodeHandle& pnh, lcs::SolverParams* p) {
  for (const std::string& error : {
           readParam(pnh, "tolerance", &p->tolerance), readParam(pnh, "maxIt", &p->maxIt),
           readParam(pnh, "mu", &p->mu), readParam(pnh, "initial_guess", &p->initial_guess),
           readParam(pnh, "build_lcp", &p->build_lcp),
           readParam(pnh, "regularizationTerm", &p->regularizationTerm), readParam(pnh, "minW", &p->minW),
           readParam(pnh, "maxF", &p->maxF),
           readParam(pnh, "computeConstraintForces", &p->computeConstraintForces),
           readParam(pnh, "displayDebug", &p->displayDebug), readParam(pnh, "max_rows", &p->max_rows),
           readParam(pnh, "sor", &p->sor), readParam(pnh, "time_budget", &p->time_budget),
           readParam(pnh, "erp", &p->erp), readParam(pnh, "softness", &p->softness),
           readParam(pnh, "time_step", &p->time_step), readConstraintLevel(pnh, p),
           readParam(pnh, "islands", &p->islands), readParam(pnh, "threads", &p->threads),
           readSolverKind(pnh, p), readStoppingRule(pnh, p), readFrictionModel(pnh, p)}) {
    if (!error.empty()) return error;
  }
  return "";
}

std::string readDisplayOptions(const ros::NodeHandle& pnh, DisplayOptions* d) {
  for (const std::string& error : {
           readParam(pnh, "force_arrow_scale", &d->force_arrow_scale),
           readParam(pnh, "show_w_heatmap", &d->show_w_heatmap), readParam(pnh, "showCellWidth", &d->showCellWidth),
           readTranslation(pnh, &d->showTranslation), readParam(pnh, "heatmap_max_rows", &d->heatmap_max_rows),
           readParam(pnh, "cone_height", &d->cone_height), readParam(pnh, "marker_lifetime", &d->marker_lifetime)}) {
    if (!error.empty()) return error;
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

bool parseDouble(const std::string& text, double* value) {
  if (text.empty()) return false;
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(text.c_str(), &end);
  if (*end != '\0' || errno == ERANGE) return false;
  *value = v;
  return true;
}

bool parseInt(const std::string& text, int* value) {
  if (text.empty()) return false;
  char* end = nullptr;
  errno = 0;
  const long v = std::strtol(text.c_str(), &end, 10);
  if (*end != '\0' || errno == ERANGE || v < INT_MIN || v > INT_MAX) return false;
  *value = static_cast<int>(v);
  return true;
}

bool parseBool(const std::string& text, bool* value) {
  if (text == "true" || text == "1") {
    *value = true;
  } else if (text == "false" || text == "0") {
    *value = false;
  } else {
    return false;
  }
  return true;
}

struct OverrideField {
  const char* name;
  std::string expected;
  std::function<bool(const std::string&, lcs::SolverParams*)> parse;
};

const std::vector<OverrideField>& overrideFields() {
  static const std::vector<OverrideField> fields = {
      {"tolerance", "a number", [](const std::string& v, lcs::SolverParams* p) { return parseDouble(v, &p->tolerance); }},
      {"maxIt", "an integer", [](const std::string& v, lcs::SolverParams* p) { return parseInt(v, &p->maxIt); }},
      {"mu", "a number", [](const std::string& v, lcs::SolverParams* p) { return parseDouble(v, &p->mu); }},
      {"build_lcp", "true or false", [](const std::string& v, lcs::SolverParams* p) { return parseBool(v, &p->build_lcp); }},
      {"regularizationTerm", "a number",
       [](const std::string& v, lcs::SolverParams* p) { return parseDouble(v, &p->regularizationTerm); }},
      {"minW", "a number", [](const std::string& v, lcs::SolverParams* p) { return parseDouble(v, &p->minW); }},
      {"maxF", "a number", [](const std::string& v, lcs::SolverParams* p) { return parseDouble(v, &p->maxF); }},
      {"displayDebug", "true or false",
       [](const std::string& v, lcs::SolverParams* p) { return parseBool(v, &p->displayDebug); }},
      {"max_rows", "an integer", [](const std::string& v, lcs::SolverParams* p) { return parseInt(v, &p->max_rows); }},
      {"sor", "a number", [](const std::string& v, lcs::SolverParams* p) { return parseDouble(v, &p->sor); }},
      {"time_budget", "a number",
       [](const std::string& v, lcs::SolverParams* p) { return parseDouble(v, &p->time_budget); }},
      {"solver", "one of " + solverChoices(),
       [](const std::string& v, lcs::SolverParams* p) { return lcs::parseSolverName(v, &p->solver); }},
      {"stopping_rule", std::string("one of ") + kStoppingRuleChoices,
       [](const std::string& v, lcs::SolverParams* p) { return lcs::parseStoppingRule(v, &p->stopping_rule); }},
      {"friction_model", "one of " + frictionModelChoices(),
       [](const std::string& v, lcs::SolverParams* p) { return lcs::parseFrictionModel(v, &p->friction_model); }},
      {"erp", "a number", [](const std::string& v, lcs::SolverParams* p) { return parseDouble(v, &p->erp); }},
      {"softness", "a number", [](const std::string& v, lcs::SolverParams* p) { return parseDouble(v, &p->softness); }},
      {"time_step", "a number", [](const std::string& v, lcs::SolverParams* p) { return parseDouble(v, &p->time_step); }},
      {"islands", "true or false", [](const std::string& v, lcs::SolverParams* p) { return parseBool(v, &p->islands); }},
      {"threads", "an integer", [](const std::string& v, lcs::SolverParams* p) { return parseInt(v, &p->threads); }},
      {"constraint_level", std::string("one of ") + kConstraintLevelChoices,
       [](const std::string& v, lcs::SolverParams* p) { return lcs::parseConstraintLevel(v, &p->constraint_level); }},
  };
  return fields;
}

}  // namespace

lcs::SolverParams defaultSolverParams() {
  lcs::SolverParams params;  // SOFA's defaults
  params.max_rows = 30000;
  return params;
}

namespace {

std::string readOverloadPolicy(const ros::NodeHandle& pnh, OverloadPolicy* policy) {
  std::string name = overloadPolicyName(*policy);
  std::string error = readParam(pnh, "overload", &name);
  if (error.empty() && !parseOverloadPolicy(name, policy))
    error = "parameter overload: unknown policy '" + name + "' (one of drop_oldest, queue)";
  return error;
}

}  // namespace

std::string loadSettings(const ros::NodeHandle& pnh, NodeSettings* s) {
  for (const std::string& error : {
           readSolverParams(pnh, &s->solver), readDisplayOptions(pnh, &s->display),
           readParam(pnh, "pairing_window", &s->pairing_window), readParam(pnh, "queue_size", &s->queue_size),
           readOverloadPolicy(pnh, &s->overload),
           readParam(pnh, "diagnostics_min_rate", &s->diagnostics_min_rate),
           readParam(pnh, "diagnostics_max_rate", &s->diagnostics_max_rate)}) {
    if (!error.empty()) return error;
  }
  return validateSettings(*s);
}

std::string validateSettings(const NodeSettings& s) {
  std::string error = lcs::validateParams(s.solver);
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

// Spaces around the name and the value are not part of them: 'tolerance = 1e-3' is
// what a user writes in YAML.
std::string trimmed(const std::string& text) {
  const char* space = " \t\r\n";
  const std::size_t first = text.find_first_not_of(space);
  if (first == std::string::npos) return "";
  return text.substr(first, text.find_last_not_of(space) - first + 1);
}

std::string applyOverride(const std::string& assignment, lcs::SolverParams* params) {
  const std::size_t eq = assignment.find('=');
  if (eq == std::string::npos) return "override '" + assignment + "' is not of the form name=value";
  const std::string name = trimmed(assignment.substr(0, eq)), value = trimmed(assignment.substr(eq + 1));
  for (const OverrideField& field : overrideFields()) {
    if (name != field.name) continue;
    if (!field.parse(value, params)) return "override " + name + "='" + value + "' must be " + field.expected;
    return "";
  }
  return "override '" + name + "' is not a solver parameter";
}

std::vector<std::string> overridableNames() {
  std::vector<std::string> names;
  for (const OverrideField& field : overrideFields()) names.emplace_back(field.name);
  return names;
}

lcp_contact_solver::ContactSolverConfig toConfig(const NodeSettings& s) {
  lcp_contact_solver::ContactSolverConfig c = lcp_contact_solver::ContactSolverConfig::__getDefault__();
  c.tolerance = s.solver.tolerance;
  c.maxIt = s.solver.maxIt;
  c.mu = s.solver.mu;
  c.initial_guess = s.solver.initial_guess;
  c.build_lcp = s.solver.build_lcp;
  c.regularizationTerm = s.solver.regularizationTerm;
  c.minW = s.solver.minW;
  c.maxF = s.solver.maxF;
  c.computeConstraintForces = s.solver.computeConstraintForces;
  c.displayDebug = s.solver.displayDebug;
  c.showCellWidth = s.display.showCellWidth;
  c.showTranslation_x = s.display.showTranslation[0];
  c.showTranslation_y = s.display.showTranslation[1];
  c.showTranslation_z = s.display.showTranslation[2];
  c.solver = lcs::solverName(s.solver.solver);
  c.stopping_rule = lcs::stoppingRuleName(s.solver.stopping_rule);
  c.friction_model = lcs::frictionModelName(s.solver.friction_model);
  c.sor = s.solver.sor;
  c.time_budget = s.solver.time_budget;
  c.max_rows = s.solver.max_rows;
  c.erp = s.solver.erp;
  c.softness = s.solver.softness;
  c.time_step = s.solver.time_step;
  c.constraint_level = lcs::constraintLevelName(s.solver.constraint_level);
  c.force_arrow_scale = s.display.force_arrow_scale;
  c.show_w_heatmap = s.display.show_w_heatmap;
  return c;
}

std::string fromConfig(const lcp_contact_solver::ContactSolverConfig& c, NodeSettings* s) {
  NodeSettings next = *s;
  if (!lcs::parseSolverName(c.solver, &next.solver.solver))
    return "solver: unknown solver '" + c.solver + "' (one of " + solverChoices() + ")";
  if (!lcs::parseStoppingRule(c.stopping_rule, &next.solver.stopping_rule))
    return "stopping_rule: unknown rule '" + c.stopping_rule + "' (one of " + kStoppingRuleChoices + ")";
  if (!lcs::parseFrictionModel(c.friction_model, &next.solver.friction_model))
    return "friction_model: unknown model '" + c.friction_model + "' (one of " + frictionModelChoices() + ")";
  if (!lcs::parseConstraintLevel(c.constraint_level, &next.solver.constraint_level))
    return "constraint_level: unknown level '" + c.constraint_level + "' (one of " + kConstraintLevelChoices + ")";
  next.solver.erp = c.erp;
  next.solver.softness = c.softness;
  next.solver.time_step = c.time_step;
  next.solver.sor = c.sor;
  next.solver.time_budget = c.time_budget;
  next.solver.tolerance = c.tolerance;
  next.solver.maxIt = c.maxIt;
  next.solver.mu = c.mu;
  next.solver.initial_guess = c.initial_guess;
  next.solver.build_lcp = c.build_lcp;
  next.solver.regularizationTerm = c.regularizationTerm;
  next.solver.minW = c.minW;
  next.solver.maxF = c.maxF;
  next.solver.computeConstraintForces = c.computeConstraintForces;
  next.solver.displayDebug = c.displayDebug;
  next.solver.max_rows = c.max_rows;
  next.display.showCellWidth = c.showCellWidth;
  next.display.showTranslation = {{c.showTranslation_x, c.showTranslation_y, c.showTranslation_z}};
  next.display.force_arrow_scale = c.force_arrow_scale;
  next.display.show_w_heatmap = c.show_w_heatmap;
  const std::string error = validateSettings(next);
  if (error.empty()) *s = next;
  return error;
}

}  // namespace lcp_contact_solver_ros
