// The frictional contact problem solved by this package:
//
//   d = W λ + d_free
//   unilateral row (contact normal):  0 ≤ λ_n ⟂ d_n ≥ 0
//   friction rows (two tangents):     |λ_t| ≤ μ λ_n, and when sliding λ_t = -μ λ_n d_t/|d_t|
//   bilateral rows:                   λ free, d = 0
//   torsional row (spin about n):     |λ_s| ≤ μ_tor λ_n, opposing the relative spin
//   rolling rows (about t1, t2):      |λ_r| ≤ μ_roll λ_n, opposing the relative rolling
// (the friction cone of a 4- or 6-row contact is the product of these with Coulomb's: each
// law is bounded by the same λ_n; μ_tor and μ_roll are lengths, λ_s and λ_r torques; MuJoCo's
// condim 4 and 6, with its elliptic cone replaced by this decoupled one)
//
// W is the compliance in constraint space (for rigid bodies J M⁻¹ Jᵀ), given dense or
// block-sparse with one block per contact pair. Rows are laid out contact after contact,
// in the order of `contacts`. This is the Siconos/FCLIB convention (u = W r + q) and
// SOFA's d = Wλ - f with d_free = -f.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <memory>
#include <string>
#include <variant>
#include <vector>

namespace lcp_contact_solver::core {

enum class ContactType : std::uint8_t {
  kFrictional = 0,    // 3 rows: normal, tangent 1, tangent 2 (Coulomb disc)
  kFrictionless = 1,  // 1 row: normal only
  kBilateral = 2,     // `rows` equality rows with free-sign force
  kTorsional = 3,     // 4 rows: normal, tangent 1, tangent 2, spin about the normal
  kRolling = 4,       // 6 rows: the 4 torsional ones, then rolling about tangent 1 and 2
};

// Frictional, torsional or rolling: the types with the sliding (Coulomb disc) rows.
inline bool hasSlidingFriction(ContactType type) {
  return type == ContactType::kFrictional || type == ContactType::kTorsional || type == ContactType::kRolling;
}

// Rows a contact of this type occupies. Bilateral contacts carry their own count.
int rowsForType(ContactType type);

struct Contact {
  std::int64_t id = 0;  // persistent across cycles; keys the warm start
  ContactType type = ContactType::kFrictional;
  int rows = 3;  // 3 frictional, 1 frictionless, 4 torsional, 6 rolling, >= 1 bilateral
  // Friction coefficient (dimensionless). kMuDefault (-1) means "not given": the solver's
  // `mu` parameter is used; any other negative value is invalid input. Only meaningful for frictional contacts; μ = 0 makes a frictional
  // contact cost one row.
  double mu = -1.0;
  // Torsional and rolling friction coefficients (m: torque per newton of normal force) of
  // kTorsional (μ_tor) and kRolling (both) contacts; >= 0.
  double mu_torsional = 0.0;
  double mu_rolling = 0.0;
  // Position-error correction and softness of the normal row (stabilization.h); unused by
  // bilateral contacts. gap: signed distance at the start of the step (m; < 0 penetration),
  // 0 when unknown. erp: Baumgarte factor β in [0, 1]; softness: added to W_nn, >= 0 in the
  // units of W. kUseDefault (-1) takes the solver's `erp` / `softness` parameter.
  double gap = 0.0;
  double erp = -1.0;
  double softness = -1.0;

  static constexpr double kMuDefault = -1.0;
  static constexpr double kUseDefault = -1.0;
};

// Block-sparse square matrix whose block rows/columns are the contacts. Block (i, j) is a
// dense rows_i × rows_j matrix stored row-major. Block rows are stored CSR-style, so a
// Gauss-Seidel sweep reads one contiguous run of blocks per contact.
struct BlockSparseMatrix {
  std::vector<int> block_offset;  // first row of each block row, size nb + 1
  std::vector<int> row_start;     // first stored block of each block row, size nb + 1
  std::vector<int> block_col;     // block column of each stored block
  std::vector<int> value_start;   // first value of each stored block
  std::vector<double> values;     // all blocks, each row-major

  int blockCount() const { return static_cast<int>(block_offset.size()) - 1; }
  int rows() const { return block_offset.empty() ? 0 : block_offset.back(); }

  // Adds a block; blocks must be added in block-row order (and then any column order).
  void beginRow();  // starts the next block row
  void addBlock(int block_col, const Eigen::Ref<const Eigen::MatrixXd>& block);
  // Starts an empty matrix with the given block sizes.
  static BlockSparseMatrix withBlockSizes(const std::vector<int>& sizes);

  Eigen::MatrixXd toDense() const;
  // y = A x (y resized).
  void multiply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const;
  // y[0..2] = block row i (three rows) times x: multiply's hot case.
  void multiplyThreeRows(int i, const double* x, double* y) const;
  // The stored diagonal block of block row i (row-major), or nullptr when none is stored.
  const double* diagonalValues(int i) const;
  // Checks the structure; returns an empty string when consistent.
  std::string validate() const;
};

// The compliance W: one of the two storages; the solvers accept both.
using ComplianceMatrix = std::variant<Eigen::MatrixXd, BlockSparseMatrix>;

int complianceRows(const ComplianceMatrix& W);
int complianceCols(const ComplianceMatrix& W);
Eigen::MatrixXd toDense(const ComplianceMatrix& W);
// W = Wᵀ to within relative_tolerance × max |W_ij|, read in W's own storage (no dense copy).
bool isSymmetric(const ComplianceMatrix& W, double relative_tolerance);
// y = W x
void multiply(const ComplianceMatrix& W, const Eigen::VectorXd& x, Eigen::VectorXd& y);
// Diagonal block of contact rows [offset, offset + n).
Eigen::MatrixXd diagonalBlock(const ComplianceMatrix& W, int offset, int n);
// One contact's diagonal block (1..6 rows): fixed capacity, so forming it allocates nothing.
using ContactBlock = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor, 6, 6>;

// The body form of the compliance (per-body compliance and contact Jacobians, W not
// assembled): body_compliance.h.
struct BodyCompliance;

struct Problem {
  std::vector<Contact> contacts;
  // The assembled compliance. Left empty (0×0) when `bodies` is set.
  ComplianceMatrix W = Eigen::MatrixXd();
  // The body form (SOFA's build_lcp = false), instead of W: ContactSolver runs the unbuilt
  // Gauss-Seidel on it (SolverParams::build_lcp = false) or assembles W once.
  std::shared_ptr<const BodyCompliance> bodies;
  Eigen::VectorXd d_free;  // free-motion violation, one entry per row
  std::string name;        // for reports (file name, topic, ...)

  int rowCount() const;                 // sum of contact rows
  std::vector<int> rowOffsets() const;  // first row of each contact, size nc + 1
};

// Builds a frictionless problem (an LCP w = M z + q) with one contact per row, ids 0..n-1.
Problem makeLcpProblem(const Eigen::MatrixXd& M, const Eigen::VectorXd& q);

// Returns an empty string if the problem is well-formed, otherwise one sentence naming the
// first fault (sizes, non-finite values, negative μ, bad row counts, too many rows).
// `max_rows` <= 0 disables the size limit.
std::string validateProblem(const Problem& problem, int max_rows = 0);

}  // namespace lcp_contact_solver::core
