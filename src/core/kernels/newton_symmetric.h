// The symmetric path of runNewton (newton_symmetric.cpp): an active-set Newton for LCPs
// (frictionless, μ = 0 and bilateral rows only) whose W is symmetric.
#pragma once

#include "lcp_contact_solver/core/kernels/kernels.h"

namespace lcp_contact_solver::core {

// True when every active contact is frictionless or bilateral and W (assembled) is
// symmetric to round-off: the problem the symmetric path solves.
bool symmetricLcp(const SolveContext& ctx);

// Runs the active-set iteration from `lambda`. On convergence returns true, `lambda` the
// solution and `report` filled (status converged). Otherwise returns false with `lambda`
// its best iterate (never worse than the start) and report->iterations the steps spent.
bool solveSymmetricActiveSet(const SolveContext& ctx, Eigen::VectorXd& lambda, KernelReport* report);

}  // namespace lcp_contact_solver::core
