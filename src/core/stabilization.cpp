#include "lcp_contact_solver/core/stabilization.h"

#include "lcp_contact_solver/core/body_compliance.h"

#include <memory>
#include <variant>

namespace lcp_contact_solver::core {

namespace {

bool hasNormalRow(const Contact& c) { return c.type != ContactType::kBilateral; }

// W_rr += s for the given rows. A block-sparse W without a stored diagonal block gets one.
void addToDiagonal(const std::vector<int>& offsets, const std::vector<double>& add, ComplianceMatrix* W) {
  if (auto* dense = std::get_if<Eigen::MatrixXd>(W)) {
    for (std::size_t i = 0; i < add.size(); ++i)
      if (add[i] != 0.0) (*dense)(offsets[i], offsets[i]) += add[i];
    return;
  }
  auto& sparse = std::get<BlockSparseMatrix>(*W);
  bool missing = false;
  for (int i = 0; i < sparse.blockCount(); ++i) {
    if (add[i] == 0.0) continue;
    bool found = false;
    for (int b = sparse.row_start[i]; b < sparse.row_start[i + 1]; ++b) {
      if (sparse.block_col[b] != i) continue;
      sparse.values[sparse.value_start[b]] += add[i];  // (0, 0): the normal row, row-major
      found = true;
    }
    missing = missing || !found;
  }
  if (!missing) return;
  // Rare (a contact with no self-compliance stored): rebuild with the diagonal blocks added.
  std::vector<int> sizes(sparse.blockCount());
  for (int i = 0; i < sparse.blockCount(); ++i)
    sizes[i] = sparse.block_offset[i + 1] - sparse.block_offset[i];
  BlockSparseMatrix out = BlockSparseMatrix::withBlockSizes(sizes);
  for (int i = 0; i < sparse.blockCount(); ++i) {
    out.beginRow();
    bool found = false;
    for (int b = sparse.row_start[i]; b < sparse.row_start[i + 1]; ++b) {
      const int j = sparse.block_col[b];
      found = found || j == i;
      out.addBlock(j,
                   Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
                       sparse.values.data() + sparse.value_start[b], sizes[i], sizes[j]));
    }
    if (!found && add[i] != 0.0) {
      Eigen::MatrixXd block = Eigen::MatrixXd::Zero(sizes[i], sizes[i]);
      block(0, 0) = add[i];
      out.addBlock(i, block);
    }
  }
  *W = std::move(out);
}

}  // namespace

double effectiveErp(const Contact& contact, const SolverParams& params) {
  if (!hasNormalRow(contact)) return 0.0;
  return contact.erp == Contact::kUseDefault ? params.erp : contact.erp;
}

double effectiveSoftness(const Contact& contact, const SolverParams& params) {
  if (!hasNormalRow(contact)) return 0.0;
  return contact.softness == Contact::kUseDefault ? params.softness : contact.softness;
}

bool needsStabilization(const Problem& problem, const SolverParams& params) {
  for (const Contact& c : problem.contacts)
    if ((c.gap < 0.0 && effectiveErp(c, params) > 0.0) || effectiveSoftness(c, params) > 0.0) return true;
  return false;
}

std::string applyStabilization(const SolverParams& params, Problem* problem) {
  const bool velocity = params.constraint_level == ConstraintLevel::kVelocity;
  const std::vector<int> offsets = problem->rowOffsets();
  std::vector<double> softness(problem->contacts.size(), 0.0);
  bool soft = false;
  for (std::size_t i = 0; i < problem->contacts.size(); ++i) {
    const Contact& c = problem->contacts[i];
    const double beta = effectiveErp(c, params);
    if (c.gap < 0.0 && beta > 0.0) {
      if (velocity && params.time_step <= 0.0)
        return "erp at constraint_level velocity needs time_step > 0 (contact id " + std::to_string(c.id) +
               ")";
      problem->d_free[offsets[i]] += velocity ? beta * c.gap / params.time_step : beta * c.gap;
    }
    softness[i] = effectiveSoftness(c, params);
    soft = soft || softness[i] > 0.0;
  }
  if (soft && problem->bodies) {
    // The body form: softness joins its extra diagonal (a copy: the input's is shared).
    auto bodies = std::make_shared<BodyCompliance>(*problem->bodies);
    if (bodies->diagonal.size() == 0) bodies->diagonal = Eigen::VectorXd::Zero(offsets.back());
    for (std::size_t i = 0; i < softness.size(); ++i) bodies->diagonal[offsets[i]] += softness[i];
    problem->bodies = std::move(bodies);
  } else if (soft) {
    addToDiagonal(offsets, softness, &problem->W);
  }
  return "";
}

bool applyStabilizationInPlace(const SolverParams& params, Problem* problem, StabilizationUndo* undo,
                               std::string* error) {
  error->clear();
  const bool velocity = params.constraint_level == ConstraintLevel::kVelocity;
  const std::vector<int> offsets = problem->rowOffsets();
  const std::size_t nc = problem->contacts.size();
  std::vector<double> shift(nc, 0.0), softness(nc, 0.0);
  std::vector<bool> shifted(nc, false);
  bool soft = false;
  for (std::size_t i = 0; i < nc; ++i) {  // first every check, so an error changes nothing
    const Contact& c = problem->contacts[i];
    const double beta = effectiveErp(c, params);
    if (c.gap < 0.0 && beta > 0.0) {
      if (velocity && params.time_step <= 0.0) {
        *error =
            "erp at constraint_level velocity needs time_step > 0 (contact id " + std::to_string(c.id) + ")";
        return true;
      }
      shift[i] = velocity ? beta * c.gap / params.time_step : beta * c.gap;
      shifted[i] = true;
    }
    softness[i] = effectiveSoftness(c, params);
    soft = soft || softness[i] > 0.0;
  }
  // Where each softness goes: W's (normal, normal) entry of the contact.
  std::vector<double*> diagonal;
  if (soft && !problem->bodies) {
    diagonal.assign(nc, nullptr);
    if (auto* dense = std::get_if<Eigen::MatrixXd>(&problem->W)) {
      for (std::size_t i = 0; i < nc; ++i)
        if (softness[i] != 0.0) diagonal[i] = &(*dense)(offsets[i], offsets[i]);
    } else {
      auto& sparse = std::get<BlockSparseMatrix>(problem->W);
      for (std::size_t i = 0; i < nc; ++i) {
        if (softness[i] == 0.0) continue;
        const int row = static_cast<int>(i);
        for (int b = sparse.row_start[row]; b < sparse.row_start[row + 1]; ++b)
          if (sparse.block_col[b] == row) diagonal[i] = &sparse.values[sparse.value_start[b]];
        if (!diagonal[i]) return false;  // no stored self-compliance: the copying path adds the block
      }
    }
  }
  for (std::size_t i = 0; i < nc; ++i) {
    if (!shifted[i]) continue;
    double& d = problem->d_free[offsets[i]];
    undo->d_free.emplace_back(offsets[i], d);
    d += shift[i];
  }
  if (soft && problem->bodies) {  // the body form's own diagonal: a copy of the (per-body) form
    auto bodies = std::make_shared<BodyCompliance>(*problem->bodies);
    if (bodies->diagonal.size() == 0) bodies->diagonal = Eigen::VectorXd::Zero(offsets.back());
    for (std::size_t i = 0; i < nc; ++i) bodies->diagonal[offsets[i]] += softness[i];
    undo->bodies = problem->bodies;
    undo->bodies_changed = true;
    problem->bodies = std::move(bodies);
  } else if (soft) {
    for (std::size_t i = 0; i < nc; ++i) {
      if (!diagonal[i]) continue;
      undo->w.emplace_back(diagonal[i], *diagonal[i]);
      *diagonal[i] += softness[i];
    }
  }
  return true;
}

void StabilizationUndo::restore(Problem* problem) const {
  for (auto it = w.rbegin(); it != w.rend(); ++it) *it->first = it->second;
  for (auto it = d_free.rbegin(); it != d_free.rend(); ++it) problem->d_free[it->first] = it->second;
  if (bodies_changed) problem->bodies = bodies;
}

}  // namespace lcp_contact_solver::core
