// Proximal point outer loop around the semismooth Newton kernel (Siconos' PROX).
//
// Derivation. The frictional contact problem asks for λ with u = W λ + q (q = d_free, W
// regularized by r when asked) such that (λ, u) satisfies Coulomb's law, i.e. λ solves the
// monotone inclusion 0 ∈ F(λ) + N(λ), where F(λ) = W λ + q + De Saxcé's shift and N is the
// cone constraint. The proximal point method (Rockafellar) solves instead a sequence of
//   0 ∈ F(λ) + σ (λ - λ_k) + N(λ),     λ_{k+1} = that λ,
// i.e. the same contact problem with W_σ = W + σ I and q_σ = q - σ λ_k: Coulomb's law on
// u_σ = W_σ λ + q_σ = u + σ (λ - λ_k). A fixed point λ_{k+1} = λ_k makes u_σ = u, so it is
// a solution of the original problem, and for a monotone F (W positive semidefinite) the
// iterates converge to one even when W is singular, with every sub-problem strongly
// monotone: W + σ I is positive definite, so Newton's Jacobian J = A + B W_σ is
// nonsingular on the sticking set, where plain semismooth Newton on a rank-deficient W
// (more sticking rows than the bodies have degrees of freedom) meets a singular J and
// stalls. Small σ makes the outer loop fast (λ_{k+1} is close to the solution), large σ
// makes the inner problem well conditioned; σ is adapted: divided by 10 after a sub-problem
// Newton solves and that does not raise the true residual (kFlat), multiplied by 10 when
// Newton fails or the residual rises, and the next step then starts again from the last
// centre. σ starts at 1e-2 times the mean diagonal of W (W's scale).
// A solved step that leaves the residual where it was is a proximal step all the same: on a
// rank-deficient W it moves λ along W's null space, by about the residual / σ, until a contact
// changes state and the residual falls. Its λ is the next centre and σ falls, so that those
// moves lengthen. The loop gives up where the best residual has not halved within
// kStallSteps steps.
//
// Inexact sub-problems: each runs newton (newton.cpp, its own nlgs warm start and bursts,
// and its damping without the raise after a cut step: σ I regularizes the sub-problem already)
// to a tolerance tied to the current true residual, max(tolerance / 2, residual / 10) on
// the sub-problem's residual, so early sub-problems are cheap and the inexactness falls
// with the outer residual (summable errors, as inexact proximal point needs), and at most
// kMaxInnerIterations: an unsolved sub-problem counts as a failure and raises σ.
//
// Every outer step measures the true residual (residual.h) on the original problem and
// keeps the best iterate. Iterations count the inner iterations (nlgs sweeps + Newton
// steps); maxIt and time_budget bound the whole loop.
//
// When to use it: high accuracy (1e-8..1e-12) on rank-deficient or ill-conditioned W where
// newton stalls (auto runs it after a stalled newton); each outer step costs one newton solve.
#include "lcp_contact_solver/core/kernels/kernels.h"
#include "lcp_contact_solver/core/residual.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace lcp_contact_solver::core {
namespace {

constexpr double kSigmaStart = 1e-2;     // times the mean diagonal of W
constexpr double kSigmaMin = 1e-12;      // times the mean diagonal
constexpr double kSigmaMax = 1e4;        // times the mean diagonal
constexpr double kInnerReduction = 0.1;  // inner tolerance: this times the outer residual
constexpr int kMaxOuterSteps = 200;
// A solved sub-problem whose true residual is at most this much (relative) above the last one
// left it flat (above). Taken for a failure, such steps restarted from the same centre with
// ever more damping: the 81-row sphere_pile step 356 at 1e-9, from apgd's iterate, ended in
// "no progress even with the largest proximal weight" after 18 iterations at 2.3e-8; taken
// as steps, 5 of them reach 3e-14.
constexpr double kFlat = 1e-3;
// Steps within which the best residual must halve: as many as σ has decades between its
// start and its floor (kSigmaStart / kSigmaMin), so flat steps have lengthened their moves
// through every scale by then. Without it, steps that lower the residual by 0.1 % each ran to
// kMaxOuterSteps (a box pyramid at 1e-10: 42 000 iterations where the loop used to stop at 970).
constexpr int kStallSteps = 10;
// Iterations (sweeps + Newton steps) one sub-problem may take: a sub-problem Newton cannot
// solve (σ so small that it is as singular as the problem) ends here and gets a larger σ,
// instead of spending the whole remaining budget (maxIt, time_budget) on one step.
constexpr int kMaxInnerIterations = 1000;

double meanDiagonal(const Problem& problem, double regularization) {
  const int n = problem.rowCount();
  if (n == 0) return 1.0;
  double sum = 0.0;
  const std::vector<int> offsets = problem.rowOffsets();
  for (std::size_t i = 0; i < problem.contacts.size(); ++i) {
    const Eigen::MatrixXd D = diagonalBlock(problem.W, offsets[i], problem.contacts[i].rows);
    sum += D.diagonal().sum();
  }
  const double mean = sum / n + regularization;
  return mean > 0.0 && std::isfinite(mean) ? mean : 1.0;
}

}  // namespace

KernelReport runProxNewton(const SolveContext& ctx, Eigen::VectorXd& lambda) {
  const Problem& problem = *ctx.problem;
  const SolverParams& params = *ctx.params;
  KernelReport report;
  report.status = SolveStatus::kMaxIterations;

  double residual = ctx.residual(lambda);
  Eigen::VectorXd best = lambda;
  double best_residual = std::isfinite(residual) ? residual : std::numeric_limits<double>::infinity();
  if (residual <= params.tolerance) {
    report.status = SolveStatus::kConverged;
    report.solver_error = residual;
    return report;
  }

  // The sub-problem: same contacts and W, d_free moved by the prox centre, W + (r + σ) I.
  Problem sub;
  sub.name = problem.name;
  sub.contacts = problem.contacts;
  sub.W = problem.W;
  SolverParams inner_params = params;
  inner_params.stopping_rule = StoppingRule::kResidual;
  inner_params.displayDebug = false;
  SolveContext inner = ctx;
  inner.problem = &sub;
  inner.params = &inner_params;
  inner.gs_memo = nullptr;  // r + σ changes at every proximal step: nothing to keep
  inner.start_residual = std::numeric_limits<double>::quiet_NaN();  // each subproblem is another
  inner.has_trial_deadline = false;  // a trial judges the proximal steps (kernels.h)
  inner.proximal_subproblem = true;

  const double scale = meanDiagonal(problem, ctx.regularization);
  double sigma = kSigmaStart * scale;
  int iterations = 0, outer = 0, failures = 0;
  Eigen::VectorXd centre = lambda;  // the last step's λ that was kept: the next step's prox centre
  int stall_start = 0;              // the step from which the best residual must halve
  double stall_best = best_residual;
  for (;;) {
    if (iterations >= params.maxIt) {
      report.message = "prox: maxIt (" + std::to_string(params.maxIt) + ") iterations over " +
                       std::to_string(outer) + " proximal steps reached before the tolerance";
      break;
    }
    if (outer >= kMaxOuterSteps) {
      report.message = "prox: " + std::to_string(outer) + " proximal steps without reaching the tolerance";
      break;
    }
    if (outer - stall_start >= kStallSteps) {
      if (!(best_residual <= 0.5 * stall_best)) {
        report.status = SolveStatus::kNumericalFailure;
        report.message = "prox: the residual did not halve in " + std::to_string(kStallSteps) +
                         " proximal steps (" + std::to_string(outer) + " in all); best iterate returned";
        break;
      }
      stall_start = outer;
      stall_best = best_residual;
    }
    if (outer > 0 && (ctx.deadlinePassed() || ctx.trialPassed(best_residual))) {
      report.status = SolveStatus::kTimeBudget;
      report.message = "prox: time budget (" + std::to_string(params.time_budget) + " s) ran out after " +
                       std::to_string(outer) + " proximal steps; best iterate returned";
      break;
    }
    ++outer;
    sub.d_free = problem.d_free - sigma * centre;
    inner.regularization = ctx.regularization + sigma;
    inner_params.tolerance = std::max(0.5 * params.tolerance, kInnerReduction * residual);
    inner_params.maxIt = std::min(params.maxIt - iterations, kMaxInnerIterations);
    const KernelReport step = runNewton(inner, lambda);
    iterations += step.iterations;
    if (!lambda.allFinite()) lambda = best;
    const double next = ctx.residual(lambda);
    if (params.displayDebug) report.history.push_back(next);
    if (next < best_residual) {
      best_residual = next;
      best = lambda;
    }
    if (next <= params.tolerance) {
      report.status = SolveStatus::kConverged;
      residual = next;
      break;
    }
    if (step.status == SolveStatus::kTimeBudget) {
      report.status = SolveStatus::kTimeBudget;
      report.message =
          "prox: time budget ran out in proximal step " + std::to_string(outer) + "; best iterate returned";
      break;
    }
    const bool solved = step.status == SolveStatus::kConverged;
    if (solved && next <= residual * (1.0 + kFlat)) {
      sigma = std::max(sigma * 0.1, kSigmaMin * scale);
    } else {
      // Newton could not solve the sub-problem, or solving it raised the residual: more
      // damping, restarting from the last centre when the step made things worse.
      if (!solved) ++failures;
      if (next > residual) lambda = centre;
      if (sigma >= kSigmaMax * scale) {
        report.status = SolveStatus::kNumericalFailure;
        report.message = "prox: no progress even with the largest proximal weight after " +
                         std::to_string(outer) + " steps; best iterate returned";
        break;
      }
      sigma *= 10.0;
    }
    residual = std::min(residual, next);
    centre = lambda;
  }
  if (report.status != SolveStatus::kConverged) lambda = best;
  report.iterations = iterations;
  if (report.message.empty())
    report.message =
        std::to_string(outer) + " proximal steps (" + std::to_string(failures) + " sub-problems unsolved)";
  report.solver_error = ctx.residual(lambda);
  return report;
}

}  // namespace lcp_contact_solver::core
