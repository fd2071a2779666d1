// Active-set Newton for the LCP with symmetric W (frictionless and bilateral rows; MuJoCo's
// pyramidal steps, μ = 0 contacts, joint limits).
//
// Derivation. The LCP 0 <= λ ⟂ u = W λ + q >= 0 (bilateral rows: u = 0, λ free) is
// Φ(λ) = min(λ, ρ u) = 0 row by row (ρ_i = 1 / W_ii > 0 only scales). For a given active
// set A = {i : λ_i - ρ_i u_i > 0} ∪ {bilateral rows} and its complement I, the generalised
// Jacobian of Φ has rows ρ_i W_i on A and e_iᵀ on I, so the semismooth Newton step lands on
//   λ_I = 0,   W_AA λ_A = -q_A,
// whatever the current λ (the step is the primal-dual active-set method of Hintermüller,
// Ito and Kunisch). W_AA is a principal submatrix of the symmetric positive (semi)definite
// W, so it is factorised by LDLᵀ, not LU: half the work and no pivoting across rows. The
// next set follows from the new λ and u: a row with λ_i <= 0 leaves A, one with u_i < 0
// joins it. When the set repeats, λ solves the LCP up to the conditioning of W_AA; one step
// of iterative refinement (residual u_A of the true W) removes round-off and any asymmetry
// below kSymmetryTolerance. The method is exact in finitely many steps when W is an
// M-matrix and locally exact in one step once the set is right, which a warm start from
// the previous solve (the last active set, by contact id) usually provides; elsewhere it
// can cycle, so it is capped and runNewton's globalised Newton continues from the best
// iterate.
//
// Sticking contacts (a scene at rest). A frictional contact that sticks has u = 0 on all
// three rows: its tangent rows are equalities, as a bilateral contact's, tied to its normal
// row's activity (λ_t = 0 where the contact opens). The same iteration then solves for
// every contact sticking at once, and the natural-map residual (cone included) decides:
// exact when the set is right and every ‖λ_t‖ <= μ λ_n, a failure (some contact slides)
// otherwise, found as soon as the normal set repeats. Resting robots and piles (MuJoCo's
// humanoids: every contact sticks) end in one or two Cholesky steps where Gauss-Seidel
// needs a sweep per digit and the general Newton several LU steps. Only where W_AA is
// gathered dense, and only positive definite: singular sticking rows (a face's corners on a
// rigid stack, no diagonal shift) have many force solutions, and the cone test of the one a
// pivoted LDLᵀ picks says nothing about the others.
//
// Factorisation: small or dense W: W_AA gathered into a dense matrix, LLᵀ (choleskyInPlace:
// column by column up to 120 rows, Eigen's blocked form above, several times faster than its
// unblocked LDLᵀ at a few hundred rows). A W_AA that is only
// semidefinite (redundant rows, no diagonal shift) gets a pivoted LDLᵀ whose zero pivots
// are dropped: one of the many solutions when W_AA λ_A = -q_A is consistent, which the
// residual then confirms. From the second step on, the set usually differs from the last one
// in a few rows (MuJoCo's cloth at 1e-3: 238 active rows, then 58, 20 and 5 dropped, 2-4
// added), and the factor follows from the last one where that costs well under a new one.
// Let the last factor be L (W_AA = L Lᵀ, rows in its own order), K the rows kept, D those
// dropped, E those added. Restricted to the kept rows, W_KK = L_K L_Kᵀ = T Tᵀ + Σ_{d∈D} x_d x_dᵀ,
// where T is L's lower-triangular K×K block and x_d the dropped column d on the kept rows (zero
// above d). So T absorbs each x_d by a rank-1 Cholesky update (stable: an update, never a
// downdate), costing (rows after d)² each. The new rows are then appended: T_EK = W_EK T⁻ᵀ by a
// triangular solve, and T_EE = chol(W_EE − T_EK T_EKᵀ). A Schur complement that is not
// positive definite means the new W_AA is not either: the full factorization decides then.
// Larger sparse
// W: Eigen's SimplicialLDLT on a matrix with W's full pattern in which the
// rows and columns of I are replaced by the identity, so the pattern (and the AMD ordering
// and elimination tree, analysed once per solve) is the same at every iteration.
#include "newton_symmetric.h"
#include "thread_workspace.h"

#include "lcp_contact_solver/core/residual.h"

#include <Eigen/Cholesky>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <variant>

namespace lcp_contact_solver::core {
namespace {

constexpr int kMaxSteps = 30;
// Sticking: the normal set settles in a few steps or a contact slides; no cycling allowed.
constexpr int kMaxStickSteps = 8;
// A friction force this close to its cone's edge is taken as sliding (Gauss-Seidel puts a
// sliding contact's force on the edge, to round-off).
constexpr double kStrictlyInside = 1.0 - 1e-6;
constexpr double kSymmetryTolerance = 1e-10;  // |W_ij - W_ji| relative to the largest |W_ii|
constexpr int kDenseMaxRows = 128;            // block-sparse W up to this size (or ≥ 1/4 full) goes dense

// kTangent: a friction row of a contact assumed to stick, active exactly when its normal
// row (the row before it, through tangent 1) is.
enum class Role : std::uint8_t { kZero, kUnilateral, kEquality, kTangent };

// Row roles; false when some active contact is not an LCP row (with `stick`: a frictional
// contact whose friction rows are taken as sticking equalities is one).
bool rowRoles(const SolveContext& ctx, bool stick, std::vector<Role>* roles) {
  const Problem& p = *ctx.problem;
  roles->assign(ctx.offsets.back(), Role::kZero);
  for (std::size_t i = 0; i < p.contacts.size(); ++i) {
    if (ctx.ignored[i]) continue;
    const Contact& c = p.contacts[i];
    const int off = ctx.offsets[i];
    switch (c.type) {
      case ContactType::kFrictionless: (*roles)[off] = Role::kUnilateral; break;
      case ContactType::kFrictional:
        (*roles)[off] = Role::kUnilateral;  // with μ = 0 the tangent rows stay zero
        if (ctx.mu[i] != 0.0) {
          if (!stick) return false;
          (*roles)[off + 1] = (*roles)[off + 2] = Role::kTangent;
        }
        break;
      case ContactType::kBilateral:
        for (int k = 0; k < c.rows; ++k) (*roles)[off + k] = Role::kEquality;
        break;
      default: return false;
    }
  }
  return true;
}

class ReducedSystem {
 public:
  virtual ~ReducedSystem() = default;
  // Factorises W_AA (+ r I); false when it is not positive definite (or, with
  // `semidefinite`, not positive semidefinite).
  virtual bool factorize(const std::vector<char>& active, bool semidefinite) = 0;
  // x_A = W_AA⁻¹ rhs_A, x_I = 0.
  virtual void solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& x) = 0;
  // u = (W + r I) λ, from the system's own copy (dense for small W: no block loop).
  virtual void multiply(const Eigen::VectorXd& lambda, Eigen::VectorXd& u) const = 0;
  virtual void diagonal(Eigen::VectorXd& d) const = 0;  // of W + r I
};

// Dense storage of one solve, kept per thread (in ActiveSetScratch): the islands of a solve
// (and the solves of a stream) reuse its capacity, so a small island's Newton allocates no
// matrix.
struct DenseScratch {
  std::vector<double> W, M, T, b;
  Eigen::VectorXd y;  // the semidefinite solve's permuted right-hand side
  std::vector<int> index, kept, dropped, added;  // the factor's rows; an update's positions and rows
  std::vector<char> mark;
  std::unique_ptr<Eigen::LDLT<Eigen::MatrixXd, Eigen::Lower>> ldlt;  // the semidefinite case
  Eigen::MatrixXd A;
};

class DenseReduced : public ReducedSystem {
 public:
  // W + r I is written by the caller into W() (n × n, column-major).
  DenseReduced(DenseScratch& s, int n) : s_(s), n_(n) { s_.W.resize(static_cast<std::size_t>(n) * n); }
  // The storage of a W of up to kKeptDenseRows rows is kept for the next solve
  // (thread_workspace.h: freed, its pages fault again); a larger one is freed, the scratch
  // being per thread.
  ~DenseReduced() override {
    constexpr std::size_t kKeep = static_cast<std::size_t>(kKeptDenseRows) * kKeptDenseRows;
    if (s_.W.capacity() > kKeep) std::vector<double>().swap(s_.W);
    if (s_.M.capacity() > kKeep) std::vector<double>().swap(s_.M);
    if (s_.T.capacity() > kKeep) std::vector<double>().swap(s_.T);
    if (s_.A.size() > static_cast<Eigen::Index>(kKeep)) {
      s_.A.resize(0, 0);
      s_.ldlt.reset();
    }
  }
  Eigen::Map<Eigen::MatrixXd> W() { return {s_.W.data(), n_, n_}; }
  bool factorize(const std::vector<char>& active, bool semidefinite) override {
    if (factored_ && !semidefinite_ && updateFactor(active)) return true;
    factored_ = false;
    s_.index.clear();
    for (int i = 0; i < n_; ++i)
      if (active[i]) s_.index.push_back(i);
    m_ = static_cast<int>(s_.index.size());
    s_.M.resize(static_cast<std::size_t>(m_) * m_);
    Eigen::Map<Eigen::MatrixXd> M(s_.M.data(), m_, m_);
    const Eigen::Map<const Eigen::MatrixXd> W(s_.W.data(), n_, n_);
    for (int c = 0; c < m_; ++c)
      for (int r = c; r < m_; ++r) M(r, c) = W(s_.index[r], s_.index[c]);  // LLT reads the lower half
    // In place (fails unless W_AA > 0): L overwrites M's lower half.
    semidefinite_ = false;
    if (choleskyInPlace(M)) return factored_ = true;
    return semidefinite && factorizeSemidefinite();
  }
  void solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& x) override {
    x.setZero(rhs.size());
    if (m_ == 0) return;
    s_.b.resize(m_);
    Eigen::Map<Eigen::VectorXd> b(s_.b.data(), m_);
    for (int k = 0; k < m_; ++k) b[k] = rhs[s_.index[k]];
    if (semidefinite_) {
      solveSemidefinite(b);
    } else {
      const Eigen::Map<const Eigen::MatrixXd> L(s_.M.data(), m_, m_);
      L.triangularView<Eigen::Lower>().solveInPlace(b);
      L.triangularView<Eigen::Lower>().adjoint().solveInPlace(b);
    }
    for (int k = 0; k < m_; ++k) x[s_.index[k]] = b[k];
  }
  void multiply(const Eigen::VectorXd& lambda, Eigen::VectorXd& u) const override {
    u.noalias() = Eigen::Map<const Eigen::MatrixXd>(s_.W.data(), n_, n_) * lambda;
  }
  void diagonal(Eigen::VectorXd& d) const override {
    d = Eigen::Map<const Eigen::MatrixXd>(s_.W.data(), n_, n_).diagonal();
  }

 private:
  // W_AA only semidefinite: redundant rows (more contacts than the bodies' degrees of freedom,
  // a box's four corners on a plane) with no diagonal shift. W_AA λ_A = -q_A then has many
  // solutions when it is consistent; a pivoted LDLᵀ whose zero pivots are dropped gives one,
  // and the caller's residual check accepts it or not. Before, the active-set path gave up
  // here for the general Newton (2x the time on a 2-row rank-1 LCP). Indefinite: false.
  bool factorizeSemidefinite() {
    const Eigen::Map<const Eigen::MatrixXd> W(s_.W.data(), n_, n_);
    Eigen::MatrixXd& A = s_.A;
    A.resize(m_, m_);
    for (int c = 0; c < m_; ++c)
      for (int r = c; r < m_; ++r) A(r, c) = W(s_.index[r], s_.index[c]);
    if (!s_.ldlt) s_.ldlt = std::make_unique<Eigen::LDLT<Eigen::MatrixXd, Eigen::Lower>>();
    s_.ldlt->compute(A);
    const Eigen::VectorXd& D = s_.ldlt->vectorD();
    const double largest = D.cwiseAbs().maxCoeff();
    if (!(largest > 0.0) || !D.allFinite()) return false;
    zero_pivot_ = kZeroPivot * largest;
    if (D.minCoeff() < -zero_pivot_) return false;
    semidefinite_ = true;
    return true;
  }
  // x = Pᵀ L⁻ᵀ D⁺ L⁻¹ P b, D⁺ dropping the zero pivots.
  void solveSemidefinite(Eigen::Map<Eigen::VectorXd>& b) const {
    Eigen::VectorXd& y = s_.y;
    y = s_.ldlt->transpositionsP() * b;
    s_.ldlt->matrixL().solveInPlace(y);
    const Eigen::VectorXd& D = s_.ldlt->vectorD();
    for (int k = 0; k < m_; ++k) y[k] = D[k] > zero_pivot_ ? y[k] / D[k] : 0.0;
    s_.ldlt->matrixU().solveInPlace(y);
    b = s_.ldlt->transpositionsP().transpose() * y;
  }
  static constexpr double kZeroPivot = 1e-12;  // relative to the largest pivot

  // The next step's set differs from the last one's in a few rows: its factor follows from
  // the last one (derivation above the class) where that costs well under a new
  // factorization; false (nothing changed) otherwise, or where a new pivot is not positive.
  bool updateFactor(const std::vector<char>& active) {
    s_.kept.clear();
    s_.dropped.clear();
    s_.added.clear();
    s_.mark.assign(n_, 0);
    for (int k = 0; k < m_; ++k) {
      (active[s_.index[k]] ? s_.kept : s_.dropped).push_back(k);
      s_.mark[s_.index[k]] = 1;
    }
    for (int i = 0; i < n_; ++i)
      if (active[i] && !s_.mark[i]) s_.added.push_back(i);
    const int q = static_cast<int>(s_.kept.size());
    const int e = static_cast<int>(s_.added.size());
    if (s_.dropped.empty() && e == 0) return true;  // the same set: the same factor
    // Flops: each dropped column a rank-1 update of the kept rows after it, each new row a
    // triangular solve, then their own block; the rank-1 updates run several times slower
    // per flop than the blocked factorization (kUpdateFlopCost).
    const double kq = q, ke = e;
    double update = kq * kq + ke * kq * kq + ke * ke * kq + ke * ke * ke / 3.0;
    for (std::size_t d = 0, r = 0; d < s_.dropped.size(); ++d) {
      while (r < s_.kept.size() && s_.kept[r] < s_.dropped[d]) ++r;
      const double after = static_cast<double>(q - static_cast<int>(r));
      update += 2.0 * after * after;
    }
    const double full = std::pow(static_cast<double>(q + e), 3) / 3.0;
    if (kUpdateFlopCost * update >= full) return false;
    const int m = q + e;
    s_.T.assign(static_cast<std::size_t>(m) * m, 0.0);
    Eigen::Map<Eigen::MatrixXd> T(s_.T.data(), m, m);
    const Eigen::Map<const Eigen::MatrixXd> L(s_.M.data(), m_, m_);
    for (int c = 0; c < q; ++c)
      for (int r = c; r < q; ++r) T(r, c) = L(s_.kept[r], s_.kept[c]);
    // W_KK = T Tᵀ + Σ_d x_d x_dᵀ (x_d: dropped column d on the kept rows): rank-1 updates.
    s_.b.resize(q);
    for (std::size_t d = 0, r0 = 0; d < s_.dropped.size(); ++d) {
      while (r0 < s_.kept.size() && s_.kept[r0] < s_.dropped[d]) ++r0;
      for (int r = static_cast<int>(r0); r < q; ++r) s_.b[r] = L(s_.kept[r], s_.dropped[d]);
      for (int k = static_cast<int>(r0); k < q; ++k) {
        const double tkk = T(k, k), xk = s_.b[k];
        const double rkk = std::hypot(tkk, xk);
        if (!(tkk > 0.0) || !std::isfinite(rkk)) return false;
        const double c = rkk / tkk, sn = xk / tkk;
        T(k, k) = rkk;
        for (int r = k + 1; r < q; ++r) {
          const double t = (T(r, k) + sn * s_.b[r]) / c;
          s_.b[r] = c * s_.b[r] - sn * t;
          T(r, k) = t;
        }
      }
    }
    // New rows E: T_EK = W_EK T_KK⁻ᵀ, T_EE = chol(W_EE - T_EK T_EKᵀ).
    const Eigen::Map<const Eigen::MatrixXd> W(s_.W.data(), n_, n_);
    if (e > 0) {
      for (int a = 0; a < e; ++a)
        for (int c = 0; c < q; ++c) T(q + a, c) = W(s_.added[a], s_.index[s_.kept[c]]);
      auto TEK = T.block(q, 0, e, q);
      if (q > 0) {
        const auto TKK = T.topLeftCorner(q, q).triangularView<Eigen::Lower>();
        TKK.transpose().solveInPlace<Eigen::OnTheRight>(TEK);
      }
      for (int a = 0; a < e; ++a)
        for (int b = a; b < e; ++b) T(q + b, q + a) = W(s_.added[b], s_.added[a]);
      auto TEE = T.block(q, q, e, e);
      if (q > 0) TEE.selfadjointView<Eigen::Lower>().rankUpdate(TEK, -1.0);
      if (!choleskyInPlace(TEE)) return false;
    }
    if (!T.diagonal().allFinite()) return false;
    // The new order: the kept rows as they were, then the new ones.
    for (int r = 0; r < q; ++r) s_.kept[r] = s_.index[s_.kept[r]];
    s_.index.assign(s_.kept.begin(), s_.kept.end());
    s_.index.insert(s_.index.end(), s_.added.begin(), s_.added.end());
    s_.M.swap(s_.T);
    m_ = m;
    return true;
  }
  static constexpr double kUpdateFlopCost = 4.0;

  DenseScratch& s_;
  int n_ = 0, m_ = 0;
  bool factored_ = false;  // M holds the Cholesky factor of the last set (index's order)
  bool semidefinite_ = false;
  double zero_pivot_ = 0.0;
};

class SparseReduced : public ReducedSystem {
 public:
  // `S`: W + r I with every diagonal entry stored, compressed, both triangles.
  explicit SparseReduced(Eigen::SparseMatrix<double> S) : S_(std::move(S)), K_(S_) {
    ldlt_.analyzePattern(K_);
  }
  bool factorize(const std::vector<char>& active, bool /*semidefinite: not handled*/) override {
    const int n = static_cast<int>(S_.cols());
    const double* w = S_.valuePtr();
    double* k = K_.valuePtr();
    const int* outer = S_.outerIndexPtr();
    const int* inner = S_.innerIndexPtr();
    for (int c = 0; c < n; ++c)
      for (int p = outer[c]; p < outer[c + 1]; ++p) {
        const int r = inner[p];
        k[p] = active[r] && active[c] ? w[p] : (r == c ? 1.0 : 0.0);
      }
    ldlt_.factorize(K_);
    return ldlt_.info() == Eigen::Success && ldlt_.vectorD().minCoeff() > 0.0;
  }
  void solve(const Eigen::VectorXd& rhs, Eigen::VectorXd& x) override { x = ldlt_.solve(rhs); }
  void multiply(const Eigen::VectorXd& lambda, Eigen::VectorXd& u) const override {
    u.noalias() = S_ * lambda;
  }
  void diagonal(Eigen::VectorXd& d) const override { d = S_.diagonal(); }

 private:
  Eigen::SparseMatrix<double> S_, K_;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower, Eigen::AMDOrdering<int>> ldlt_;
};

// W_AA is gathered dense (small, dense, or block-sparse at least a quarter full).
bool denseSystem(const SolveContext& ctx) {
  const int n = ctx.offsets.back();
  const auto* blocks = std::get_if<BlockSparseMatrix>(&ctx.problem->W);
  return blocks == nullptr || n <= kDenseMaxRows || 4.0 * static_cast<double>(blocks->values.size()) >= double(n) * n;
}

// f(row, column, value) for every entry of W's stored blocks.
template <typename F>
void forEachStoredEntry(const BlockSparseMatrix& B, F&& f) {
  for (int bi = 0; bi < B.blockCount(); ++bi)
    for (int s = B.row_start[bi]; s < B.row_start[bi + 1]; ++s) {
      const int bj = B.block_col[s];
      const int r0 = B.block_offset[bi], rows = B.block_offset[bi + 1] - r0;
      const int c0 = B.block_offset[bj], cols = B.block_offset[bj + 1] - c0;
      const double* v = B.values.data() + B.value_start[s];
      for (int r = 0; r < rows; ++r)
        for (int c = 0; c < cols; ++c) f(r0 + r, c0 + c, v[r * cols + c]);
    }
}

// W + r I gathered into `system` (its storage the thread's scratch); false when W is not
// symmetric to kSymmetryTolerance.
bool gatherDense(const SolveContext& ctx, DenseReduced& system) {
  const Problem& p = *ctx.problem;
  const int n = ctx.offsets.back();
  const auto* dense = std::get_if<Eigen::MatrixXd>(&p.W);
  Eigen::Map<Eigen::MatrixXd> W = system.W();
  if (dense != nullptr) {
    W = *dense;
  } else {  // scatter the blocks (toDense's temporaries cost more than the island's solve)
    W.setZero();
    forEachStoredEntry(std::get<BlockSparseMatrix>(p.W), [&](int r, int c, double w) { W(r, c) = w; });
  }
  W.diagonal().array() += ctx.regularization;
  const double limit = kSymmetryTolerance * (n > 0 ? W.diagonal().cwiseAbs().maxCoeff() : 0.0);
  for (int c = 0; c < n; ++c)
    for (int r = c + 1; r < n; ++r)
      if (std::abs(W(r, c) - W(c, r)) > limit) return false;
  return true;
}

// W + r I as a sparse system (block-sparse W), or null when W is not symmetric to
// kSymmetryTolerance.
std::unique_ptr<ReducedSystem> makeSparseSystem(const SolveContext& ctx) {
  const Problem& p = *ctx.problem;
  const int n = ctx.offsets.back();
  const auto& B = std::get<BlockSparseMatrix>(p.W);
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(B.values.size() + n);
  for (int i = 0; i < n; ++i) triplets.emplace_back(i, i, ctx.regularization);
  forEachStoredEntry(B, [&](int r, int c, double w) { triplets.emplace_back(r, c, w); });
  Eigen::SparseMatrix<double> S(n, n);
  S.setFromTriplets(triplets.begin(), triplets.end());
  S.makeCompressed();
  const double scale = S.diagonal().cwiseAbs().maxCoeff();
  const Eigen::SparseMatrix<double> T = S.transpose();
  const Eigen::SparseMatrix<double> D = S - T;
  for (int k = 0; k < D.nonZeros(); ++k)
    if (std::abs(D.valuePtr()[k]) > kSymmetryTolerance * scale) return nullptr;
  // The pattern of S must be symmetric too (it is when the values are): K reuses it.
  if (T.nonZeros() != S.nonZeros()) return nullptr;
  return std::make_unique<SparseReduced>(std::move(S));
}

// The iteration's vectors and its dense storage, kept per thread: MuJoCo's islands and the
// microsecond LCPs run this path once per solve, where its allocations had cost a fifth of
// the solve.
struct ActiveSetScratch {
  std::vector<Role> roles;
  Eigen::VectorXd rho, u, rhs, x, correction, best;
  std::vector<char> active, next;
  DenseScratch dense;
};

// One thread-local lookup per solve. Not inlined: in a shared library the compiler otherwise
// recomputes a thread_local's address (a call) wherever it reuses it (200 calls per solve).
[[gnu::noinline]] ActiveSetScratch& activeSetScratch() {
  thread_local ActiveSetScratch scratch;
  return scratch;
}

// The active-set iteration of solveSymmetricActiveSet (`stick` false) and
// solveStickingActiveSet (true).
bool activeSetNewton(const SolveContext& ctx, bool stick, int max_steps, int dense_rows, Eigen::VectorXd& lambda,
                     KernelReport* report) {
  const Problem& problem = *ctx.problem;
  const SolverParams& params = *ctx.params;
  report->iterations = 0;
  ActiveSetScratch& scratch = activeSetScratch();
  std::vector<Role>& roles = scratch.roles;
  if (problem.bodies || !rowRoles(ctx, stick, &roles)) return false;
  if (stick && !stickingPathApplies(ctx, dense_rows)) return false;
  const int n = ctx.offsets.back();
  // A dense system is a view of the thread's scratch, made on the stack: no allocation on a
  // microsecond LCP or a small island.
  const bool gather_dense = denseSystem(ctx) || (stick && n <= dense_rows);
  std::optional<DenseReduced> dense;
  std::unique_ptr<ReducedSystem> sparse;
  ReducedSystem* system = nullptr;
  if (gather_dense) {
    dense.emplace(scratch.dense, n);
    if (gatherDense(ctx, *dense)) system = &*dense;
  } else {
    sparse = makeSparseSystem(ctx);
    system = sparse.get();
  }
  if (system == nullptr) return false;

  // ρ_i = 1 / (W_ii + r): only the sign of λ_i - ρ_i u_i matters, ρ keeps it scale-free.
  Eigen::VectorXd& rho = scratch.rho;
  system->diagonal(rho);
  for (int i = 0; i < n; ++i) rho[i] = rho[i] > 0.0 ? 1.0 / rho[i] : 1.0;
  Eigen::VectorXd &u = scratch.u, &rhs = scratch.rhs, &x = scratch.x, &correction = scratch.correction;
  rhs.resize(n);
  auto velocities = [&](const Eigen::VectorXd& l) {
    system->multiply(l, u);
    u += problem.d_free;
  };
  velocities(lambda);
  // The start's residual, unless the caller measured it already (auto: the same measure).
  double best_residual = !stick && !std::isnan(ctx.start_residual)
                             ? ctx.start_residual
                             : naturalMapResidual(problem, ctx.mu, lambda, u, ctx.ignored);
  Eigen::VectorXd& best = scratch.best;
  best = lambda;
  if (best_residual <= params.tolerance) {  // the warm start solves it already
    report->status = SolveStatus::kConverged;
    report->solver_error = best_residual;
    return true;
  }
  std::vector<char>& active = scratch.active;
  std::vector<char>& next = scratch.next;
  active.assign(n, 0);
  next.assign(n, 0);
  auto chooseSet = [&](const Eigen::VectorXd& l, std::vector<char>& set) {
    for (int i = 0; i < n; ++i)  // a tangent row is never row 0: its normal row precedes it
      set[i] = roles[i] == Role::kEquality || (roles[i] == Role::kUnilateral && l[i] - rho[i] * u[i] > 0.0) ||
               (roles[i] == Role::kTangent && set[i - 1]);
  };
  chooseSet(lambda, active);
  bool refined = false;
  for (int step = 0; step < max_steps && step < params.maxIt; ++step) {
    if (step > 0 && ctx.deadlinePassed()) break;
    ++report->iterations;
    if (!system->factorize(active, !stick)) break;  // W_AA singular: forces not unique
    for (int i = 0; i < n; ++i) rhs[i] = active[i] ? -problem.d_free[i] : 0.0;
    system->solve(rhs, x);
    if (!x.allFinite()) break;
    lambda = x;
    velocities(lambda);
    double residual = naturalMapResidual(problem, ctx.mu, lambda, u, ctx.ignored);
    chooseSet(lambda, next);
    if (next == active && residual > params.tolerance && !refined) {
      // Right set, round-off (or asymmetry) left: one refinement step with the true W.
      refined = true;
      for (int i = 0; i < n; ++i) rhs[i] = active[i] ? u[i] : 0.0;
      system->solve(rhs, correction);
      lambda -= correction;
      velocities(lambda);
      residual = naturalMapResidual(problem, ctx.mu, lambda, u, ctx.ignored);
      chooseSet(lambda, next);
    }
    if (residual < best_residual) {
      best_residual = residual;
      best = lambda;
    }
    if (residual <= params.tolerance) {
      report->status = SolveStatus::kConverged;
      report->solver_error = residual;
      // A fixed text (the steps are report->iterations): composing one had cost a tenth of a
      // 2-row LCP's solve.
      report->message = stick ? "sticking active-set Newton on symmetric W (Cholesky)"
                              : "active-set Newton on symmetric W (Cholesky)";
      return true;
    }
    // The set is right but the tolerance is out of reach (with `stick`: some contact's
    // friction leaves its cone, so it slides).
    if (next == active) break;
    active.swap(next);
  }
  lambda = best;
  return false;
}

}  // namespace

// Column by column (Cholesky-Crout): L_kk = √(a_kk − ‖L_k,0:k‖²), then the column
// below it, (a_k+1:n,k − L_k+1:n,0:k L_k,0:kᵀ) / L_kk, one matrix-vector product per column.
// Eigen's blocked LLᵀ pays a packing step per panel that only pays back on larger matrices:
// bench/cholesky_forms.cpp (docs/BENCHMARKS.md) measures the crossover.
bool columnCholeskyInPlace(Eigen::Ref<Eigen::MatrixXd> a) {
  const Eigen::Index n = a.rows();
  for (Eigen::Index k = 0; k < n; ++k) {
    const double pivot = a(k, k) - a.row(k).head(k).squaredNorm();
    if (!(pivot > 0.0)) return false;
    const double diagonal = std::sqrt(pivot);
    a(k, k) = diagonal;
    const Eigen::Index below = n - k - 1;
    if (below == 0) break;
    if (k > 0) a.col(k).tail(below).noalias() -= a.bottomLeftCorner(below, k) * a.row(k).head(k).transpose();
    a.col(k).tail(below) /= diagonal;
  }
  return true;
}

bool choleskyInPlace(Eigen::Ref<Eigen::MatrixXd> a) {
  if (a.rows() <= kColumnCholeskyRows) return columnCholeskyInPlace(a);
  return Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>, Eigen::Lower>(a).info() == Eigen::Success;
}

bool symmetricLcp(const SolveContext& ctx) {
  std::vector<Role> roles;
  return !ctx.problem->bodies && rowRoles(ctx, false, &roles);
}

bool solveSymmetricActiveSet(const SolveContext& ctx, Eigen::VectorXd& lambda, KernelReport* report) {
  return activeSetNewton(ctx, false, kMaxSteps, 0, lambda, report);
}

bool allSticking(const SolveContext& ctx, const Eigen::VectorXd& lambda) {
  const Problem& p = *ctx.problem;
  bool any = false;
  for (std::size_t i = 0; i < p.contacts.size(); ++i) {
    if (ctx.ignored[i] || ctx.mu[i] == 0.0) continue;
    if (p.contacts[i].type != ContactType::kFrictional) {
      if (hasSlidingFriction(p.contacts[i].type)) return false;
      continue;
    }
    const int off = ctx.offsets[i];
    const double normal = lambda[off];
    if (!(normal > 0.0)) continue;
    const double tangent = std::hypot(lambda[off + 1], lambda[off + 2]);
    if (!(tangent < kStrictlyInside * ctx.mu[i] * normal)) return false;
    any = true;
  }
  return any;
}

bool stickingPathApplies(const SolveContext& ctx, int dense_rows) {
  return !ctx.problem->bodies && (denseSystem(ctx) || ctx.offsets.back() <= dense_rows);
}

bool solveStickingActiveSet(const SolveContext& ctx, Eigen::VectorXd& lambda, KernelReport* report, int dense_rows) {
  return activeSetNewton(ctx, true, kMaxStickSteps, dense_rows, lambda, report);
}

}  // namespace lcp_contact_solver::core
