#include "zero_friction.h"

namespace lcp_contact_solver::core {

bool zeroFriction(const Contact& c, double default_mu) {
  return c.type == ContactType::kFrictional &&
         (c.mu == 0.0 || (c.mu == Contact::kMuDefault && default_mu == 0.0));
}

Compaction compactZeroFriction(const Problem& p, double default_mu) {
  Compaction out;
  out.reduced.name = p.name;
  out.reduced.contacts = p.contacts;
  const std::vector<int> offsets = p.rowOffsets();
  std::vector<std::vector<int>> local(p.contacts.size());  // kept rows of each contact, local index
  for (std::size_t i = 0; i < p.contacts.size(); ++i) {
    Contact& c = out.reduced.contacts[i];
    if (zeroFriction(c, default_mu)) {
      c.type = ContactType::kFrictionless;
      c.rows = 1;
    }
    for (int k = 0; k < c.rows; ++k) {
      local[i].push_back(k);
      out.kept.push_back(offsets[i] + k);
    }
  }
  out.reduced.d_free = p.d_free(out.kept);
  if (const auto* dense = std::get_if<Eigen::MatrixXd>(&p.W)) {
    out.reduced.W = Eigen::MatrixXd((*dense)(out.kept, out.kept));
    return out;
  }
  const auto& W = std::get<BlockSparseMatrix>(p.W);
  std::vector<int> sizes;
  for (const Contact& c : out.reduced.contacts) sizes.push_back(c.rows);
  BlockSparseMatrix R = BlockSparseMatrix::withBlockSizes(sizes);
  for (int i = 0; i < W.blockCount(); ++i) {
    R.beginRow();
    for (int b = W.row_start[i]; b < W.row_start[i + 1]; ++b) {
      const int j = W.block_col[b];
      const int cols = p.contacts[j].rows;
      const Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> block(
          W.values.data() + W.value_start[b], p.contacts[i].rows, cols);
      R.addBlock(j, Eigen::MatrixXd(block(local[i], local[j])));
    }
  }
  out.reduced.W = std::move(R);
  return out;
}

}  // namespace lcp_contact_solver::core
