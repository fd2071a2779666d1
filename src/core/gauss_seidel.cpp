// Gauss-Seidel kernels: projected Gauss-Seidel (PGS, SOFA's gaussSeidelLCP1) for
// frictionless problems and nonlinear block Gauss-Seidel (NLGS, SOFA's nlcp_gaussseidel)
// for Coulomb friction. Both run the same sweep; each contact type has its local step.
#include "lcp_contact_solver/core/kernels.h"
#include "lcp_contact_solver/core/residual.h"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <limits>
#include <variant>

namespace lcp_contact_solver {

namespace {

constexpr int kMaxLocalIterations = 20;
constexpr double kLocalTolerance = 1e-14;
// Maintained d drifts by round-off; refresh it exactly this often (sweeps).
constexpr int kRefreshInterval = 50;

enum class LocalKind : std::uint8_t { kSkip, kNormalOnly, kCoulomb, kBilateral };

// What a contact's local step needs, computed once per solve. Stored flat, one per contact.
struct LocalBlock {
  LocalKind kind = LocalKind::kSkip;
  int offset = 0;
  int rows = 0;
  double mu = 0.0;
  double inv_nn = 0.0;          // 1 / D_nn
  Eigen::Matrix3d D = Eigen::Matrix3d::Zero();  // diagonal block (+ r I), frictional only
  // Tangential 2x2 block T = Q diag(a) Qᵀ, for the disc-constrained local problem.
  Eigen::Matrix2d tangent_basis = Eigen::Matrix2d::Identity();
  Eigen::Vector2d tangent_eigen = Eigen::Vector2d::Zero();
  bool tangent_symmetric = true;
  double tangent_step = 0.0;    // 1 / largest eigenvalue, for the non-symmetric fallback
  Eigen::MatrixXd bilateral_block;    // D, bilateral only
  Eigen::MatrixXd bilateral_inverse;  // D⁻¹, bilateral only
};

// Minimises ½ xᵀT x + bᵀx over the disc |x| <= radius, T = Q diag(a) Qᵀ symmetric.
// KKT: (T + νI) x = -b, ν >= 0, ν(|x| - radius) = 0, so the minimiser's velocity
// u_t = T x + b = -ν x opposes the force: exactly Coulomb's sliding law.
// On the boundary ν solves the secular equation |x(ν)| = radius, monotone in ν, found by
// safeguarded Newton on 1/|x(ν)| - 1/radius (close to linear in ν).
Eigen::Vector2d solveDiscProblem(const LocalBlock& blk, const Eigen::Vector2d& b, double radius) {
  if (radius <= 0.0) return Eigen::Vector2d::Zero();
  const Eigen::Vector2d g = blk.tangent_basis.transpose() * b;
  const Eigen::Vector2d& a = blk.tangent_eigen;
  const double a_min = std::min(a[0], a[1]);
  if (a_min > 0.0) {
    const Eigen::Vector2d interior(-g[0] / a[0], -g[1] / a[1]);
    if (interior.norm() <= radius) return blk.tangent_basis * interior;
  }
  const double g_norm = g.norm();
  if (g_norm == 0.0) return Eigen::Vector2d::Zero();  // no preferred direction, no drive
  auto xNorm = [&](double nu) { return std::hypot(g[0] / (a[0] + nu), g[1] / (a[1] + nu)); };
  double lo = std::max(0.0, -a_min);  // |x(ν)| decreases on (lo, ∞)
  double hi = lo + g_norm / radius + std::abs(a_min) + 1e-300;  // |x(hi)| <= radius
  while (xNorm(hi) > radius && hi < 1e300) hi *= 2.0;
  double nu = hi;
  for (int it = 0; it < 60; ++it) {
    const double n = xNorm(nu);
    const double phi = 1.0 / n - 1.0 / radius;
    if (std::abs(phi) * radius < 1e-15) break;
    if (phi > 0.0) hi = nu; else lo = nu;  // phi increases with ν
    // d|x|/dν = -Σ g²/(a+ν)³ / |x|;  d(1/|x|)/dν = Σ g²/(a+ν)³ / |x|³
    const double c0 = g[0] * g[0] / std::pow(a[0] + nu, 3), c1 = g[1] * g[1] / std::pow(a[1] + nu, 3);
    const double slope = (c0 + c1) / (n * n * n);
    double next = nu - phi / slope;
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    if (next == nu) break;
    nu = next;
  }
  const Eigen::Vector2d x(-g[0] / (a[0] + nu), -g[1] / (a[1] + nu));
  // Round-off can leave |x| a hair outside; the cone constraint is the hard one.
  const double n = x.norm();
  return blk.tangent_basis * (n > radius ? Eigen::Vector2d(x * (radius / n)) : x);
}

// Projects the tangential force onto the disc of the given radius.
Eigen::Vector2d clampToDisc(const Eigen::Vector2d& t, double radius) {
  const double n = t.norm();
  return n > radius ? Eigen::Vector2d(t * (radius / n)) : t;
}

// Local Coulomb problem of one contact, with the others frozen: u = D λ + b.
// Alternates the exact normal step λ_n = max(0, λ_n - u_n / D_nn) with the exact
// tangential step (disc problem above) until the local iterate stops moving; the fixed
// point satisfies 0 <= λ_n ⟂ u_n >= 0 and the Coulomb law, so the sweep is a true NSGS.
void coulombLocalStep(const LocalBlock& blk, const Eigen::Vector3d& b, Eigen::Vector3d& lambda) {
  for (int it = 0; it < kMaxLocalIterations; ++it) {
    const Eigen::Vector3d before = lambda;
    const double un = blk.D.row(0).dot(lambda) + b[0];
    lambda[0] = std::max(0.0, lambda[0] - un * blk.inv_nn);
    // Tangential problem with λ_n fixed: b_t' = b_t + D_tn λ_n.
    const Eigen::Vector2d bt = b.tail<2>() + blk.D.block<2, 1>(1, 0) * lambda[0];
    const double radius = blk.mu * lambda[0];
    if (blk.tangent_symmetric) {
      lambda.tail<2>() = solveDiscProblem(blk, bt, radius);
    } else {
      // Non-symmetric tangential block: projected gradient step; its fixed point still
      // has u_t opposing λ_t.
      const Eigen::Vector2d ut = blk.D.block<2, 2>(1, 1) * lambda.tail<2>() + bt;
      lambda.tail<2>() = clampToDisc(lambda.tail<2>() - blk.tangent_step * ut, radius);
    }
    if ((lambda - before).norm() <= kLocalTolerance * (lambda.norm() + 1e-300)) break;
  }
}

// Builds the per-contact local data; returns a failure message for a diagonal that the
// local step would divide by (SOFA divides anyway and returns NaN).
std::string prepareBlocks(const SolveContext& ctx, std::vector<LocalBlock>& blocks) {
  const Problem& problem = *ctx.problem;
  const double r = ctx.regularization;
  blocks.resize(problem.contacts.size());
  for (std::size_t i = 0; i < problem.contacts.size(); ++i) {
    const Contact& c = problem.contacts[i];
    LocalBlock& blk = blocks[i];
    blk.offset = ctx.offsets[i];
    blk.rows = c.rows;
    blk.mu = ctx.mu[i];
    if (ctx.ignored[i]) {
      blk.kind = LocalKind::kSkip;
      continue;
    }
    Eigen::MatrixXd D = diagonalBlock(problem.W, blk.offset, c.rows);
    D.diagonal().array() += r;
    const std::string where = "contact " + std::to_string(i) + " (id " + std::to_string(c.id) + ")";
    if (c.type == ContactType::kBilateral) {
      Eigen::FullPivLU<Eigen::MatrixXd> lu(D);
      if (!lu.isInvertible()) return where + " has a singular bilateral block of W";
      blk.kind = LocalKind::kBilateral;
      blk.bilateral_block = D;
      blk.bilateral_inverse = lu.inverse();
      continue;
    }
    if (!(D(0, 0) > 0.0))
      return where + " has W_nn = " + std::to_string(D(0, 0)) + " <= 0; set minW or regularizationTerm";
    blk.inv_nn = 1.0 / D(0, 0);
    if (c.type == ContactType::kFrictionless || blk.mu == 0.0) {
      blk.kind = LocalKind::kNormalOnly;
      continue;
    }
    blk.kind = LocalKind::kCoulomb;
    blk.D = D;
    const Eigen::Matrix2d T = D.block<2, 2>(1, 1);
    const double scale = T.cwiseAbs().maxCoeff();
    blk.tangent_symmetric = std::abs(T(0, 1) - T(1, 0)) <= 1e-12 * scale;
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(0.5 * (T + T.transpose()));
    blk.tangent_basis = eig.eigenvectors();
    blk.tangent_eigen = eig.eigenvalues();
    const double a_max = blk.tangent_eigen.maxCoeff();
    if (!blk.tangent_symmetric && !(a_max > 0.0))
      return where + " has a tangential block of W with no positive eigenvalue";
    blk.tangent_step = a_max > 0.0 ? 1.0 / a_max : 0.0;
  }
  return "";
}

// Current d of one contact. Dense W: read from the maintained d. Block-sparse W: one block
// row times λ (the CSR layout makes this a contiguous walk).
struct DenseAccess {
  const Eigen::MatrixXd& W;
  const SolveContext& ctx;
  Eigen::VectorXd d;

  void refresh(const Eigen::VectorXd& lambda) { ctx.computeD(lambda, d); }
  void contactD(const LocalBlock& blk, const Eigen::VectorXd&, double* out) const {
    for (int k = 0; k < blk.rows; ++k) out[k] = d[blk.offset + k];
  }
  // Column access is contiguous in Eigen's column-major storage.
  void applyDelta(const LocalBlock& blk, const double* delta) {
    for (int k = 0; k < blk.rows; ++k) {
      if (delta[k] == 0.0) continue;
      d.noalias() += W.col(blk.offset + k) * delta[k];
      d[blk.offset + k] += ctx.regularization * delta[k];
    }
  }
  const Eigen::VectorXd& currentD(const Eigen::VectorXd&) { return d; }
};

struct SparseAccess {
  const BlockSparseMatrix& W;
  const SolveContext& ctx;
  Eigen::VectorXd d;

  void refresh(const Eigen::VectorXd&) {}
  void contactD(const LocalBlock& blk, const Eigen::VectorXd& lambda, double* out) const {
    const int i = static_cast<int>(&blk - first_block);
    for (int k = 0; k < blk.rows; ++k)
      out[k] = ctx.problem->d_free[blk.offset + k] + ctx.regularization * lambda[blk.offset + k];
    for (int s = W.row_start[i]; s < W.row_start[i + 1]; ++s) {
      const int j = W.block_col[s];
      const int col0 = W.block_offset[j];
      const int cols = W.block_offset[j + 1] - col0;
      const double* v = W.values.data() + W.value_start[s];
      for (int r = 0; r < blk.rows; ++r) {
        double sum = 0.0;
        for (int c = 0; c < cols; ++c) sum += v[r * cols + c] * lambda[col0 + c];
        out[r] += sum;
      }
    }
  }
  void applyDelta(const LocalBlock&, const double*) {}
  const Eigen::VectorXd& currentD(const Eigen::VectorXd& lambda) {
    ctx.computeD(lambda, d);
    return d;
  }
  const LocalBlock* first_block = nullptr;
};

// One contact's local step on its current d; returns the change of λ_c in `delta`.
void localStep(const LocalBlock& blk, const double* d_c, double* lambda_c, double* delta) {
  switch (blk.kind) {
    case LocalKind::kSkip:
      break;
    case LocalKind::kNormalOnly: {
      const double next = std::max(0.0, lambda_c[0] - d_c[0] * blk.inv_nn);
      delta[0] = next - lambda_c[0];
      lambda_c[0] = next;
      break;
    }
    case LocalKind::kCoulomb: {
      Eigen::Map<Eigen::Vector3d> lambda(lambda_c);
      const Eigen::Vector3d old = lambda;
      const Eigen::Vector3d b = Eigen::Map<const Eigen::Vector3d>(d_c) - blk.D * old;
      Eigen::Vector3d next = old;
      coulombLocalStep(blk, b, next);
      Eigen::Map<Eigen::Vector3d> change(delta);
      change = next - old;
      lambda = next;
      break;
    }
    case LocalKind::kBilateral: {
      Eigen::Map<Eigen::VectorXd> lambda(lambda_c, blk.rows);
      Eigen::Map<const Eigen::VectorXd> d(d_c, blk.rows);
      Eigen::Map<Eigen::VectorXd> change(delta, blk.rows);
      change = -blk.bilateral_inverse * d;
      lambda += change;
      break;
    }
  }
}

// SOFA's per-sweep measure: the displacement each contact's change causes on itself.
double sofaContactError(const LocalBlock& blk, const double* delta) {
  switch (blk.kind) {
    case LocalKind::kNormalOnly: return std::abs(delta[0]) / blk.inv_nn;
    case LocalKind::kCoulomb: return (blk.D * Eigen::Map<const Eigen::Vector3d>(delta)).norm();
    case LocalKind::kBilateral:
      return (blk.bilateral_block * Eigen::Map<const Eigen::VectorXd>(delta, blk.rows)).norm();
    case LocalKind::kSkip: break;
  }
  return 0.0;
}

bool allFinite(const Eigen::VectorXd& v) { return v.allFinite(); }

template <class Access>
KernelReport sweepUntilDone(const SolveContext& ctx, const std::vector<LocalBlock>& blocks,
                            Access& access, Eigen::VectorXd& lambda) {
  const SolverParams& params = *ctx.params;
  KernelReport report;
  Eigen::VectorXd best = lambda;
  double best_residual = std::numeric_limits<double>::infinity();
  double delta[6];
  double d_c[6];
  access.refresh(lambda);
  for (int sweep = 1; sweep <= params.maxIt; ++sweep) {
    double sofa_error = 0.0;
    for (const LocalBlock& blk : blocks) {
      if (blk.kind == LocalKind::kSkip) continue;
      access.contactD(blk, lambda, d_c);
      std::fill(delta, delta + blk.rows, 0.0);
      localStep(blk, d_c, lambda.data() + blk.offset, delta);
      access.applyDelta(blk, delta);
      if (params.stopping_rule == StoppingRule::kSofa) sofa_error += sofaContactError(blk, delta);
    }
    report.iterations = sweep;
    if (!allFinite(lambda)) {
      lambda = best;
      report.status = SolveStatus::kNumericalFailure;
      report.message = "the iterate became non-finite in sweep " + std::to_string(sweep) +
                       " (W is probably not positive semidefinite); best iterate returned";
      return report;
    }
    if (sweep % kRefreshInterval == 0) access.refresh(lambda);
    const bool need_residual = params.stopping_rule == StoppingRule::kResidual || params.displayDebug;
    double residual = 0.0;
    if (need_residual) {
      const Eigen::VectorXd& d = access.currentD(lambda);
      residual = naturalMapResidual(*ctx.problem, ctx.mu, lambda, d, ctx.ignored);
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
        return report;
      }
    } else {
      report.solver_error = residual;
      if (residual <= params.tolerance) {
        // Confirm on an exactly recomputed d: the maintained one carries round-off.
        access.refresh(lambda);
        report.solver_error = ctx.residual(lambda);
        if (report.solver_error <= params.tolerance) {
          report.status = SolveStatus::kConverged;
          return report;
        }
      }
    }
  }
  lambda = best;
  report.status = SolveStatus::kMaxIterations;
  report.message = "maxIt (" + std::to_string(params.maxIt) + ") sweeps reached before the tolerance";
  return report;
}

KernelReport runGaussSeidel(const SolveContext& ctx, Eigen::VectorXd& lambda) {
  std::vector<LocalBlock> blocks;
  if (std::string err = prepareBlocks(ctx, blocks); !err.empty()) {
    KernelReport report;
    report.status = SolveStatus::kZeroDiagonal;
    report.message = err;
    return report;
  }
  if (const auto* dense = std::get_if<Eigen::MatrixXd>(&ctx.problem->W)) {
    DenseAccess access{*dense, ctx, Eigen::VectorXd()};
    return sweepUntilDone(ctx, blocks, access, lambda);
  }
  SparseAccess access{std::get<BlockSparseMatrix>(ctx.problem->W), ctx, Eigen::VectorXd()};
  access.first_block = blocks.data();
  return sweepUntilDone(ctx, blocks, access, lambda);
}

}  // namespace

KernelReport runProjectedGaussSeidel(const SolveContext& ctx, Eigen::VectorXd& lambda) {
  if (ctx.hasFriction()) {
    KernelReport report;
    report.status = SolveStatus::kNotApplicable;
    report.message = "pgs solves frictionless problems; this one has contacts with mu > 0 (use nlgs)";
    return report;
  }
  return runGaussSeidel(ctx, lambda);
}

KernelReport runNonlinearGaussSeidel(const SolveContext& ctx, Eigen::VectorXd& lambda) {
  return runGaussSeidel(ctx, lambda);
}

}  // namespace lcp_contact_solver
