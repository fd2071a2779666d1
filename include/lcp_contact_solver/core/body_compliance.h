// The body form of the compliance (SOFA's build_lcp = false): instead of the assembled
// W, per body a 6×6 compliance C_b and per contact its Jacobian blocks on the (at most
// two) bodies it touches, so that
//
//   W_ij = Σ_{sides s of i, t of j with the same body b} J_is C_b J_jtᵀ   (+ diag on i = j)
//
// For rigid bodies at position level C_b = dt² M_b⁻¹ (m/N per unit Jacobian: J is
// [uᵀ, (r × u)ᵀ], dimensionless and m), which gives W = dt² J M⁻¹ Jᵀ; at velocity level
// C_b = M_b⁻¹ (or dt M_b⁻¹ for impulses). Anything with W in the units of d per unit λ
// works: the core never looks inside C_b.
//
// Storage grows with bodies + contacts, not with contacts²; W λ costs O(rows) through
// per-body accumulators u_b = C_b Σ J_bᵀ λ (bodyResponse), which is what the unbuilt
// Gauss-Seidel (kernels/sweep_access.h) maintains. `assemble` builds the block-sparse W (one
// block per pair of contacts sharing a body) for every other solver.
#pragma once

#include "lcp_contact_solver/core/problem.h"

#include <Eigen/Core>

#include <string>
#include <vector>

namespace lcp_contact_solver::core {

using BodyMatrix = Eigen::Matrix<double, 6, 6>;
using BodyVector = Eigen::Matrix<double, 6, 1>;
// One side of a contact: rows × 6, row-major, at most 6 rows (stored inline, no heap).
using JacobianBlock = Eigen::Matrix<double, Eigen::Dynamic, 6, Eigen::RowMajor, 6, 6>;

struct ContactJacobian {
  int rows = 0;     // the contact's rows (1..6), as in Problem::contacts
  int body_a = -1;  // index into BodyCompliance::body_compliance; -1: static (no block)
  int body_b = -1;
  JacobianBlock jacobian_a;  // rows × 6 when body_a >= 0, else unused (may be 0 × 6)
  JacobianBlock jacobian_b;  // rows × 6 when body_b >= 0
};

struct BodyCompliance {
  std::vector<BodyMatrix> body_compliance;  // C_b per body
  std::vector<ContactJacobian> contacts;    // one per contact, in problem order
  // Optional extra compliance on W's diagonal, one value per row (softness / CFM added by
  // the stabilization stage); empty = none.
  Eigen::VectorXd diagonal;

  int bodyCount() const { return static_cast<int>(body_compliance.size()); }
  int contactCount() const { return static_cast<int>(contacts.size()); }
  int rowCount() const;
  std::vector<int> rowOffsets() const;  // first row of each contact, size nc + 1

  // Empty string when consistent, otherwise one sentence naming the first fault: rows
  // outside 1..6, a body index out of range, a Jacobian block of the wrong size, a
  // non-finite value (C_b, J, diagonal), a diagonal of the wrong length.
  std::string validate() const;

  // u_b = C_b Σ_{sides s on b} J_sᵀ λ_c for every body (resized to bodyCount()).
  void bodyResponse(const Eigen::VectorXd& lambda, std::vector<BodyVector>* u) const;
  // y = W x without forming W (O(rows + bodies)).
  void multiply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const;
  // W_ij, rows_i × rows_j (zero when i and j share no body; the diagonal added on i = j).
  Eigen::MatrixXd block(int i, int j) const;
  // W_ii of contact i whose first row is `first_row` (no search for the row).
  Eigen::MatrixXd diagonalBlock(int i, int first_row) const;
  // Σ J_is C_b J_jtᵀ alone, without the extra diagonal.
  Eigen::MatrixXd jacobianBlock(int i, int j) const;
  // The assembled W: block (i, j) stored when i and j share a body (and always (i, i)),
  // columns ascending. Cost O(contacts × neighbours).
  BlockSparseMatrix assemble() const;
  Eigen::MatrixXd toDense() const;
};

// The diagonal block of contact i of the problem's compliance, whichever form it has.
ContactBlock contactDiagonalBlock(const Problem& problem, const std::vector<int>& offsets, int i);
// The leading n × n window of the problem's W, whichever form it has (markers).
Eigen::MatrixXd leadingComplianceWindow(const Problem& problem, int n);
// y = W x for the problem's compliance, whichever form it has.
void multiplyCompliance(const Problem& problem, const Eigen::VectorXd& x, Eigen::VectorXd& y);

}  // namespace lcp_contact_solver::core
