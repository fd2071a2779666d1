// Scalar-row storage: W of a problem whose contacts all have one row (frictionless normals,
// the edges of a pyramidal cone, joint limits, one-row bilateral constraints) as flat
// compressed rows of scalars instead of 1×1 blocks, and the Gauss-Seidel sweep on it.
//
// The block-sparse sweep walks a descriptor per block (row, height, pointer) and a local-step
// record per contact sized for the largest contact type; on 1×1 blocks that bookkeeping costs
// several times the one multiply-add each stored entry needs. Here a stored entry is an int
// index and a double value, contiguous, and a row's local data is one inverse diagonal and
// one kind byte. Chosen automatically by the pgs / nlgs / boxed pgs kernels (and so by auto,
// which runs them) when W is block-sparse and every contact of the (island) problem has one
// row; the iterates are those of the block-sparse sweep (same order, same arithmetic).
#pragma once

#include "lcp_contact_solver/core/kernels/kernels.h"
#include "lcp_contact_solver/core/problem.h"

#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <vector>

namespace lcp_contact_solver::core {

// Compressed scalar rows (CSR) of a square matrix.
struct ScalarRows {
  int n = 0;
  std::vector<int> start;     // size n + 1: entries of row i are [start[i], start[i + 1])
  std::vector<int> index;     // column of each entry
  std::vector<double> value;  // value of each entry
  std::size_t entries() const { return value.size(); }
  // Bytes of the stored arrays (the sweep's working set without λ and d).
  std::size_t bytes() const;
};

// True when W is block-sparse and every contact has one row.
bool fitsScalarRows(const Problem& problem);

// The CSR of Wᵀ (W's columns as rows; W itself when W is symmetric) from a block-sparse W of
// 1×1 blocks: the layout of the maintained-d sweep, where a change of λ_j adds column j of W
// to d in one contiguous walk.
ScalarRows scalarColumnsOf(const BlockSparseMatrix& W);

// Projected Gauss-Seidel on scalar rows (fitsScalarRows(*ctx.problem) must hold): unilateral
// rows λ_i = max(0, ·), one-row bilateral rows free, ignored rows skipped; the stopping rules,
// sor, maxIt, time budget and best-iterate return of the block-sparse sweep (gauss_seidel.cpp),
// on the natural-map residual (residual.h), which on one-row contacts is also the pyramid's.
KernelReport runScalarRowGaussSeidel(const SolveContext& ctx, Eigen::VectorXd& lambda);

}  // namespace lcp_contact_solver::core
