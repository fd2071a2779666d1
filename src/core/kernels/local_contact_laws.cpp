// The per-contact data of the local contact laws (local_contact_laws.h), formed once per solve:
// each contact's diagonal block of W (or of the body form), its inverse or eigen-decomposition,
// and the faults that would make a local step divide by zero.
#include "local_contact_laws.h"

#include "lcp_contact_solver/core/body_compliance.h"

#include <Eigen/LU>

#include <cstdio>

namespace lcp_contact_solver::core::local_laws {

namespace {

// The torsional/rolling part of a contact's local data (D is its whole diagonal block).
std::string prepareExtendedRows(const Contact& c, const ContactBlock& D, const std::string& where,
                                LocalBlock& blk) {
  blk.D_full.setZero();
  blk.D_full.topLeftCorner(c.rows, c.rows) = D;
  blk.mu_torsional = c.mu_torsional;
  blk.mu_rolling = c.type == ContactType::kRolling ? c.mu_rolling : 0.0;
  if (blk.mu_torsional > 0.0) {
    if (!(D(3, 3) > 0.0)) return where + " has a torsional self-compliance W_ss <= 0";
    blk.inv_spin = 1.0 / D(3, 3);
  }
  if (blk.mu_rolling > 0.0) {
    const Eigen::Matrix2d R = D.block<2, 2>(4, 4);
    const double scale = R.cwiseAbs().maxCoeff();
    blk.roll_symmetric = std::abs(R(0, 1) - R(1, 0)) <= 1e-12 * scale;
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(0.5 * (R + R.transpose()));
    blk.roll_basis = eig.eigenvectors();
    blk.roll_eigen = eig.eigenvalues();
    if (!(blk.roll_eigen.maxCoeff() > 0.0))
      return where + " has a rolling block of W with no positive eigenvalue";
    blk.roll_step = 1.0 / blk.roll_eigen.maxCoeff();
  }
  return "";
}

}  // namespace

std::string prepareBlocks(const SolveContext& ctx, std::vector<LocalBlock>& blocks,
                          const FrictionPolygon* polygon) {
  const Problem& problem = *ctx.problem;
  const double r = ctx.regularization;
  blocks.resize(problem.contacts.size());
  for (std::size_t i = 0; i < problem.contacts.size(); ++i) {
    const Contact& c = problem.contacts[i];
    LocalBlock& blk = blocks[i];
    blk.offset = ctx.offsets[i];
    blk.rows = c.rows;
    blk.mu = ctx.mu[i];
    if (ctx.ignored[i]) {
      blk.kind = LocalKind::kSkip;
      continue;
    }
    ContactBlock D = contactDiagonalBlock(problem, ctx.offsets, static_cast<int>(i));  // W or the body form
    D.diagonal().array() += r;
    // Named only for a message: no string per contact per solve.
    const auto where = [&] { return "contact " + std::to_string(i) + " (id " + std::to_string(c.id) + ")"; };
    if (c.type == ContactType::kBilateral) {
      Eigen::FullPivLU<ContactBlock> lu(D);
      if (!lu.isInvertible()) return where() + " has a singular bilateral block of W";
      blk.kind = LocalKind::kBilateral;
      blk.bilateral_block = D;
      blk.bilateral_inverse = lu.inverse();
      if (c.rows == 1) blk.inv_nn = blk.bilateral_inverse(0, 0);  // a scalar row's whole inverse (localStep)
      continue;
    }
    if (!(D(0, 0) > 0.0)) {
      char value[32];
      std::snprintf(value, sizeof(value), "%.6g", D(0, 0));  // to_string prints 1e-20 as 0.000000
      return where() + " has W_nn = " + value + " <= 0; set minW or regularizationTerm";
    }
    blk.inv_nn = 1.0 / D(0, 0);
    const bool extended = c.type == ContactType::kTorsional || c.type == ContactType::kRolling;
    if (c.type == ContactType::kFrictionless || (blk.mu == 0.0 && !extended)) {
      blk.kind = LocalKind::kNormalOnly;
      continue;
    }
    blk.kind = polygon != nullptr ? LocalKind::kPolygon : LocalKind::kCoulomb;
    if (extended) {
      if (std::string err = prepareExtendedRows(c, D, where(), blk); !err.empty()) return err;
      blk.kind = LocalKind::kCoulombExtended;
    }
    blk.D = D.topLeftCorner<3, 3>();
    blk.coupled = D(0, 1) != 0.0 || D(0, 2) != 0.0 || D(1, 0) != 0.0 || D(2, 0) != 0.0;
    {
      // Closed-form inverse (cofactors), kept only for a well-conditioned block (reciprocal
      // condition number in the 1-norm): the one-shot solution must be as accurate as the
      // iteration it replaces.
      const Eigen::Matrix3d D3 = D.topLeftCorner<3, 3>();
      const Eigen::Matrix3d inverse = D3.inverse();
      const double norm = D3.cwiseAbs().colwise().sum().maxCoeff();
      const double inverse_norm = inverse.cwiseAbs().colwise().sum().maxCoeff();
      const double cond_floor = 1e-10;
      blk.invertible = inverse.allFinite() && norm > 0.0 && 1.0 / (norm * inverse_norm) > cond_floor;
      if (blk.invertible) blk.D_inverse = inverse;
    }
    const Eigen::Matrix2d T = D.block<2, 2>(1, 1);
    const double scale = T.cwiseAbs().maxCoeff();
    blk.tangent_symmetric = std::abs(T(0, 1) - T(1, 0)) <= 1e-12 * scale;
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(0.5 * (T + T.transpose()));
    blk.tangent_basis = eig.eigenvectors();
    blk.tangent_eigen = eig.eigenvalues();
    const double a_max = blk.tangent_eigen.maxCoeff();
    if (!blk.tangent_symmetric && !(a_max > 0.0))
      return where() + " has a tangential block of W with no positive eigenvalue";
    blk.tangent_step = a_max > 0.0 ? 1.0 / a_max : 0.0;
  }
  return "";
}

}  // namespace lcp_contact_solver::core::local_laws

namespace lcp_contact_solver::core {

void SparseColumnIndex::build(const BlockSparseMatrix& W) {
  const int nb = W.blockCount();
  start.assign(nb + 1, 0);
  for (int j : W.block_col) ++start[j + 1];
  for (int j = 0; j < nb; ++j) start[j + 1] += start[j];
  blocks.resize(W.block_col.size());
  std::vector<int> fill(start.begin(), start.end() - 1);
  for (int i = 0; i < nb; ++i) {
    for (int s = W.row_start[i]; s < W.row_start[i + 1]; ++s) {
      const int j = W.block_col[s];
      blocks[fill[j]++] = {W.block_offset[i], W.block_offset[i + 1] - W.block_offset[i],
                           W.values.data() + W.value_start[s]};
    }
  }
}

bool KeptD::take(const SolveContext& ctx, const Eigen::VectorXd& x, Eigen::VectorXd& out, int* since_refresh) {
  if (problem != ctx.problem || regularization != ctx.regularization || lambda.size() != x.size() ||
      lambda != x)
    return false;
  out.swap(d);
  *since_refresh = sweeps;
  problem = nullptr;  // given away
  return true;
}

void KeptD::keep(const SolveContext& ctx, const Eigen::VectorXd& x, Eigen::VectorXd& d_now, int since_refresh) {
  problem = ctx.problem;
  regularization = ctx.regularization;
  lambda = x;
  d.swap(d_now);
  sweeps = since_refresh;
}

}  // namespace lcp_contact_solver::core
