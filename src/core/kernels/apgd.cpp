// APGD: accelerated projected gradient for the Coulomb disc (Nesterov's method with an
// adaptive step and restart, in the style of Mazhar, Heyn, Negrut & Tasora 2015).
//
// Derivation. For a fixed shift s (one number per frictional contact) the convex problem
//   min f(λ) = ½ λᵀ W λ + (d_free + S s)ᵀ λ   over   λ ∈ K,
// S s putting s_c on contact c's normal row and K the product of the contacts' feasible
// sets (Coulomb cone, R+ for a normal row, R^k for bilateral rows, {0} for ignored rows and
// for the tangents of μ = 0 contacts), has the optimality condition
//   λ = Proj_K(λ - t ∇f(λ)),   ∇f(λ) = W λ + d_free + S s = u + S s   (any t > 0),
// the cone complementarity problem K ∋ λ ⟂ u + S s ∈ K*. With s_c = μ_c |u_t,c| this is
// De Saxcé's bipotential form of Coulomb's law (residual.h), so Coulomb is the fixed
// point of "solve the convex problem, update s" (Acary & Brogliato's fixed point on the
// shift). Each convex problem is solved by Nesterov's accelerated projected gradient:
//   x_{k+1} = Proj_K(y_k - ∇f(y_k) / L)
//   θ_{k+1} = (√(θ_k⁴ + 4 θ_k²) - θ_k²) / 2,   β = θ_k (1 - θ_k) / (θ_k² + θ_{k+1})
//   y_{k+1} = x_{k+1} + β (x_{k+1} - x_k)
// which converges like O(1/k²) in f when L bounds W's curvature. L is adaptive: the step
// is accepted when the curvature along d = x_{k+1} - y_k satisfies dᵀ W d <= L |d|²
// (for a quadratic this is exactly the sufficient-decrease test
// f(x) <= f(y) + ∇f(y)ᵀ d + L/2 |d|², computed without cancellation), otherwise L
// doubles; after each iteration L shrinks by 0.9 so the step follows the local
// curvature. Gradient restart (O'Donoghue & Candès): when ∇f(y_k)ᵀ(x_{k+1} - x_k) > 0 the
// momentum points uphill and θ resets to 1. One product with W per iteration (plus one
// per rejected step): W y_{k+1} = (1 + β) W x_{k+1} - β W x_k is a combination of
// products already computed, and u(x_{k+1}) = W x_{k+1} + d_free gives the true Coulomb
// residual of every iterate for free. The shift is updated (and the momentum reset)
// when the convex problem's own residual drops below 0.3 times the Coulomb residual,
// i.e. when the stale shift dominates the error, or when that residual sits on a plateau
// (kPlateauIterations): with W singular the convex problem for a given shift may have no
// minimizer, and its residual then stops falling short of that ratio.
//
// When to use it: large frictional problems where each iteration must be cheap and
// parallel-friendly (matrix-vector products only, no sequential sweep), at 1e-4..1e-8;
// insensitive to the contact ordering. On small, well
// conditioned problems nlgs needs fewer products; for 1e-8 and below use newton.
#include "lcp_contact_solver/core/kernels/kernels.h"
#include "lcp_contact_solver/core/residual.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

namespace lcp_contact_solver::core {
namespace {

// The shift is refreshed when the convex problem's residual falls to this fraction of the
// Coulomb residual. Tried 0.02..1 on the shared FCLIB problems: 0.2..0.5 need the fewest
// iterations; smaller ratios over-solve each convex problem, 1 restarts the momentum too
// often.
constexpr double kShiftUpdateRatio = 0.3;
constexpr int kPowerIterations = 8;
constexpr int kMaxBacktracks = 60;
constexpr double kStepShrink = 0.9;
// A convex problem whose residual has not fallen by 1 % in this many iterations is on a
// plateau: the shift moves anyway, the momentum kept. Started from another solver's iterate
// on rank-deficient contacts (a box pyramid after 3 Gauss-Seidel sweeps) the convex residual
// stayed flat at 0.35 times the Coulomb residual, above the ratio that moves the shift, for
// 2 000 iterations. An ill-conditioned convex problem (stacks with a mass ratio of 100) still
// falls by 1 % within it. With 50 iterations BoxesStack1's cold solves took up to 1.5x their
// iterations, and with no halving in 50 as the plateau and the momentum restarted as after a
// solved convex problem, 20-50x.
constexpr int kPlateauIterations = 100;
constexpr double kPlateauProgress = 0.99;

enum class SetKind : std::uint8_t { kZero, kFree, kNormal, kCone };

struct ContactSet {
  SetKind kind = SetKind::kZero;
  int offset = 0;
  int rows = 0;
  double mu = 0.0;
};

std::vector<ContactSet> contactSets(const SolveContext& ctx) {
  const Problem& problem = *ctx.problem;
  std::vector<ContactSet> sets(problem.contacts.size());
  for (std::size_t i = 0; i < problem.contacts.size(); ++i) {
    const Contact& c = problem.contacts[i];
    ContactSet& set = sets[i];
    set.offset = ctx.offsets[i];
    set.rows = c.rows;
    set.mu = ctx.mu[i];
    if (ctx.ignored[i])
      set.kind = SetKind::kZero;
    else if (c.type == ContactType::kBilateral)
      set.kind = SetKind::kFree;
    else if (c.type == ContactType::kFrictionless || set.mu == 0.0)
      set.kind = SetKind::kNormal;
    else
      set.kind = SetKind::kCone;
  }
  return sets;
}

// x <- Proj_K(x)
void project(const std::vector<ContactSet>& sets, Eigen::VectorXd& x) {
  double* v = x.data();
  for (const ContactSet& set : sets) {
    double* r = v + set.offset;
    switch (set.kind) {
      case SetKind::kZero:
        for (int k = 0; k < set.rows; ++k) r[k] = 0.0;
        break;
      case SetKind::kFree: break;
      case SetKind::kNormal:
        r[0] = std::max(0.0, r[0]);
        for (int k = 1; k < set.rows; ++k) r[k] = 0.0;
        break;
      case SetKind::kCone: projectOntoCone(set.mu, r); break;
    }
  }
}

// y = (W + r I) x
void applyW(const SolveContext& ctx, const Eigen::VectorXd& x, Eigen::VectorXd& y) {
  multiply(ctx.problem->W, x, y);
  if (ctx.regularization != 0.0) y += ctx.regularization * x;
}

// s_c = μ_c |u_t,c| on each cone's normal row (zero elsewhere).
void deSaxceShift(const std::vector<ContactSet>& sets, const Eigen::VectorXd& u, Eigen::VectorXd& shift) {
  shift.setZero();
  for (const ContactSet& set : sets) {
    if (set.kind != SetKind::kCone) continue;
    const double* ut = u.data() + set.offset + 1;
    shift[set.offset] = set.mu * std::sqrt(ut[0] * ut[0] + ut[1] * ut[1]);
  }
}

// Natural-map residual of the convex problem with the current shift,
// |x - Proj_K(x - (u + S s))| / |d_free|.
double shiftedResidual(const std::vector<ContactSet>& sets, const Eigen::VectorXd& x,
                       const Eigen::VectorXd& u, const Eigen::VectorXd& shift, double scale) {
  double sum = 0.0;
  for (const ContactSet& set : sets) {
    const double* l = x.data() + set.offset;
    const double* w = u.data() + set.offset;
    switch (set.kind) {
      case SetKind::kZero: break;
      case SetKind::kFree:
        for (int k = 0; k < set.rows; ++k) sum += w[k] * w[k];
        break;
      case SetKind::kNormal: {
        const double e = l[0] - std::max(0.0, l[0] - w[0]);
        sum += e * e;
        break;
      }
      case SetKind::kCone: {
        double p[3] = {l[0] - w[0] - shift[set.offset], l[1] - w[1], l[2] - w[2]};
        projectOntoCone(set.mu, p);
        for (int k = 0; k < 3; ++k) sum += (l[k] - p[k]) * (l[k] - p[k]);
        break;
      }
    }
  }
  const double residual = std::sqrt(sum) / scale;
  return std::isfinite(residual) ? residual : std::numeric_limits<double>::max();
}

// Largest eigenvalue of W + r I from a few power iterations (an underestimate; the
// backtracking corrects it). Deterministic start so results repeat bit for bit.
double curvatureEstimate(const SolveContext& ctx, int n) {
  Eigen::VectorXd v(n), w(n);
  for (int i = 0; i < n; ++i) v[i] = 1.0 + 0.5 * std::sin(1.0 + i);
  v.normalize();
  double estimate = 0.0;
  for (int it = 0; it < kPowerIterations; ++it) {
    applyW(ctx, v, w);
    const double norm = w.norm();
    if (!(norm > 0.0) || !std::isfinite(norm)) break;
    estimate = norm;
    v = w / norm;
  }
  return estimate;
}

}  // namespace

KernelReport runApgd(const SolveContext& ctx, Eigen::VectorXd& lambda) {
  const Problem& problem = *ctx.problem;
  const SolverParams& params = *ctx.params;
  KernelReport report;
  const int n = problem.rowCount();
  const std::vector<ContactSet> sets = contactSets(ctx);
  const double q_norm = problem.d_free.stableNorm();
  const double scale = q_norm > 0.0 && std::isfinite(q_norm) ? q_norm : 1.0;
  const Eigen::VectorXd& q = problem.d_free;

  Eigen::VectorXd x = lambda, x_new(n), Wx(n), Wx_new(n), y(n), Wy(n), g(n), u(n), shift(n);
  project(sets, x);
  applyW(ctx, x, Wx);
  u = Wx + q;
  deSaxceShift(sets, u, shift);
  double residual = naturalMapResidual(problem, ctx.mu, x, u, ctx.ignored);
  Eigen::VectorXd best = x;
  double best_residual = residual;
  report.solver_error = residual;
  if (residual <= params.tolerance) {
    lambda = x;
    report.status = SolveStatus::kConverged;
    return report;
  }

  // Warm start stage: a caller that hands back exactly what the last call returned resumes
  // that call's iteration (momentum, step, shift), so that running in slices costs what one
  // long run costs; the start above stays the best iterate until one beats it.
  ApgdMemo* memo = ctx.apgd_memo;
  double L = 0.0, theta = 1.0;
  // The convex problem's residual at its last 1 % decrease, and the iterations since.
  double convex_mark = std::numeric_limits<double>::infinity();
  int convex_stall = 0;
  if (memo != nullptr && memo->problem == ctx.problem && memo->regularization == ctx.regularization &&
      memo->returned.size() == n && memo->returned == lambda) {
    x = memo->x;
    Wx = memo->Wx;
    y = memo->y;
    Wy = memo->Wy;
    shift = memo->shift;
    theta = memo->theta;
    L = memo->L;
    convex_mark = memo->convex_mark;
    convex_stall = memo->convex_stall;
  } else {
    L = curvatureEstimate(ctx, n);
    if (!(L > 0.0) || !std::isfinite(L)) L = 1.0;
    y = x;
    Wy = Wx;
  }
  // Every exit but a converged one leaves the state for the next call.
  const auto keepState = [&]() {
    if (memo == nullptr) return;
    memo->problem = ctx.problem;
    memo->regularization = ctx.regularization;
    memo->returned = lambda;
    memo->x = x;
    memo->Wx = Wx;
    memo->y = y;
    memo->Wy = Wy;
    memo->shift = shift;
    memo->theta = theta;
    memo->L = L;
    memo->convex_mark = convex_mark;
    memo->convex_stall = convex_stall;
  };
  if (memo != nullptr) memo->clear();
  report.status = SolveStatus::kMaxIterations;
  for (int it = 1; it <= params.maxIt; ++it) {
    g = Wy + q + shift;
    // Projected gradient step from y, backtracking on the curvature along the step.
    for (int bt = 0;; ++bt) {
      x_new = y - g / L;
      project(sets, x_new);
      applyW(ctx, x_new, Wx_new);
      double dd = 0.0, curvature = 0.0;
      for (int i = 0; i < n; ++i) {
        const double d = x_new[i] - y[i];
        dd += d * d;
        curvature += d * (Wx_new[i] - Wy[i]);
      }
      if (curvature <= L * dd || bt >= kMaxBacktracks || !std::isfinite(curvature)) break;
      L *= 2.0;
    }
    report.iterations = it;
    if (!x_new.allFinite() || !Wx_new.allFinite()) {
      lambda = best;
      report.status = SolveStatus::kNumericalFailure;
      report.message = "apgd: the iterate became non-finite at iteration " + std::to_string(it) +
                       " (W is probably not positive semidefinite); best iterate returned";
      report.solver_error = best_residual;
      return report;
    }
    const double theta_next =
        0.5 * (std::sqrt(theta * theta * theta * theta + 4.0 * theta * theta) - theta * theta);
    double beta = theta * (1.0 - theta) / (theta * theta + theta_next);
    // Gradient restart: momentum that climbs f is dropped.
    const bool restart = g.dot(x_new - x) > 0.0;
    if (restart) beta = 0.0;

    u = Wx_new + q;
    residual = naturalMapResidual(problem, ctx.mu, x_new, u, ctx.ignored);
    if (params.displayDebug) report.history.push_back(residual);
    if (residual < best_residual) {
      best_residual = residual;
      best = x_new;
    }
    if (residual <= params.tolerance) {
      lambda = x_new;
      report.status = SolveStatus::kConverged;
      report.solver_error = residual;
      return report;
    }
    const double convex_residual = shiftedResidual(sets, x_new, u, shift, scale);
    if (convex_residual <= kPlateauProgress * convex_mark) {
      convex_mark = convex_residual;
      convex_stall = 0;
    } else {
      ++convex_stall;
    }
    const bool solved = convex_residual <= kShiftUpdateRatio * residual;
    if (solved || convex_stall >= kPlateauIterations) {
      deSaxceShift(sets, u, shift);
      convex_mark = std::numeric_limits<double>::infinity();
      convex_stall = 0;
    }
    if (solved) {  // the convex problem is solved well enough: restart the momentum
      y = x_new;
      Wy = Wx_new;
      theta = 1.0;
    } else {  // also after a plateau's new shift, which moves little
      y = x_new + beta * (x_new - x);
      Wy = (1.0 + beta) * Wx_new - beta * Wx;
      theta = restart ? 1.0 : theta_next;
    }
    std::swap(x, x_new);
    std::swap(Wx, Wx_new);
    L *= kStepShrink;
    if (it < params.maxIt && (ctx.deadlinePassed() || ctx.trialPassed(best_residual))) {
      lambda = best;
      keepState();
      report.status = SolveStatus::kTimeBudget;
      report.solver_error = best_residual;
      report.message = "time budget (" + std::to_string(params.time_budget) + " s) ran out after " +
                       std::to_string(it) + " iterations; best iterate returned";
      return report;
    }
  }
  lambda = best;
  keepState();
  report.solver_error = best_residual;
  report.message = "maxIt (" + std::to_string(params.maxIt) + ") iterations reached before the tolerance";
  return report;
}

}  // namespace lcp_contact_solver::core
