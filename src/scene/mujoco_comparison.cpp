// Our forces against MuJoCo's (mujoco_comparison.h).
#include "lcp_contact_solver/scene/mujoco_comparison.h"

#include "lcp_contact_solver/core/residual.h"

#include <algorithm>
#include <cmath>

namespace lcp_contact_solver {
namespace scene {

Eigen::Vector3d contactFrameForce(const MujocoProblem& problem, const Eigen::VectorXd& lambda, int mj_contact,
                                  const mjData* d) {
  Eigen::Vector3d force = Eigen::Vector3d::Zero();
  const std::vector<int> offsets = problem.problem.rowOffsets();
  for (std::size_t i = 0; i < problem.entries.size(); ++i) {
    const MujocoEntry& entry = problem.entries[i];
    if (entry.mj_contact != mj_contact) continue;
    const int p = offsets[i];
    switch (entry.kind) {
      case MujocoRowKind::kFrictionless: force[0] += lambda[p]; break;
      case MujocoRowKind::kPyramidEdge: {
        const double f = lambda[p] / problem.row_scale[p];
        const int j = entry.edge / 2;
        force[0] += f;
        if (j < 2)
          force[1 + j] += (entry.edge % 2 == 0 ? 1.0 : -1.0) * d->contact[mj_contact].friction[j] * f;
        break;
      }
      case MujocoRowKind::kElliptic:
        for (int r = 0; r < 3; ++r) force[r] += lambda[p + r] / problem.row_scale[p + r];
        break;
      default: break;
    }
  }
  return force;
}

// ---- comparison --------------------------------------------------------------------------

ForceComparison compareForces(const MujocoProblem& problem, const Eigen::VectorXd& lambda,
                              const std::vector<core::ContactState>& states) {
  ForceComparison cmp;
  const std::vector<int> offsets = problem.problem.rowOffsets();
  cmp.rows = static_cast<int>(problem.efc_row.size());
  double scale = 0.0;
  for (int p = 0; p < cmp.rows; ++p)
    scale = std::max(scale, std::abs(problem.mujoco_lambda[p] / problem.row_scale[p]));
  for (std::size_t i = 0; i < problem.entries.size(); ++i) {
    double entry_max = 0.0;
    for (int p = offsets[i]; p < offsets[i + 1]; ++p) {
      const double ours = p < lambda.size() ? lambda[p] / problem.row_scale[p] : 0.0;
      const double theirs = problem.mujoco_lambda[p] / problem.row_scale[p];
      entry_max = std::max(entry_max, std::abs(ours - theirs));
    }
    cmp.max_abs = std::max(cmp.max_abs, entry_max);
    if (i < states.size()) {
      const int s = static_cast<int>(states[i]);
      if (s >= 0 && s < core::kContactStateCount) {
        ++cmp.state_count[s];
        cmp.state_max_abs[s] = std::max(cmp.state_max_abs[s], entry_max);
      }
    }
  }
  cmp.scale = scale > 0.0 ? scale : 1.0;
  cmp.max_rel = cmp.max_abs / cmp.scale;
  return cmp;
}

double problemResidual(const MujocoProblem& problem, const Eigen::VectorXd& lambda) {
  if (problem.problem.contacts.empty()) return 0.0;
  Eigen::VectorXd d;
  core::multiply(problem.problem.W, lambda, d);
  d += problem.problem.d_free;
  return core::naturalMapResidual(problem.problem, core::effectiveMu(problem.problem, 0.0), lambda, d);
}

}  // namespace scene
}  // namespace lcp_contact_solver
