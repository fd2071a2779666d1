// The body form of the compliance (body_compliance.h): validation, W λ through per-body
// accumulators, single blocks and the assembled block-sparse W.
#include "lcp_contact_solver/core/body_compliance.h"

#include <algorithm>

namespace lcp_contact_solver::core {

namespace {

// The body of side s (0: a, 1: b) and its Jacobian block.
inline int sideBody(const ContactJacobian& c, int s) { return s == 0 ? c.body_a : c.body_b; }
inline const JacobianBlock& sideJacobian(const ContactJacobian& c, int s) {
  return s == 0 ? c.jacobian_a : c.jacobian_b;
}

}  // namespace

int BodyCompliance::rowCount() const {
  int rows = 0;
  for (const ContactJacobian& c : contacts) rows += c.rows;
  return rows;
}

std::vector<int> BodyCompliance::rowOffsets() const {
  std::vector<int> offsets(contacts.size() + 1, 0);
  for (std::size_t i = 0; i < contacts.size(); ++i) offsets[i + 1] = offsets[i] + contacts[i].rows;
  return offsets;
}

std::string BodyCompliance::validate() const {
  const int nb = bodyCount();
  for (int b = 0; b < nb; ++b)
    if (!body_compliance[b].allFinite())
      return "the body form: body " + std::to_string(b) + " has a non-finite compliance";
  for (std::size_t i = 0; i < contacts.size(); ++i) {
    const ContactJacobian& c = contacts[i];
    const std::string name = "the body form: contact " + std::to_string(i);
    if (c.rows < 1 || c.rows > 6) return name + " has " + std::to_string(c.rows) + " rows (1..6 expected)";
    for (int s = 0; s < 2; ++s) {
      const int b = sideBody(c, s);
      const char* side = s == 0 ? "body_a" : "body_b";
      if (b < -1 || b >= nb)
        return name + " names " + side + " " + std::to_string(b) + ", outside -1.." + std::to_string(nb - 1) +
               " (-1 = static)";
      if (b < 0) continue;
      const JacobianBlock& J = sideJacobian(c, s);
      if (J.rows() != c.rows)
        return name + " has a " + std::to_string(J.rows()) + "x6 Jacobian on " + side + ", " +
               std::to_string(c.rows) + "x6 expected";
      if (!J.allFinite()) return name + " has a non-finite Jacobian on " + side;
    }
  }
  if (diagonal.size() != 0) {
    if (diagonal.size() != rowCount())
      return "the body form's diagonal has " + std::to_string(diagonal.size()) +
             " values, the contacts have " + std::to_string(rowCount()) + " rows";
    if (!diagonal.allFinite()) return "the body form's diagonal holds a non-finite value";
  }
  return "";
}

void BodyCompliance::bodyResponse(const Eigen::VectorXd& lambda, std::vector<BodyVector>* u) const {
  // First Σ Jᵀ λ per body (the generalized force), then C_b once per body.
  std::vector<BodyVector>& acc = *u;
  acc.assign(body_compliance.size(), BodyVector::Zero());
  int row = 0;
  for (const ContactJacobian& c : contacts) {
    for (int s = 0; s < 2; ++s) {
      const int b = sideBody(c, s);
      if (b >= 0) acc[b].noalias() += sideJacobian(c, s).transpose() * lambda.segment(row, c.rows);
    }
    row += c.rows;
  }
  for (std::size_t b = 0; b < acc.size(); ++b) acc[b] = body_compliance[b] * acc[b];
}

void BodyCompliance::multiply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const {
  std::vector<BodyVector> u;
  bodyResponse(x, &u);
  y.setZero(rowCount());
  int row = 0;
  for (const ContactJacobian& c : contacts) {
    for (int s = 0; s < 2; ++s) {
      const int b = sideBody(c, s);
      if (b >= 0) y.segment(row, c.rows).noalias() += sideJacobian(c, s) * u[b];
    }
    row += c.rows;
  }
  if (diagonal.size() != 0) y.array() += diagonal.array() * x.array();
}

Eigen::MatrixXd BodyCompliance::block(int i, int j) const {
  if (i != j || diagonal.size() == 0) return jacobianBlock(i, j);
  int row = 0;
  for (int k = 0; k < i; ++k) row += contacts[k].rows;
  return diagonalBlock(i, row);
}

Eigen::MatrixXd BodyCompliance::diagonalBlock(int i, int first_row) const {
  Eigen::MatrixXd out = jacobianBlock(i, i);
  if (diagonal.size() != 0) out.diagonal() += diagonal.segment(first_row, contacts[i].rows);
  return out;
}

Eigen::MatrixXd BodyCompliance::jacobianBlock(int i, int j) const {
  const ContactJacobian& ci = contacts[i];
  const ContactJacobian& cj = contacts[j];
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(ci.rows, cj.rows);
  for (int s = 0; s < 2; ++s) {
    const int b = sideBody(ci, s);
    if (b < 0) continue;
    for (int t = 0; t < 2; ++t) {
      if (sideBody(cj, t) != b) continue;
      out.noalias() += sideJacobian(ci, s) * (body_compliance[b] * sideJacobian(cj, t).transpose());
    }
  }
  return out;
}

BlockSparseMatrix BodyCompliance::assemble() const {
  const int nc = contactCount();
  // Per body, the contacts touching it (ascending, once each).
  std::vector<std::vector<int>> body_contacts(body_compliance.size());
  for (int i = 0; i < nc; ++i) {
    for (int s = 0; s < 2; ++s) {
      const int b = sideBody(contacts[i], s);
      if (b >= 0 && (body_contacts[b].empty() || body_contacts[b].back() != i)) body_contacts[b].push_back(i);
    }
  }
  std::vector<int> sizes(nc);
  for (int i = 0; i < nc; ++i) sizes[i] = contacts[i].rows;
  const std::vector<int> offsets = rowOffsets();
  BlockSparseMatrix W = BlockSparseMatrix::withBlockSizes(sizes);
  std::vector<int> neighbours;
  for (int i = 0; i < nc; ++i) {
    W.beginRow();
    neighbours.assign(1, i);  // the diagonal block is always stored (minW, zero diagonals)
    for (int s = 0; s < 2; ++s) {
      const int b = sideBody(contacts[i], s);
      if (b >= 0) neighbours.insert(neighbours.end(), body_contacts[b].begin(), body_contacts[b].end());
    }
    std::sort(neighbours.begin(), neighbours.end());
    neighbours.erase(std::unique(neighbours.begin(), neighbours.end()), neighbours.end());
    for (int j : neighbours) W.addBlock(j, j == i ? diagonalBlock(i, offsets[i]) : jacobianBlock(i, j));
  }
  return W;
}

Eigen::MatrixXd BodyCompliance::toDense() const { return assemble().toDense(); }

ContactBlock contactDiagonalBlock(const Problem& problem, const std::vector<int>& offsets, int i) {
  const int n = offsets[i + 1] - offsets[i];
  if (problem.bodies) return problem.bodies->diagonalBlock(i, offsets[i]);
  if (const auto* dense = std::get_if<Eigen::MatrixXd>(&problem.W)) return dense->block(offsets[i], offsets[i], n, n);
  const auto& sparse = std::get<BlockSparseMatrix>(problem.W);
  // Usual case: block row i is contact i; its diagonal block is read in place.
  if (i < sparse.blockCount() && sparse.block_offset[i] == offsets[i] && sparse.block_offset[i + 1] == offsets[i + 1]) {
    ContactBlock block = ContactBlock::Zero(n, n);
    if (const double* v = sparse.diagonalValues(i))
      block = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(v, n, n);
    return block;
  }
  return diagonalBlock(problem.W, offsets[i], n);
}

Eigen::MatrixXd leadingComplianceWindow(const Problem& problem, int n) {
  if (!problem.bodies) return diagonalBlock(problem.W, 0, n);
  const BodyCompliance& bodies = *problem.bodies;
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(n, n);
  const std::vector<int> offsets = bodies.rowOffsets();
  // Contacts overlapping the window; their blocks, clipped to it.
  int last = 0;
  while (last < bodies.contactCount() && offsets[last] < n) ++last;
  for (int i = 0; i < last; ++i) {
    for (int j = 0; j < last; ++j) {
      const Eigen::MatrixXd blk = i == j ? bodies.diagonalBlock(i, offsets[i]) : bodies.jacobianBlock(i, j);
      const int r = std::min<int>(blk.rows(), n - offsets[i]);
      const int c = std::min<int>(blk.cols(), n - offsets[j]);
      out.block(offsets[i], offsets[j], r, c) = blk.topLeftCorner(r, c);
    }
  }
  return out;
}

void multiplyCompliance(const Problem& problem, const Eigen::VectorXd& x, Eigen::VectorXd& y) {
  if (problem.bodies) {
    problem.bodies->multiply(x, y);
  } else {
    multiply(problem.W, x, y);
  }
}

}  // namespace lcp_contact_solver::core
