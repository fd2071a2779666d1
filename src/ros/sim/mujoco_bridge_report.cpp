// The MuJoCo bridge's reporting (mujoco_bridge_node.h): the values of a ~step_report, the
// status lines and the final summary.
#include "lcp_contact_solver/ros/sim/mujoco_bridge_node.h"

#include <diagnostic_msgs/KeyValue.h>

#include <iomanip>
#include <iostream>
#include <sstream>

namespace lcp_contact_solver_ros {

namespace scene = lcs::scene;

const char* const MujocoBridgeNode::kStateNames[lcs::core::kContactStateCount] = {"open", "stick", "slip",
                                                                                  "ignored", "closed"};

void MujocoBridgeNode::addValue(diagnostic_msgs::DiagnosticStatus* status, const std::string& key,
                                const std::string& value) {
  diagnostic_msgs::KeyValue kv;
  kv.key = key;
  kv.value = value;
  status->values.push_back(kv);
}

void MujocoBridgeNode::addValue(diagnostic_msgs::DiagnosticStatus* status, const std::string& key,
                                double value) {
  std::ostringstream out;
  out << std::setprecision(17) << value;
  addValue(status, key, out.str());
}

void MujocoBridgeNode::statusLine(int contacts, int rows) {
  const double t = world_->data()->time;
  if (t + 1e-9 * dt_ < next_status_time_) return;
  while (next_status_time_ <= t + 1e-9 * dt_) next_status_time_ += settings_.status_period;
  if (settings_.print_summary) {
    std::ostringstream line;
    if (!header_printed_) {
      line << "  sim time  contacts  rows  max residual  max rel diff  penetration [m]  energy [J]  missed\n";
      header_printed_ = true;
    }
    const bool compares = !drive_ || settings_.compare;
    line << std::fixed << std::setprecision(2) << std::setw(8) << t << " s" << std::setw(10) << contacts
         << std::setw(6) << rows << std::scientific << std::setprecision(2) << std::setw(14)
         << period_max_residual_;
    if (compares)
      line << std::setw(14) << period_max_rel_;
    else
      line << std::setw(14) << "-";
    line << std::setw(17) << totals_.last_penetration << std::fixed << std::setprecision(3) << std::setw(12)
         << totals_.last_energy << std::setw(8) << link_.counters().misses() << '\n';
    std::cout << line.str() << std::flush;
  }
  period_max_rel_ = 0.0;
  period_max_residual_ = 0.0;
}

void MujocoBridgeNode::writeSummary(std::ostream& out) const {
  const mjModel* m = world_->model();
  const mjData* d = world_->data();
  std::ostringstream text;
  text << std::fixed << std::setprecision(2);
  text << "mujoco " << settings_.model << " (cone " << scene::mujocoConeName(m->opt.cone) << ", mode "
       << settings_.mode << "): " << counters_.steps << " steps, " << d->time << " s simulated";
  if (run_wall_time_ > 0.0) text << " in " << run_wall_time_ << " s wall";
  text << "\nforces: " << counters_.forces_applied << " of " << counters_.steps_with_rows
       << " steps with contacts from the solver; " << link_.counters().force_timeouts << " timeouts, "
       << link_.counters().solver_failures << " solver failures, " << link_.counters().bad_forces
       << " mismatched";
  if (drive_) text << "; " << counters_.fallbacks << " steps by MuJoCo's own solver";
  if (counters_.extract_errors > 0) text << "; " << counters_.extract_errors << " steps not convertible";
  text << "\ncontacts: " << totals_.last_contacts << " at the end, " << totals_.max_contacts << " at most ("
       << totals_.max_rows << " rows at most)";
  text << std::scientific << std::setprecision(2);
  text << "\nour residual: " << totals_.last_residual << " at the end, " << totals_.max_residual
       << " at most";
  if (counters_.compared > 0) {
    text << "\nmax difference to MuJoCo's forces (" << scene::mujocoSolverName(m->opt.solver)
         << "): " << totals_.max_rel_diff << " relative, " << totals_.max_abs_diff << " N absolute, over "
         << counters_.compared << " steps";
    if (m->opt.cone == mjCONE_ELLIPTIC) {
      text << "\n  per state of our contacts (MuJoCo solves the convex relaxation, we solve Coulomb):";
      for (int k = 0; k < 3; ++k)
        text << ' ' << kStateNames[k] << ' ' << totals_.state_max_rel[k] << " (" << totals_.state_count[k]
             << ")";
    }
  }
  if (totals_.our_solves > 0 && totals_.mujoco_solves > 0)
    text << "\nsolve time per step: ours " << totals_.our_solve_time / totals_.our_solves * 1e3
         << " ms, MuJoCo's " << totals_.mujoco_solve_time / totals_.mujoco_solves * 1e3 << " ms ("
         << scene::mujocoSolverName(m->opt.solver) << ", " << m->opt.iterations << " iterations, tolerance "
         << std::defaultfloat << m->opt.tolerance << "; not matched in accuracy: see mujoco_bench)";
  text << std::fixed << std::setprecision(4) << "\nstate: energy " << totals_.first_energy << " J -> "
       << totals_.last_energy << " J, penetration " << totals_.last_penetration << " m at the end, "
       << totals_.max_penetration << " m at most";
  if (m->nq >= 3 && m->njnt > 0 && m->jnt_type[0] == mjJNT_FREE)
    text << ", root height " << d->qpos[2] << " m";
  if (reference_)
    text << "\nMuJoCo's own run beside (~reference): bodies up to " << totals_.max_ref_position_diff
         << " m from theirs, energy up to " << totals_.max_ref_energy_diff
         << " J apart, contact pairs differ on " << totals_.ref_contact_pair_steps_differ << " steps";
  text << '\n';
  out << text.str();
}

}  // namespace lcp_contact_solver_ros
