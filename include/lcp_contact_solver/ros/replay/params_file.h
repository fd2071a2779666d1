// The node's parameter files offline: the YAML of its private parameters (config/default.yaml,
// or the one recorded beside a bag) and name=value overrides, read into SolverParams.
#pragma once

#include "lcp_contact_solver/core/solver_params.h"

#include <string>

namespace lcp_contact_solver_ros {

namespace lcs = ::lcp_contact_solver;

// One "name=value" of any solver parameter (core/solver_param_table.def), also those the
// service does not take per call (initial_guess, computeConstraintForces).
std::string applyReplayOverride(const std::string& assignment, lcs::core::SolverParams* params);

// Reads a YAML file of the node's private parameters (config/default.yaml, or the one
// recorded beside a bag) over `params`. Solver parameters are applied (computeConstraintForces
// has no effect offline); the node's other parameters (markers, pairing, queues,
// diagnostics) are accepted and ignored; an unknown name or a bad value is an error. Returns
// an empty string or one sentence naming the file and the fault.
std::string loadParamsFile(const std::string& path, lcs::core::SolverParams* params);

// Writes every solver parameter as such a YAML file (loadParamsFile reads it back exactly).
std::string writeParamsFile(const std::string& path, const lcs::core::SolverParams& params);

// The parameter file kept beside a recorded bag: "dir/name.bag" → "dir/name.params.yaml".
std::string paramsFileBeside(const std::string& bag_path);

}  // namespace lcp_contact_solver_ros
