#include "lcp_contact_solver/core/solver_params.h"

#include <cmath>

namespace lcp_contact_solver::core {

namespace {

struct SolverEntry {
  SolverKind kind;
  const char* name;
};

constexpr SolverEntry kSolvers[] = {
    {SolverKind::kAuto, "auto"},
    {SolverKind::kPgs, "pgs"},
    {SolverKind::kNlgs, "nlgs"},
    {SolverKind::kLemke, "lemke"},
    {SolverKind::kApgd, "apgd"},
    {SolverKind::kNewton, "newton"},
    {SolverKind::kProx, "prox"},
};

struct FrictionModelEntry {
  FrictionModel model;
  const char* name;
};

constexpr FrictionModelEntry kFrictionModels[] = {
    {FrictionModel::kCoulombDisc, "disc"},
    {FrictionModel::kPyramid4, "pyramid4"},
    {FrictionModel::kPyramid8, "pyramid8"},
};

}  // namespace

const char* solverName(SolverKind kind) {
  for (const auto& entry : kSolvers)
    if (entry.kind == kind) return entry.name;
  return "unknown";
}

bool parseSolverName(const std::string& name, SolverKind* kind) {
  for (const auto& entry : kSolvers) {
    if (name == entry.name) {
      *kind = entry.kind;
      return true;
    }
  }
  return false;
}

std::vector<std::string> solverNames() {
  std::vector<std::string> names;
  for (const auto& entry : kSolvers) names.emplace_back(entry.name);
  return names;
}

const char* stoppingRuleName(StoppingRule rule) {
  return rule == StoppingRule::kSofa ? "sofa" : "residual";
}

bool parseStoppingRule(const std::string& name, StoppingRule* rule) {
  if (name == "residual") {
    *rule = StoppingRule::kResidual;
  } else if (name == "sofa") {
    *rule = StoppingRule::kSofa;
  } else {
    return false;
  }
  return true;
}

const char* frictionModelName(FrictionModel model) {
  for (const auto& entry : kFrictionModels)
    if (entry.model == model) return entry.name;
  return "unknown";
}

bool parseFrictionModel(const std::string& name, FrictionModel* model) {
  for (const auto& entry : kFrictionModels) {
    if (name == entry.name) {
      *model = entry.model;
      return true;
    }
  }
  return false;
}

std::vector<std::string> frictionModelNames() {
  std::vector<std::string> names;
  for (const auto& entry : kFrictionModels) names.emplace_back(entry.name);
  return names;
}

const char* constraintLevelName(ConstraintLevel level) {
  switch (level) {
    case ConstraintLevel::kPosition: return "position";
    case ConstraintLevel::kVelocity: return "velocity";
  }
  return "unknown";
}

bool parseConstraintLevel(const std::string& name, ConstraintLevel* level) {
  if (name == "position") {
    *level = ConstraintLevel::kPosition;
  } else if (name == "velocity") {
    *level = ConstraintLevel::kVelocity;
  } else {
    return false;
  }
  return true;
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
  if (std::string(frictionModelName(p.friction_model)) == "unknown") return "friction_model is not a known model";
  if (std::string(solverName(p.solver)) == "unknown") return "solver is not a known solver";
  if (!std::isfinite(p.erp) || p.erp < 0.0 || p.erp > 1.0) return "erp must be a number in [0, 1]";
  if (!nonNegative(p.softness)) return "softness must be a finite number >= 0";
  if (!nonNegative(p.time_step)) return "time_step must be a finite number >= 0";
  if (std::string(constraintLevelName(p.constraint_level)) == "unknown") return "constraint_level is not a known level";
  return "";
}

}  // namespace lcp_contact_solver::core
