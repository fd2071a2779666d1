// The symmetric paths of runNewton (newton_symmetric.cpp): an active-set Newton for LCPs
// (frictionless, μ = 0 and bilateral rows only) whose W is symmetric, and the same with every
// frictional contact assumed to stick (a scene at rest).
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

// True when `lambda` has some frictional contact pressed (λ_n > 0) and every one of them
// strictly inside its friction cone: the iterate says every contact sticks. False with
// torsional or rolling friction.
bool allSticking(const SolveContext& ctx, const Eigen::VectorXd& lambda);

// Where solveStickingActiveSet runs at all: W assembled, and W_AA gathered dense (dense, up
// to 128 rows or `dense_rows` if more, or block-sparse at least a quarter full): a sparse
// analysis costs more than a failed attempt is worth. A caller that weighs the dense
// Cholesky's n³/3 flops against its own work (auto: stickingCostSweeps) passes a larger
// `dense_rows`; newton, which tries the path unweighed after its warm-up, does not.
bool stickingPathApplies(const SolveContext& ctx, int dense_rows = 0);

// The active-set iteration with each frictional contact's tangent rows as equalities
// (u_t = 0) wherever its normal row is active: exact in one step when the set is right and
// every contact sticks, which the natural-map residual (the cone included) then confirms.
// Returns as solveSymmetricActiveSet; false also when a contact's friction leaves its cone,
// when W_AA is singular (the sticking forces are not unique), and at once where
// stickingPathApplies is false.
bool solveStickingActiveSet(const SolveContext& ctx, Eigen::VectorXd& lambda, KernelReport* report, int dense_rows = 0);

}  // namespace lcp_contact_solver::core
