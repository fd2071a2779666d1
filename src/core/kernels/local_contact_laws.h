// Local contact laws of the Gauss-Seidel kernels: with every other contact frozen, contact c
// sees u_c = D_c λ_c + b_c (D_c its diagonal block of W, + r I) and solves its own small
// problem exactly: a scalar LCP for a normal row, a linear solve for bilateral rows, the local
// Coulomb problem on the disc, the local polygon problem for a pyramid, and block Gauss-Seidel
// inside torsional and rolling contacts. Each law's derivation stands above it. The sweep that
// visits the contacts is gauss_seidel.cpp; how it reads W is sweep_access.h.
//
// Inline and header-only: these run once per contact per sweep, in the sweep's hot loop.
#pragma once

#include "friction_pyramid.h"

#include "lcp_contact_solver/core/kernels/kernels.h"
#include "lcp_contact_solver/core/kernels/scalar_rows.h"
#include "lcp_contact_solver/core/residual.h"

#include <Eigen/Core>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace lcp_contact_solver::core::local_laws {

constexpr int kMaxLocalIterations = 20;
constexpr double kLocalTolerance = 1e-14;

enum class LocalKind : std::uint8_t { kSkip, kNormalOnly, kCoulomb, kBilateral, kPolygon, kCoulombExtended };

// What a contact's local step needs, computed once per solve. Stored flat, one per contact.
struct LocalBlock {
  LocalKind kind = LocalKind::kSkip;
  int offset = 0;
  int rows = 0;
  double mu = 0.0;
  double inv_nn = 0.0;                          // 1 / D_nn
  Eigen::Matrix3d D = Eigen::Matrix3d::Zero();  // diagonal block (+ r I), frictional only
  // Tangential 2x2 block T = Q diag(a) Qᵀ, for the disc-constrained local problem.
  Eigen::Matrix2d tangent_basis = Eigen::Matrix2d::Identity();
  Eigen::Vector2d tangent_eigen = Eigen::Vector2d::Zero();
  bool tangent_symmetric = true;
  double tangent_step = 0.0;  // 1 / largest eigenvalue, for the non-symmetric fallback
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
inline Eigen::Vector2d solveDiscProblem(const Eigen::Matrix2d& basis, const Eigen::Vector2d& a,
                                        const Eigen::Vector2d& b, double radius) {
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
  double hi = std::max(lo, shift - a_min);                     // |x(hi)| <= radius
  double nu = a_min + lo > 0.0 ? lo : 0.5 * (lo + hi);         // a pole at lo: start inside
  double e0 = 1.0 / (a[0] + nu), e1 = 1.0 / (a[1] + nu);
  for (int it = 0; it < 60; ++it) {
    const double x0 = g[0] * e0, x1 = g[1] * e1;
    const double n2 = x0 * x0 + x1 * x1;
    const double n = std::sqrt(n2);
    const double phi = 1.0 / n - 1.0 / radius;
    if (std::abs(phi) * radius < 1e-15) break;
    if (phi > 0.0)
      hi = nu;
    else
      lo = nu;  // phi increases with ν
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

inline Eigen::Vector2d solveDiscProblem(const LocalBlock& blk, const Eigen::Vector2d& b, double radius) {
  return solveDiscProblem(blk.tangent_basis, blk.tangent_eigen, b, radius);
}

// Projects the tangential force onto the disc of the given radius.
inline Eigen::Vector2d clampToDisc(const Eigen::Vector2d& t, double radius) {
  const double n = t.norm();
  return n > radius ? Eigen::Vector2d(t * (radius / n)) : t;
}

// Tangential part of the local Coulomb step: λ_n fixed, u_t = T λ_t + bt.
inline void coulombTangentStep(const LocalBlock& blk, const Eigen::Vector2d& bt, Eigen::Vector3d& lambda) {
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

// Sliding solution of the local Coulomb problem for any 3×3 block D (coupled normal and
// tangents, or a tangential block that round-off left non-symmetric). Sliding means
// u_n = 0 and λ = λ_n (1, μ s) with s = (cos θ, sin θ), so
//   λ_n(θ) = -b_n / g(θ),        g(θ) = D_nn + μ D_nt·s   (λ_n > 0: b_n < 0 and g > 0),
//   u_t(θ) = λ_n(θ) v(θ) + b_t,  v(θ) = D_tn + μ D_tt s,
// and Coulomb's law asks the slip to oppose the force: f(θ) = s⊥·u_t(θ) = 0 with
// s·u_t(θ) <= 0, s⊥ = (-sin θ, cos θ). One unknown instead of three: Newton on θ (the
// slip direction s, started from the guess `s`) with
//   f'(θ) = -s·u_t + s⊥·(λ_n' v + λ_n μ D_tt s⊥),   λ_n' = -λ_n μ (D_nt·s⊥) / g,
// quadratic near a simple root, where the alternation below converges only linearly (10+
// rounds when D couples normal and tangents, and never exactly for a non-symmetric D_tt).
// Returns false, leaving λ alone, unless it lands on a root that satisfies the law.
inline bool slidingLocalSolve(const Eigen::Matrix3d& D, double mu, const Eigen::Vector3d& b, Eigen::Vector2d s,
                              Eigen::Vector3d& lambda) {
  if (!(b[0] < 0.0)) return false;
  const double length = s.norm();
  if (!(length > 0.0)) return false;
  s /= length;
  const Eigen::Vector2d d_nt = D.block<1, 2>(0, 1).transpose();
  const Eigen::Vector2d d_tn = D.block<2, 1>(1, 0);
  const Eigen::Matrix2d d_tt = D.block<2, 2>(1, 1);
  const double scale = std::abs(b[1]) + std::abs(b[2]) +
                       std::abs(b[0] / D(0, 0)) * (d_tn.cwiseAbs().sum() + mu * d_tt.cwiseAbs().sum());
  for (int it = 0; it < 16; ++it) {
    const Eigen::Vector2d s_perp(-s[1], s[0]);
    const double g = D(0, 0) + mu * d_nt.dot(s);
    if (!(g > 0.0)) return false;
    const double normal = -b[0] / g;
    const Eigen::Vector2d v = d_tn + mu * (d_tt * s);
    const Eigen::Vector2d ut = normal * v + b.tail<2>();
    const double f = s_perp.dot(ut);
    const double along = s.dot(ut);
    if (std::abs(f) <= 1e-13 * scale) {
      if (along > 1e-12 * scale) return false;  // the slip would push the force: not Coulomb
      lambda = Eigen::Vector3d(normal, mu * normal * s[0], mu * normal * s[1]);
      return true;
    }
    const double normal_rate = -normal * mu * d_nt.dot(s_perp) / g;
    const double slope = -along + s_perp.dot(normal_rate * v + normal * mu * (d_tt * s_perp));
    if (!(std::abs(slope) > 0.0)) return false;
    // Turn by the Newton step along the circle: s + δ s⊥, normalised, turns by atan δ,
    // which agrees with δ to third order (still quadratic), without trigonometry; |δ| <= 1
    // (45°) keeps a far step from skipping roots.
    const double delta = std::clamp(-f / slope, -1.0, 1.0);
    s = (s + delta * s_perp) / std::sqrt(1.0 + delta * delta);
  }
  return false;
}

// Local Coulomb problem of one contact, with the others frozen: u = D λ + b.
// Shortcuts first: b_n >= 0 leaves the contact open (λ = 0 gives u = b, a solution); a
// sticking contact has u = 0, so λ = -D⁻¹ b, accepted when it lies inside the cone
// (λ_n > 0, |λ_t| <= μ λ_n); without normal-tangential coupling (D_nt = D_tn = 0) and with
// a symmetric D_tt, λ_n = max(0, -b_n / D_nn) is exact at once and one disc problem
// finishes the step. Otherwise the contact slides: slidingLocalSolve above, started from
// the direction of the sticking force, then of the current force, then against the slip
// the normal force alone would cause. Only if none lands on a root does it alternate the
// exact normal step λ_n = max(0, λ_n - u_n / D_nn) with the tangential step (disc problem
// or, for a non-symmetric D_tt, a projected gradient step) until λ stops moving.
inline void coulombLocalStep(const LocalBlock& blk, const Eigen::Vector3d& b, Eigen::Vector3d& lambda) {
  if (b[0] >= 0.0 && lambda[0] == 0.0 && lambda[1] == 0.0 && lambda[2] == 0.0) return;
  Eigen::Vector2d stick_t = Eigen::Vector2d::Zero();
  if (blk.invertible) {
    const Eigen::Vector3d stick = -(blk.D_inverse * b);
    const double radius = blk.mu * stick[0];
    if (stick[0] > 0.0 && stick[1] * stick[1] + stick[2] * stick[2] <= radius * radius) {
      lambda = stick;
      return;
    }
    stick_t = stick.tail<2>();
  }
  if (!blk.coupled && blk.tangent_symmetric) {
    lambda[0] = std::max(0.0, -b[0] * blk.inv_nn);
    coulombTangentStep(blk, b.tail<2>(), lambda);
    return;
  }
  const Eigen::Vector2d slip_alone = -(b.tail<2>() - blk.D.block<2, 1>(1, 0) * (b[0] * blk.inv_nn));
  for (const Eigen::Vector2d& guess : {Eigen::Vector2d(lambda.tail<2>()), stick_t, slip_alone}) {
    if (guess.squaredNorm() > 0.0 && slidingLocalSolve(blk.D, blk.mu, b, guess, lambda))
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
inline void polygonLocalStep(const LocalBlock& blk, const FrictionPolygon& polygon, const double* d_c,
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

// Local step of a torsional (4-row) or rolling (6-row) contact: block Gauss-Seidel inside
// the contact. First the Coulomb step on the sliding rows (the spin and rolling forces act
// through d_c), then the spin row, λ_s = clamp(λ_s - u_s / D_ss, ±μ_tor λ_n), then the
// rolling pair as a disc problem of radius μ_roll λ_n on its 2×2 block, each on the d the
// previous rows' changes left (u_x = d_x + D_x,prev Δ_prev) and bounded by the new λ_n. Its
// fixed point satisfies every row's law with the others' forces: the contact's law.
inline void extendedLocalStep(const LocalBlock& blk, double omega, const double* d_c, double* lambda_c,
                              double* delta) {
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
  double spin =
      blk.mu_torsional > 0.0 ? std::clamp(lambda_c[3] - u_s * blk.inv_spin, -spin_bound, spin_bound) : 0.0;
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
    next_r = blk.roll_symmetric
                 ? solveDiscProblem(blk.roll_basis, blk.roll_eigen, u_r - R * old_r, roll_bound)
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
inline void localStep(const LocalBlock& blk, const FrictionPolygon* polygon, double omega, const double* d_c,
                      double* lambda_c, double* delta) {
  switch (blk.kind) {
    case LocalKind::kSkip: break;
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
    case LocalKind::kCoulombExtended: extendedLocalStep(blk, omega, d_c, lambda_c, delta); break;
    case LocalKind::kPolygon: {
      const Eigen::Vector3d old = Eigen::Map<const Eigen::Vector3d>(lambda_c);
      polygonLocalStep(blk, *polygon, d_c, omega, lambda_c);
      for (int k = 0; k < 3; ++k) delta[k] = lambda_c[k] - old[k];
      break;
    }
    case LocalKind::kBilateral: {
      if (blk.rows == 1) {  // a joint's or an equality's scalar row: no trip through the inverse's heap storage
        delta[0] = -omega * (blk.inv_nn * d_c[0]);  // the general loop's products, in its order
        lambda_c[0] += delta[0];
        break;
      }
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
inline double sofaContactError(const LocalBlock& blk, const double* delta) {
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

// Builds the per-contact local data; returns a failure message for a diagonal that the
// local step would divide by (SOFA divides anyway and returns NaN).
// `polygon` (pyramid models) turns frictional contacts into polygon steps.
std::string prepareBlocks(const SolveContext& ctx, std::vector<LocalBlock>& blocks,
                          const FrictionPolygon* polygon = nullptr);

}  // namespace lcp_contact_solver::core::local_laws

namespace lcp_contact_solver::core {

// A block-sparse W's blocks by block column (sweep_access.h's SparseAccess walks a contact's
// column to update d), pointing into W's values.
struct SparseColumnIndex {
  struct Block {
    int row0;         // first row of the block row
    int rows;         // its height
    const double* v;  // the block's values, row-major
  };
  std::vector<int> start;     // per block column, into `blocks`
  std::vector<Block> blocks;  // ordered by block column
  void build(const BlockSparseMatrix& W);
};

// The d = W λ + d_free a sweep maintained when its call ended, and the λ it belongs to (the
// last iterate, which the call returns unless an earlier one was better): a call that starts
// from exactly that λ on the same problem goes on with it instead of forming W λ again.
// auto's probe stages and slices are such calls, each a product with W otherwise.
struct KeptD {
  const Problem* problem = nullptr;  // none: nothing kept
  double regularization = 0.0;
  Eigen::VectorXd d, lambda;
  int sweeps = 0;  // since d was last recomputed exactly (the drift refresh counts on)
  // Whether d belongs to `x` on ctx's problem: then `d` is swapped into `out`.
  bool take(const SolveContext& ctx, const Eigen::VectorXd& x, Eigen::VectorXd& out, int* since_refresh);
  // Keeps `d` (swapped out) as belonging to `x`, `since_refresh` sweeps after an exact d.
  void keep(const SolveContext& ctx, const Eigen::VectorXd& x, Eigen::VectorXd& d_now, int since_refresh);
};

// kernels.h: the blocks of one problem, regularization and polygon (facets; 0 for the disc),
// and for one-row contacts the scalar-row sweep's data (scalar_rows.h).
struct GaussSeidelMemo {
  const Problem* problem = nullptr;  // none: no blocks
  double regularization = 0.0;
  int facets = 0;
  std::vector<local_laws::LocalBlock> blocks;
  const Problem* index_problem = nullptr;  // none: no column index
  SparseColumnIndex columns_by_block;

  const Problem* rows_problem = nullptr;  // none: no scalar rows
  double rows_regularization = 0.0;
  ScalarRows columns;               // W's columns
  std::vector<double> inverse;      // 1 / (W_ii + r)
  std::vector<std::uint8_t> kind;   // each row's kind (scalar_rows.cpp)

  KeptD kept;

  void clear() { problem = rows_problem = index_problem = kept.problem = nullptr; }
};

}  // namespace lcp_contact_solver::core
