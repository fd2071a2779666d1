#include "lcp_contact_solver/ros/sim/mujoco_bridge_settings.h"

#include "lcp_contact_solver/scene/mujoco_world.h"

#include <cmath>

namespace lcp_contact_solver_ros {

namespace {

namespace scene = ::lcp_contact_solver::scene;

bool finite(double v) { return std::isfinite(v); }

std::string validate(const MujocoBridgeSettings& s) {
  int dummy = 0;
  std::string why;
  if (s.model.empty()) return "parameter model must name an MJCF file";
  if (s.mode != "cross_check" && s.mode != "drive") return "parameter mode must be cross_check or drive";
  if (s.cone != "model" && !scene::parseMujocoCone(s.cone, &dummy, &why))
    return "parameter cone: " + why + " or model";
  if (s.mujoco_solver != "model" && !scene::parseMujocoSolver(s.mujoco_solver, &dummy, &why))
    return "parameter mujoco_solver: " + why + " or model";
  if (!finite(s.mujoco_tolerance)) return "parameter mujoco_tolerance must be finite (< 0 keeps the model's)";
  if (s.steps < 0) return "parameter steps must be >= 0 (0 runs for ever, or for ~duration)";
  if (!finite(s.dt) || s.dt < 0.0) return "parameter dt must be >= 0 (0 keeps the model's timestep)";
  if (s.min_report_subscribers < 0) return "parameter min_report_subscribers must be >= 0";
  if (s.storage != "auto" && s.storage != "dense" && s.storage != "block_sparse")
    return "parameter storage must be auto, dense or block_sparse";
  if (s.dense_max_rows < 0) return "parameter dense_max_rows must be >= 0";
  if (!finite(s.dense_min_fill) || s.dense_min_fill < 0.0)
    return "parameter dense_min_fill must be >= 0 (above 1: block-sparse above dense_max_rows whatever the fill)";
  if (!finite(s.max_rel_warn) || s.max_rel_warn <= 0.0) return "parameter max_rel_warn must be > 0";
  return "";
}

}  // namespace

std::string loadMujocoBridgeSettings(const ros::NodeHandle& pnh, MujocoBridgeSettings* s) {
  return loadSettings(
      pnh, s,
      {LCS_PARAM_FIELD(s, model), LCS_PARAM_FIELD(s, mode), LCS_PARAM_FIELD(s, cone),
       LCS_PARAM_FIELD(s, mujoco_solver), LCS_PARAM_FIELD(s, mujoco_iterations),
       LCS_PARAM_FIELD(s, mujoco_tolerance), LCS_PARAM_FIELD(s, compare), LCS_PARAM_FIELD(s, reference),
       LCS_PARAM_FIELD(s, steps), LCS_PARAM_FIELD(s, dt), LCS_PARAM_FIELD(s, min_report_subscribers),
       LCS_PARAM_FIELD(s, include_limits), LCS_PARAM_FIELD(s, include_equalities),
       LCS_PARAM_FIELD(s, storage), LCS_PARAM_FIELD(s, dense_max_rows), LCS_PARAM_FIELD(s, dense_min_fill),
       LCS_PARAM_FIELD(s, max_rel_warn),
       LCS_PARAM_FIELD(s, print_summary)},
      [s] { return validate(*s); });
}

}  // namespace lcp_contact_solver_ros
