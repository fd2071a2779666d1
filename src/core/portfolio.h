// auto: the portfolio of the other kernels (its rules are written above runPortfolio in
// portfolio.cpp and in docs/ARCHITECTURE.md). Private to the core library.
#pragma once

#include "lcp_contact_solver/core/kernels/kernels.h"

#include <Eigen/Core>

#include <string>
#include <utility>
#include <vector>

namespace lcp_contact_solver::core {

// Solves from `lambda` with the members auto predicts, handing over on stalls and failures;
// maxIt and time_budget bound the whole path. report.stages holds each member's time.
KernelReport runPortfolio(const SolveContext& ctx, Eigen::VectorXd& lambda);

// The residual auto measures its start by (ctx.start_residual when the caller measured it; from
// λ = 0 without a product with W, d = d_free).
double autoStartResidual(const SolveContext& ctx, const Eigen::VectorXd& lambda);

// Before W's islands are solved apart (islands.h), from λ = 0 (its residual measured in
// ctx.start_residual) at two or three digits: a few plain nlgs sweeps on the whole problem,
// which end the solve where they meet the whole tolerance (true: `lambda`, `report` and the
// sweeps' `seconds` are the answer). Otherwise `lambda` is left at zero and `report` holds the
// sweeps spent (iterations; none where they were not worth trying).
bool autoWholeSweepsEnd(const SolveContext& ctx, Eigen::VectorXd& lambda, KernelReport& report, double& seconds);

// stats.solver of an auto solve: "auto:" and the members in the order they ran.
std::string autoPath(const std::vector<std::pair<std::string, double>>& stages);

}  // namespace lcp_contact_solver::core
