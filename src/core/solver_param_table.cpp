#include "lcp_contact_solver/core/solver_param_table.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace lcp_contact_solver::core {

namespace {

// The .def's origin and access tokens.
constexpr bool SOFA = true;
constexpr bool LCS = false;
constexpr unsigned RECONFIGURE = kParamReconfigure;
constexpr unsigned OVERRIDE = kParamOverride;

const char* boolText(bool value) { return value ? "true" : "false"; }

std::vector<ParamSpec> buildSpecs() {
  std::vector<ParamSpec> specs;
  auto choice = [&specs](const char* name, const char* value) {
    for (ParamSpec& spec : specs)
      if (spec.name == name) spec.choices.emplace_back(value);
  };
#define LCS_DOUBLE(name, def, lo, hi, origin, access, doc) \
  specs.push_back({#name, ParamType::kDouble, exactDoubleText(def), lo, hi, origin, access, doc, {}});
#define LCS_INT(name, def, lo, hi, origin, access, doc) \
  specs.push_back({#name, ParamType::kInt, std::to_string(def), lo, hi, origin, access, doc, {}});
#define LCS_BOOL(name, def, origin, access, doc) \
  specs.push_back({#name, ParamType::kBool, boolText(def), 0.0, 0.0, origin, access, doc, {}});
#define LCS_ENUM(name, Type, def, origin, access, doc) \
  specs.push_back({#name, ParamType::kEnum, def, 0.0, 0.0, origin, access, doc, {}});
#define LCS_CHOICE(name, value, doc) choice(#name, value);
#include "lcp_contact_solver/core/solver_param_table.def"
#undef LCS_DOUBLE
#undef LCS_INT
#undef LCS_BOOL
#undef LCS_ENUM
#undef LCS_CHOICE
  return specs;
}

// ---- one parser per type ------------------------------------------------------------------

bool parseDouble(const std::string& text, double* value) {
  if (text.empty() || std::isspace(static_cast<unsigned char>(text[0]))) return false;
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(text.c_str(), &end);
  if (*end != '\0' || errno == ERANGE || !std::isfinite(v)) return false;
  *value = v;
  return true;
}

bool parseInt(const std::string& text, int* value) {
  if (text.empty() || std::isspace(static_cast<unsigned char>(text[0]))) return false;
  char* end = nullptr;
  errno = 0;
  const long v = std::strtol(text.c_str(), &end, 10);
  if (*end != '\0' || errno == ERANGE || v < INT_MIN || v > INT_MAX) return false;
  *value = static_cast<int>(v);
  return true;
}

// rosparam's and YAML 1.1's spellings.
bool parseBool(const std::string& text, bool* value) {
  std::string v = text;
  std::transform(v.begin(), v.end(), v.begin(), [](unsigned char c) { return std::tolower(c); });
  if (v == "true" || v == "1" || v == "yes" || v == "on") {
    *value = true;
  } else if (v == "false" || v == "0" || v == "no" || v == "off") {
    *value = false;
  } else {
    return false;
  }
  return true;
}

bool parseEnum(const std::string& text, SolverKind* value) { return parseSolverName(text, value); }
bool parseEnum(const std::string& text, FrictionModel* value) { return parseFrictionModel(text, value); }
bool parseEnum(const std::string& text, StoppingRule* value) { return parseStoppingRule(text, value); }
bool parseEnum(const std::string& text, ConstraintLevel* value) { return parseConstraintLevel(text, value); }
std::string enumText(SolverKind value) { return solverName(value); }
std::string enumText(FrictionModel value) { return frictionModelName(value); }
std::string enumText(StoppingRule value) { return stoppingRuleName(value); }
std::string enumText(ConstraintLevel value) { return constraintLevelName(value); }

// Parses `text` into the member `name`; false if it does not parse, true (and *found) if it did.
bool setMember(SolverParams* p, const std::string& name, const std::string& text, bool* found) {
  *found = true;
#define LCS_DOUBLE(member, def, lo, hi, origin, access, doc) \
  if (name == #member) return parseDouble(text, &p->member);
#define LCS_INT(member, def, lo, hi, origin, access, doc) \
  if (name == #member) return parseInt(text, &p->member);
#define LCS_BOOL(member, def, origin, access, doc) \
  if (name == #member) return parseBool(text, &p->member);
#define LCS_ENUM(member, Type, def, origin, access, doc) \
  if (name == #member) return parseEnum(text, &p->member);
#define LCS_CHOICE(member, value, doc)
#include "lcp_contact_solver/core/solver_param_table.def"
#undef LCS_DOUBLE
#undef LCS_INT
#undef LCS_BOOL
#undef LCS_ENUM
#undef LCS_CHOICE
  *found = false;
  return false;
}

}  // namespace

std::string exactDoubleText(double value) {
  char text[32];
  for (int precision = 1; precision <= 17; ++precision) {
    std::snprintf(text, sizeof text, "%.*g", precision, value);
    if (std::strtod(text, nullptr) == value) break;
  }
  return text;
}

const std::vector<ParamSpec>& solverParamSpecs() {
  static const std::vector<ParamSpec> specs = buildSpecs();
  return specs;
}

const ParamSpec* findSolverParam(const std::string& name) {
  for (const ParamSpec& spec : solverParamSpecs())
    if (spec.name == name) return &spec;
  return nullptr;
}

std::string expectedValue(const ParamSpec& spec) {
  switch (spec.type) {
    case ParamType::kDouble: return "a finite number";
    case ParamType::kInt: return "an integer";
    case ParamType::kBool: return "true or false";
    case ParamType::kEnum: break;
  }
  std::string choices;
  for (const std::string& c : spec.choices) choices += (choices.empty() ? "" : ", ") + c;
  return "one of " + choices;
}

std::string setParam(SolverParams* params, const std::string& name, const std::string& text) {
  SolverParams next = *params;
  bool found = false;
  if (setMember(&next, name, text, &found)) {
    *params = next;
    return "";
  }
  if (!found) return "'" + name + "' is not a solver parameter";
  return name + "='" + text + "' must be " + expectedValue(*findSolverParam(name));
}

std::string applyAssignment(SolverParams* params, const std::string& assignment, unsigned required_access) {
  auto trimmed = [](const std::string& text) -> std::string {
    const char* space = " \t\r\n";
    const std::size_t first = text.find_first_not_of(space);
    if (first == std::string::npos) return "";
    return text.substr(first, text.find_last_not_of(space) - first + 1);
  };
  const std::size_t eq = assignment.find('=');
  if (eq == std::string::npos) return "'" + assignment + "' is not of the form name=value";
  const std::string name = trimmed(assignment.substr(0, eq)), value = trimmed(assignment.substr(eq + 1));
  const ParamSpec* spec = findSolverParam(name);
  if (spec == nullptr || (spec->access & required_access) != required_access)
    return "'" + name + "' is not a solver parameter";
  return setParam(params, name, value);
}

std::string paramText(const SolverParams& p, const std::string& name) {
#define LCS_DOUBLE(member, def, lo, hi, origin, access, doc) \
  if (name == #member) return exactDoubleText(p.member);
#define LCS_INT(member, def, lo, hi, origin, access, doc) \
  if (name == #member) return std::to_string(p.member);
#define LCS_BOOL(member, def, origin, access, doc) \
  if (name == #member) return boolText(p.member);
#define LCS_ENUM(member, Type, def, origin, access, doc) \
  if (name == #member) return enumText(p.member);
#define LCS_CHOICE(member, value, doc)
#include "lcp_contact_solver/core/solver_param_table.def"
#undef LCS_DOUBLE
#undef LCS_INT
#undef LCS_BOOL
#undef LCS_ENUM
#undef LCS_CHOICE
  return "";
}

}  // namespace lcp_contact_solver::core
