// Semismooth Newton on the Alart-Curnier function, regularized and globalised by a line
// search, warm-started by a few nlgs sweeps.
//
// Derivation. With u = W λ + d_free (W + r I when regularized) and per contact weights
// ρ_n, ρ_t > 0 (the inverse diagonal of the contact's block, so every row is scaled like
// a force), Coulomb's law is Φ(λ) = 0 for the Alart-Curnier function
//   Φ_n = λ_n - max(0, s_n),                  s_n = λ_n - ρ_n u_n
//   Φ_t = λ_t - Proj_D(R)(z),  R = μ max(0, s_n),  z = λ_t - ρ_t u_t
// (D(R) the disc of radius R): the normal part is 0 <= λ_n ⟂ u_n >= 0, and the tangential
// part says λ_t = z when |z| <= R (stick, u_t = 0) and λ_t = R z/|z| otherwise (slip, the
// force on the disc opposite u_t). Frictionless rows use Φ_n alone, bilateral rows
// Φ = ρ u, ignored rows and the tangents of μ = 0 contacts Φ = λ. Φ is piecewise smooth;
// one element of its generalised Jacobian is J = A + B W with contact-block-diagonal A, B:
//   s_n > 0:  dΦ_n = ρ_n W_n            s_n <= 0:  dΦ_n = e_nᵀ
//   |z| <= R: dΦ_t = ρ_t W_t
//   |z| > R:  dΦ_t = (I - P) E_t + ρ_t P W_t - [s_n > 0] μ ẑ (e_nᵀ - ρ_n W_n),
//             P = (R/|z|)(I - ẑ ẑᵀ),  ẑ = z/|z|
// (rows W_n, W_t of W; E_t picks λ_t). Newton's step solves (J + ε I) Δ = -Φ.
//
// Rank-deficient W. When more rows stick than the bodies have degrees of freedom, the
// rows ρ W of J are linearly dependent and J is singular; the forces are not unique but
// the velocities are. The ε I term is a Levenberg-Marquardt / proximal regularization
// of the linearisation only: it picks a small step among the many that solve it, while
// Φ = 0 (the unregularized law) stays the target, so the limit is an exact solution. ε
// follows the residual (ε = c · min(1, residual) >= 1e-8, c adaptive: divided by 10
// after a step the line search took whole or halved once, multiplied by 10, up to 1,
// after one it had to cut to a quarter or less, and by 100 when no step decreases the
// merit), which keeps the local convergence fast and turns the step into a damped
// projected-Jacobi step (Δ ≈ -Φ/ε) far from the solution; the floor keeps steps along W's
// null space short. A step cut that far says the linearisation mispredicts the merit along
// Δ, which on a rank-deficient W is a long step along J's near-null space: more damping
// shortens it, up to ε = min(1, residual), the Levenberg-Marquardt weight μ = ‖Φ‖ under
// which the iteration still converges quadratically where the solutions are not isolated
// (a local error bound; Yamashita-Fukushima, Fan-Yuan). Only ever decreasing c instead
// left ε at its floor after a few steps, and the line search cut step after step: to 1e-8,
// OneObject-i1028 took 61 iterations (now 29) and the capsule piles 208 and 380 (now 26 and
// 17). Not in prox's sub-problems, whose σ I regularizes them already: there the raise made
// prox 1.17x slower over the study's cells and turned one LCP it solved into a failure.
//
// Hybrid. Semismooth Newton converges fast once the contact states (open, stick, slip)
// are right but can crawl while they change. So it starts from 20 nlgs sweeps (or
// residual 1e-3; none where nlgs cannot start, a non-positive W_nn), and whenever 10
// Newton steps fail to halve the residual, up to 100 nlgs sweeps from the best iterate (or
// a tenfold decrease) move the states on before Newton resumes; three full steps in a row
// that barely move the residual get ten such sweeps at once, kept only if they reach the
// tenfold decrease. A warm-started solve that stalls a second time restarts once from
// λ = 0; one whose best residual has not halved over five such rounds stops with
// numerical_failure (a floor of its own, not worth the rest of the budget), and so does one
// that comes back to an earlier stall's residual with nothing better found between (a limit
// cycle: the iteration is deterministic, it would repeat). Iterations count Newton steps
// plus nlgs sweeps.
//
// Globalisation: Armijo backtracking on the merit ψ = ½ |Φ|²,
// ψ(λ + t Δ) <= (1 - 2 σ t) ψ(λ), with u(λ + t Δ) = u + t W Δ (one product per iteration).
// Each iteration costs one factorisation: dense LU for dense W, sparse LU on the
// block pattern of W for block-sparse W. An LCP (no friction) with symmetric W first
// runs the active-set Newton of newton_symmetric.cpp (LDLᵀ of W_AA).
//
// When to use it: when high accuracy is wanted (1e-8..1e-12), on small and medium
// problems (up to a few thousand rows), including ill-conditioned or rank-deficient W
// where Gauss-Seidel stalls; each iteration is far more expensive than a sweep.
#include "lcp_contact_solver/core/body_compliance.h"
#include "lcp_contact_solver/core/kernels/kernels.h"
#include "lcp_contact_solver/core/residual.h"
#include "local_contact_laws.h"
#include "newton_symmetric.h"
#include "thread_workspace.h"

#include <Eigen/LU>
#include <Eigen/SparseCore>
#include <Eigen/SparseLU>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <string>
#include <variant>

namespace lcp_contact_solver::core {
namespace {

// Warm start: nlgs sweeps until kNewtonWarmupTolerance (or the tolerance, if larger) or
// kNewtonWarmupSweeps sweeps (kernels.h: auto's probe stops at the same point).
constexpr double kArmijo = 1e-4;
constexpr int kMaxLineSearch = 30;
constexpr double kRegularizationMin = 1e-8;
constexpr double kRegularizationMax = 1e4;
constexpr double kRegularizationStart = 1.0;
// A step the line search cut to this length or less raises c tenfold, up to
// kRegularizationAfterCut (ε = min(1, residual): the Levenberg-Marquardt weight ‖Φ‖).
constexpr double kCutStep = 0.25;
constexpr double kRegularizationAfterCut = 1.0;
// Stall: the residual must fall below kStallFactor times its value kStallWindow Newton
// steps earlier; otherwise up to kBurstSweeps nlgs sweeps (or a kBurstReduction-fold
// decrease) run before Newton resumes.
constexpr int kStallWindow = 10;
constexpr double kStallFactor = 0.5;
constexpr int kBurstSweeps = 100;
constexpr double kBurstReduction = 0.1;
// Stagnation: kStagnantSteps full Newton steps in a row, each lowering the residual by
// less than 1 %, get a burst of up to kStagnantBurstSweeps sweeps (below).
constexpr double kStagnation = 0.99;
constexpr int kStagnantSteps = 3;
constexpr int kStagnantBurstSweeps = 10;
// A warm-started solve that stalls this often restarts once from λ = 0.
constexpr std::size_t kStallsBeforeColdStart = 2;
// Giving up: when the best residual has not halved over this many stalls (each 10 Newton
// steps and a burst), Newton sits at a floor of its own (round-off on a singular
// linearisation) and more rounds only burn the budget; it says so instead.
constexpr int kFruitlessStalls = 5;

// A limit cycle: the iteration is deterministic, so a stall that comes back to the residual
// of an earlier stall (to round-off) with the best residual unchanged since then repeats
// the same rounds forever (a capsule pile's 48-row island: a period of 120 iterations, run
// five times before the fruitless-stall test ended it). Stalls are few (one per 10 steps).
constexpr double kCycleTolerance = 1e-12;
struct Stall {
  double best;      // the best residual so far
  double residual;  // the current one (NaN: not comparable, the iteration changed since)
};
bool stallRepeats(const std::vector<Stall>& stalls, double best_residual, double residual) {
  for (const Stall& s : stalls)
    if (s.best == best_residual && std::abs(s.residual - residual) <= kCycleTolerance * residual) return true;
  return false;
}

enum class RowKind : std::uint8_t { kIdentity, kNormal, kFrictional, kFrictionalNormalOnly, kBilateral };

struct NewtonContact {
  RowKind kind = RowKind::kIdentity;
  int offset = 0;
  int rows = 0;
  double mu = 0.0;
  double rho_n = 1.0;
  double rho_t = 1.0;
};

// Per contact, row-major rows×rows blocks: J_c = A_c E_c + B_c W_c (see above).
struct JacobianBlocks {
  double A[36];
  double B[36];
};

void newtonContacts(const SolveContext& ctx, std::vector<NewtonContact>& contacts) {
  const Problem& problem = *ctx.problem;
  contacts.assign(problem.contacts.size(), NewtonContact{});
  // First the weights' diagonals (each contact's block read once), then their inverses with
  // a fallback for a non-positive one: the largest diagonal of W.
  double fallback = 0.0;
  for (std::size_t i = 0; i < problem.contacts.size(); ++i) {
    const Contact& c = problem.contacts[i];
    NewtonContact& nc = contacts[i];
    nc.offset = ctx.offsets[i];
    nc.rows = c.rows;
    nc.mu = ctx.mu[i];
    ContactBlock D = contactDiagonalBlock(problem, ctx.offsets, static_cast<int>(i));
    D.diagonal().array() += ctx.regularization;
    fallback = std::max(fallback, D.diagonal().maxCoeff());
    if (ctx.ignored[i]) continue;  // kIdentity: Φ = λ keeps the force at zero
    switch (c.type) {
      case ContactType::kBilateral:
        nc.kind = RowKind::kBilateral;
        nc.rho_n = D.diagonal().maxCoeff();
        break;
      case ContactType::kFrictionless:
        nc.kind = RowKind::kNormal;
        nc.rho_n = D(0, 0);
        break;
      case ContactType::kFrictional:
        nc.kind = nc.mu > 0.0 ? RowKind::kFrictional : RowKind::kFrictionalNormalOnly;
        nc.rho_n = D(0, 0);
        nc.rho_t = 0.5 * (D(1, 1) + D(2, 2));
        break;
      case ContactType::kTorsional:  // refused before any kernel runs (contact_solver.cpp)
      case ContactType::kRolling: break;
    }
  }
  const double rho_fallback = fallback > 0.0 ? 1.0 / fallback : 1.0;
  auto inverse = [&](double w) { return w > 0.0 ? 1.0 / w : rho_fallback; };
  for (NewtonContact& nc : contacts) {
    if (nc.kind == RowKind::kIdentity) continue;
    nc.rho_n = inverse(nc.rho_n);
    if (nc.kind == RowKind::kFrictional || nc.kind == RowKind::kFrictionalNormalOnly) nc.rho_t = inverse(nc.rho_t);
  }
}

// Φ of one contact from λ_c, u_c; with `blocks`, also its Jacobian blocks.
void contactFunction(const NewtonContact& nc, const double* l, const double* u, double* phi,
                     JacobianBlocks* blocks) {
  const int m = nc.rows;
  if (blocks != nullptr) {
    std::fill(blocks->A, blocks->A + m * m, 0.0);
    std::fill(blocks->B, blocks->B + m * m, 0.0);
  }
  auto A = [&](int i, int j) -> double& { return blocks->A[i * m + j]; };
  auto B = [&](int i, int j) -> double& { return blocks->B[i * m + j]; };
  switch (nc.kind) {
    case RowKind::kIdentity:
      for (int k = 0; k < m; ++k) {
        phi[k] = l[k];
        if (blocks) A(k, k) = 1.0;
      }
      return;
    case RowKind::kBilateral:
      for (int k = 0; k < m; ++k) {
        phi[k] = nc.rho_n * u[k];
        if (blocks) B(k, k) = nc.rho_n;
      }
      return;
    case RowKind::kNormal:
    case RowKind::kFrictionalNormalOnly:
    case RowKind::kFrictional: break;
  }
  const double s_n = l[0] - nc.rho_n * u[0];
  if (s_n > 0.0) {
    phi[0] = nc.rho_n * u[0];
    if (blocks) B(0, 0) = nc.rho_n;
  } else {
    phi[0] = l[0];
    if (blocks) A(0, 0) = 1.0;
  }
  if (nc.kind == RowKind::kNormal) return;
  if (nc.kind == RowKind::kFrictionalNormalOnly) {
    phi[1] = l[1];
    phi[2] = l[2];
    if (blocks) A(1, 1) = A(2, 2) = 1.0;
    return;
  }
  const double R = nc.mu * std::max(0.0, s_n);
  const double z0 = l[1] - nc.rho_t * u[1], z1 = l[2] - nc.rho_t * u[2];
  const double zn = std::sqrt(z0 * z0 + z1 * z1);
  if (zn <= R) {  // stick: λ_t = z, i.e. u_t = 0
    phi[1] = nc.rho_t * u[1];
    phi[2] = nc.rho_t * u[2];
    if (blocks) B(1, 1) = B(2, 2) = nc.rho_t;
    return;
  }
  // slip (zn > R >= 0, so zn > 0)
  const double h0 = z0 / zn, h1 = z1 / zn;
  phi[1] = l[1] - R * h0;
  phi[2] = l[2] - R * h1;
  if (!blocks) return;
  const double ratio = R / zn;
  const double P00 = ratio * (1.0 - h0 * h0), P01 = -ratio * h0 * h1, P11 = ratio * (1.0 - h1 * h1);
  A(1, 1) = 1.0 - P00;
  A(1, 2) = -P01;
  A(2, 1) = -P01;
  A(2, 2) = 1.0 - P11;
  B(1, 1) = nc.rho_t * P00;
  B(1, 2) = nc.rho_t * P01;
  B(2, 1) = nc.rho_t * P01;
  B(2, 2) = nc.rho_t * P11;
  if (s_n > 0.0) {
    A(1, 0) = -nc.mu * h0;
    A(2, 0) = -nc.mu * h1;
    B(1, 0) = nc.mu * nc.rho_n * h0;
    B(2, 0) = nc.mu * nc.rho_n * h1;
  }
}

// Φ(λ) for all contacts; returns ½|Φ|².
double evaluate(const std::vector<NewtonContact>& contacts, const Eigen::VectorXd& lambda,
                const Eigen::VectorXd& u, Eigen::VectorXd& phi, std::vector<JacobianBlocks>* blocks) {
  for (std::size_t i = 0; i < contacts.size(); ++i) {
    const NewtonContact& nc = contacts[i];
    contactFunction(nc, lambda.data() + nc.offset, u.data() + nc.offset, phi.data() + nc.offset,
                    blocks ? &(*blocks)[i] : nullptr);
  }
  return 0.5 * phi.squaredNorm();
}

// The Newton matrix J + ε I and its factorisation, dense or on W's block pattern.
class NewtonSystem {
 public:
  virtual ~NewtonSystem() = default;
  // Builds and factorises; false if the factorisation failed.
  virtual bool factorize(const std::vector<NewtonContact>& contacts,
                         const std::vector<JacobianBlocks>& blocks, double epsilon) = 0;
  virtual void solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& x) = 0;
};

// Its arrays keep their capacity from one problem to the next (kKeptDenseRows): a MuJoCo
// stream's row count changes every step, where a MatrixXd would be reallocated.
class DenseSystem : public NewtonSystem {
 public:
  void reset(const Eigen::MatrixXd& W, double regularization) {
    n_ = W.rows();
    w_.resize(static_cast<std::size_t>(n_ * n_));
    j_.resize(static_cast<std::size_t>(n_ * n_));
    shiftedW() = W;
    shiftedW().diagonal().array() += regularization;
  }
  bool factorize(const std::vector<NewtonContact>& contacts, const std::vector<JacobianBlocks>& blocks,
                 double epsilon) override {
    // J's rows of a contact: B_c times W's rows of it, plus A_c on the diagonal block. Plain
    // loops: a GEMM call per contact cost more than the product on one- and three-row blocks.
    const Eigen::Index n = n_;
    const Eigen::Map<const Eigen::MatrixXd> W(w_.data(), n_, n_);
    Eigen::Map<Eigen::MatrixXd> J = newtonMatrix();
    for (std::size_t i = 0; i < contacts.size(); ++i) {
      const NewtonContact& nc = contacts[i];
      const int m = nc.rows;
      const double* B = blocks[i].B;
      for (Eigen::Index j = 0; j < n; ++j) {
        const double* w = W.col(j).data() + nc.offset;  // W's column j on the contact's rows
        double* out = J.col(j).data() + nc.offset;
        for (int r = 0; r < m; ++r) {
          double sum = 0.0;
          for (int k = 0; k < m; ++k) sum += B[r * m + k] * w[k];
          out[r] = sum;
        }
      }
      const double* A = blocks[i].A;
      for (int r = 0; r < m; ++r)
        for (int c = 0; c < m; ++c) J(nc.offset + r, nc.offset + c) += A[r * m + c];
    }
    J.diagonal().array() += epsilon;
    small_ = n <= kSmallLuRows;
    if (small_)
      factorSmall();
    else
      lu_ = std::make_unique<Eigen::PartialPivLU<Eigen::Ref<Eigen::MatrixXd>>>(J);  // in place: J's storage
    return true;
  }
  void solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& x) override {
    if (small_)
      solveSmall(rhs, x);
    else
      x = lu_->solve(rhs);
  }

 private:
  Eigen::Map<Eigen::MatrixXd> shiftedW() { return {w_.data(), n_, n_}; }
  Eigen::Map<Eigen::MatrixXd> newtonMatrix() { return {j_.data(), n_, n_}; }

  // Up to this size J is factorised by the plain loops below: on a 4-row system Eigen's
  // blocked LU spent more on its set-up than on the arithmetic.
  static constexpr int kSmallLuRows = 32;

  // LU with partial pivoting in place on J (column-major, right-looking): the unit lower
  // factor below the diagonal, the upper one on and above it, row swaps in pivots_. A zero
  // pivot column is left as it is (as Eigen does): the solve then yields a non-finite Δ,
  // which the caller rejects.
  void factorSmall() {
    const int n = static_cast<int>(n_);
    pivots_.resize(n);
    double* a = j_.data();
    for (int k = 0; k < n; ++k) {
      int p = k;
      double biggest = std::abs(a[k + k * n]);
      for (int i = k + 1; i < n; ++i) {
        if (std::abs(a[i + k * n]) > biggest) {
          biggest = std::abs(a[i + k * n]);
          p = i;
        }
      }
      pivots_[k] = p;
      if (biggest == 0.0) continue;
      if (p != k)
        for (int j = 0; j < n; ++j) std::swap(a[k + j * n], a[p + j * n]);
      const double inverse = 1.0 / a[k + k * n];
      for (int i = k + 1; i < n; ++i) a[i + k * n] *= inverse;
      for (int j = k + 1; j < n; ++j) {
        const double f = a[k + j * n];
        if (f == 0.0) continue;
        for (int i = k + 1; i < n; ++i) a[i + j * n] -= a[i + k * n] * f;
      }
    }
  }
  void solveSmall(const Eigen::VectorXd& rhs, Eigen::VectorXd& x) const {
    const int n = static_cast<int>(n_);
    const double* a = j_.data();
    x = rhs;
    // The swaps moved whole rows (L's columns too): all of them first, as LAPACK's getrs.
    for (int k = 0; k < n; ++k) std::swap(x[k], x[pivots_[k]]);
    for (int k = 0; k < n; ++k)
      for (int i = k + 1; i < n; ++i) x[i] -= a[i + k * n] * x[k];
    for (int k = n - 1; k >= 0; --k) {
      x[k] /= a[k + k * n];
      for (int i = 0; i < k; ++i) x[i] -= a[i + k * n] * x[k];
    }
  }

  Eigen::Index n_ = 0;
  std::vector<double> w_, j_;  // W + r I and J + ε I (then its LU), column-major
  std::unique_ptr<Eigen::PartialPivLU<Eigen::Ref<Eigen::MatrixXd>>> lu_;
  std::vector<int> pivots_;
  bool small_ = false;
};

// Its pattern and its LU's ordering (analyzePattern: COLAMD and the elimination tree) depend on
// W's block pattern only, so newton's kept workspace reuses them for the next solve on the same
// pattern (rebind): prox's outer steps and auto's newton slices call newton again and again on
// one W, and BoxesStack1's 156-row system took about 0.25 ms to build and analyse, a fifth of
// prox's time there. W_ is only read by factorize, after the solve's rebind.
class SparseSystem : public NewtonSystem {
 public:
  SparseSystem(const BlockSparseMatrix& W, double regularization)
      : W_(&W),
        regularization_(regularization),
        block_offset_(W.block_offset),
        row_start_(W.row_start),
        block_col_(W.block_col) {
    const int n = W.rows();
    const int nb = W.blockCount();
    std::vector<Eigen::Triplet<double>> triplets;
    auto addBlock = [&](int bi, int bj) {
      for (int r = W.block_offset[bi]; r < W.block_offset[bi + 1]; ++r)
        for (int c = W.block_offset[bj]; c < W.block_offset[bj + 1]; ++c) triplets.emplace_back(r, c, 1.0);
    };
    for (int bi = 0; bi < nb; ++bi) {
      addBlock(bi, bi);
      for (int s = W.row_start[bi]; s < W.row_start[bi + 1]; ++s) addBlock(bi, W.block_col[s]);
    }
    J_.resize(n, n);
    J_.setFromTriplets(triplets.begin(), triplets.end());
    J_.makeCompressed();
    // Where each stored W entry and each diagonal-block entry lives in J's values.
    auto position = [&](int r, int c) { return static_cast<int>(&J_.coeffRef(r, c) - J_.valuePtr()); };
    block_positions_.resize(W.block_col.size());
    for (int bi = 0; bi < nb; ++bi) {
      for (int s = W.row_start[bi]; s < W.row_start[bi + 1]; ++s) {
        const int bj = W.block_col[s];
        for (int r = W.block_offset[bi]; r < W.block_offset[bi + 1]; ++r)
          for (int c = W.block_offset[bj]; c < W.block_offset[bj + 1]; ++c)
            block_positions_[s].push_back(position(r, c));
      }
    }
    diagonal_positions_.resize(nb);
    for (int bi = 0; bi < nb; ++bi)
      for (int r = W.block_offset[bi]; r < W.block_offset[bi + 1]; ++r)
        for (int c = W.block_offset[bi]; c < W.block_offset[bi + 1]; ++c)
          diagonal_positions_[bi].push_back(position(r, c));
    lu_.analyzePattern(J_);
  }

  // Whether W has the block pattern this system was built for.
  bool matches(const BlockSparseMatrix& W) const {
    return W.block_offset == block_offset_ && W.row_start == row_start_ && W.block_col == block_col_;
  }
  // The same pattern, W's current values (read by factorize) and regularization.
  void rebind(const BlockSparseMatrix& W, double regularization) {
    W_ = &W;
    regularization_ = regularization;
  }

  bool factorize(const std::vector<NewtonContact>& contacts, const std::vector<JacobianBlocks>& blocks,
                 double epsilon) override {
    double* values = J_.valuePtr();
    std::fill(values, values + J_.nonZeros(), 0.0);
    // Block rows of W are the contacts (validateProblem checks the offsets match).
    for (std::size_t bi = 0; bi < contacts.size(); ++bi) {
      const int m = contacts[bi].rows;
      const double* B = blocks[bi].B;
      for (int s = W_->row_start[bi]; s < W_->row_start[bi + 1]; ++s) {
        const int bj = W_->block_col[s];
        const int cols = W_->block_offset[bj + 1] - W_->block_offset[bj];
        const double* w = W_->values.data() + W_->value_start[s];
        const int* pos = block_positions_[s].data();
        for (int r = 0; r < m; ++r)
          for (int c = 0; c < cols; ++c) {
            double sum = 0.0;
            for (int k = 0; k < m; ++k) sum += B[r * m + k] * w[k * cols + c];
            values[pos[r * cols + c]] += sum;
          }
      }
      const int* diag = diagonal_positions_[bi].data();
      const double* A = blocks[bi].A;
      for (int r = 0; r < m; ++r)
        for (int c = 0; c < m; ++c) {
          // (B (r I))_rc = r B_rc on the diagonal block.
          values[diag[r * m + c]] += A[r * m + c] + regularization_ * B[r * m + c] + (r == c ? epsilon : 0.0);
        }
    }
    lu_.factorize(J_);
    return lu_.info() == Eigen::Success;
  }
  void solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& x) override { x = lu_.solve(rhs); }

 private:
  const BlockSparseMatrix* W_;
  double regularization_;
  std::vector<int> block_offset_, row_start_, block_col_;  // the pattern it was built for
  Eigen::SparseMatrix<double> J_;
  std::vector<std::vector<int>> block_positions_;
  std::vector<std::vector<int>> diagonal_positions_;
  Eigen::SparseLU<Eigen::SparseMatrix<double>, Eigen::COLAMDOrdering<int>> lu_;
};

// Everything one solve allocates (thread_workspace.h).
struct NewtonWorkspace {
  SolveContext warm_ctx, burst_ctx;
  GaussSeidelMemo memo;  // the warm-up's blocks serve every burst
  Eigen::VectorXd start, best, u, phi, rhs, delta, w_delta, trial, u_trial, phi_trial;
  std::vector<NewtonContact> contacts;
  std::vector<JacobianBlocks> blocks;
  DenseSystem dense;
  std::unique_ptr<SparseSystem> sparse;  // the last block pattern's (SparseSystem::matches)
  std::vector<Stall> stalls;  // one per stall, in order
};

}  // namespace

KernelReport runNewton(const SolveContext& ctx, Eigen::VectorXd& lambda) {
  const Problem& problem = *ctx.problem;
  const SolverParams& params = *ctx.params;
  KernelReport report;
  const int n = problem.rowCount();

  // An LCP with symmetric W takes the active-set path with LDLT (newton_symmetric.cpp); when
  // it does not converge, the Newton below continues from its best iterate.
  int symmetric_steps = 0;
  {
    KernelReport symmetric;
    if (solveSymmetricActiveSet(ctx, lambda, &symmetric)) return symmetric;
    symmetric_steps = symmetric.iterations;
  }
  // Already solved (a warm start from the previous answer): nothing to do.
  {
    const double residual = std::isnan(ctx.start_residual) ? ctx.residual(lambda) : ctx.start_residual;
    if (residual <= params.tolerance) {
      report.status = SolveStatus::kConverged;
      report.solver_error = residual;
      return report;
    }
  }
  // Warm start: a few nlgs sweeps find the contact states cheaply.
  SolverParams warm_params = params;
  warm_params.tolerance = std::max(params.tolerance, kNewtonWarmupTolerance);
  // Sweeps the caller ran already (auto's probe) are not run twice.
  const int warm_left = std::max(0, kNewtonWarmupSweeps - ctx.warmup_sweeps_done);
  warm_params.maxIt = std::min(params.maxIt, warm_left);
  warm_params.stopping_rule = StoppingRule::kResidual;
  const WorkspaceLease<NewtonWorkspace, kKeptDenseRows> lease(n);  // its Newton matrix is n x n
  NewtonWorkspace& ws = *lease;
  SolveContext& warm_ctx = ws.warm_ctx;
  warm_ctx = ctx;
  warm_ctx.params = &warm_params;
  warm_ctx.has_trial_deadline = false;  // a trial judges newton's steps (kernels.h)
  if (warm_ctx.gs_memo == nullptr) {
    ws.memo.clear();  // a kept memo may describe another problem at the same address
    warm_ctx.gs_memo = &ws.memo;
  }
  Eigen::VectorXd& start = ws.start;
  start = lambda;
  KernelReport warm;
  // nlgs would stop at once with zero_diagonal where a non-bilateral contact has W_nn + r <= 0:
  // known here without forming its blocks (the body form stores no W: nlgs finds out itself).
  if (!problem.bodies && !ctx.positiveDiagonal(/*bilateral=*/false))
    warm.status = SolveStatus::kZeroDiagonal;  // as nlgs would say, without its set-up
  else if (warm_left > 0)
    warm = runNonlinearGaussSeidel(warm_ctx, lambda);
  int warm_sweeps = 0;
  if (warm.status == SolveStatus::kZeroDiagonal || !lambda.allFinite()) {
    lambda = start;  // nlgs cannot run here; Newton can (ε I regularizes)
  } else {
    warm_sweeps = warm.iterations;
    report.history = warm.history;
  }
  report.iterations = warm_sweeps;
  if (warm.status == SolveStatus::kTimeBudget) {
    report.status = SolveStatus::kTimeBudget;
    report.solver_error = ctx.residual(lambda);
    report.message = warm.message;
    return report;
  }
  // The warm-up says every contact sticks (a scene at rest): the sticking active-set path
  // solves that in a Cholesky step or two; when some contact slides after all, the Newton
  // below goes on from the warm-up's iterate.
  int stick_steps = 0;
  if (symmetric_steps == 0 && allSticking(ctx, lambda)) {
    KernelReport stick;
    Eigen::VectorXd trial = lambda;
    const bool solved = solveStickingActiveSet(ctx, trial, &stick);
    stick_steps = stick.iterations;
    if (solved) {
      lambda = trial;
      stick.iterations += warm_sweeps;
      stick.history = report.history;
      return stick;
    }
  }

  std::vector<NewtonContact>& contacts = ws.contacts;
  newtonContacts(ctx, contacts);
  std::vector<JacobianBlocks>& blocks = ws.blocks;
  blocks.resize(contacts.size());
  NewtonSystem* system = &ws.dense;
  if (const auto* dense = std::get_if<Eigen::MatrixXd>(&problem.W)) {
    ws.dense.reset(*dense, ctx.regularization);
  } else {
    const auto& sparse_w = std::get<BlockSparseMatrix>(problem.W);
    if (ws.sparse && ws.sparse->matches(sparse_w))
      ws.sparse->rebind(sparse_w, ctx.regularization);
    else
      ws.sparse = std::make_unique<SparseSystem>(sparse_w, ctx.regularization);
    system = ws.sparse.get();
  }

  Eigen::VectorXd &u = ws.u, &phi = ws.phi, &rhs = ws.rhs, &delta = ws.delta, &w_delta = ws.w_delta,
                  &trial = ws.trial, &u_trial = ws.u_trial, &phi_trial = ws.phi_trial;
  for (Eigen::VectorXd* v : {&u, &phi, &rhs, &delta, &w_delta, &trial, &u_trial, &phi_trial}) v->resize(n);
  auto applyW = [&](const Eigen::VectorXd& x, Eigen::VectorXd& y) {
    multiply(problem.W, x, y);
    if (ctx.regularization != 0.0) y += ctx.regularization * x;
  };
  Eigen::VectorXd& best = ws.best;
  best = lambda;
  double best_residual = std::numeric_limits<double>::infinity();
  double c_reg = kRegularizationStart;
  int newton_steps = 0;
  int sweeps = warm_sweeps;
  bool nlgs_usable =
      warm.status != SolveStatus::kZeroDiagonal && warm.status != SolveStatus::kNumericalFailure;
  const bool warm_started = ctx.warmup_sweeps_done > 0 ? ctx.warmup_start_was_warm : start.squaredNorm() > 0.0;
  std::vector<Stall>& stalls = ws.stalls;
  stalls.clear();
  double checkpoint_residual = std::numeric_limits<double>::infinity();
  int since_checkpoint = 0;
  double previous_residual = std::numeric_limits<double>::infinity();
  double converged_residual = 0.0;  // the last iterate's, when it met the tolerance
  int stagnant_steps = 0;
  bool stagnation_burst_tried = false;
  double previous_epsilon = kRegularizationMax;
  SolverParams burst_params = warm_params;
  SolveContext& burst_ctx = ws.burst_ctx;
  burst_ctx = warm_ctx;
  burst_ctx.params = &burst_params;
  report.status = SolveStatus::kMaxIterations;
  double burst_residual = std::numeric_limits<double>::infinity();  // the last burst's
  // Up to max_sweeps nlgs sweeps from the best iterate; false when the budget ran out.
  auto burst = [&](int max_sweeps) {
    lambda = best;
    burst_params.tolerance = std::max(params.tolerance, kBurstReduction * best_residual);
    burst_params.maxIt = std::min(max_sweeps, params.maxIt - newton_steps - sweeps);
    const KernelReport r = runNonlinearGaussSeidel(burst_ctx, lambda);
    burst_residual = r.solver_error;
    sweeps += r.iterations;
    report.history.insert(report.history.end(), r.history.begin(), r.history.end());
    if (r.status == SolveStatus::kZeroDiagonal || r.status == SolveStatus::kNumericalFailure) {
      nlgs_usable = false;
      lambda = best;
    }
    if (r.status == SolveStatus::kTimeBudget) {
      report.status = SolveStatus::kTimeBudget;
      report.message = r.message;
      return false;
    }
    c_reg = kRegularizationStart;
    return true;
  };
  for (;;) {
    applyW(lambda, u);
    u += problem.d_free;
    const double residual = naturalMapResidual(problem, ctx.mu, lambda, u, ctx.ignored);
    if (residual < best_residual) {
      best_residual = residual;
      best = lambda;
    }
    if (residual <= params.tolerance) {
      report.status = SolveStatus::kConverged;
      converged_residual = residual;
      break;
    }
    if (newton_steps + sweeps >= params.maxIt) {
      report.message = "maxIt (" + std::to_string(params.maxIt) + ") iterations (" + std::to_string(sweeps) +
                       " nlgs sweeps, " + std::to_string(newton_steps) +
                       " Newton steps) reached before the tolerance";
      break;
    }
    if (newton_steps > 0 && (ctx.deadlinePassed() || ctx.trialPassed(best_residual))) {
      report.status = SolveStatus::kTimeBudget;
      report.message = "time budget (" + std::to_string(params.time_budget) + " s) ran out after " +
                       std::to_string(newton_steps) + " Newton steps and " + std::to_string(sweeps) +
                       " nlgs sweeps; best iterate returned";
      break;
    }
    // Stall detection: Newton must halve the residual every kStallWindow steps. When it
    // does not (active set still changing, kinks, tiny steps), a burst of nlgs sweeps
    // from the best iterate moves the contact states, then Newton resumes.
    if (since_checkpoint == 0) checkpoint_residual = residual;
    const bool flat = residual >= kStagnation * previous_residual && previous_epsilon <= kRegularizationMin;
    stagnant_steps = flat ? stagnant_steps + 1 : 0;
    previous_residual = residual;
    if (since_checkpoint >= kStallWindow) {
      since_checkpoint = 0;
      stagnation_burst_tried = false;
      const bool stalled = residual > kStallFactor * checkpoint_residual;
      if (stalled) {
        // (not where this stall restarts a warm start cold: that changes the iteration)
        const bool restart_due = warm_started && stalls.size() + 1 == kStallsBeforeColdStart;
        const bool cycling = !restart_due && stallRepeats(stalls, best_residual, residual);
        stalls.push_back({best_residual, residual});
        const std::size_t k = stalls.size();
        if (cycling || (k > kFruitlessStalls && best_residual > 0.5 * stalls[k - 1 - kFruitlessStalls].best)) {
          report.status = SolveStatus::kNumericalFailure;
          char line[200];
          if (cycling)
            std::snprintf(line, sizeof line,
                          "newton: cycling at residual %.3g (a stall came back to an earlier stall's residual "
                          "with no better iterate between); best iterate returned",
                          best_residual);
          else
            std::snprintf(line, sizeof line,
                          "newton: stalled at residual %.3g (not halved over %d rounds of Newton steps and "
                          "nlgs sweeps); best iterate returned",
                          best_residual, kFruitlessStalls);
          report.message = line;
          break;
        }
      }
      if (stalled && stalls.size() == kStallsBeforeColdStart && warm_started) {
        // A warm start that still stalls after a burst is dropped: on a rank-deficient W
        // the previous forces can carry internal (null-space) forces that leave the
        // linearisation badly conditioned; the cold start does not (best is kept). It gets
        // the same warm-up sweeps as the start did.
        lambda.setZero();
        for (Stall& stall : stalls) stall.residual = std::numeric_limits<double>::quiet_NaN();
        if (nlgs_usable) {
          warm_params.maxIt = std::min(kNewtonWarmupSweeps, params.maxIt - newton_steps - sweeps);
          sweeps += runNonlinearGaussSeidel(warm_ctx, lambda).iterations;
          if (!lambda.allFinite()) lambda.setZero();
        }
        c_reg = kRegularizationStart;
        continue;
      }
      if (stalled && nlgs_usable) {
        if (!burst(kBurstSweeps)) break;
        continue;
      }
      checkpoint_residual = residual;
    }
    // Stagnation: full steps (ε at its floor) that no longer move the residual sit on a
    // kink or a singular direction of J. A short burst is tried at once instead of waiting
    // out the window (box pyramids: 16 such steps, then one sweep met the tolerance). It is
    // kept only if it reaches its tenfold decrease; otherwise it is undone (Newton's iterate
    // and ε restored: where Newton escapes by itself, as on OneObject, a half-way burst sent
    // it elsewhere and doubled the solve) and not tried again before the next window. Not a
    // stall: the window's counters (cold start, giving up) are unchanged.
    if (stagnant_steps >= kStagnantSteps && nlgs_usable && !stagnation_burst_tried) {
      stagnant_steps = 0;
      trial = lambda;
      const double kept_c_reg = c_reg;
      if (!burst(kStagnantBurstSweeps)) break;
      if (!(burst_residual <= kBurstReduction * best_residual)) {
        lambda = trial;
        c_reg = kept_c_reg;
        stagnation_burst_tried = true;
      }
      continue;
    }
    ++since_checkpoint;
    ++newton_steps;
    const double merit = evaluate(contacts, lambda, u, phi, &blocks);
    const double epsilon =
        std::clamp(c_reg * std::min(1.0, residual), kRegularizationMin, kRegularizationMax);
    previous_epsilon = epsilon;
    bool stepped = false;
    double step_t = 1.0;  // the accepted step's length (read only when stepped)
    if (system->factorize(contacts, blocks, epsilon)) {
      rhs = -phi;
      system->solve(rhs, delta);
      if (delta.allFinite()) {
        applyW(delta, w_delta);
        double t = 1.0;
        for (int ls = 0; ls < kMaxLineSearch; ++ls, t *= 0.5) {
          trial = lambda + t * delta;
          u_trial = u + t * w_delta;
          const double trial_merit = evaluate(contacts, trial, u_trial, phi_trial, nullptr);
          if (trial_merit <= (1.0 - 2.0 * kArmijo * t) * merit) {
            lambda = trial;
            stepped = true;
            step_t = t;
            break;
          }
        }
      }
    }
    if (params.displayDebug) report.history.push_back(residual);
    if (!stepped) {
      c_reg *= 100.0;  // toward a short projected step
      if (c_reg * std::min(1.0, residual) > kRegularizationMax) {
        report.status = SolveStatus::kNumericalFailure;
        report.message = "newton: no step decreases the merit even with the largest regularization after " +
                         std::to_string(newton_steps) + " steps; best iterate returned";
        break;
      }
    } else {
      if (step_t <= kCutStep && !ctx.proximal_subproblem)
        c_reg = std::min(c_reg * 10.0, kRegularizationAfterCut);
      else
        c_reg = std::max(c_reg * 0.1, kRegularizationMin);
    }
  }
  // The loop measured whichever iterate is returned (with u = W λ + d_free kept alongside).
  const bool converged = report.status == SolveStatus::kConverged;
  if (!converged) lambda = best;
  report.iterations = symmetric_steps + stick_steps + sweeps + newton_steps;
  if (report.message.empty())
    report.message =
        std::to_string(sweeps) + " nlgs sweeps + " + std::to_string(newton_steps) + " Newton steps";
  report.solver_error = converged                      ? converged_residual
                        : std::isfinite(best_residual) ? best_residual
                                                       : ctx.residual(lambda);
  return report;
}

}  // namespace lcp_contact_solver::core
