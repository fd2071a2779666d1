// Running one kernel on a prepared problem, and the small rules every caller of a kernel
// shares (ContactSolver's stages, the auto portfolio, the island solver): which kernel a
// SolverKind and friction model mean, which rows must stay at zero, which statuses are no
// approximate solution. Private to the core library.
#pragma once

#include "lcp_contact_solver/core/kernels/kernels.h"
#include "lcp_contact_solver/core/problem.h"
#include "lcp_contact_solver/core/solver_params.h"

#include <Eigen/Core>

namespace lcp_contact_solver::core {

// The kernel of `kind` (auto: the portfolio), with the pyramid variant where the friction
// model asks for it.
KernelReport runKernel(SolverKind kind, const SolveContext& ctx, Eigen::VectorXd& lambda);

// A pyramid friction model (pyramid4/pyramid8) rather than Coulomb's disc.
bool pyramidModel(const SolverParams& params);

// Torsional or rolling contacts: only nlgs (and auto through it) has their local step.
bool hasExtendedFriction(const Problem& problem);

// Rows the kernels must leave at zero: ignored contacts, tangents of μ = 0 contacts.
void zeroInactiveRows(const SolveContext& ctx, Eigen::VectorXd& lambda);

// The problem with the body form replaced by its assembled, block-sparse W.
Problem assembledProblem(const Problem& problem);

// The kernel could not run, or ended on something that is not an approximate solution:
// its forces must not drive maxF drops nor seed the next warm start.
bool failedToRun(SolveStatus status);

}  // namespace lcp_contact_solver::core
