// Our forces against MuJoCo's for the same step (ROS-free): per row in MuJoCo's units, per
// contact in its frame, and the package's residual. The problem is mujoco_adapter.h's.
#pragma once

#include "lcp_contact_solver/core/solve_result.h"
#include "lcp_contact_solver/scene/mujoco_adapter.h"

#include <Eigen/Core>

#include <vector>

namespace lcp_contact_solver {
namespace scene {

// The contact force of entry `i` as MuJoCo's mj_contactForce reports it for a contact, in
// its contact frame (normal, t1, t2) from problem forces λ: an edge contributes its share
// (f n ± μ f t_j); for cross-checks of the row mapping.
Eigen::Vector3d contactFrameForce(const MujocoProblem& problem, const Eigen::VectorXd& lambda, int mj_contact,
                                  const mjData* d);

// Our forces against MuJoCo's for the same step, in MuJoCo's units (efc_force): max_abs =
// max over kept rows |f_ours − f_mujoco|, max_rel = max_abs / max |f_mujoco| (the step's
// scale). Per contact state of our solution (open, stick, slip, ignored) the same figures.
struct ForceComparison {
  int rows = 0;
  double max_abs = 0.0;
  double max_rel = 0.0;
  double scale = 0.0;  // max |f_mujoco| (1 when all are zero)
  // Indexed by ContactState: entries and the max abs difference among their rows.
  int state_count[core::kContactStateCount] = {};
  double state_max_abs[core::kContactStateCount] = {};
};
ForceComparison compareForces(const MujocoProblem& problem, const Eigen::VectorXd& lambda,
                              const std::vector<core::ContactState>& states = {});

// The package's solver-independent residual (residual.h) of problem forces λ, e.g.
// MuJoCo's own (mujoco_lambda), so every solver is measured the same way.
double problemResidual(const MujocoProblem& problem, const Eigen::VectorXd& lambda);

}  // namespace scene
}  // namespace lcp_contact_solver
