#include "lcp_contact_solver/core/problem.h"

#include "lcp_contact_solver/core/body_compliance.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <unordered_set>

namespace lcp_contact_solver::core {

int rowsForType(ContactType type) {
  switch (type) {
    case ContactType::kFrictional: return 3;
    case ContactType::kFrictionless: return 1;
    case ContactType::kBilateral: return 1;
    case ContactType::kTorsional: return 4;
    case ContactType::kRolling: return 6;
  }
  return 1;
}

// ---- BlockSparseMatrix --------------------------------------------------------------------

BlockSparseMatrix BlockSparseMatrix::withBlockSizes(const std::vector<int>& sizes) {
  BlockSparseMatrix m;
  m.block_offset.assign(1, 0);
  for (int s : sizes) m.block_offset.push_back(m.block_offset.back() + s);
  m.row_start.assign(1, 0);
  return m;
}

void BlockSparseMatrix::beginRow() {
  if (row_start.empty()) row_start.push_back(0);
  row_start.push_back(static_cast<int>(block_col.size()));
}

void BlockSparseMatrix::addBlock(int col, const Eigen::Ref<const Eigen::MatrixXd>& block) {
  block_col.push_back(col);
  value_start.push_back(static_cast<int>(values.size()));
  for (int r = 0; r < block.rows(); ++r)
    for (int c = 0; c < block.cols(); ++c) values.push_back(block(r, c));
  row_start.back() = static_cast<int>(block_col.size());
}

std::string BlockSparseMatrix::validate() const {
  const int nb = blockCount();
  if (nb < 0) return "block-sparse W has no block offsets";
  if (static_cast<int>(row_start.size()) != nb + 1)
    return "block-sparse W: " + std::to_string(row_start.size() - 1) + " block rows started, " +
           std::to_string(nb) + " expected";
  if (block_col.size() != value_start.size()) return "block-sparse W: block index arrays differ in size";
  if (row_start.front() != 0 || row_start.back() != static_cast<int>(block_col.size()))
    return "block-sparse W: row starts do not cover the stored blocks";
  for (int i = 0; i < nb; ++i) {
    if (block_offset[i + 1] <= block_offset[i]) return "block-sparse W: empty or negative block size";
    if (row_start[i + 1] < row_start[i]) return "block-sparse W: row starts decrease";
  }
  std::size_t expected_value = 0;
  std::vector<int> last_row_seen(nb, -1);  // catches a block (i, j) stored twice
  for (int i = 0; i < nb; ++i) {
    const int ri = block_offset[i + 1] - block_offset[i];
    for (int k = row_start[i]; k < row_start[i + 1]; ++k) {
      const int j = block_col[k];
      if (j < 0 || j >= nb) return "block-sparse W: block column " + std::to_string(j) + " out of range";
      if (last_row_seen[j] == i)
        return "block-sparse W: block (" + std::to_string(i) + ", " + std::to_string(j) + ") stored twice";
      last_row_seen[j] = i;
      if (value_start[k] != static_cast<int>(expected_value))
        return "block-sparse W: block values not contiguous";
      expected_value += static_cast<std::size_t>(ri) * (block_offset[j + 1] - block_offset[j]);
    }
  }
  if (expected_value != values.size())
    return "block-sparse W: " + std::to_string(values.size()) + " values stored, " +
           std::to_string(expected_value) + " expected";
  return "";
}

Eigen::MatrixXd BlockSparseMatrix::toDense() const {
  const int n = rows();
  Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(n, n);
  for (int i = 0; i < blockCount(); ++i) {
    const int ri = block_offset[i + 1] - block_offset[i];
    for (int k = row_start[i]; k < row_start[i + 1]; ++k) {
      const int j = block_col[k];
      const int cj = block_offset[j + 1] - block_offset[j];
      const double* v = values.data() + value_start[k];
      for (int r = 0; r < ri; ++r)
        for (int c = 0; c < cj; ++c) dense(block_offset[i] + r, block_offset[j] + c) += v[r * cj + c];
    }
  }
  return dense;
}

const double* BlockSparseMatrix::diagonalValues(int i) const {
  const double* values = nullptr;
  for (int k = row_start[i]; k < row_start[i + 1]; ++k)
    if (block_col[k] == i) values = this->values.data() + value_start[k];
  return values;
}

void BlockSparseMatrix::multiply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const {
  y.setZero(rows());
  // Every block 1 x 1 (an LCP, MuJoCo's pyramid edges): a compressed-row product, since block
  // k's one value is values[k] (validate: contiguous) and block j's row is j. The loop below
  // spent five loads of bookkeeping per stored value there (a third of a MuJoCo dominoes
  // step's instructions outside its kernels); the sum is taken in the same order.
  if (rows() == blockCount()) {
    for (int i = 0; i < blockCount(); ++i) {
      double sum = 0.0;
      for (int k = row_start[i]; k < row_start[i + 1]; ++k) sum += values[k] * x[block_col[k]];
      y[i] = sum;
    }
    return;
  }
  for (int i = 0; i < blockCount(); ++i) {
    const int row0 = block_offset[i];
    const int ri = block_offset[i + 1] - row0;
    if (ri == 1) {  // a one-row contact (frictionless, limit, pyramid edge): one dot product
      double sum = 0.0;
      for (int k = row_start[i]; k < row_start[i + 1]; ++k) {
        const int col0 = block_offset[block_col[k]];
        const int cj = block_offset[block_col[k] + 1] - col0;
        const double* v = values.data() + value_start[k];
        for (int c = 0; c < cj; ++c) sum += v[c] * x[col0 + c];
      }
      y[row0] = sum;
      continue;
    }
    if (ri == 3) {  // a frictional contact: its three rows summed in registers (below)
      multiplyThreeRows(i, x.data(), y.data() + row0);
      continue;
    }
    for (int k = row_start[i]; k < row_start[i + 1]; ++k) {
      const int j = block_col[k];
      const int col0 = block_offset[j];
      const int cj = block_offset[j + 1] - col0;
      const double* v = values.data() + value_start[k];
      for (int r = 0; r < ri; ++r) {
        double sum = 0.0;
        for (int c = 0; c < cj; ++c) sum += v[r * cj + c] * x[col0 + c];
        y[row0 + r] += sum;
      }
    }
  }
}

// The hot case of every product with a contact problem's W (before it was unrolled, three
// quarters of apgd's time on a box pyramid): a 3-row block row against 3-column blocks.
// Accumulating in locals and not in y lets the compiler keep them in registers (y may alias
// x, as far as it knows), and the fixed trip count unrolls. Each block's dot products are
// summed in the generic loop's order and then added to the row's total, so the result is the
// same to the bit.
void BlockSparseMatrix::multiplyThreeRows(int i, const double* x, double* y) const {
  double y0 = 0.0, y1 = 0.0, y2 = 0.0;
  for (int k = row_start[i]; k < row_start[i + 1]; ++k) {
    const int j = block_col[k];
    const int col0 = block_offset[j];
    const int cj = block_offset[j + 1] - col0;
    const double* v = values.data() + value_start[k];
    const double* xj = x + col0;
    if (cj == 3) {
      y0 += v[0] * xj[0] + v[1] * xj[1] + v[2] * xj[2];
      y1 += v[3] * xj[0] + v[4] * xj[1] + v[5] * xj[2];
      y2 += v[6] * xj[0] + v[7] * xj[1] + v[8] * xj[2];
      continue;
    }
    double s0 = 0.0, s1 = 0.0, s2 = 0.0;
    for (int c = 0; c < cj; ++c) {
      s0 += v[c] * xj[c];
      s1 += v[cj + c] * xj[c];
      s2 += v[2 * cj + c] * xj[c];
    }
    y0 += s0;
    y1 += s1;
    y2 += s2;
  }
  y[0] = y0;
  y[1] = y1;
  y[2] = y2;
}

// ---- ComplianceMatrix helpers ---------------------------------------------------------------

int complianceRows(const ComplianceMatrix& W) {
  if (const auto* dense = std::get_if<Eigen::MatrixXd>(&W)) return static_cast<int>(dense->rows());
  return std::get<BlockSparseMatrix>(W).rows();
}

int complianceCols(const ComplianceMatrix& W) {
  if (const auto* dense = std::get_if<Eigen::MatrixXd>(&W)) return static_cast<int>(dense->cols());
  return std::get<BlockSparseMatrix>(W).rows();
}

namespace {

bool denseIsSymmetric(const Eigen::MatrixXd& M, double relative_tolerance) {
  // The tolerance (a pass over M) only once a pair differs at all: an assembled W is often
  // exactly symmetric, and auto asks this of microsecond LCPs.
  double tol = -1.0;
  for (Eigen::Index j = 0; j < M.cols(); ++j)
    for (Eigen::Index i = j + 1; i < M.rows(); ++i) {
      const double gap = std::abs(M(i, j) - M(j, i));
      if (!(gap > 0.0)) continue;
      if (tol < 0.0) tol = relative_tolerance * std::max(M.cwiseAbs().maxCoeff(), 1e-300);
      if (!(gap <= tol)) return false;
    }
  return true;
}

}  // namespace

bool isSymmetric(const ComplianceMatrix& W, double relative_tolerance) {
  if (const auto* dense = std::get_if<Eigen::MatrixXd>(&W))
    return denseIsSymmetric(*dense, relative_tolerance);
  const auto& B = std::get<BlockSparseMatrix>(W);
  // A small W (auto asks this of every island, most of them a few dozen rows) is cheapest
  // compared dense: a few microseconds.
  constexpr int kDenseCheckRows = 128;
  if (B.rows() <= kDenseCheckRows) return denseIsSymmetric(B.toDense(), relative_tolerance);
  const int nb = B.blockCount();
  double largest = 1e-300;
  for (double v : B.values) largest = std::max(largest, std::abs(v));
  const double tol = relative_tolerance * largest;
  auto near = [tol](double a, double b) { return std::abs(a - b) <= tol; };
  // The stored blocks by block column (a counting sort, O(stored blocks)): column i lists the
  // blocks (k, i), whose mirrors (i, k) are found through `in_row`, the blocks of row i by column.
  std::vector<int> column_start(nb + 1, 0), by_column(B.block_col.size()), row_of(B.block_col.size());
  for (int j : B.block_col) ++column_start[j + 1];
  for (int j = 0; j < nb; ++j) column_start[j + 1] += column_start[j];
  std::vector<int> fill(column_start.begin(), column_start.end() - 1);
  for (int i = 0; i < nb; ++i)
    for (int s = B.row_start[i]; s < B.row_start[i + 1]; ++s) {
      row_of[s] = i;
      by_column[fill[B.block_col[s]]++] = s;
    }
  std::vector<int> in_row(nb, -1);
  std::vector<char> in_column(nb, 0);
  for (int i = 0; i < nb; ++i) {
    const int rows_i = B.block_offset[i + 1] - B.block_offset[i];
    for (int s = B.row_start[i]; s < B.row_start[i + 1]; ++s) in_row[B.block_col[s]] = s;
    for (int c = column_start[i]; c < column_start[i + 1]; ++c) in_column[row_of[by_column[c]]] = 1;
    // Every block (k, i) against its mirror (i, k), stored or zero.
    for (int c = column_start[i]; c < column_start[i + 1]; ++c) {
      const int t = by_column[c], k = row_of[t];
      const int rows_k = B.block_offset[k + 1] - B.block_offset[k];
      const double* v = B.values.data() + B.value_start[t];  // rows_k × rows_i
      const double* m =
          in_row[k] >= 0 ? B.values.data() + B.value_start[in_row[k]] : nullptr;  // rows_i × rows_k
      for (int r = 0; r < rows_k; ++r)
        for (int q = 0; q < rows_i; ++q)
          if (!near(v[r * rows_i + q], m != nullptr ? m[q * rows_k + r] : 0.0)) return false;
    }
    // A stored (i, k) whose mirror (k, i) is not stored must be zero.
    for (int s = B.row_start[i]; s < B.row_start[i + 1]; ++s) {
      const int k = B.block_col[s];
      if (in_column[k]) continue;
      const int n = rows_i * (B.block_offset[k + 1] - B.block_offset[k]);
      for (int e = 0; e < n; ++e)
        if (!near(B.values[B.value_start[s] + e], 0.0)) return false;
    }
    for (int s = B.row_start[i]; s < B.row_start[i + 1]; ++s) in_row[B.block_col[s]] = -1;
    for (int c = column_start[i]; c < column_start[i + 1]; ++c) in_column[row_of[by_column[c]]] = 0;
  }
  return true;
}

Eigen::MatrixXd toDense(const ComplianceMatrix& W) {
  if (const auto* dense = std::get_if<Eigen::MatrixXd>(&W)) return *dense;
  return std::get<BlockSparseMatrix>(W).toDense();
}

void multiply(const ComplianceMatrix& W, const Eigen::VectorXd& x, Eigen::VectorXd& y) {
  if (const auto* dense = std::get_if<Eigen::MatrixXd>(&W)) {
    y.noalias() = *dense * x;
  } else {
    std::get<BlockSparseMatrix>(W).multiply(x, y);
  }
}

Eigen::MatrixXd diagonalBlock(const ComplianceMatrix& W, int offset, int n) {
  if (const auto* dense = std::get_if<Eigen::MatrixXd>(&W)) return dense->block(offset, offset, n, n);
  const auto& sparse = std::get<BlockSparseMatrix>(W);
  Eigen::MatrixXd block = Eigen::MatrixXd::Zero(n, n);
  // Usual case: the window is exactly one contact's block; find its row by bisection.
  const auto row = std::lower_bound(sparse.block_offset.begin(), sparse.block_offset.end(), offset);
  if (row != sparse.block_offset.end() && *row == offset && row + 1 != sparse.block_offset.end() &&
      *(row + 1) == offset + n) {
    if (const double* v = sparse.diagonalValues(static_cast<int>(row - sparse.block_offset.begin())))
      block = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(v, n, n);
    return block;
  }
  // Any other window: sum every stored piece that overlaps it.
  for (int i = 0; i < sparse.blockCount(); ++i) {
    const int r0 = sparse.block_offset[i], r1 = sparse.block_offset[i + 1];
    if (r1 <= offset || r0 >= offset + n) continue;
    for (int k = sparse.row_start[i]; k < sparse.row_start[i + 1]; ++k) {
      const int j = sparse.block_col[k];
      const int c0 = sparse.block_offset[j], c1 = sparse.block_offset[j + 1];
      if (c1 <= offset || c0 >= offset + n) continue;
      const double* v = sparse.values.data() + sparse.value_start[k];
      const int cj = c1 - c0;
      for (int r = std::max(r0, offset); r < std::min(r1, offset + n); ++r)
        for (int c = std::max(c0, offset); c < std::min(c1, offset + n); ++c)
          block(r - offset, c - offset) += v[(r - r0) * cj + (c - c0)];
    }
  }
  return block;
}

// ---- Problem -------------------------------------------------------------------------------

int Problem::rowCount() const {
  int rows = 0;
  for (const Contact& c : contacts) rows += c.rows;
  return rows;
}

std::vector<int> Problem::rowOffsets() const {
  std::vector<int> offsets(contacts.size() + 1, 0);
  for (std::size_t i = 0; i < contacts.size(); ++i) offsets[i + 1] = offsets[i] + contacts[i].rows;
  return offsets;
}

Problem makeLcpProblem(const Eigen::MatrixXd& M, const Eigen::VectorXd& q) {
  Problem problem;
  problem.contacts.resize(q.size());
  for (int i = 0; i < q.size(); ++i) {
    problem.contacts[i].id = i;
    problem.contacts[i].type = ContactType::kFrictionless;
    problem.contacts[i].rows = 1;
    problem.contacts[i].mu = 0.0;
  }
  problem.W = M;
  problem.d_free = q;
  return problem;
}

namespace {

bool allFinite(const double* v, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i)
    if (!std::isfinite(v[i])) return false;
  return true;
}

std::string validateContacts(const Problem& problem) {
  // The warm start is keyed by id: ids must be unique. One sorted copy (no per-contact
  // allocation); the set that names the repeat runs only when there is one.
  std::vector<std::int64_t> sorted(problem.contacts.size());
  for (std::size_t i = 0; i < sorted.size(); ++i) sorted[i] = problem.contacts[i].id;
  std::sort(sorted.begin(), sorted.end());
  const bool repeats = std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end();
  std::unordered_set<std::int64_t> ids;
  for (std::size_t i = 0; i < problem.contacts.size(); ++i) {
    const Contact& c = problem.contacts[i];
    // Built only for a message (a string per contact was most of a small solve's cost).
    const auto name = [&] { return "contact " + std::to_string(i) + " (id " + std::to_string(c.id) + ")"; };
    if (repeats && !ids.insert(c.id).second) return name() + " repeats the id of an earlier contact";
    switch (c.type) {
      case ContactType::kFrictional:
        if (c.rows != 3)
          return name() + " is frictional but has " + std::to_string(c.rows) + " rows (3 expected)";
        break;
      case ContactType::kFrictionless:
        if (c.rows != 1)
          return name() + " is frictionless but has " + std::to_string(c.rows) + " rows (1 expected)";
        break;
      case ContactType::kTorsional:
      case ContactType::kRolling:
        if (c.rows != rowsForType(c.type))
          return name() + " is " + (c.type == ContactType::kTorsional ? "torsional" : "rolling") +
                 " but has " + std::to_string(c.rows) + " rows (" + std::to_string(rowsForType(c.type)) +
                 " expected)";
        break;
      case ContactType::kBilateral:
        if (c.rows < 1 || c.rows > 6)
          return name() + " is bilateral with " + std::to_string(c.rows) + " rows (1..6 expected)";
        break;
      default: return name() + " has an unknown type " + std::to_string(static_cast<int>(c.type));
    }
    if (std::isnan(c.mu) || std::isinf(c.mu)) return name() + " has a non-finite mu";
    // Negative means "use the default": only exactly the sentinel range is allowed, so a
    // typo like -0.3 is not silently replaced by the default.
    if (c.mu < 0.0 && c.mu != -1.0)
      return name() + " has a negative mu " + std::to_string(c.mu) + " (use -1 for the default)";
    if (!std::isfinite(c.mu_torsional) || c.mu_torsional < 0.0)
      return name() + " has a negative or non-finite torsional friction coefficient";
    if (!std::isfinite(c.mu_rolling) || c.mu_rolling < 0.0)
      return name() + " has a negative or non-finite rolling friction coefficient";
    if (!std::isfinite(c.gap)) return name() + " has a non-finite gap";
    if (!std::isfinite(c.erp) || (c.erp != Contact::kUseDefault && (c.erp < 0.0 || c.erp > 1.0)))
      return name() + " has erp " + std::to_string(c.erp) + " outside [0, 1] (use -1 for the default)";
    if (!std::isfinite(c.softness) || (c.softness != Contact::kUseDefault && c.softness < 0.0))
      return name() + " has a negative softness " + std::to_string(c.softness) + " (use -1 for the default)";
  }
  return "";
}

// The body form instead of W: W must be empty, one Jacobian entry per contact with the
// contact's rows, and the body form consistent in itself.
std::string validateBodyForm(const Problem& problem) {
  const BodyCompliance& bodies = *problem.bodies;
  if (complianceRows(problem.W) != 0 || complianceCols(problem.W) != 0)
    return "the problem gives both an assembled W and the body form; give one";
  if (bodies.contactCount() != static_cast<int>(problem.contacts.size()))
    return "the body form has " + std::to_string(bodies.contactCount()) + " contacts, the problem has " +
           std::to_string(problem.contacts.size());
  for (std::size_t i = 0; i < problem.contacts.size(); ++i)
    if (bodies.contacts[i].rows != problem.contacts[i].rows)
      return "the body form gives contact " + std::to_string(i) + " (id " +
             std::to_string(problem.contacts[i].id) + ") " + std::to_string(bodies.contacts[i].rows) +
             " rows, the contact has " + std::to_string(problem.contacts[i].rows);
  return bodies.validate();
}

}  // namespace

std::string validateProblem(const Problem& problem, int max_rows) {
  if (problem.contacts.empty()) return "the problem has no contacts";
  if (std::string err = validateContacts(problem); !err.empty()) return err;
  const long long rows = problem.rowCount();
  if (max_rows > 0 && rows > max_rows)
    return "the problem has " + std::to_string(rows) + " rows, more than the limit of " +
           std::to_string(max_rows);
  if (problem.d_free.size() != rows)
    return "d_free has " + std::to_string(problem.d_free.size()) + " entries, the contacts have " +
           std::to_string(rows) + " rows";
  if (!allFinite(problem.d_free.data(), problem.d_free.size())) return "d_free holds a non-finite value";
  if (problem.bodies) return validateBodyForm(problem);
  if (complianceRows(problem.W) != rows || complianceCols(problem.W) != rows)
    return "W is " + std::to_string(complianceRows(problem.W)) + "x" +
           std::to_string(complianceCols(problem.W)) + ", the contacts have " + std::to_string(rows) +
           " rows";
  if (const auto* dense = std::get_if<Eigen::MatrixXd>(&problem.W)) {
    if (!allFinite(dense->data(), dense->size())) return "W holds a non-finite value";
  } else {
    const auto& sparse = std::get<BlockSparseMatrix>(problem.W);
    if (std::string err = sparse.validate(); !err.empty()) return err;
    if (!allFinite(sparse.values.data(), sparse.values.size())) return "W holds a non-finite value";
    const std::vector<int> offsets = problem.rowOffsets();
    if (sparse.block_offset != offsets) return "block-sparse W's blocks do not match the contacts' rows";
  }
  return "";
}

}  // namespace lcp_contact_solver::core
