// Lexicographic Lemke pivoting for the frictionless part of the contact problem.
#include "lcp_contact_solver/core/kernels/kernels.h"
#include "lcp_contact_solver/core/residual.h"
#include "thread_workspace.h"

#include <Eigen/Core>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>
#include <string>
#include <utility>
#include <variant>
#include <vector>

namespace lcp_contact_solver::core {
namespace {

// Relative size below which an entering-column entry does not count as positive.
constexpr double kPivotTolerance = 1e-12;
// Rounding noise, relative to the magnitudes a tableau entry is computed from. On
// degenerate problems many entries are exactly zero in exact arithmetic but come out as
// ±1e-16..1e-14 times their row's scale; below this bound they count as zero, so that
// they tie and go to the lexicographic rule instead of deciding the pivot by noise (which
// makes the method cycle, e.g. on lcp_tobenna.dat).
constexpr double kRoundoffTolerance = 1e-12;
// Relative difference under which two ratios count as equal.
constexpr double kTieTolerance = 1e-12;
// Rounds of iterative refinement of the final basic solution.
constexpr int kRefinementRounds = 2;
// Largest LCP Lemke takes on: its dense tableau, M and the dense W need 3 × 8 n² bytes
// (400 MB at this size) and O(n²) per pivot. Larger problems are refused with
// not_applicable before anything is allocated, so a large problem (or a hostile message
// with solver=lemke) cannot end in an allocation failure.
constexpr long long kMaxLemkeSize = 4096;

using RowMajorMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// One LCP variable: a row of the problem and the sign with which it enters the force.
// Unilateral rows give one variable (sign +1); bilateral rows give two (+1 and -1) with
// λ = λ⁺ - λ⁻.
struct LcpVariable {
  int row = 0;
  double sign = 1.0;
};

// The LCP w = M z + q assembled from the active rows of the problem.
// M's storage keeps its capacity from one problem to the next (thread_workspace.h).
struct LcpData {
  std::vector<LcpVariable> variables;
  std::vector<double> m_storage;  // M, column-major: the entering column of z_j is M.col(j)
  Eigen::VectorXd q;
  Eigen::Map<Eigen::MatrixXd> M() { return {m_storage.data(), q.size(), q.size()}; }
  Eigen::Map<const Eigen::MatrixXd> M() const { return {m_storage.data(), q.size(), q.size()}; }
};

void buildLcp(const SolveContext& ctx, const std::vector<int>& offsets, LcpData& lcp) {
  const Problem& problem = *ctx.problem;
  lcp.variables.clear();
  for (std::size_t c = 0; c < problem.contacts.size(); ++c) {
    if (!ctx.ignored.empty() && ctx.ignored[c]) continue;
    const Contact& contact = problem.contacts[c];
    const int first = offsets[c];
    switch (contact.type) {
      case ContactType::kFrictional:  // μ = 0 here: the normal row only
      case ContactType::kFrictionless: lcp.variables.push_back({first, 1.0}); break;
      case ContactType::kBilateral:
        for (int k = 0; k < offsets[c + 1] - first; ++k) {
          lcp.variables.push_back({first + k, 1.0});
          lcp.variables.push_back({first + k, -1.0});
        }
        break;
      case ContactType::kTorsional:  // refused before any kernel runs (contact_solver.cpp)
      case ContactType::kRolling: break;
    }
  }
  const int n = static_cast<int>(lcp.variables.size());
  // A dense W is read in place (no copy on a microsecond solve).
  Eigen::MatrixXd converted;
  const auto* dense = std::get_if<Eigen::MatrixXd>(&problem.W);
  if (dense == nullptr) converted = toDense(problem.W);
  const Eigen::MatrixXd& W = dense != nullptr ? *dense : converted;
  lcp.m_storage.resize(static_cast<std::size_t>(n) * n);
  lcp.q.resize(n);
  Eigen::Map<Eigen::MatrixXd> M = lcp.M();
  for (int j = 0; j < n; ++j) {
    const LcpVariable& vj = lcp.variables[j];
    for (int i = 0; i < n; ++i) {
      const LcpVariable& vi = lcp.variables[i];
      double value = W(vi.row, vj.row);
      if (vi.row == vj.row) value += ctx.regularization;
      M(i, j) = vi.sign * vj.sign * value;
    }
    lcp.q(j) = vj.sign * problem.d_free(vj.row);
  }
}

// The contact with friction that makes the problem no LCP, or -1.
int firstFrictionalContact(const SolveContext& ctx, const std::vector<double>& mu) {
  const Problem& problem = *ctx.problem;
  for (std::size_t c = 0; c < problem.contacts.size(); ++c) {
    if (!ctx.ignored.empty() && ctx.ignored[c]) continue;
    if (problem.contacts[c].type == ContactType::kFrictional && mu[c] > 0.0) {
      return static_cast<int>(c);
    }
  }
  return -1;
}

// The basis of the system  I w - M z - e z0 = q  kept as the explicit inverse B⁻¹ (the
// w-columns of the classical tableau) and the basic values B⁻¹ q. Variable numbering:
// w_k = k, z_k = n + k, z0 = 2n.
class LemkeTableau {
 public:
  static constexpr int kPlainLoopSize = 16;

  // The start: every w basic (B⁻¹'s storage keeps its capacity from the last problem).
  void reset(const LcpData& lcp) {
    lcp_ = &lcp;
    n_ = static_cast<int>(lcp.q.size());
    inverse_storage_.resize(static_cast<std::size_t>(n_) * n_);
    inverse().setIdentity();
    values_ = lcp.q;
    basis_.resize(n_);
    for (int i = 0; i < n_; ++i) basis_[i] = i;
  }

  int size() const { return n_; }
  int z0() const { return 2 * n_; }
  int complementOf(int variable) const { return variable < n_ ? variable + n_ : variable - n_; }
  const std::vector<int>& basis() const { return basis_; }
  const Eigen::VectorXd& values() const { return values_; }

  // B⁻¹ times the constraint column of `variable`; returns the column's largest entry
  // before the product (the scale of its rounding error).
  double enteringColumn(int variable, Eigen::VectorXd& column) const {
    if (variable < n_) {
      column = inverse().col(variable);
      return 1.0;
    }
    if (variable < 2 * n_) {
      const Eigen::Map<const Eigen::MatrixXd> M = lcp_->M();
      const auto m = M.col(variable - n_);
      const Eigen::Map<const RowMajorMatrix> inv = inverse();
      if (n_ > kPlainLoopSize) {
        column.noalias() = -(inv * m);
      } else {
        // -B⁻¹ M_j by rows of the row-major B⁻¹: on a few rows a plain loop costs a fraction of
        // a GEMV call's set-up.
        for (int i = 0; i < n_; ++i) {
          const double* row = inv.row(i).data();
          double sum = 0.0;
          for (int k = 0; k < n_; ++k) sum += row[k] * m[k];
          column[i] = -sum;
        }
      }
      return m.cwiseAbs().maxCoeff();
    }
    column = -inverse().rowwise().sum();
    return 1.0;
  }

  // First pivot: z0 enters at the level that makes all w ≥ 0; the w of the most negative
  // q leaves. Among equal q the largest index leaves, which is what keeps every row of
  // [B⁻¹q, B⁻¹] lexicographically positive afterwards (see the comment of runLemke).
  int initialRow() const {
    int row = 0;
    for (int i = 1; i < n_; ++i) {
      if (lcp_->q[i] <= lcp_->q[row]) row = i;
    }
    return row;
  }

  // Lexicographic minimum ratio test on `column` (entering_scale as returned by
  // enteringColumn); -1 if no entry blocks (ray).
  int leavingRow(const Eigen::VectorXd& column, double entering_scale) const {
    const double column_scale = column.cwiseAbs().maxCoeff();
    if (!(column_scale > 0.0)) return -1;
    const double pivot_floor = kPivotTolerance * column_scale;
    const double q_scale = lcp_->q.cwiseAbs().maxCoeff();
    const double value_floor = kRoundoffTolerance * std::max(values_.cwiseAbs().maxCoeff(), q_scale);

    // Candidates: rows whose entry is positive beyond rounding. Row i of B⁻¹ produces both
    // the column entry (B⁻¹_i A_j) and the value (B⁻¹_i q), so its scale bounds their noise.
    candidates_.clear();
    double min_ratio = std::numeric_limits<double>::infinity();
    for (int i = 0; i < n_; ++i) {
      if (column[i] <= pivot_floor) continue;
      const double row_scale = inverse().row(i).cwiseAbs().maxCoeff();
      if (column[i] <= kRoundoffTolerance * row_scale * entering_scale) continue;
      const double noise = std::max(value_floor, kRoundoffTolerance * row_scale * q_scale);
      const double value = values_[i] > noise ? values_[i] : 0.0;
      const double ratio = value / column[i];
      candidates_.push_back({i, ratio, row_scale});
      min_ratio = std::min(min_ratio, ratio);
    }
    if (candidates_.empty()) return -1;

    ties_.clear();
    const double tie_width = kTieTolerance * min_ratio;
    for (const Candidate& c : candidates_) {
      if (c.ratio <= min_ratio + tie_width) ties_.push_back(c);
    }
    // z0 leaving ends the method with a solution, so it wins any tie.
    for (const Candidate& c : ties_) {
      if (basis_[c.row] == z0()) return c.row;
    }
    // Lexicographic rule: compare the rows of B⁻¹ divided by the column entry, one
    // column of B⁻¹ after the other, until one row is left. Entries at rounding level
    // count as the zeros they are.
    for (int col = 0; col < n_ && ties_.size() > 1; ++col) {
      double min_entry = std::numeric_limits<double>::infinity();
      double entry_scale = 0.0;
      for (Candidate& c : ties_) {
        const double raw = inverse()(c.row, col);
        c.ratio = std::abs(raw) <= kRoundoffTolerance * c.row_scale ? 0.0 : raw / column[c.row];
        min_entry = std::min(min_entry, c.ratio);
        entry_scale = std::max(entry_scale, std::abs(c.ratio));
      }
      const double width = kTieTolerance * entry_scale;
      std::size_t kept = 0;
      for (const Candidate& c : ties_) {
        if (c.ratio <= min_entry + width) ties_[kept++] = c;
      }
      ties_.resize(kept);
    }
    // Rows of B⁻¹ are independent, so exact arithmetic leaves one row; if rounding
    // leaves several, the largest pivot is the stablest.
    int best = ties_.front().row;
    for (const Candidate& c : ties_) {
      if (column[c.row] > column[best]) best = c.row;
    }
    return best;
  }

  // Makes `variable` basic in `row`; returns the variable that left.
  int pivot(int row, int variable, const Eigen::VectorXd& column) {
    const double inverse_pivot = 1.0 / column[row];
    inverse().row(row) *= inverse_pivot;
    values_[row] *= inverse_pivot;
    // Eliminate the entering column from the other rows: a rank-one update with the
    // pivot row copied out, so the update never reads a row it is writing.
    pivot_row_ = inverse().row(row);
    multipliers_ = column;
    multipliers_[row] = 0.0;
    inverse().noalias() -= multipliers_ * pivot_row_;
    values_ -= multipliers_ * values_[row];
    const int left = basis_[row];
    basis_[row] = variable;
    return left;
  }

  bool rowFinite(int row) const { return inverse().row(row).allFinite(); }

  // Two rounds of iterative refinement of the basic values with the current B⁻¹:
  // x += B⁻¹ (q - B x). Recovers digits lost to rounding across many pivots.
  Eigen::VectorXd refinedValues() const {
    Eigen::VectorXd x = values_;
    Eigen::VectorXd defect(n_);
    const Eigen::Map<const Eigen::MatrixXd> M = lcp_->M();
    for (int round = 0; round < kRefinementRounds; ++round) {
      defect = lcp_->q;
      for (int i = 0; i < n_; ++i) {
        const int variable = basis_[i];
        if (variable < n_) {
          defect[variable] -= x[i];
        } else if (variable < 2 * n_) {
          defect.noalias() += M.col(variable - n_) * x[i];
        } else {
          defect.array() += x[i];
        }
      }
      x.noalias() += inverse() * defect;
    }
    return x;
  }

  // The z part of the basic solution (`basis`, `values`) as full-length forces, z clipped
  // to ≥ 0.
  void forces(const std::vector<int>& basis, const Eigen::VectorXd& values, int row_count,
              Eigen::VectorXd& lambda) const {
    lambda.setZero(row_count);
    for (int i = 0; i < n_; ++i) {
      const int variable = basis[i];
      if (variable < n_ || variable >= 2 * n_) continue;
      const LcpVariable& v = lcp_->variables[variable - n_];
      const double z = std::isfinite(values[i]) ? std::max(values[i], 0.0) : 0.0;
      lambda[v.row] += v.sign * z;
    }
  }

  double z0Value() const {
    for (int i = 0; i < n_; ++i) {
      if (basis_[i] == z0()) return values_[i];
    }
    return 0.0;
  }

 private:
  Eigen::Map<RowMajorMatrix> inverse() { return {inverse_storage_.data(), n_, n_}; }
  Eigen::Map<const RowMajorMatrix> inverse() const { return {inverse_storage_.data(), n_, n_}; }

  const LcpData* lcp_ = nullptr;
  int n_ = 0;
  std::vector<double> inverse_storage_;  // B⁻¹, row-major: a pivot updates whole rows
  Eigen::VectorXd values_;  // B⁻¹ q, the basic variables' values
  std::vector<int> basis_;  // basic variable of each row

  // Pivot and ratio-test scratch, kept to avoid allocating at every pivot.
  Eigen::VectorXd multipliers_;
  Eigen::RowVectorXd pivot_row_;
  struct Candidate {
    int row;
    double ratio;      // value / entry, then the lexicographic key of the current column
    double row_scale;  // largest |B⁻¹| entry of the row
  };
  mutable std::vector<Candidate> candidates_;
  mutable std::vector<Candidate> ties_;
};

// Everything one solve allocates (thread_workspace.h).
struct LemkeWorkspace {
  LcpData lcp;
  LemkeTableau tableau;
  Eigen::VectorXd column, saved_values, refined;
  std::vector<int> saved_basis;
};

}  // namespace

// Lemke's complementary pivoting, lexicographic variant.
//
// Tableau. The LCP w = M z + q, 0 ≤ z ⟂ w ≥ 0 is written as the linear system
//   I w - M z - e z0 = q,   w, z, z0 ≥ 0,   e = (1, ..., 1),
// with one artificial variable z0. Start with basis w (B = I, values q). If q ≥ 0, z = 0
// solves. Otherwise z0 enters at t = max(-q_i); the w_r of the most negative q_r leaves,
// and all values become q + t e ≥ 0: a feasible, almost complementary basis (the pair
// (w_r, z_r) has both members nonbasic, every other pair exactly one basic member).
// We keep B⁻¹ explicitly: it equals the w-columns of the classical tableau, the entering
// column is B⁻¹ A_j and the values are B⁻¹ q.
//
// Entering rule (complementary): the variable that enters is the complement of the one
// that just left (z_r after w_r left, w_r after z_r left), which keeps the basis almost
// complementary. Leaving rule: the minimum ratio test over rows with a positive column
// entry a_i keeps the values nonnegative. If z0 leaves, the basis is complementary and
// (w, z) solves the LCP. If no a_i is positive, the path runs to infinity (secondary ray):
// no solution found (for copositive-plus M, e.g. W + r I positive semidefinite with the
// bilateral split below, this proves the LCP infeasible).
//
// Why lexicographic. When several rows tie in the ratio test (degenerate problems: a
// basic value is zero or two rows block at the same step), an arbitrary choice can bring
// the method back to a basis it visited, and it cycles forever. Instead we compare the
// rows of [B⁻¹q, B⁻¹] divided by a_i lexicographically and take the smallest. Rows of B⁻¹
// are linearly independent, so the minimum is unique, and every row of [B⁻¹q, B⁻¹] stays
// lexicographically positive. This is the same as solving the LCP with q replaced by
// q + (ε, ε², ..., εⁿ) for an infinitesimal ε > 0, which is nondegenerate: each almost
// complementary basis has at most two neighbours on the path, the path cannot revisit a
// basis, and there are finitely many bases, so the method terminates.
//
// Bilateral rows have free-sign forces: λ = λ⁺ - λ⁻ with λ± ≥ 0, w⁺ = d, w⁻ = -d, so a
// solution has d = 0. For LCP variables k, l of rows r_k, r_l with signs s_k, s_l this
// gives M_kl = s_k s_l (W + r I)_{r_k r_l} and q_k = s_k d_free_{r_k}.
//
// The warm start in `lambda` is not used: Lemke's path always starts at z = 0. After
// convergence the basic solution is polished by iterative refinement with B⁻¹, kept only
// if it lowers the residual.
KernelReport runLemke(const SolveContext& ctx, Eigen::VectorXd& lambda) {
  KernelReport report;
  const Problem& problem = *ctx.problem;
  const SolverParams& params = *ctx.params;
  // The context's offsets and μ, computed here only when a caller left them out.
  std::vector<int> own_offsets;
  std::vector<double> own_mu;
  if (ctx.offsets.empty()) own_offsets = problem.rowOffsets();
  if (ctx.mu.empty()) own_mu = effectiveMu(problem, params.mu);
  const std::vector<int>& offsets = ctx.offsets.empty() ? own_offsets : ctx.offsets;
  const std::vector<double>& mu = ctx.mu.empty() ? own_mu : ctx.mu;
  const int row_count = problem.rowCount();

  const int frictional = firstFrictionalContact(ctx, mu);
  if (frictional >= 0) {
    std::ostringstream message;
    message << "Lemke solves linear complementarity problems, but the problem has friction "
            << "(contact " << frictional << " has mu = " << mu[frictional]
            << "); use nlgs, mu = 0, or a pyramid friction_model (pyramid4, pyramid8), "
            << "which makes the friction an LCP";
    report.status = SolveStatus::kNotApplicable;
    report.message = message.str();
    return report;
  }

  long long variables = 0;
  for (std::size_t c = 0; c < problem.contacts.size(); ++c) {
    if (!ctx.ignored.empty() && ctx.ignored[c]) continue;
    variables += problem.contacts[c].type == ContactType::kBilateral ? 2 * problem.contacts[c].rows : 1;
  }
  if (variables > kMaxLemkeSize || row_count > kMaxLemkeSize) {
    std::ostringstream message;
    message << "Lemke's dense tableau is limited to " << kMaxLemkeSize
            << " variables and rows; this problem has " << variables << " variables on " << row_count
            << " rows (it would need about "
            << 24.0 * static_cast<double>(std::max<long long>(variables, row_count)) *
                   static_cast<double>(std::max<long long>(variables, row_count)) / 1e9
            << " GB); use pgs, nlgs, apgd or newton";
    lambda = Eigen::VectorXd::Zero(row_count);
    report.status = SolveStatus::kNotApplicable;
    report.message = message.str();
    return report;
  }

  // Its M and B⁻¹ are n x n in the LCP's variables, up to two per row (bilateral rows).
  const WorkspaceLease<LemkeWorkspace, kKeptDenseRows / 2> lease(row_count);
  LemkeWorkspace& ws = *lease;
  LcpData& lcp = ws.lcp;
  buildLcp(ctx, offsets, lcp);
  const int n = static_cast<int>(lcp.q.size());
  if (!lcp.q.allFinite() || !lcp.M().allFinite()) {
    lambda = Eigen::VectorXd::Zero(row_count);
    report.status = SolveStatus::kNumericalFailure;
    report.message = "Lemke: the matrix or d_free has non-finite entries";
    report.solver_error = ctx.residual(lambda);
    return report;
  }

  // Trivial case: z = 0 satisfies w = q ≥ 0.
  if (n == 0 || lcp.q.minCoeff() >= 0.0) {
    lambda = Eigen::VectorXd::Zero(row_count);
    report.status = SolveStatus::kConverged;
    report.solver_error = ctx.residual(lambda);
    return report;
  }

  LemkeTableau& tableau = ws.tableau;
  tableau.reset(lcp);
  const bool record = params.displayDebug;
  const int pivot_cap = params.maxIt;
  Eigen::VectorXd& column = ws.column;
  Eigen::VectorXd& saved_values = ws.saved_values;
  std::vector<int>& saved_basis = ws.saved_basis;
  column.resize(n);
  int pivots = 0;
  int entering = tableau.z0();
  SolveStatus status = SolveStatus::kMaxIterations;
  std::string message;

  while (true) {
    if (ctx.deadlinePassed()) {
      std::ostringstream out;
      out << "Lemke ran out of the time budget after " << pivots << " pivots (z0 = " << tableau.z0Value()
          << "); forces are the last basic solution, not an LCP solution";
      status = SolveStatus::kTimeBudget;
      message = out.str();
      break;
    }
    if (pivots >= pivot_cap) {
      std::ostringstream out;
      out << "Lemke hit the pivot cap (maxIt = " << pivot_cap << " pivots) before z0 left "
          << "the basis (z0 = " << tableau.z0Value() << "); forces are the last basic "
          << "solution, not an LCP solution";
      status = SolveStatus::kMaxIterations;
      message = out.str();
      break;
    }
    int row;
    if (pivots == 0) {
      column = Eigen::VectorXd::Constant(n, -1.0);
      row = tableau.initialRow();
    } else {
      const double entering_scale = tableau.enteringColumn(entering, column);
      if (!column.allFinite()) {
        status = SolveStatus::kNumericalFailure;
        message = "Lemke: non-finite tableau entry after " + std::to_string(pivots) + " pivots";
        break;
      }
      row = tableau.leavingRow(column, entering_scale);
      if (row < 0) {
        // Shortest to_chars, not printf or a stream: auto's plans on non-monotone LCPs end here
        // routinely, and formatting z0 to a precision cost a one-pivot Lemke a quarter of its time.
        char z0[32];
        const auto z0_end = std::to_chars(z0, z0 + sizeof z0, tableau.z0Value()).ptr;
        status = SolveStatus::kRayTermination;
        message.reserve(256);
        message.append("Lemke ended on a secondary ray after ").append(std::to_string(pivots)).append(" pivots (z0 = ");
        message.append(z0, z0_end).append(
            "): no solution found; for positive semidefinite M (e.g. frictionless contacts with W + r I) this "
            "means the constraints are infeasible");
        break;
      }
    }
    saved_values = tableau.values();
    saved_basis = tableau.basis();
    const int left = tableau.pivot(row, entering, column);
    ++pivots;
    if (!tableau.values().allFinite() || !tableau.rowFinite(row)) {
      tableau.forces(saved_basis, saved_values, row_count, lambda);
      report.status = SolveStatus::kNumericalFailure;
      report.iterations = pivots;
      report.message = "Lemke: pivot " + std::to_string(pivots) + " produced a non-finite value";
      report.solver_error = ctx.residual(lambda);
      return report;
    }
    if (record) {
      tableau.forces(tableau.basis(), tableau.values(), row_count, ws.refined);
      report.history.push_back(ctx.residual(ws.refined));
    }
    if (left == tableau.z0()) {
      status = SolveStatus::kConverged;
      break;
    }
    entering = tableau.complementOf(left);
  }

  tableau.forces(tableau.basis(), tableau.values(), row_count, lambda);
  double residual = ctx.residual(lambda);
  if (status == SolveStatus::kConverged) {
    Eigen::VectorXd& refined = ws.refined;
    tableau.forces(tableau.basis(), tableau.refinedValues(), row_count, refined);
    const double refined_residual = ctx.residual(refined);
    if (refined_residual < residual) {
      lambda = refined;
      residual = refined_residual;
    }
  }
  report.status = status;
  report.iterations = pivots;
  report.solver_error = residual;
  report.message = std::move(message);
  return report;
}

}  // namespace lcp_contact_solver::core
