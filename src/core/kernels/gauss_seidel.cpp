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
#include "friction_pyramid.h"

#include "lcp_contact_solver/core/body_compliance.h"
#include "lcp_contact_solver/core/kernels/kernels.h"
#include "lcp_contact_solver/core/residual.h"
#include "lcp_contact_solver/core/kernels/scalar_rows.h"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <variant>

namespace lcp_contact_solver::core {

namespace {

constexpr int kMaxLocalIterations = 20;
constexpr double kLocalTolerance = 1e-14;
// Maintained d drifts by round-off; refresh it exactly this often (sweeps).
constexpr int kRefreshInterval = 50;

enum class LocalKind : std::uint8_t { kSkip, kNormalOnly, kCoulomb, kBilateral, kPolygon, kCoulombExtended };

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
  // D_nt or D_tn nonzero: the normal and tangential local steps must be alternated.
  bool coupled = true;
  // D⁻¹ when D is well conditioned, for the one-shot sticking solution.
  bool invertible = false;
  Eigen::Matrix3d D_inverse = Eigen::Matrix3d::Zero();
  Eigen::MatrixXd bilateral_block;    // D, bilateral only
  Eigen::MatrixXd bilateral_inverse;  // D⁻¹, bilateral only
  // Torsional (4 rows) and rolling (6 rows) contacts: the whole diagonal block (zero
  // padded), the coefficients, 1 / D_ss, and the rolling 2×2 block R = Q diag(a) Qᵀ.
  Eigen::Matrix<double, 6, 6> D_full = Eigen::Matrix<double, 6, 6>::Zero();
  double mu_torsional = 0.0;
  double mu_rolling = 0.0;
  double inv_spin = 0.0;
  Eigen::Matrix2d roll_basis = Eigen::Matrix2d::Identity();
  Eigen::Vector2d roll_eigen = Eigen::Vector2d::Zero();
  bool roll_symmetric = true;
  double roll_step = 0.0;
};

// Minimises ½ xᵀT x + bᵀx over the disc |x| <= radius, T = Q diag(a) Qᵀ symmetric.
// KKT: (T + νI) x = -b, ν >= 0, ν(|x| - radius) = 0, so the minimiser's velocity
// u_t = T x + b = -ν x opposes the force: exactly Coulomb's sliding law.
// On the boundary ν solves the secular equation |x(ν)| = radius with g = Qᵀ b and
// |x(ν)|² = Σ g_i² / (a_i + ν)². Since a_min <= a_i <= a_max, the root lies in
//   [|g|/radius - a_max, |g|/radius - a_min]
// (equal ends for an isotropic block: ν = |g|/radius - a, no iteration). h(ν) = 1/|x(ν)|
// is increasing and concave there (Moré & Sorensen), so Newton on h(ν) = 1/radius started
// at the left end climbs monotonically and quadratically to the root; a bisection
// safeguard covers the indefinite case. h'(ν) = Σ g_i²/(a_i+ν)³ / |x|³ uses products,
// not pow.
Eigen::Vector2d solveDiscProblem(const Eigen::Matrix2d& basis, const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                                 double radius) {
  if (radius <= 0.0) return Eigen::Vector2d::Zero();
  const Eigen::Vector2d g = basis.transpose() * b;
  const double a_min = std::min(a[0], a[1]);
  const double a_max = std::max(a[0], a[1]);
  if (a_min > 0.0) {
    const Eigen::Vector2d interior(-g[0] / a[0], -g[1] / a[1]);
    if (interior.norm() <= radius) return basis * interior;
  }
  const double g_norm = std::sqrt(g[0] * g[0] + g[1] * g[1]);
  if (g_norm == 0.0) return Eigen::Vector2d::Zero();  // no preferred direction, no drive
  const double shift = g_norm / radius;
  double lo = std::max(std::max(0.0, -a_min), shift - a_max);  // |x(lo)| >= radius
  double hi = std::max(lo, shift - a_min);                      // |x(hi)| <= radius
  double nu = a_min + lo > 0.0 ? lo : 0.5 * (lo + hi);  // a pole at lo: start inside
  double e0 = 1.0 / (a[0] + nu), e1 = 1.0 / (a[1] + nu);
  for (int it = 0; it < 60; ++it) {
    const double x0 = g[0] * e0, x1 = g[1] * e1;
    const double n2 = x0 * x0 + x1 * x1;
    const double n = std::sqrt(n2);
    const double phi = 1.0 / n - 1.0 / radius;
    if (std::abs(phi) * radius < 1e-15) break;
    if (phi > 0.0) hi = nu; else lo = nu;  // phi increases with ν
    const double slope = (x0 * x0 * e0 + x1 * x1 * e1) / (n2 * n);
    double next = nu - phi / slope;
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    if (next == nu) break;
    nu = next;
    e0 = 1.0 / (a[0] + nu);
    e1 = 1.0 / (a[1] + nu);
  }
  const Eigen::Vector2d x(-g[0] * e0, -g[1] * e1);
  // Round-off can leave |x| a hair outside; the cone constraint is the hard one.
  const double n = x.norm();
  return basis * (n > radius ? Eigen::Vector2d(x * (radius / n)) : x);
}

Eigen::Vector2d solveDiscProblem(const LocalBlock& blk, const Eigen::Vector2d& b, double radius) {
  return solveDiscProblem(blk.tangent_basis, blk.tangent_eigen, b, radius);
}

// Projects the tangential force onto the disc of the given radius.
Eigen::Vector2d clampToDisc(const Eigen::Vector2d& t, double radius) {
  const double n = t.norm();
  return n > radius ? Eigen::Vector2d(t * (radius / n)) : t;
}

// Tangential part of the local Coulomb step: λ_n fixed, u_t = T λ_t + bt.
void coulombTangentStep(const LocalBlock& blk, const Eigen::Vector2d& bt, Eigen::Vector3d& lambda) {
  const double radius = blk.mu * lambda[0];
  if (blk.tangent_symmetric) {
    lambda.tail<2>() = solveDiscProblem(blk, bt, radius);
  } else {
    // Non-symmetric tangential block: projected gradient step; its fixed point still
    // has u_t opposing λ_t.
    const Eigen::Vector2d ut = blk.D.block<2, 2>(1, 1) * lambda.tail<2>() + bt;
    lambda.tail<2>() = clampToDisc(lambda.tail<2>() - blk.tangent_step * ut, radius);
  }
}

// Local Coulomb problem of one contact, with the others frozen: u = D λ + b.
// Alternates the exact normal step λ_n = max(0, λ_n - u_n / D_nn) with the exact
// tangential step (disc problem above) until the local iterate stops moving; the fixed
// point satisfies 0 <= λ_n ⟂ u_n >= 0 and the Coulomb law, so the sweep is a true NSGS.
// Three shortcuts reach the same solution with less work: a contact at rest (λ = 0) with
// b_n >= 0 stays open (the normal step keeps λ_n = 0, so the disc has radius 0); a
// sticking contact has u = 0, so λ = -D⁻¹ b, accepted when it lies inside the cone
// (λ_n > 0, |λ_t| <= μ λ_n) — the alternation converges linearly to that same point, often
// in 10+ rounds when D couples normal and tangents (symmetric tangential blocks only: the
// non-symmetric fallback below stops after kMaxLocalIterations rounds, short of that
// point, and its results are kept as they were); and without normal-tangential coupling
// (D_nt = D_tn = 0) λ_n = max(0, -b_n / D_nn) is exact at once and one disc problem
// finishes the step.
void coulombLocalStep(const LocalBlock& blk, const Eigen::Vector3d& b, Eigen::Vector3d& lambda) {
  if (b[0] >= 0.0 && lambda[0] == 0.0 && lambda[1] == 0.0 && lambda[2] == 0.0) return;
  if (blk.invertible && blk.tangent_symmetric) {
    const Eigen::Vector3d stick = -(blk.D_inverse * b);
    const double radius = blk.mu * stick[0];
    if (stick[0] > 0.0 && stick[1] * stick[1] + stick[2] * stick[2] <= radius * radius) {
      lambda = stick;
      return;
    }
  }
  if (!blk.coupled && blk.tangent_symmetric) {
    lambda[0] = std::max(0.0, -b[0] * blk.inv_nn);
    coulombTangentStep(blk, b.tail<2>(), lambda);
    return;
  }
  for (int it = 0; it < kMaxLocalIterations; ++it) {
    const Eigen::Vector3d before = lambda;
    const double un = blk.D.row(0).dot(lambda) + b[0];
    lambda[0] = std::max(0.0, lambda[0] - un * blk.inv_nn);
    // Tangential problem with λ_n fixed: b_t' = b_t + D_tn λ_n.
    const Eigen::Vector2d bt = b.tail<2>() + blk.D.block<2, 1>(1, 0) * lambda[0];
    coulombTangentStep(blk, bt, lambda);
    if ((lambda - before).norm() <= kLocalTolerance * (lambda.norm() + 1e-300)) break;
  }
}

// Local step of the boxed PGS (pyramid friction): one exact normal step with the current
// tangential force, then the tangential force minimising ½ xᵀ D_tt x + b_tᵀ x over the
// polygon P(μ λ_n) with the new λ_n (friction_pyramid.h). Its fixed point satisfies
// 0 <= λ_n ⟂ u_n >= 0 and maximum dissipation over the polygon: the pyramid law. For the
// box (pyramid4) with an uncoupled diagonal D_tt this is the classical clamp
// λ_ti = clamp(λ_ti - u_ti / D_ti, -μ λ_n, μ λ_n) of boxed PGS.
void polygonLocalStep(const LocalBlock& blk, const FrictionPolygon& polygon, const double* d_c,
                      double omega, double* lambda_c) {
  const double old_n = lambda_c[0];
  double next_n = std::max(0.0, old_n - d_c[0] * blk.inv_nn);
  if (omega != 1.0) next_n = std::max(0.0, old_n + omega * (next_n - old_n));
  const Eigen::Vector2d old_t(lambda_c[1], lambda_c[2]);
  // u_t(x) = D_tt x + bt with the normal force already moved.
  const Eigen::Vector2d bt = Eigen::Vector2d(d_c[1], d_c[2]) - blk.D.block<2, 2>(1, 1) * old_t +
                             blk.D.block<2, 1>(1, 0) * (next_n - old_n);
  const double radius = blk.mu * next_n;
  Eigen::Vector2d next_t;
  if (blk.tangent_symmetric) {
    next_t = minimizeOverPolygon(polygon, blk.D.block<2, 2>(1, 1), bt, radius);
  } else {
    const Eigen::Vector2d ut = blk.D.block<2, 2>(1, 1) * old_t + bt;
    next_t = projectOntoPolygon(polygon, old_t - blk.tangent_step * ut, radius);
  }
  if (omega != 1.0) next_t = projectOntoPolygon(polygon, old_t + omega * (next_t - old_t), radius);
  lambda_c[0] = next_n;
  lambda_c[1] = next_t[0];
  lambda_c[2] = next_t[1];
}

// The torsional/rolling part of a contact's local data (D is its whole diagonal block).
std::string prepareExtendedRows(const Contact& c, const Eigen::MatrixXd& D, const std::string& where,
                                LocalBlock& blk) {
  blk.D_full.setZero();
  blk.D_full.topLeftCorner(c.rows, c.rows) = D;
  blk.mu_torsional = c.mu_torsional;
  blk.mu_rolling = c.type == ContactType::kRolling ? c.mu_rolling : 0.0;
  if (blk.mu_torsional > 0.0) {
    if (!(D(3, 3) > 0.0)) return where + " has a torsional self-compliance W_ss <= 0";
    blk.inv_spin = 1.0 / D(3, 3);
  }
  if (blk.mu_rolling > 0.0) {
    const Eigen::Matrix2d R = D.block<2, 2>(4, 4);
    const double scale = R.cwiseAbs().maxCoeff();
    blk.roll_symmetric = std::abs(R(0, 1) - R(1, 0)) <= 1e-12 * scale;
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(0.5 * (R + R.transpose()));
    blk.roll_basis = eig.eigenvectors();
    blk.roll_eigen = eig.eigenvalues();
    if (!(blk.roll_eigen.maxCoeff() > 0.0)) return where + " has a rolling block of W with no positive eigenvalue";
    blk.roll_step = 1.0 / blk.roll_eigen.maxCoeff();
  }
  return "";
}

// Builds the per-contact local data; returns a failure message for a diagonal that the
// local step would divide by (SOFA divides anyway and returns NaN).
// `polygon` (pyramid models) turns frictional contacts into polygon steps.
std::string prepareBlocks(const SolveContext& ctx, std::vector<LocalBlock>& blocks,
                          const FrictionPolygon* polygon = nullptr) {
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
    Eigen::MatrixXd D = contactDiagonalBlock(problem, ctx.offsets, static_cast<int>(i));  // W or the body form
    D.diagonal().array() += r;
    // Named only for a message: no string per contact per solve.
    const auto where = [&] { return "contact " + std::to_string(i) + " (id " + std::to_string(c.id) + ")"; };
    if (c.type == ContactType::kBilateral) {
      Eigen::FullPivLU<Eigen::MatrixXd> lu(D);
      if (!lu.isInvertible()) return where() + " has a singular bilateral block of W";
      blk.kind = LocalKind::kBilateral;
      blk.bilateral_block = D;
      blk.bilateral_inverse = lu.inverse();
      continue;
    }
    if (!(D(0, 0) > 0.0)) {
      char value[32];
      std::snprintf(value, sizeof(value), "%.6g", D(0, 0));  // to_string prints 1e-20 as 0.000000
      return where() + " has W_nn = " + value + " <= 0; set minW or regularizationTerm";
    }
    blk.inv_nn = 1.0 / D(0, 0);
    const bool extended = c.type == ContactType::kTorsional || c.type == ContactType::kRolling;
    if (c.type == ContactType::kFrictionless || (blk.mu == 0.0 && !extended)) {
      blk.kind = LocalKind::kNormalOnly;
      continue;
    }
    blk.kind = polygon != nullptr ? LocalKind::kPolygon : LocalKind::kCoulomb;
    if (extended) {
      if (std::string err = prepareExtendedRows(c, D, where(), blk); !err.empty()) return err;
      blk.kind = LocalKind::kCoulombExtended;
    }
    blk.D = D.topLeftCorner<3, 3>();
    blk.coupled = D(0, 1) != 0.0 || D(0, 2) != 0.0 || D(1, 0) != 0.0 || D(2, 0) != 0.0;
    {
      const Eigen::Matrix3d D3 = D.topLeftCorner<3, 3>();
      Eigen::FullPivLU<Eigen::Matrix3d> lu(D3);
      // Only a well-conditioned block: the one-shot solution must be as accurate as the
      // iteration it replaces.
      const double cond_floor = 1e-10;
      const Eigen::Vector3d pivots = lu.matrixLU().diagonal().cwiseAbs();
      blk.invertible = lu.isInvertible() && pivots.minCoeff() > cond_floor * pivots.maxCoeff();
      if (blk.invertible) blk.D_inverse = lu.inverse();
    }
    const Eigen::Matrix2d T = D.block<2, 2>(1, 1);
    const double scale = T.cwiseAbs().maxCoeff();
    blk.tangent_symmetric = std::abs(T(0, 1) - T(1, 0)) <= 1e-12 * scale;
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(0.5 * (T + T.transpose()));
    blk.tangent_basis = eig.eigenvectors();
    blk.tangent_eigen = eig.eigenvalues();
    const double a_max = blk.tangent_eigen.maxCoeff();
    if (!blk.tangent_symmetric && !(a_max > 0.0))
      return where() + " has a tangential block of W with no positive eigenvalue";
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

// Block-sparse W: d is maintained like the dense case, through the block columns. The
// blocks of column j (block row i, values row-major rows_i × cols_j) are indexed once per
// solve, so a contact's change updates d with one contiguous walk over its column and a
// contact whose force does not move (an open contact staying open) costs nothing; d is
// recomputed exactly every kRefreshInterval sweeps and before declaring convergence.
struct SparseAccess {
  const BlockSparseMatrix& W;
  const SolveContext& ctx;
  Eigen::VectorXd d;
  struct ColumnBlock {
    int row0;        // first row of the block row
    int rows;        // its height
    const double* v; // the block's values
  };
  std::vector<int> column_start;           // per block column, into `column_blocks`
  std::vector<ColumnBlock> column_blocks;  // blocks ordered by block column

  SparseAccess(const BlockSparseMatrix& w, const SolveContext& context) : W(w), ctx(context) {
    const int nb = W.blockCount();
    column_start.assign(nb + 1, 0);
    for (int j : W.block_col) ++column_start[j + 1];
    for (int j = 0; j < nb; ++j) column_start[j + 1] += column_start[j];
    column_blocks.resize(W.block_col.size());
    std::vector<int> fill(column_start.begin(), column_start.end() - 1);
    for (int i = 0; i < nb; ++i) {
      for (int s = W.row_start[i]; s < W.row_start[i + 1]; ++s) {
        const int j = W.block_col[s];
        column_blocks[fill[j]++] = {W.block_offset[i], W.block_offset[i + 1] - W.block_offset[i],
                                    W.values.data() + W.value_start[s]};
      }
    }
  }

  void refresh(const Eigen::VectorXd& lambda) { ctx.computeD(lambda, d); }
  void contactD(const LocalBlock& blk, const Eigen::VectorXd&, double* out) const {
    for (int k = 0; k < blk.rows; ++k) out[k] = d[blk.offset + k];
  }
  void applyDelta(const LocalBlock& blk, const double* delta) {
    const int cols = blk.rows;
    bool moved = false;
    for (int k = 0; k < cols; ++k) moved = moved || delta[k] != 0.0;
    if (!moved) return;
    const int j = static_cast<int>(&blk - first_block);
    double* dd = d.data();
    for (int s = column_start[j]; s < column_start[j + 1]; ++s) {
      const ColumnBlock& b = column_blocks[s];
      for (int r = 0; r < b.rows; ++r) {
        double sum = 0.0;
        for (int c = 0; c < cols; ++c) sum += b.v[r * cols + c] * delta[c];
        dd[b.row0 + r] += sum;
      }
    }
    if (ctx.regularization != 0.0)
      for (int k = 0; k < cols; ++k) dd[blk.offset + k] += ctx.regularization * delta[k];
  }
  const Eigen::VectorXd& currentD(const Eigen::VectorXd&) { return d; }
  const LocalBlock* first_block = nullptr;
};

// ---- The unbuilt solve (SolverParams::build_lcp = false, Problem::bodies) ----------------
//
// Why this is the same iteration as the sweep on the assembled W. The body form
// (body_compliance.h) gives W_ij = Σ_{bodies b shared by i and j} J_ib C_b J_jbᵀ, so
//   d = (W + rI) λ + d_free,   d_c = Σ_{sides s of c} J_cs u_b(s) + d_free_c + r λ_c,
//   u_b = C_b Σ_{contacts k touching b} J_kbᵀ λ_k       (the body's correction)
// (+ the body form's extra diagonal, softness, beside r): a contact's d needs only the u of
// the two bodies it touches. The built sweep visits contact c, reads its maintained d_c,
// takes the local step on D_c = W_cc + rI and adds the column block (W + rI)_:c Δλ_c to d.
// Here the local step and D_c are the same (D_c = Σ_{s,t on one body} J_cs C_b J_ctᵀ + rI,
// formed once per solve), d_c is read through u, and adding W_:c Δλ_c to every d is exactly
// u_b += C_b J_cbᵀ Δλ_c on c's bodies: every later contact then reads the d the built sweep
// would have maintained. Same contact order, same local steps, same sor, stopping rule,
// minW, maxF and warm start, so the iterates are those of pgs/nlgs on the assembled W up to
// the round-off of a different summation order. This is the sequential-impulse form
// (Catto's Box2D: per body a velocity correction, per contact an impulse): a sweep costs
// O(rows · 6) and the storage O(bodies + rows), where the built W needs O(contacts ×
// neighbours) (block-sparse) or O(rows²) (dense) to store and as much per sweep.
struct BodyAccess {
  const BodyCompliance& B;
  const SolveContext& ctx;
  std::vector<BodyVector> u;  // per body: C_b Σ Jᵀ λ, maintained
  Eigen::VectorXd d;          // the whole d, formed only for the residual
  const LocalBlock* first_block = nullptr;

  BodyAccess(const BodyCompliance& bodies, const SolveContext& context) : B(bodies), ctx(context) {}

  // J_row · v for row k of a row-major rows × 6 block.
  static double rowDot(const JacobianBlock& J, int k, const BodyVector& v) {
    const double* j = J.data() + 6 * k;
    return j[0] * v[0] + j[1] * v[1] + j[2] * v[2] + j[3] * v[3] + j[4] * v[4] + j[5] * v[5];
  }
  // d of contact `ci` (rows from `offset`) from u.
  void rowsD(int ci, int offset, const double* lambda, double* out) const {
    const ContactJacobian& c = B.contacts[ci];
    const bool extra = B.diagonal.size() != 0;
    for (int k = 0; k < c.rows; ++k) {
      double v = ctx.problem->d_free[offset + k] + ctx.regularization * lambda[offset + k];
      if (extra) v += B.diagonal[offset + k] * lambda[offset + k];
      if (c.body_a >= 0) v += rowDot(c.jacobian_a, k, u[c.body_a]);
      if (c.body_b >= 0) v += rowDot(c.jacobian_b, k, u[c.body_b]);
      out[k] = v;
    }
  }

  void refresh(const Eigen::VectorXd& lambda) { B.bodyResponse(lambda, &u); }
  void contactD(const LocalBlock& blk, const Eigen::VectorXd& lambda, double* out) const {
    rowsD(static_cast<int>(&blk - first_block), blk.offset, lambda.data(), out);
  }
  void applyDelta(const LocalBlock& blk, const double* delta) {
    bool moved = false;
    for (int k = 0; k < blk.rows; ++k) moved = moved || delta[k] != 0.0;
    if (!moved) return;
    const ContactJacobian& c = B.contacts[&blk - first_block];
    const int bodies[2] = {c.body_a, c.body_b};
    const JacobianBlock* jacobians[2] = {&c.jacobian_a, &c.jacobian_b};
    for (int s = 0; s < 2; ++s) {
      if (bodies[s] < 0) continue;
      BodyVector f = BodyVector::Zero();  // J_sᵀ Δλ
      const double* j = jacobians[s]->data();
      for (int k = 0; k < blk.rows; ++k)
        for (int q = 0; q < 6; ++q) f[q] += j[6 * k + q] * delta[k];
      u[bodies[s]].noalias() += B.body_compliance[bodies[s]] * f;
    }
  }
  const Eigen::VectorXd& currentD(const Eigen::VectorXd& lambda) {
    d.resize(lambda.size());
    int offset = 0;
    for (int ci = 0; ci < B.contactCount(); ++ci) {
      rowsD(ci, offset, lambda.data(), d.data() + offset);
      offset += B.contacts[ci].rows;
    }
    return d;
  }
};

// Local step of a torsional (4-row) or rolling (6-row) contact: block Gauss-Seidel inside
// the contact. First the Coulomb step on the sliding rows (the spin and rolling forces act
// through d_c), then the spin row, λ_s = clamp(λ_s - u_s / D_ss, ±μ_tor λ_n), then the
// rolling pair as a disc problem of radius μ_roll λ_n on its 2×2 block, each on the d the
// previous rows' changes left (u_x = d_x + D_x,prev Δ_prev) and bounded by the new λ_n. Its
// fixed point satisfies every row's law with the others' forces: the contact's law.
void extendedLocalStep(const LocalBlock& blk, double omega, const double* d_c, double* lambda_c, double* delta) {
  Eigen::Map<Eigen::Vector3d> sliding(lambda_c);
  const Eigen::Vector3d old = sliding;
  const Eigen::Vector3d b = Eigen::Map<const Eigen::Vector3d>(d_c) - blk.D * old;
  Eigen::Vector3d next = old;
  if (blk.mu > 0.0) {
    coulombLocalStep(blk, b, next);
  } else {  // frictionless sliding rows: the normal step alone
    next[0] = std::max(0.0, old[0] - d_c[0] * blk.inv_nn);
    next[1] = next[2] = 0.0;
  }
  if (omega != 1.0) {
    next = old + omega * (next - old);
    projectOntoCone(blk.mu, next.data());
  }
  for (int k = 0; k < 3; ++k) delta[k] = next[k] - old[k];
  sliding = next;
  const auto& D = blk.D_full;
  // Spin about the normal.
  const double u_s = d_c[3] + D(3, 0) * delta[0] + D(3, 1) * delta[1] + D(3, 2) * delta[2];
  const double spin_bound = blk.mu_torsional * lambda_c[0];
  double spin = blk.mu_torsional > 0.0 ? std::clamp(lambda_c[3] - u_s * blk.inv_spin, -spin_bound, spin_bound) : 0.0;
  if (omega != 1.0) spin = std::clamp(lambda_c[3] + omega * (spin - lambda_c[3]), -spin_bound, spin_bound);
  delta[3] = spin - lambda_c[3];
  lambda_c[3] = spin;
  if (blk.rows < 6) return;
  // Rolling about the two tangents.
  Eigen::Vector2d u_r(d_c[4], d_c[5]);
  for (int k = 0; k < 4; ++k) u_r += D.block<2, 1>(4, k) * delta[k];
  const Eigen::Vector2d old_r(lambda_c[4], lambda_c[5]);
  const Eigen::Matrix2d R = D.block<2, 2>(4, 4);
  const double roll_bound = blk.mu_rolling * lambda_c[0];
  Eigen::Vector2d next_r = Eigen::Vector2d::Zero();
  if (roll_bound > 0.0) {
    next_r = blk.roll_symmetric ? solveDiscProblem(blk.roll_basis, blk.roll_eigen, u_r - R * old_r, roll_bound)
                                : clampToDisc(old_r - blk.roll_step * u_r, roll_bound);
  }
  if (omega != 1.0) next_r = clampToDisc(old_r + omega * (next_r - old_r), roll_bound);
  delta[4] = next_r[0] - old_r[0];
  delta[5] = next_r[1] - old_r[1];
  lambda_c[4] = next_r[0];
  lambda_c[5] = next_r[1];
}

// One contact's local step on its current d with over-relaxation ω (see the top of the
// file); returns the change of λ_c in `delta`.
void localStep(const LocalBlock& blk, const FrictionPolygon* polygon, double omega, const double* d_c,
               double* lambda_c, double* delta) {
  switch (blk.kind) {
    case LocalKind::kSkip:
      break;
    case LocalKind::kNormalOnly: {
      double next = std::max(0.0, lambda_c[0] - d_c[0] * blk.inv_nn);
      if (omega != 1.0) next = std::max(0.0, lambda_c[0] + omega * (next - lambda_c[0]));
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
      if (omega != 1.0) {
        next = old + omega * (next - old);
        projectOntoCone(blk.mu, next.data());
      }
      Eigen::Map<Eigen::Vector3d> change(delta);
      change = next - old;
      lambda = next;
      break;
    }
    case LocalKind::kCoulombExtended:
      extendedLocalStep(blk, omega, d_c, lambda_c, delta);
      break;
    case LocalKind::kPolygon: {
      const Eigen::Vector3d old = Eigen::Map<const Eigen::Vector3d>(lambda_c);
      polygonLocalStep(blk, *polygon, d_c, omega, lambda_c);
      for (int k = 0; k < 3; ++k) delta[k] = lambda_c[k] - old[k];
      break;
    }
    case LocalKind::kBilateral: {
      // Plain loops: no dynamic-size temporaries (the sweep must not allocate).
      const int n = blk.rows;
      const Eigen::MatrixXd& inv = blk.bilateral_inverse;
      for (int i = 0; i < n; ++i) {
        double sum = 0.0;
        for (int k = 0; k < n; ++k) sum += inv(i, k) * d_c[k];
        delta[i] = -omega * sum;
      }
      for (int i = 0; i < n; ++i) lambda_c[i] += delta[i];
      break;
    }
  }
}

// SOFA's per-sweep measure: the displacement each contact's change causes on itself.
double sofaContactError(const LocalBlock& blk, const double* delta) {
  switch (blk.kind) {
    case LocalKind::kNormalOnly: return std::abs(delta[0]) / blk.inv_nn;
    case LocalKind::kCoulomb:
    case LocalKind::kPolygon: return (blk.D * Eigen::Map<const Eigen::Vector3d>(delta)).norm();
    case LocalKind::kCoulombExtended: {
      Eigen::Matrix<double, 6, 1> v = Eigen::Matrix<double, 6, 1>::Zero();
      v.head(blk.rows) = Eigen::Map<const Eigen::VectorXd>(delta, blk.rows);
      return (blk.D_full * v).norm();
    }
    case LocalKind::kBilateral: {
      double sum = 0.0;
      for (int i = 0; i < blk.rows; ++i) {
        double row = 0.0;
        for (int k = 0; k < blk.rows; ++k) row += blk.bilateral_block(i, k) * delta[k];
        sum += row * row;
      }
      return std::sqrt(sum);
    }
    case LocalKind::kSkip: break;
  }
  return 0.0;
}

bool allFinite(const Eigen::VectorXd& v) { return v.allFinite(); }

template <class Access>
KernelReport sweepUntilDone(const SolveContext& ctx, const std::vector<LocalBlock>& blocks,
                            Access& access, Eigen::VectorXd& lambda,
                            const FrictionPolygon* polygon) {
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
  access.refresh(lambda);
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
    if (sweep % kRefreshInterval == 0) access.refresh(lambda);
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
        return report;
      }
    } else {
      report.solver_error = residual;
      if (residual <= params.tolerance) {
        access.refresh(lambda);
        Eigen::VectorXd d_exact;
        ctx.computeD(lambda, d_exact);
        if (confirmConverged(report, residualOf(lambda, d_exact), params.tolerance)) return report;
      }
    }
    // At most one clock read per sweep.
    if (sweep < params.maxIt && ctx.deadlinePassed()) {
      endOnTimeBudget(report, lambda, best, params.time_budget, sweep);
      return report;
    }
  }
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
  std::vector<LocalBlock> blocks;
  if (std::string err = prepareBlocks(ctx, blocks, polygon); !err.empty()) {
    KernelReport report;
    report.status = SolveStatus::kZeroDiagonal;
    report.message = err;
    return report;
  }
  if (const BodyCompliance* bodies = ctx.problem->bodies.get()) {  // build_lcp = false
    BodyAccess access(*bodies, ctx);
    access.first_block = blocks.data();
    return sweepUntilDone(ctx, blocks, access, lambda, polygon);
  }
  if (const auto* dense = std::get_if<Eigen::MatrixXd>(&ctx.problem->W)) {
    DenseAccess access{*dense, ctx, Eigen::VectorXd()};
    return sweepUntilDone(ctx, blocks, access, lambda, polygon);
  }
  SparseAccess access(std::get<BlockSparseMatrix>(ctx.problem->W), ctx);
  access.first_block = blocks.data();
  return sweepUntilDone(ctx, blocks, access, lambda, polygon);
}

}  // namespace

KernelReport runProjectedGaussSeidel(const SolveContext& ctx, Eigen::VectorXd& lambda) {
  if (ctx.hasFriction()) {
    KernelReport report;
    report.status = SolveStatus::kNotApplicable;
    report.message = "pgs solves frictionless problems; this one has contacts with mu > 0 "
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
