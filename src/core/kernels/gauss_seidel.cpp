// Gauss-Seidel kernels: projected Gauss-Seidel (PGS, SOFA's gaussSeidelLCP1) for
// frictionless problems, nonlinear block Gauss-Seidel (NLGS, SOFA's nlcp_gaussseidel)
// for Coulomb friction, and the boxed PGS for a pyramid friction model. All run the same
// sweep; each contact type has its local step.
//
// Derivation (one sweep). With the other contacts frozen, contact c sees
//   u_c = D_c λ_c + b_c,   D_c = W_cc (+ r I),   b_c = d_c - D_c λ_c   (d_c its current d)
// and solves its own small problem exactly: a scalar LCP for a normal row
// (λ = max(0, λ - d / D_nn)), a linear solve for bilateral rows (λ -= D⁻¹ d), the local
// Coulomb problem for a frictional contact (coulombLocalStep), or the local polygon
// problem for a pyramid (polygonLocalStep). Then d is updated with W's columns of c
// (dense) or re-read from c's block row (block-sparse) before the next contact; the unbuilt
// solve (body form, build_lcp = false) updates the bodies' corrections instead (BodyAccess,
// with its derivation). A fixed
// point of the sweep satisfies every contact's law with every other contact's force, so
// it solves the problem.
//
// Over-relaxation (SolverParams::sor = ω): the local answer λ_c* is not taken as is but
// λ_c <- Proj_c(λ_c + ω (λ_c* - λ_c)), Proj_c the projection onto the contact's feasible
// set (R+ for a normal, the cone for Coulomb, the polygon pyramid, nothing for bilateral),
// so the iterate stays admissible. Fixed points are unchanged (λ_c* = λ_c there). For the
// frictionless LCP with symmetric positive definite W this is PSOR, convergent for
// 0 < ω < 2; ω > 1 often saves sweeps on stiff stacks, ω < 1 damps oscillating
// frictional problems. ω = 1 runs the plain step (bit-identical).
//
// When to use it: pgs for frictionless problems (and boxed pgs for pyramid friction) of
// any size, nlgs for Coulomb friction at moderate accuracy (1e-3..1e-8): cheap sweeps,
// robust on rank-deficient W, but linear convergence that stalls near 1e-5..1e-6 on
// ill-conditioned stacks (use newton there).
//
// The local laws are local_contact_laws.h, the three ways of reading W sweep_access.h; this
// file is the sweep.
#include "local_contact_laws.h"
#include "sweep_access.h"

#include "lcp_contact_solver/core/kernels/kernels.h"
#include "lcp_contact_solver/core/kernels/scalar_rows.h"
#include "lcp_contact_solver/core/residual.h"

#include <algorithm>
#include <limits>
#include <string>
#include <type_traits>
#include <variant>

namespace lcp_contact_solver::core {

namespace {

using namespace local_laws;

// Maintained d drifts by round-off; refresh it exactly this often (sweeps).
constexpr int kRefreshInterval = 50;

bool allFinite(const Eigen::VectorXd& v) { return v.allFinite(); }

// `kept` (a caller's memo, dense and block-sparse W only): the d a previous call ended with,
// taken where this call starts from that call's last iterate, and this call's own d kept.
template <class Access>
KernelReport sweepUntilDone(const SolveContext& ctx, const std::vector<LocalBlock>& blocks, Access& access,
                            Eigen::VectorXd& lambda, const FrictionPolygon* polygon, KeptD* kept = nullptr) {
  // The dense and block-sparse accesses maintain d itself: their refresh is W λ + d_free
  // (SolveContext::computeD), so a d just refreshed is the exact one.
  constexpr bool kMaintainedD = !std::is_same_v<Access, BodyAccess>;
  const SolverParams& params = *ctx.params;
  const double omega = params.sor;
  // The problem solved: the disc's natural map, or the pyramid's (friction_pyramid.h).
  auto residualOf = [&](const Eigen::VectorXd& l, const Eigen::VectorXd& d) {
    return polygon != nullptr ? pyramidResidual(*ctx.problem, ctx.mu, *polygon, l, d, ctx.ignored)
                              : naturalMapResidual(*ctx.problem, ctx.mu, l, d, ctx.ignored);
  };
  KernelReport report;
  if (polygon != nullptr) report.friction_model = params.friction_model;
  Eigen::VectorXd best = lambda;
  double best_residual = std::numeric_limits<double>::infinity();
  double delta[6];
  double d_c[6];
  int since_refresh = 0;
  if (!(kept != nullptr && kept->take(ctx, lambda, access.d, &since_refresh))) access.refresh(lambda);
  // The last iterate's d kept for the next call, before λ becomes the best iterate.
  auto keepD = [&] {
    if constexpr (kMaintainedD) {
      if (kept != nullptr) kept->keep(ctx, lambda, access.d, since_refresh);
    }
  };
  for (int sweep = 1; sweep <= params.maxIt; ++sweep) {
    double sofa_error = 0.0;
    for (const LocalBlock& blk : blocks) {
      if (blk.kind == LocalKind::kSkip) continue;
      access.contactD(blk, lambda, d_c);
      std::fill(delta, delta + blk.rows, 0.0);
      localStep(blk, polygon, omega, d_c, lambda.data() + blk.offset, delta);
      access.applyDelta(blk, delta);
      if (params.stopping_rule == StoppingRule::kSofa) sofa_error += sofaContactError(blk, delta);
    }
    report.iterations = sweep;
    if (!allFinite(lambda)) {
      lambda = best;
      report.status = SolveStatus::kNumericalFailure;
      report.message = "the iterate became non-finite in sweep " + std::to_string(sweep) +
                       " (W is probably not positive semidefinite, or a diagonal is so small that the force "
                       "overflows: minW excludes such contacts); best iterate returned";
      return report;
    }
    if (++since_refresh == kRefreshInterval) {
      access.refresh(lambda);
      since_refresh = 0;
    }
    const bool need_residual = params.stopping_rule == StoppingRule::kResidual || params.displayDebug;
    double residual = 0.0;
    if (need_residual) {
      const Eigen::VectorXd& d = access.currentD(lambda);
      residual = residualOf(lambda, d);
      if (params.displayDebug) report.history.push_back(residual);
      if (residual < best_residual) {
        best_residual = residual;
        best = lambda;
      }
    }
    if (params.stopping_rule == StoppingRule::kSofa) {
      report.solver_error = sofa_error;
      best = lambda;
      if (sofa_error < params.tolerance) {
        report.status = SolveStatus::kConverged;
        keepD();
        return report;
      }
    } else {
      report.solver_error = residual;
      if (residual <= params.tolerance) {
        access.refresh(lambda);
        since_refresh = 0;
        bool confirmed;
        if constexpr (kMaintainedD) {
          confirmed = confirmConverged(report, residualOf(lambda, access.currentD(lambda)), params.tolerance);
        } else {
          Eigen::VectorXd d_exact;
          ctx.computeD(lambda, d_exact);
          confirmed = confirmConverged(report, residualOf(lambda, d_exact), params.tolerance);
        }
        if (confirmed) {
          keepD();
          return report;
        }
      }
    }
    // At most one clock read per sweep.
    if (sweep < params.maxIt && (ctx.deadlinePassed() || ctx.trialPassed(best_residual))) {
      keepD();
      endOnTimeBudget(report, lambda, best, params.time_budget, sweep);
      return report;
    }
  }
  keepD();
  endOnMaxIt(report, lambda, best, params.maxIt);
  return report;
}

KernelReport runGaussSeidel(const SolveContext& ctx, Eigen::VectorXd& lambda,
                            const FrictionPolygon* polygon = nullptr) {
  if (fitsScalarRows(*ctx.problem)) {  // every contact one row: the scalar-row sweep (scalar_rows.h)
    KernelReport report = runScalarRowGaussSeidel(ctx, lambda);
    if (polygon != nullptr) report.friction_model = ctx.params->friction_model;
    return report;
  }
  // The blocks depend on W's diagonal blocks, μ, the ignored contacts and r, not on λ: a
  // caller's memo (kernels.h) forms them once for all its calls.
  const int facets = polygon != nullptr ? polygon->facets : 0;
  GaussSeidelMemo* memo = ctx.gs_memo;
  std::vector<LocalBlock> own;
  std::vector<LocalBlock>& blocks = memo != nullptr ? memo->blocks : own;
  if (memo == nullptr || memo->problem != ctx.problem || memo->regularization != ctx.regularization ||
      memo->facets != facets) {
    if (memo != nullptr) memo->clear();
    if (std::string err = prepareBlocks(ctx, blocks, polygon); !err.empty()) {
      KernelReport report;
      report.status = SolveStatus::kZeroDiagonal;
      report.message = err;
      return report;
    }
    if (memo != nullptr) {
      memo->problem = ctx.problem;
      memo->regularization = ctx.regularization;
      memo->facets = facets;
    }
  }
  if (const BodyCompliance* bodies = ctx.problem->bodies.get()) {  // build_lcp = false
    BodyAccess access(*bodies, ctx);
    access.first_block = blocks.data();
    return sweepUntilDone(ctx, blocks, access, lambda, polygon);
  }
  KeptD* kept = memo != nullptr ? &memo->kept : nullptr;
  if (const auto* dense = std::get_if<Eigen::MatrixXd>(&ctx.problem->W)) {
    DenseAccess access{*dense, ctx, Eigen::VectorXd()};
    return sweepUntilDone(ctx, blocks, access, lambda, polygon, kept);
  }
  const auto& sparse = std::get<BlockSparseMatrix>(ctx.problem->W);
  SparseColumnIndex own_index;
  SparseColumnIndex& index = memo != nullptr ? memo->columns_by_block : own_index;
  if (memo == nullptr || memo->index_problem != ctx.problem) {
    index.build(sparse);
    if (memo != nullptr) memo->index_problem = ctx.problem;
  }
  SparseAccess access{ctx, index, Eigen::VectorXd()};
  access.first_block = blocks.data();
  return sweepUntilDone(ctx, blocks, access, lambda, polygon, kept);
}

}  // namespace

KernelReport runProjectedGaussSeidel(const SolveContext& ctx, Eigen::VectorXd& lambda) {
  if (ctx.hasFriction()) {
    KernelReport report;
    report.status = SolveStatus::kNotApplicable;
    report.message =
        "pgs solves frictionless problems; this one has contacts with mu > 0 "
        "(use nlgs, or a pyramid friction_model for boxed pgs)";
    return report;
  }
  return runGaussSeidel(ctx, lambda);
}

KernelReport runNonlinearGaussSeidel(const SolveContext& ctx, Eigen::VectorXd& lambda) {
  return runGaussSeidel(ctx, lambda);
}

KernelReport runBoxedGaussSeidel(const SolveContext& ctx, Eigen::VectorXd& lambda) {
  const FrictionPolygon polygon = makeFrictionPolygon(ctx.params->friction_model);
  if (polygon.facets == 0) return runGaussSeidel(ctx, lambda);
  KernelReport report = runGaussSeidel(ctx, lambda, &polygon);
  report.friction_model = ctx.params->friction_model;
  return report;
}

}  // namespace lcp_contact_solver::core
