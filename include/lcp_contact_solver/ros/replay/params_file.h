// The node's parameter files offline: the YAML of its private parameters (config/default.yaml,
// or the one recorded beside a bag) and name=value overrides, read into SolverParams.
#pragma once

#include "lcp_contact_solver/core/solver_params.h"

#include <string>

namespace lcp_contact_solver_ros {

namespace lcs = ::lcp_contact_solver;

// One "name=value": the names of the service's param_overrides (applyOverride) plus
// `initial_guess` (the warm start, which only matters across cycles).
std::string applyReplayOverride(const std::string& assignment, lcs::SolverParams* params);

// Reads a YAML file of the node's private parameters (config/default.yaml, or the one
// recorded beside a bag) over `params`. Solver parameters are applied; the node's other
// parameters (markers, pairing, queues, diagnostics, computeConstraintForces) are
// accepted and have no effect offline; an unknown name or a bad value is an error. Returns
// an empty string or one sentence naming the file and the fault.
std::string loadParamsFile(const std::string& path, lcs::SolverParams* params);

// Writes the solver parameters as such a YAML file (loadParamsFile reads it back exactly).
std::string writeParamsFile(const std::string& path, const lcs::SolverParams& params);

// The parameter file kept beside a recorded bag: "dir/name.bag" → "dir/name.params.yaml".
std::string paramsFileBeside(const std::string& bag_path);

}  // namespace lcp_contact_solver_ros
