#include "lcp_contact_solver/core/kernels/scalar_rows.h"

#include "local_contact_laws.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <variant>

namespace lcp_contact_solver::core {

std::size_t ScalarRows::bytes() const {
  return start.size() * sizeof(int) + index.size() * sizeof(int) + value.size() * sizeof(double);
}

bool fitsScalarRows(const Problem& problem) {
  if (problem.bodies || problem.contacts.empty() || !std::holds_alternative<BlockSparseMatrix>(problem.W))
    return false;
  for (const Contact& c : problem.contacts)
    if (c.rows != 1) return false;
  return true;
}

ScalarRows scalarColumnsOf(const BlockSparseMatrix& W) {
  ScalarRows out;
  const int n = W.blockCount();
  out.n = n;
  out.start.assign(n + 1, 0);
  for (int j : W.block_col) ++out.start[j + 1];
  for (int j = 0; j < n; ++j) out.start[j + 1] += out.start[j];
  out.index.resize(W.block_col.size());
  out.value.resize(W.block_col.size());
  std::vector<int> fill(out.start.begin(), out.start.end() - 1);
  for (int i = 0; i < n; ++i) {  // rows ascending within each column, as the block sweep
    for (int s = W.row_start[i]; s < W.row_start[i + 1]; ++s) {
      const int at = fill[W.block_col[s]]++;
      out.index[at] = i;
      out.value[at] = W.values[W.value_start[s]];
    }
  }
  return out;
}

namespace {

enum RowKind : std::uint8_t { kSkipRow = 0, kUnilateralRow = 1, kBilateralRow = 2 };
// Maintained d drifts by round-off; refresh it exactly this often (sweeps), as the block sweep.
constexpr int kRefreshInterval = 50;

// W_ii of a block-sparse W of 1×1 blocks (0 when not stored).
double storedDiagonal(const BlockSparseMatrix& W, int i) {
  const double* block = W.diagonalValues(i);
  return block ? block[0] : 0.0;
}

}  // namespace

// Derivation (one sweep, maintained d). With d = (W + rI) λ + d_free known, row j alone sees
//   u_j = D_j λ_j + b_j,   D_j = W_jj + r,   b_j = d_j - D_j λ_j,
// and solves its scalar problem exactly: unilateral 0 <= λ_j ⟂ u_j >= 0 gives
// λ_j* = max(0, λ_j - d_j / D_j); bilateral u_j = 0 gives λ_j* = λ_j - d_j / D_j. With
// over-relaxation ω the step is λ_j <- max(0, λ_j + ω(λ_j* - λ_j)) (no max for bilateral).
// Then d += (W + rI) e_j Δλ_j: column j of W, which the CSR of Wᵀ holds contiguously, so the
// update is one walk over that column's stored entries and a row whose force does not move
// (an open contact staying open) costs one read of d_j. A fixed point satisfies every row's
// law with the others' forces: it solves the LCP. Work per sweep: at most one multiply-add per
// stored entry (12 bytes read, d_i read and written) plus a few loads per row; the residual of
// the stopping test reads the maintained d (O(rows), no product with W).
KernelReport runScalarRowGaussSeidel(const SolveContext& ctx, Eigen::VectorXd& lambda) {
  const Problem& problem = *ctx.problem;
  const SolverParams& params = *ctx.params;
  const auto& W = std::get<BlockSparseMatrix>(problem.W);
  const int n = W.blockCount();
  const double r = ctx.regularization;
  const double omega = params.sor;
  KernelReport report;

  // Each row's kind, 1 / (W_ii + r) and W's columns depend on W, the ignored rows and r, not
  // on λ: a caller's memo (kernels.h) forms them once for all its calls.
  GaussSeidelMemo* memo = ctx.gs_memo;
  GaussSeidelMemo own;
  GaussSeidelMemo& rows = memo != nullptr ? *memo : own;
  if (memo == nullptr || memo->rows_problem != ctx.problem || memo->rows_regularization != r) {
    rows.rows_problem = nullptr;
    std::vector<double>& inverse = rows.inverse;
    std::vector<std::uint8_t>& kind = rows.kind;
    inverse.assign(n, 0.0);
    kind.assign(n, kSkipRow);
    for (int i = 0; i < n; ++i) {
      if (!ctx.ignored.empty() && ctx.ignored[i]) continue;
      const Contact& c = problem.contacts[i];
      const double D = storedDiagonal(W, i) + r;
      auto fail = [&](const std::string& what) {
        report.status = SolveStatus::kZeroDiagonal;
        report.message = "contact " + std::to_string(i) + " (id " + std::to_string(c.id) + ") " + what;
        return report;
      };
      if (c.type == ContactType::kBilateral) {
        if (D == 0.0 || !std::isfinite(D)) return fail("has a singular bilateral block of W");
        kind[i] = kBilateralRow;
      } else {
        if (!(D > 0.0)) {
          char value[32];
          std::snprintf(value, sizeof(value), "%.6g", D);
          return fail(std::string("has W_nn = ") + value + " <= 0; set minW or regularizationTerm");
        }
        kind[i] = kUnilateralRow;
      }
      inverse[i] = 1.0 / D;
    }
    rows.columns = scalarColumnsOf(W);
    rows.rows_problem = ctx.problem;
    rows.rows_regularization = r;
  }
  const std::vector<double>& inverse = rows.inverse;
  const std::vector<std::uint8_t>& kind = rows.kind;
  const ScalarRows& columns = rows.columns;
  const int* start = columns.start.data();
  const int* index = columns.index.data();
  const double* value = columns.value.data();

  // The natural-map residual (residual.h; the pyramid's is the same on one-row contacts):
  // e_i = min(λ_i, d_i) on unilateral rows, d_i on bilateral ones, over |d_free|. Its row
  // loop reads two flat arrays and the kinds, not a contact record per row.
  const double q_norm = problem.d_free.norm();
  const double scale = q_norm > 0.0 ? q_norm : 1.0;
  auto residualOf = [&](const Eigen::VectorXd& lv, const Eigen::VectorXd& dv) {
    double sum = 0.0;
    for (int i = 0; i < n; ++i) {
      if (kind[i] == kSkipRow) continue;
      const double e = kind[i] == kUnilateralRow ? std::min(lv[i], dv[i]) : dv[i];
      sum += e * e;
    }
    const double residual = std::sqrt(sum) / scale;
    return std::isfinite(residual) ? residual : std::numeric_limits<double>::max();
  };
  const bool sofa = params.stopping_rule == StoppingRule::kSofa;
  // d from the previous call where this one starts from its last iterate (KeptD).
  Eigen::VectorXd d;
  int since_refresh = 0;
  KeptD* kept = memo != nullptr ? &memo->kept : nullptr;
  if (!(kept != nullptr && kept->take(ctx, lambda, d, &since_refresh))) ctx.computeD(lambda, d);
  auto keepD = [&] {
    if (kept != nullptr) kept->keep(ctx, lambda, d, since_refresh);
  };
  Eigen::VectorXd best = lambda;
  double best_residual = std::numeric_limits<double>::infinity();
  double* l = lambda.data();
  double* dd = d.data();
  for (int sweep = 1; sweep <= params.maxIt; ++sweep) {
    double sofa_error = 0.0;
    for (int j = 0; j < n; ++j) {
      const std::uint8_t k = kind[j];
      if (k == kSkipRow) continue;
      double delta;
      if (k == kUnilateralRow) {
        double next = std::max(0.0, l[j] - dd[j] * inverse[j]);
        if (omega != 1.0) next = std::max(0.0, l[j] + omega * (next - l[j]));
        delta = next - l[j];
        l[j] = next;
      } else {
        delta = -omega * (inverse[j] * dd[j]);
        l[j] += delta;
      }
      if (sofa) sofa_error += std::abs(delta / inverse[j]);
      if (delta == 0.0) continue;
      // Distinct indices in a column: the four updates of an unrolled step are independent.
      int s = start[j];
      const int end = start[j + 1];
      for (; s + 4 <= end; s += 4) {
        const int i0 = index[s], i1 = index[s + 1], i2 = index[s + 2], i3 = index[s + 3];
        const double v0 = value[s] * delta, v1 = value[s + 1] * delta;
        const double v2 = value[s + 2] * delta, v3 = value[s + 3] * delta;
        dd[i0] += v0;
        dd[i1] += v1;
        dd[i2] += v2;
        dd[i3] += v3;
      }
      for (; s < end; ++s) dd[index[s]] += value[s] * delta;
      if (r != 0.0) dd[j] += r * delta;
    }
    report.iterations = sweep;
    if (!lambda.allFinite()) {
      lambda = best;
      report.status = SolveStatus::kNumericalFailure;
      report.message = "the iterate became non-finite in sweep " + std::to_string(sweep) +
                       " (W is probably not positive semidefinite, or a diagonal is so small that the force "
                       "overflows: minW excludes such contacts); best iterate returned";
      return report;
    }
    if (++since_refresh == kRefreshInterval) {
      ctx.computeD(lambda, d);
      since_refresh = 0;
    }
    dd = d.data();
    const bool need_residual = !sofa || params.displayDebug;
    double residual = 0.0;
    if (need_residual) {
      residual = residualOf(lambda, d);
      if (params.displayDebug) report.history.push_back(residual);
      if (residual < best_residual) {
        best_residual = residual;
        best = lambda;
      }
    }
    if (sofa) {
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
        ctx.computeD(lambda, d);
        since_refresh = 0;
        dd = d.data();
        if (confirmConverged(report, residualOf(lambda, d), params.tolerance)) {
          keepD();
          return report;
        }
      }
    }
    if (sweep < params.maxIt && ctx.deadlinePassed()) {
      keepD();
      endOnTimeBudget(report, lambda, best, params.time_budget, sweep);
      return report;
    }
  }
  keepD();
  endOnMaxIt(report, lambda, best, params.maxIt);
  return report;
}

}  // namespace lcp_contact_solver::core
