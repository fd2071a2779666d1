// The solver parameters as data (solver_param_table.def): name, type, default, range, doc,
// and one text parser per type. The ROS reader, the service overrides, dynamic_reconfigure,
// replay's parameter files, lcp_solve's options and the scene files all go through it, so
// a parameter is added in one place.
#pragma once

#include "lcp_contact_solver/core/solver_params.h"

#include <string>
#include <vector>

namespace lcp_contact_solver::core {

enum class ParamType { kDouble, kInt, kBool, kEnum };

// Where a parameter can change besides the start-up sources (bit flags).
enum ParamAccess : unsigned {
  kParamReconfigure = 1u,  // dynamic_reconfigure
  kParamOverride = 2u,     // the service's per-call param_overrides
};

struct ParamSpec {
  std::string name;  // ROS parameter name = SolverParams member
  ParamType type;
  std::string default_text;     // as paramText() writes it
  double min = 0.0, max = 0.0;  // dynamic_reconfigure's range (kDouble, kInt)
  bool sofa = false;            // a SOFA LCPConstraintSolver field
  unsigned access = 0;          // ParamAccess bits
  std::string doc;
  std::vector<std::string> choices;  // kEnum
};

// Every parameter, in the table's order.
const std::vector<ParamSpec>& solverParamSpecs();
// nullptr for an unknown name.
const ParamSpec* findSolverParam(const std::string& name);

// What a value of the parameter must be: "a finite number", "an integer", "true or
// false", "one of auto, pgs, ...".
std::string expectedValue(const ParamSpec& spec);

// Sets one parameter from text. Numbers: the whole text (no spaces), finite; integers in
// int's range; booleans: true/false, 1/0, yes/no, on/off (any case); enums: a choice.
// Returns "" or "name='text' must be <expected>" / "'name' is not a solver parameter";
// `params` is unchanged on error. Ranges and consistency are validateParams' job.
std::string setParam(SolverParams* params, const std::string& name, const std::string& text);

// One "name=value" (spaces around name and value ignored, as written in YAML lists): the
// parameter must have every bit of `required_access`. Returns "" or the fault, as setParam,
// or "'text' is not of the form name=value".
std::string applyAssignment(SolverParams* params, const std::string& assignment,
                            unsigned required_access = 0);

// The value as text that setParam reads back exactly (doubles: shortest round trip).
std::string paramText(const SolverParams& params, const std::string& name);

// Shortest %.{1..17}g text that reads back as the same double.
std::string exactDoubleText(double value);

}  // namespace lcp_contact_solver::core
