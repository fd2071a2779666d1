// The three ways the Gauss-Seidel sweep (gauss_seidel.cpp) reads and updates d = W λ + d_free
// around a contact's local step: dense W (maintained d, column updates), block-sparse W
// (maintained d, block-column walks) and the unbuilt body form (per-body corrections). Each
// offers refresh (recompute exactly), contactD (a contact's current d), applyDelta (add
// W_:c Δλ_c) and currentD (the whole d, for the residual). Header-only: the sweep is a
// template over them.
#pragma once

#include "local_contact_laws.h"

#include "lcp_contact_solver/core/body_compliance.h"
#include "lcp_contact_solver/core/kernels/kernels.h"

#include <Eigen/Core>

#include <vector>

namespace lcp_contact_solver::core::local_laws {

// Current d of one contact. Dense W: read from the maintained d. Block-sparse W: one block
// row times λ (the CSR layout makes this a contiguous walk).
struct DenseAccess {
  const Eigen::MatrixXd& W;
  const SolveContext& ctx;
  Eigen::VectorXd d;

  void refresh(const Eigen::VectorXd& lambda) { ctx.computeD(lambda, d); }
  void contactD(const LocalBlock& blk, const Eigen::VectorXd&, double* out) const {
    for (int k = 0; k < blk.rows; ++k) out[k] = d[blk.offset + k];
  }
  // Column access is contiguous in Eigen's column-major storage.
  void applyDelta(const LocalBlock& blk, const double* delta) {
    for (int k = 0; k < blk.rows; ++k) {
      if (delta[k] == 0.0) continue;
      d.noalias() += W.col(blk.offset + k) * delta[k];
      d[blk.offset + k] += ctx.regularization * delta[k];
    }
  }
  const Eigen::VectorXd& currentD(const Eigen::VectorXd&) { return d; }
};

// Block-sparse W: d is maintained like the dense case, through the block columns. The
// blocks of column j (block row i, values row-major rows_i × cols_j) are indexed once per
// problem (SparseColumnIndex, kept in a caller's memo), so a contact's change updates d with
// one contiguous walk over its column and a contact whose force does not move (an open
// contact staying open) costs nothing; d is recomputed exactly every kRefreshInterval sweeps
// and before declaring convergence.
struct SparseAccess {
  const SolveContext& ctx;
  const SparseColumnIndex& columns;  // W's blocks by block column (a caller's memo or the call's own)
  Eigen::VectorXd d;

  void refresh(const Eigen::VectorXd& lambda) { ctx.computeD(lambda, d); }
  void contactD(const LocalBlock& blk, const Eigen::VectorXd&, double* out) const {
    for (int k = 0; k < blk.rows; ++k) out[k] = d[blk.offset + k];
  }
  void applyDelta(const LocalBlock& blk, const double* delta) {
    const int cols = blk.rows;
    bool moved = false;
    for (int k = 0; k < cols; ++k) moved = moved || delta[k] != 0.0;
    if (!moved) return;
    const int j = static_cast<int>(&blk - first_block);
    double* dd = d.data();
    if (cols == 1) {  // a scalar row's column: no inner loop over columns
      const double change = delta[0];
      for (int s = columns.start[j]; s < columns.start[j + 1]; ++s) {
        const SparseColumnIndex::Block& b = columns.blocks[s];
        for (int r = 0; r < b.rows; ++r) dd[b.row0 + r] += b.v[r] * change;
      }
      if (ctx.regularization != 0.0) dd[blk.offset] += ctx.regularization * change;
      return;
    }
    // delta in locals: the stores into d could alias it, as far as the compiler knows.
    const double a0 = delta[0], a1 = delta[1], a2 = cols == 3 ? delta[2] : 0.0;
    for (int s = columns.start[j]; s < columns.start[j + 1]; ++s) {
      const SparseColumnIndex::Block& b = columns.blocks[s];
      if (cols == 3 && b.rows == 3) {  // contact on contact: unrolled, the same sums in the same order
        const double* v = b.v;
        const double s0 = v[0] * a0 + v[1] * a1 + v[2] * a2;
        const double s1 = v[3] * a0 + v[4] * a1 + v[5] * a2;
        const double s2 = v[6] * a0 + v[7] * a1 + v[8] * a2;
        dd[b.row0] += s0;
        dd[b.row0 + 1] += s1;
        dd[b.row0 + 2] += s2;
        continue;
      }
      for (int r = 0; r < b.rows; ++r) {
        double sum = 0.0;
        for (int c = 0; c < cols; ++c) sum += b.v[r * cols + c] * delta[c];
        dd[b.row0 + r] += sum;
      }
    }
    if (ctx.regularization != 0.0)
      for (int k = 0; k < cols; ++k) dd[blk.offset + k] += ctx.regularization * delta[k];
  }
  const Eigen::VectorXd& currentD(const Eigen::VectorXd&) { return d; }
  const LocalBlock* first_block = nullptr;
};

// ---- The unbuilt solve (SolverParams::build_lcp = false, Problem::bodies) ----------------
//
// Why this is the same iteration as the sweep on the assembled W. The body form
// (body_compliance.h) gives W_ij = Σ_{bodies b shared by i and j} J_ib C_b J_jbᵀ, so
//   d = (W + rI) λ + d_free,   d_c = Σ_{sides s of c} J_cs u_b(s) + d_free_c + r λ_c,
//   u_b = C_b Σ_{contacts k touching b} J_kbᵀ λ_k       (the body's correction)
// (+ the body form's extra diagonal, softness, beside r): a contact's d needs only the u of
// the two bodies it touches. The built sweep visits contact c, reads its maintained d_c,
// takes the local step on D_c = W_cc + rI and adds the column block (W + rI)_:c Δλ_c to d.
// Here the local step and D_c are the same (D_c = Σ_{s,t on one body} J_cs C_b J_ctᵀ + rI,
// formed once per solve), d_c is read through u, and adding W_:c Δλ_c to every d is exactly
// u_b += C_b J_cbᵀ Δλ_c on c's bodies: every later contact then reads the d the built sweep
// would have maintained. Same contact order, same local steps, same sor, stopping rule,
// minW, maxF and warm start, so the iterates are those of pgs/nlgs on the assembled W up to
// the round-off of a different summation order. This is the sequential-impulse form
// (Catto's Box2D: per body a velocity correction, per contact an impulse): a sweep costs
// O(rows · 6) and the storage O(bodies + rows), where the built W needs O(contacts ×
// neighbours) (block-sparse) or O(rows²) (dense) to store and as much per sweep.
struct BodyAccess {
  const BodyCompliance& B;
  const SolveContext& ctx;
  std::vector<BodyVector> u;  // per body: C_b Σ Jᵀ λ, maintained
  Eigen::VectorXd d;          // the whole d, formed only for the residual
  const LocalBlock* first_block = nullptr;

  BodyAccess(const BodyCompliance& bodies, const SolveContext& context) : B(bodies), ctx(context) {}

  // J_row · v for row k of a row-major rows × 6 block.
  static double rowDot(const JacobianBlock& J, int k, const BodyVector& v) {
    const double* j = J.data() + 6 * k;
    return j[0] * v[0] + j[1] * v[1] + j[2] * v[2] + j[3] * v[3] + j[4] * v[4] + j[5] * v[5];
  }
  // d of contact `ci` (rows from `offset`) from u.
  void rowsD(int ci, int offset, const double* lambda, double* out) const {
    const ContactJacobian& c = B.contacts[ci];
    const bool extra = B.diagonal.size() != 0;
    for (int k = 0; k < c.rows; ++k) {
      double v = ctx.problem->d_free[offset + k] + ctx.regularization * lambda[offset + k];
      if (extra) v += B.diagonal[offset + k] * lambda[offset + k];
      if (c.body_a >= 0) v += rowDot(c.jacobian_a, k, u[c.body_a]);
      if (c.body_b >= 0) v += rowDot(c.jacobian_b, k, u[c.body_b]);
      out[k] = v;
    }
  }

  void refresh(const Eigen::VectorXd& lambda) { B.bodyResponse(lambda, &u); }
  void contactD(const LocalBlock& blk, const Eigen::VectorXd& lambda, double* out) const {
    rowsD(static_cast<int>(&blk - first_block), blk.offset, lambda.data(), out);
  }
  void applyDelta(const LocalBlock& blk, const double* delta) {
    bool moved = false;
    for (int k = 0; k < blk.rows; ++k) moved = moved || delta[k] != 0.0;
    if (!moved) return;
    const ContactJacobian& c = B.contacts[&blk - first_block];
    const int bodies[2] = {c.body_a, c.body_b};
    const JacobianBlock* jacobians[2] = {&c.jacobian_a, &c.jacobian_b};
    for (int s = 0; s < 2; ++s) {
      if (bodies[s] < 0) continue;
      BodyVector f = BodyVector::Zero();  // J_sᵀ Δλ
      const double* j = jacobians[s]->data();
      for (int k = 0; k < blk.rows; ++k)
        for (int q = 0; q < 6; ++q) f[q] += j[6 * k + q] * delta[k];
      u[bodies[s]].noalias() += B.body_compliance[bodies[s]] * f;
    }
  }
  const Eigen::VectorXd& currentD(const Eigen::VectorXd& lambda) {
    d.resize(lambda.size());
    int offset = 0;
    for (int ci = 0; ci < B.contactCount(); ++ci) {
      rowsD(ci, offset, lambda.data(), d.data() + offset);
      offset += B.contacts[ci].rows;
    }
    return d;
  }
};

}  // namespace lcp_contact_solver::core::local_laws
