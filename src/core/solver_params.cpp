#include "lcp_contact_solver/core/solver_params.h"

#include <cmath>
#include <cstddef>
#include <cstring>
#include <string>
#include <vector>

namespace lcp_contact_solver::core {

namespace {

// One table per enum: its values and their names, read by the name, parse and list functions.
template <class Enum>
struct Named {
  Enum value;
  const char* name;
};

constexpr Named<SolverKind> kSolvers[] = {
    {SolverKind::kAuto, "auto"},   {SolverKind::kPgs, "pgs"},   {SolverKind::kNlgs, "nlgs"},
    {SolverKind::kLemke, "lemke"}, {SolverKind::kApgd, "apgd"}, {SolverKind::kNewton, "newton"},
    {SolverKind::kProx, "prox"},
};
constexpr Named<FrictionModel> kFrictionModels[] = {
    {FrictionModel::kCoulombDisc, "disc"},
    {FrictionModel::kPyramid4, "pyramid4"},
    {FrictionModel::kPyramid8, "pyramid8"},
};
constexpr Named<StoppingRule> kStoppingRules[] = {
    {StoppingRule::kResidual, "residual"},
    {StoppingRule::kSofa, "sofa"},
};
constexpr Named<ConstraintLevel> kConstraintLevels[] = {
    {ConstraintLevel::kPosition, "position"},
    {ConstraintLevel::kVelocity, "velocity"},
};

template <class Enum, std::size_t N>
const char* nameOf(const Named<Enum> (&table)[N], Enum value) {
  for (const auto& entry : table)
    if (entry.value == value) return entry.name;
  return "unknown";
}

template <class Enum, std::size_t N>
bool parseName(const Named<Enum> (&table)[N], const std::string& name, Enum* value) {
  for (const auto& entry : table) {
    if (name == entry.name) {
      *value = entry.value;
      return true;
    }
  }
  return false;
}

template <class Enum, std::size_t N>
std::vector<std::string> namesOf(const Named<Enum> (&table)[N]) {
  std::vector<std::string> names;
  for (const auto& entry : table) names.emplace_back(entry.name);
  return names;
}

}  // namespace

const char* solverName(SolverKind kind) { return nameOf(kSolvers, kind); }
bool parseSolverName(const std::string& name, SolverKind* kind) { return parseName(kSolvers, name, kind); }
std::vector<std::string> solverNames() { return namesOf(kSolvers); }

const char* stoppingRuleName(StoppingRule rule) { return nameOf(kStoppingRules, rule); }
bool parseStoppingRule(const std::string& name, StoppingRule* rule) {
  return parseName(kStoppingRules, name, rule);
}

const char* frictionModelName(FrictionModel model) { return nameOf(kFrictionModels, model); }
bool parseFrictionModel(const std::string& name, FrictionModel* model) {
  return parseName(kFrictionModels, name, model);
}
std::vector<std::string> frictionModelNames() { return namesOf(kFrictionModels); }

const char* constraintLevelName(ConstraintLevel level) { return nameOf(kConstraintLevels, level); }
bool parseConstraintLevel(const std::string& name, ConstraintLevel* level) {
  return parseName(kConstraintLevels, name, level);
}

std::string validateParams(const SolverParams& p) {
  auto nonNegative = [](double v) { return std::isfinite(v) && v >= 0.0; };
  if (!std::isfinite(p.tolerance) || p.tolerance <= 0.0) return "tolerance must be a finite number > 0";
  if (p.maxIt < 1) return "maxIt must be >= 1";
  if (!nonNegative(p.mu)) return "mu must be a finite number >= 0";
  if (!nonNegative(p.regularizationTerm)) return "regularizationTerm must be a finite number >= 0";
  if (!nonNegative(p.minW)) return "minW must be a finite number >= 0";
  if (!nonNegative(p.maxF)) return "maxF must be a finite number >= 0 (0 disables it)";
  if (p.max_rows < 0) return "max_rows must be >= 0 (0 disables the limit)";
  if (!std::isfinite(p.sor) || p.sor <= 0.0 || p.sor >= 2.0) return "sor must be a number in (0, 2)";
  if (!nonNegative(p.time_budget)) return "time_budget must be a finite number >= 0 (0 disables it)";
  if (p.threads < 0) return "threads must be >= 0 (0 = the core count)";
  if (std::strcmp(frictionModelName(p.friction_model), "unknown") == 0)
    return "friction_model is not a known model";
  if (std::strcmp(solverName(p.solver), "unknown") == 0) return "solver is not a known solver";
  if (!std::isfinite(p.erp) || p.erp < 0.0 || p.erp > 1.0) return "erp must be a number in [0, 1]";
  if (!nonNegative(p.softness)) return "softness must be a finite number >= 0";
  if (!nonNegative(p.time_step)) return "time_step must be a finite number >= 0";
  if (std::strcmp(constraintLevelName(p.constraint_level), "unknown") == 0)
    return "constraint_level is not a known level";
  return "";
}

}  // namespace lcp_contact_solver::core
