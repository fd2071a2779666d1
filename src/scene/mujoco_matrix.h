// The numbers of an extracted problem (src/scene/mujoco_adapter.cpp walks the rows, these
// fill them in): row scales, d_free, MuJoCo's forces, and W from efc_AR. Internal to the
// MuJoCo adapter library.
#pragma once

#include "lcp_contact_solver/scene/mujoco_adapter.h"

#include <Eigen/Core>

#include <vector>

namespace lcp_contact_solver {
namespace scene {
namespace detail {

// Row scales, d_free and MuJoCo's forces of the kept rows (out->efc_row); with fold_dropped,
// the dropped rows' forces folded into d_free. Returns the problem row of each MuJoCo row
// (-1: dropped).
std::vector<int> fillRows(const mjModel* m, const mjData* d, const MujocoExtractOptions& options,
                          const std::vector<double>& scale_of_row, MujocoProblem* out);

// W: AR restricted to the kept rows, scaled, dense.
Eigen::MatrixXd denseW(const mjModel* m, const mjData* d, const MujocoProblem& mp,
                       const std::vector<int>& row_of_efc);

// The share of W's n x n entries (the kept rows' AR) that are nonzero.
double fillOfW(const mjModel* m, const mjData* d, const MujocoProblem& mp, const std::vector<int>& row_of_efc);

// The same W block-sparse: one block per pair of coupled entries.
core::BlockSparseMatrix blockSparseW(const mjModel* m, const mjData* d, const MujocoProblem& mp,
                                     const std::vector<int>& row_of_efc);

}  // namespace detail
}  // namespace scene
}  // namespace lcp_contact_solver
