// The solver kernels. ContactSolver (contact_solver.h) prepares a SolveContext, picks a
// kernel and turns its report into a SolveResult; kernels only iterate.
#pragma once

#include "lcp_contact_solver/core/problem.h"
#include "lcp_contact_solver/core/solve_result.h"
#include "lcp_contact_solver/core/solver_params.h"

#include <Eigen/Core>

#include <chrono>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace lcp_contact_solver::core {

// The per-contact data the Gauss-Seidel kernels form from W alone (local_contact_laws.h),
// and the d = W λ + d_free their last call maintained with the λ it belongs to (a call from
// exactly that λ goes on with it instead of a product with W), kept by a caller that runs them
// several times on one problem: auto's probe stages and slices, newton's warm-up and bursts.
// Its owner clears it whenever the problem, μ, the ignored contacts or the regularization may
// have changed.
struct GaussSeidelMemo;

// APGD's state at the end of a call (apgd.cpp): iterate, extrapolated point, momentum, step
// and shift. A caller that hands apgd back exactly the λ it returned (auto's next slice of
// it) resumes the method there instead of restarting its momentum and its curvature
// estimate. Same ownership rule as GaussSeidelMemo.
struct ApgdMemo {
  const Problem* problem = nullptr;  // none: empty
  double regularization = 0.0;
  Eigen::VectorXd returned;  // the λ the call returned (its best iterate)
  Eigen::VectorXd x, Wx, y, Wy, shift;
  double theta = 1.0, L = 0.0;
  double convex_mark = 0.0;  // the convex problem's plateau test (apgd.cpp)
  int convex_stall = 0;
  void clear() { problem = nullptr; }
};

// Everything a kernel needs, computed once per solve.
struct SolveContext {
  // With Problem::bodies (the unbuilt solve) only the Gauss-Seidel kernels run; ContactSolver
  // hands every other kernel a problem with the assembled W.
  const Problem* problem = nullptr;
  const SolverParams* params = nullptr;
  std::vector<int> offsets;     // first row of each contact, size nc + 1
  std::vector<double> mu;       // effective μ per contact
  std::vector<bool> ignored;    // contacts left out (minW, maxF): force stays zero
  double regularization = 0.0;  // r added to W's diagonal
  int body_dof = 0;             // 6 × bodies when the body form is known: auto's rank-deficiency estimate
  // The residual of the λ a kernel is handed, when the caller already measured it (auto's
  // check of λ = 0 on the whole problem, then per member the best iterate's); NaN when not
  // known. newton reads it instead of measuring its start again.
  double start_residual = std::numeric_limits<double>::quiet_NaN();
  GaussSeidelMemo* gs_memo = nullptr;  // see above; none: each call forms its own
  // newton's warm-up sweeps the caller already ran (auto's probe: the same nlgs sweeps from
  // the solve's start, which was a warm start or not): newton runs only the rest of them
  // (none from kNewtonWarmupSweeps on), and its path is the one it takes from that start.
  int warmup_sweeps_done = 0;
  bool warmup_start_was_warm = false;
  ApgdMemo* apgd_memo = nullptr;       // see above; none: each call starts afresh
  // A proximal sub-problem (prox_newton.cpp): its W + σI is regularized by the prox term
  // already, so newton keeps its damping to the one rule of a well-posed problem (newton.cpp).
  bool proximal_subproblem = false;
  // End of the time budget (SolverParams::time_budget), if any. Kernels call
  // deadlinePassed() at most once per sweep, iteration or pivot and, when it returns
  // true, stop with their best iterate and SolveStatus::kTimeBudget.
  bool has_deadline = false;
  std::chrono::steady_clock::time_point deadline;
  bool deadlinePassed() const { return has_deadline && std::chrono::steady_clock::now() >= deadline; }
  // auto's trial of a member handed a stall (portfolio.cpp): past trial_deadline a run whose
  // best residual is still not below start_residual (NaN: no trial) stops as at the deadline.
  // Kernels check it where they check deadlinePassed(), on their own best residual; their
  // inner runs (newton's nlgs sweeps, prox's Newton solves) do not.
  bool has_trial_deadline = false;
  std::chrono::steady_clock::time_point trial_deadline;
  bool trialPassed(double best_residual) const {
    return has_trial_deadline && !std::isnan(start_residual) && !(best_residual < start_residual) &&
           std::chrono::steady_clock::now() >= trial_deadline;
  }

  // Solver-independent residual of λ (computes d itself).
  double residual(const Eigen::VectorXd& lambda) const;
  // d = (W + r I) λ + d_free
  void computeD(const Eigen::VectorXd& lambda, Eigen::VectorXd& d) const;
  bool hasFriction() const;  // some active frictional contact with μ > 0
  // W_nn of contact i: its first diagonal entry (a block-sparse W's stored diagonal block; 0
  // when none is stored). The body form has no W: 0.
  double normalDiagonal(int i) const;
  // Every active contact has a positive W_nn + r (Gauss-Seidel's scalar local steps divide by
  // it). `bilateral`: bilateral contacts too; without, only the others (their local step
  // inverts the whole block, so W_nn alone does not stop nlgs there).
  bool positiveDiagonal(bool bilateral = true) const;
};

struct KernelReport {
  SolveStatus status = SolveStatus::kMaxIterations;
  int iterations = 0;
  int total_iterations = 0;     // IslandSolver only: `iterations` summed over the islands
  double solver_error = 0.0;    // the kernel's own stopping measure at exit
  std::string message;          // detail for failures
  std::vector<double> history;  // residual per iteration when params->displayDebug
  FrictionModel friction_model = FrictionModel::kCoulombDisc;  // the law actually solved
  std::vector<std::pair<std::string, double>> stages;          // auto: (member, seconds) per stage
};

// The two ends of a sweep loop that did not converge: the time budget ran out after `sweeps`,
// or maxIt was reached. Both leave the best iterate in `lambda`.
inline void endOnTimeBudget(KernelReport& report, Eigen::VectorXd& lambda, const Eigen::VectorXd& best,
                            double time_budget, int sweeps) {
  lambda = best;
  report.status = SolveStatus::kTimeBudget;
  report.message = "time budget (" + std::to_string(time_budget) + " s) ran out after " +
                   std::to_string(sweeps) + " sweeps; best iterate returned";
}
// A sweep whose maintained d says "converged" is confirmed on an exactly recomputed d (the
// maintained one carries round-off): true when that residual meets the tolerance too.
inline bool confirmConverged(KernelReport& report, double exact_residual, double tolerance) {
  report.solver_error = exact_residual;
  if (exact_residual > tolerance) return false;
  report.status = SolveStatus::kConverged;
  return true;
}
inline void endOnMaxIt(KernelReport& report, Eigen::VectorXd& lambda, const Eigen::VectorXd& best,
                       int max_it) {
  lambda = best;
  report.status = SolveStatus::kMaxIterations;
  report.message = "maxIt (" + std::to_string(max_it) + ") sweeps reached before the tolerance";
}

// Each kernel starts from `lambda` (the warm start, rows of ignored contacts zero) and
// leaves its best finite iterate there, whatever the status.
KernelReport runProjectedGaussSeidel(const SolveContext& ctx, Eigen::VectorXd& lambda);
KernelReport runNonlinearGaussSeidel(const SolveContext& ctx, Eigen::VectorXd& lambda);
KernelReport runLemke(const SolveContext& ctx, Eigen::VectorXd& lambda);
// Accelerated projected gradient on the Coulomb disc (apgd.cpp).
KernelReport runApgd(const SolveContext& ctx, Eigen::VectorXd& lambda);
// Semismooth Newton on the Alart-Curnier function (newton.cpp), after a warm-up of nlgs sweeps
// that ends at this residual (or the tolerance, if larger) or after this many sweeps.
constexpr double kNewtonWarmupTolerance = 1e-3;
constexpr int kNewtonWarmupSweeps = 20;
KernelReport runNewton(const SolveContext& ctx, Eigen::VectorXd& lambda);
// Proximal point loop around runNewton on W + σI (prox_newton.cpp).
KernelReport runProxNewton(const SolveContext& ctx, Eigen::VectorXd& lambda);
// Polyhedral friction (ctx.params->friction_model a pyramid), pyramid.cpp and
// gauss_seidel.cpp: Lemke on the Stewart-Trinkle LCP, and Gauss-Seidel on the boxed form.
KernelReport runPyramidLemke(const SolveContext& ctx, Eigen::VectorXd& lambda);
KernelReport runBoxedGaussSeidel(const SolveContext& ctx, Eigen::VectorXd& lambda);

// In-place Cholesky of the lower half of `a` (L overwrites it; the upper half is not read):
// false where a pivot is not positive. newton's active-set paths factor W_AA with it
// (newton_symmetric.cpp): column by column up to kColumnCholeskyRows rows, Eigen's blocked
// LLᵀ above, whichever is faster at that size.
constexpr int kColumnCholeskyRows = 120;
bool choleskyInPlace(Eigen::Ref<Eigen::MatrixXd> a);
// The column-by-column form alone, at any size (bench/cholesky_forms.cpp times both).
bool columnCholeskyInPlace(Eigen::Ref<Eigen::MatrixXd> a);

}  // namespace lcp_contact_solver::core
