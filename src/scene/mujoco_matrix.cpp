// The numbers of an extracted problem (mujoco_matrix.h).
#include "mujoco_matrix.h"

#include <algorithm>

namespace lcp_contact_solver {
namespace scene {
namespace detail {

namespace {

// Row e of AR as (column, value) pairs, dense or CSR.
template <typename F>
void forEachARInRow(const mjModel* m, const mjData* d, int e, F&& f) {
  const int n = d->nefc;
  if (mj_isSparse(m)) {
    const int adr = d->efc_AR_rowadr[e];
    for (int k = 0; k < d->efc_AR_rownnz[e]; ++k) f(d->efc_AR_colind[adr + k], d->efc_AR[adr + k]);
  } else {
    const mjtNum* row = d->efc_AR + static_cast<std::size_t>(e) * n;
    for (int c = 0; c < n; ++c)
      if (row[c] != 0.0) f(c, row[c]);
  }
}

}  // namespace

std::vector<int> fillRows(const mjModel* m, const mjData* d, const MujocoExtractOptions& options,
                          const std::vector<double>& scale_of_row, MujocoProblem* out) {
  const int n = static_cast<int>(out->efc_row.size());
  out->row_scale = Eigen::Map<const Eigen::VectorXd>(scale_of_row.data(), n);
  std::vector<int> row_of_efc(d->nefc, -1);
  for (int p = 0; p < n; ++p) row_of_efc[out->efc_row[p]] = p;
  out->problem.d_free.resize(n);
  out->mujoco_lambda.resize(n);
  for (int p = 0; p < n; ++p) {
    const int ep = out->efc_row[p];
    out->problem.d_free[p] = d->efc_b[ep] / out->row_scale[p];
    out->mujoco_lambda[p] = d->efc_force[ep] * out->row_scale[p];
  }
  if (options.fold_dropped && !out->dropped_rows.empty()) {
    std::vector<char> dropped(d->nefc, 0);
    for (int r : out->dropped_rows) dropped[r] = 1;
    for (int p = 0; p < n; ++p) {
      double coupling = 0.0;
      forEachARInRow(m, d, out->efc_row[p], [&](int col, double value) {
        if (dropped[col]) coupling += value * d->efc_force[col];
      });
      out->problem.d_free[p] += coupling / out->row_scale[p];
    }
  }
  return row_of_efc;
}

Eigen::MatrixXd denseW(const mjModel* m, const mjData* d, const MujocoProblem& mp,
                       const std::vector<int>& row_of_efc) {
  const int n = static_cast<int>(mp.efc_row.size());
  Eigen::MatrixXd W = Eigen::MatrixXd::Zero(n, n);
  for (int p = 0; p < n; ++p) {
    forEachARInRow(m, d, mp.efc_row[p], [&](int col, double value) {
      const int q = row_of_efc[col];
      if (q >= 0) W(p, q) = value / (mp.row_scale[p] * mp.row_scale[q]);
    });
  }
  return W;
}

double fillOfW(const mjModel* m, const mjData* d, const MujocoProblem& mp, const std::vector<int>& row_of_efc) {
  const std::size_t n = mp.efc_row.size();
  if (n == 0) return 0.0;
  std::size_t nonzero = 0;
  for (std::size_t p = 0; p < n; ++p)
    forEachARInRow(m, d, mp.efc_row[p], [&](int col, double) { nonzero += row_of_efc[col] >= 0 ? 1 : 0; });
  return static_cast<double>(nonzero) / (static_cast<double>(n) * static_cast<double>(n));
}

core::BlockSparseMatrix blockSparseW(const mjModel* m, const mjData* d, const MujocoProblem& mp,
                                     const std::vector<int>& row_of_efc) {
  const std::vector<int> offsets = mp.problem.rowOffsets();
  const int nb = static_cast<int>(mp.entries.size());
  std::vector<int> entry_of_row(mp.efc_row.size());
  std::vector<int> sizes(nb);
  for (int i = 0; i < nb; ++i) {
    sizes[i] = offsets[i + 1] - offsets[i];
    for (int p = offsets[i]; p < offsets[i + 1]; ++p) entry_of_row[p] = i;
  }
  core::BlockSparseMatrix W = core::BlockSparseMatrix::withBlockSizes(sizes);
  std::vector<int> slot(nb, -1);  // block index of entry j within the current block row
  std::vector<int> cols;
  std::vector<Eigen::MatrixXd> blocks;
  for (int i = 0; i < nb; ++i) {
    cols.clear();
    blocks.clear();
    for (int p = offsets[i]; p < offsets[i + 1]; ++p) {
      forEachARInRow(m, d, mp.efc_row[p], [&](int col, double value) {
        const int q = row_of_efc[col];
        if (q < 0) return;
        const int j = entry_of_row[q];
        if (slot[j] < 0) {
          slot[j] = static_cast<int>(cols.size());
          cols.push_back(j);
          blocks.push_back(Eigen::MatrixXd::Zero(sizes[i], sizes[j]));
        }
        blocks[slot[j]](p - offsets[i], q - offsets[j]) = value / (mp.row_scale[p] * mp.row_scale[q]);
      });
    }
    std::vector<int> order(cols.size());
    for (std::size_t k = 0; k < order.size(); ++k) order[k] = static_cast<int>(k);
    std::sort(order.begin(), order.end(), [&](int a, int b) { return cols[a] < cols[b]; });
    W.beginRow();
    for (int k : order) W.addBlock(cols[k], blocks[k]);
    for (int j : cols) slot[j] = -1;
  }
  return W;
}

}  // namespace detail
}  // namespace scene
}  // namespace lcp_contact_solver
