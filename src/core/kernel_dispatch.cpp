#include "kernel_dispatch.h"

#include "portfolio.h"

#include "lcp_contact_solver/core/body_compliance.h"
#include "lcp_contact_solver/core/residual.h"

#include <sstream>

namespace lcp_contact_solver::core {

// ---- SolveContext ---------------------------------------------------------------------------

void SolveContext::computeD(const Eigen::VectorXd& lambda, Eigen::VectorXd& d) const {
  multiplyCompliance(*problem, lambda, d);  // the body form (unbuilt solve) without forming W
  d += problem->d_free;
  if (regularization != 0.0) d += regularization * lambda;
}

double SolveContext::residual(const Eigen::VectorXd& lambda) const {
  // Kernels call this several times per solve: a kept d saves a microsecond solve its mallocs.
  thread_local Eigen::VectorXd d;
  computeD(lambda, d);
  return naturalMapResidual(*problem, mu, lambda, d, ignored);
}

bool SolveContext::hasFriction() const {
  for (std::size_t i = 0; i < problem->contacts.size(); ++i)
    if ((ignored.empty() || !ignored[i]) && hasSlidingFriction(problem->contacts[i].type) && mu[i] > 0.0)
      return true;
  return false;
}

double SolveContext::normalDiagonal(int i) const {
  if (const auto* dense = std::get_if<Eigen::MatrixXd>(&problem->W)) return (*dense)(offsets[i], offsets[i]);
  const auto* sparse = std::get_if<BlockSparseMatrix>(&problem->W);
  if (!sparse || i >= sparse->blockCount()) return 0.0;
  const double* block = sparse->diagonalValues(i);
  return block ? block[0] : 0.0;
}

bool SolveContext::positiveDiagonal(bool bilateral) const {
  const int nc = static_cast<int>(problem->contacts.size());
  auto checked = [&](int i) {
    return !ignored[i] && (bilateral || problem->contacts[i].type != ContactType::kBilateral);
  };
  if (const auto* dense = std::get_if<Eigen::MatrixXd>(&problem->W)) {  // the storage resolved once
    for (int i = 0; i < nc; ++i)
      if (checked(i) && !((*dense)(offsets[i], offsets[i]) + regularization > 0.0)) return false;
    return true;
  }
  for (int i = 0; i < nc; ++i)
    if (checked(i) && !(normalDiagonal(i) + regularization > 0.0)) return false;
  return true;
}

namespace {

// Lemke ends when z0 leaves the basis: exact in exact arithmetic, but on an ill-conditioned
// W (mass ratios of 1e6, rank deficiency) the basic solution can miss the tolerance by
// round-off. "converged" means the residual reached the tolerance, for every solver, so
// that is a numerical failure (the pyramid variant does the same in pyramid.cpp).
KernelReport honestLemke(KernelReport report, const SolverParams& params) {
  if (report.status == SolveStatus::kConverged && params.stopping_rule == StoppingRule::kResidual &&
      report.solver_error > params.tolerance) {
    report.status = SolveStatus::kNumericalFailure;
    std::ostringstream message;
    message << "Lemke's final basis leaves a residual of " << report.solver_error << " > tolerance "
            << params.tolerance << " (round-off over " << report.iterations
            << " pivots on an ill-conditioned W); the forces are that basic solution";
    report.message = message.str();
  }
  return report;
}

}  // namespace

bool pyramidModel(const SolverParams& params) { return params.friction_model != FrictionModel::kCoulombDisc; }

bool hasExtendedFriction(const Problem& problem) {
  for (const Contact& c : problem.contacts)
    if (c.type == ContactType::kTorsional || c.type == ContactType::kRolling) return true;
  return false;
}

KernelReport runKernel(SolverKind kind, const SolveContext& ctx, Eigen::VectorXd& lambda) {
  const bool pyramid = pyramidModel(*ctx.params) && ctx.hasFriction();
  switch (kind) {
    case SolverKind::kPgs:
      return pyramid ? runBoxedGaussSeidel(ctx, lambda) : runProjectedGaussSeidel(ctx, lambda);
    case SolverKind::kLemke:
      return pyramid ? runPyramidLemke(ctx, lambda) : honestLemke(runLemke(ctx, lambda), *ctx.params);
    case SolverKind::kApgd: return runApgd(ctx, lambda);
    case SolverKind::kNewton: return runNewton(ctx, lambda);
    case SolverKind::kProx: return runProxNewton(ctx, lambda);
    case SolverKind::kAuto: return runPortfolio(ctx, lambda);
    case SolverKind::kNlgs: break;
  }
  return runNonlinearGaussSeidel(ctx, lambda);
}

void zeroInactiveRows(const SolveContext& ctx, Eigen::VectorXd& lambda) {
  const Problem& problem = *ctx.problem;
  for (std::size_t i = 0; i < problem.contacts.size(); ++i) {
    const int off = ctx.offsets[i];
    const Contact& c = problem.contacts[i];
    if (ctx.ignored[i]) {
      lambda.segment(off, c.rows).setZero();
    } else if (hasSlidingFriction(c.type) && ctx.mu[i] == 0.0) {
      lambda.segment(off + 1, 2).setZero();
    }
  }
}

Problem assembledProblem(const Problem& problem) {
  Problem out;
  out.contacts = problem.contacts;
  out.d_free = problem.d_free;
  out.name = problem.name;
  out.W = problem.bodies->assemble();
  return out;
}

bool failedToRun(SolveStatus status) {
  return status == SolveStatus::kZeroDiagonal || status == SolveStatus::kNotApplicable ||
         status == SolveStatus::kRayTermination || status == SolveStatus::kNumericalFailure;
}

}  // namespace lcp_contact_solver::core
