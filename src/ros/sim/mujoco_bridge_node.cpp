#include "lcp_contact_solver/ros/sim/mujoco_bridge_node.h"

#include "lcp_contact_solver/ros/msg_conversion/mujoco_msg_conversion.h"
#include "lcp_contact_solver/scene/mujoco_comparison.h"

#include <boost/make_shared.hpp>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <sstream>
#include <stdexcept>

namespace lcp_contact_solver_ros {

namespace {

namespace scene = lcs::scene;

MujocoBridgeSettings loadOrThrow(const ros::NodeHandle& pnh) {
  MujocoBridgeSettings settings;
  const std::string error = loadMujocoBridgeSettings(pnh, &settings);
  if (!error.empty()) throw std::invalid_argument(error);
  return settings;
}

std::unique_ptr<scene::MujocoWorld> loadWorld(const MujocoBridgeSettings& s) {
  scene::MujocoOptions options;
  if (s.cone != "model") options.cone = s.cone;
  if (s.mujoco_solver != "model") options.solver = s.mujoco_solver;
  if (s.mujoco_iterations > 0) options.iterations = s.mujoco_iterations;
  if (s.mujoco_tolerance >= 0.0) options.tolerance = s.mujoco_tolerance;
  if (s.dt > 0.0) options.timestep = s.dt;
  std::string error;
  auto world = scene::MujocoWorld::load(s.model, options, &error);
  if (!world) throw std::invalid_argument("parameter model: " + error);
  if (s.mode == "drive" && world->model()->opt.integrator != mjINT_EULER)
    throw std::invalid_argument("parameter model: " + s.model +
                                " does not use MuJoCo's Euler integrator, which drive mode needs");
  return world;
}

}  // namespace

MujocoBridgeNode::MujocoBridgeNode(const ros::NodeHandle& nh, const ros::NodeHandle& pnh)
    : nh_(nh),
      pnh_(pnh),
      settings_(loadOrThrow(pnh)),
      world_(loadWorld(settings_)),
      link_(nh, settings_, linkOptions(this)) {
  drive_ = settings_.mode == "drive";
  dt_ = world_->model()->opt.timestep;
  extract_.include_limits = settings_.include_limits;
  extract_.include_equalities = settings_.include_equalities;
  extract_.dense_max_rows = settings_.dense_max_rows;
  extract_.dense_min_fill = settings_.dense_min_fill;
  if (settings_.storage == "dense") extract_.storage = scene::MujocoExtractOptions::Storage::kDense;
  if (settings_.storage == "block_sparse")
    extract_.storage = scene::MujocoExtractOptions::Storage::kBlockSparse;

  report_pub_ = pnh_.advertise<diagnostic_msgs::DiagnosticStatus>("step_report", 100);
  reference_pub_ = pnh_.advertise<lcp_contact_solver::ConstraintForces>("reference_forces", 100);
  next_status_time_ = settings_.status_period;
  if (settings_.steps == 0 && settings_.duration > 0.0)
    settings_.steps = std::max(1, static_cast<int>(std::llround(settings_.duration / dt_)));
}

MujocoBridgeNode::~MujocoBridgeNode() = default;

// The bridge waits for the solver until its forces' timeout (no early end when it leaves),
// gives the stats of a solve a moment to follow its forces (for the report) and, for tests,
// waits for ~step_report subscribers too.
SolverLink::Options MujocoBridgeNode::linkOptions(const MujocoBridgeNode* node) {
  SolverLink::Options options;
  options.stop_when_solver_leaves = false;
  options.stats_grace = 0.05;
  options.also_ready = [node] {
    return node->report_pub_.getNumSubscribers() >=
           static_cast<std::uint32_t>(node->settings_.min_report_subscribers);
  };
  return options;
}

bool MujocoBridgeNode::run() {
  const mjModel* m = world_->model();
  ROS_INFO_STREAM("MuJoCo " << mj_versionString() << ": " << settings_.model << " (nq " << m->nq << ", nv "
                            << m->nv << "), cone " << scene::mujocoConeName(m->opt.cone) << ", dt " << dt_
                            << " s, mode " << settings_.mode << ", MuJoCo solver "
                            << scene::mujocoSolverName(m->opt.solver) << " (" << m->opt.iterations
                            << " iterations, tolerance " << m->opt.tolerance << ")");
  link_.publishClock(stepStamp(0, dt_));
  if (!link_.waitForSolver()) return false;
  if (drive_ && settings_.reference) reference_ = world_->clone();
  link_.startRun();
  while (ros::ok() && (settings_.steps == 0 || counters_.steps < settings_.steps)) {
    step();
    link_.pace(world_->data()->time);
  }
  run_wall_time_ = link_.runWallTime();
  std::ostringstream summary;
  writeSummary(summary);
  link_.logSummary("MuJoCo bridge", settings_.print_summary, summary.str(), counters_.steps);
  link_.linger();
  return ros::ok();
}

void MujocoBridgeNode::step() {
  mjModel* m = world_->model();
  mjData* d = world_->data();
  const bool mujoco_solves = !drive_ || settings_.compare;
  double mujoco_time = 0.0;
  scene::forwardToConstraints(m, d, mujoco_solves, &mujoco_time);
  if (mujoco_solves && d->nefc > 0) {
    totals_.mujoco_solve_time += mujoco_time;
    ++totals_.mujoco_solves;
  }
  const double energy = scene::totalEnergy(m, d);
  const double penetration = scene::maxPenetration(d);
  if (counters_.steps == 0) totals_.first_energy = energy;
  totals_.last_energy = energy;
  totals_.last_penetration = penetration;
  totals_.max_penetration = std::max(totals_.max_penetration, penetration);
  if (reference_) forwardReference();

  const ros::Time stamp = stepStamp(counters_.steps, dt_);
  link_.publishClock(stamp);

  scene::MujocoProblem mp;
  const std::string extract_error = scene::extractProblem(m, d, extract_, &mp);
  bool ours_applied = false;
  if (!extract_error.empty()) {
    ++counters_.extract_errors;
    ROS_ERROR_STREAM_THROTTLE(1.0, "Step at " << stampText(stamp) << ": " << extract_error
                                              << "; MuJoCo's own solver takes this step");
  } else if (!mp.problem.contacts.empty()) {
    ours_applied = exchange(mp, stamp, mujoco_solves ? mujoco_time : -1.0);
  }

  // Drive without our forces for a step with constraints: MuJoCo's solver decides it.
  if (drive_ && !ours_applied && d->nefc > 0) {
    if (!mujoco_solves) mj_fwdConstraint(m, d);
    ++counters_.fallbacks;
  }
  const std::string error = scene::integrateEuler(m, d);
  if (!error.empty()) throw std::runtime_error(error);  // checked at load; kept as a guard
  if (reference_) stepReference();
  ++counters_.steps;
  statusLine(mp.ncon, mp.problem.rowCount());
}

bool MujocoBridgeNode::exchange(const scene::MujocoProblem& mp, const ros::Time& stamp, double mujoco_time) {
  const mjModel* m = world_->model();
  mjData* d = world_->data();
  ++counters_.steps_with_rows;
  totals_.last_contacts = mp.ncon;
  totals_.max_contacts = std::max(totals_.max_contacts, mp.ncon);
  totals_.max_rows = std::max(totals_.max_rows, mp.problem.rowCount());

  std_msgs::Header header;
  header.stamp = stamp;
  header.frame_id = settings_.frame_id;
  auto contacts =
      boost::make_shared<lcp_contact_solver::ContactArray>(toContactArrayMsg(mp, *world_, header));
  auto compliance = boost::make_shared<lcp_contact_solver::Compliance>(toComplianceMsg(mp, header));
  if (mujoco_time >= 0.0 && reference_pub_.getNumSubscribers() > 0) {  // MuJoCo's solver ran for this step
    auto reference = boost::make_shared<lcp_contact_solver::ConstraintForces>();
    const std::string error = toReferenceForcesMsg(mp, *contacts, *compliance, reference.get());
    if (error.empty())
      reference_pub_.publish(reference);
    else
      ROS_ERROR_STREAM_THROTTLE(1.0, "Step at " << stampText(stamp) << ": no reference forces: " << error);
  }
  const SolverLink::Outcome outcome = link_.exchange(stamp, contacts, compliance);

  diagnostic_msgs::DiagnosticStatus report;
  report.name = "mujoco_bridge";
  report.hardware_id = settings_.model;
  addValue(&report, "step", static_cast<double>(counters_.steps));
  addValue(&report, "time", d->time);
  addValue(&report, "mode", settings_.mode);
  addValue(&report, "cone", scene::mujocoConeName(m->opt.cone));
  addValue(&report, "contacts", mp.ncon);
  addValue(&report, "entries", static_cast<double>(mp.entries.size()));
  addValue(&report, "rows", mp.problem.rowCount());
  addValue(&report, "dropped_rows", static_cast<double>(mp.dropped_rows.size()));
  addValue(&report, "penetration", totals_.last_penetration);
  addValue(&report, "energy", totals_.last_energy);
  if (mujoco_time >= 0.0) addValue(&report, "mujoco_solve_time", mujoco_time);
  if (reference_) {
    addValue(&report, "ref_position_diff", ref_position_diff_);
    addValue(&report, "ref_energy", ref_energy_);
    addValue(&report, "ref_contacts", ref_contacts_);
    addValue(&report, "ref_contact_pairs_differ", ref_pairs_differ_);
  }

  Eigen::VectorXd lambda;
  const std::string problem_text = receive(outcome, mp, &lambda);
  bool ours_applied = false;
  if (problem_text.empty()) {
    ours_applied = useForces(mp, lambda, stamp, mujoco_time >= 0.0, &report);
  } else {
    report.level = diagnostic_msgs::DiagnosticStatus::WARN;
    report.message = problem_text;
    addValue(&report, "forces", problem_text);
    if (outcome != SolverLink::Outcome::kShutdown)
      ROS_WARN_STREAM_THROTTLE(1.0, "Step at " << stampText(stamp) << ": " << problem_text
                                               << (drive_ ? "; MuJoCo's own solver takes this step" : ""));
  }
  report_pub_.publish(report);
  return ours_applied;
}

// λ from the forces of the exchange; empty string, or why the step has none.
std::string MujocoBridgeNode::receive(SolverLink::Outcome outcome, const scene::MujocoProblem& mp,
                                      Eigen::VectorXd* lambda) {
  switch (outcome) {
    case SolverLink::Outcome::kForces: {
      const std::string error = toProblemForces(link_.forces(), mp, lambda);
      if (error.empty()) return "";
      link_.countBadForces();
      return "forces do not fit: " + error;
    }
    case SolverLink::Outcome::kTimeout:
      return "no forces within " + std::to_string(settings_.force_timeout) + " s";
    case SolverLink::Outcome::kNoSolver: return "no solver publishes " + link_.forcesTopic();
    case SolverLink::Outcome::kSolverFailed: return "the solver gave no forces (" + link_.failure() + ")";
    case SolverLink::Outcome::kShutdown: break;
  }
  return "shutdown";
}

// Our forces came: residual, comparison with MuJoCo's, and in drive mode into the step.
bool MujocoBridgeNode::useForces(const scene::MujocoProblem& mp, const Eigen::VectorXd& lambda,
                                 const ros::Time& stamp, bool mujoco_solves,
                                 diagnostic_msgs::DiagnosticStatus* report) {
  ++counters_.forces_applied;
  const double residual = scene::problemResidual(mp, lambda);
  totals_.last_residual = residual;
  totals_.max_residual = std::max(totals_.max_residual, residual);
  period_max_residual_ = std::max(period_max_residual_, residual);
  addValue(report, "forces", "received");
  addValue(report, "residual", residual);
  if (const auto& stats = link_.stats()) {
    addValue(report, "iterations", stats->iterations);
    addValue(report, "solve_time", stats->solve_time);
    addValue(report, "solver", stats->solver);
    totals_.our_solve_time += stats->solve_time;
    ++totals_.our_solves;
  }
  if (mujoco_solves) compare(mp, lambda, stamp, report);
  if (drive_) scene::applyConstraintForces(world_->model(), world_->data(), mp.toEfcForce(lambda));
  std::ostringstream message;
  message << mp.ncon << " contacts, " << mp.problem.rowCount() << " rows, residual " << residual;
  report->message = message.str();
  return drive_;
}

void MujocoBridgeNode::compare(const scene::MujocoProblem& mp, const Eigen::VectorXd& lambda,
                               const ros::Time& stamp, diagnostic_msgs::DiagnosticStatus* report) {
  std::vector<lcs::core::ContactState> states;
  for (const auto& f : link_.forces().forces)
    states.push_back(
        static_cast<lcs::core::ContactState>(std::min<int>(f.state, lcs::core::kContactStateCount - 1)));
  const scene::ForceComparison cmp = scene::compareForces(mp, lambda, states);
  ++counters_.compared;
  totals_.max_abs_diff = std::max(totals_.max_abs_diff, cmp.max_abs);
  totals_.max_rel_diff = std::max(totals_.max_rel_diff, cmp.max_rel);
  period_max_rel_ = std::max(period_max_rel_, cmp.max_rel);
  addValue(report, "max_abs_diff", cmp.max_abs);
  addValue(report, "max_rel_diff", cmp.max_rel);
  addValue(report, "force_scale", cmp.scale);
  for (int k = 0; k < lcs::core::kContactStateCount; ++k) {
    totals_.state_count[k] += cmp.state_count[k];
    if (cmp.state_count[k] == 0) continue;
    totals_.state_max_rel[k] = std::max(totals_.state_max_rel[k], cmp.state_max_abs[k] / cmp.scale);
    addValue(report, std::string("max_rel_diff_") + kStateNames[k], cmp.state_max_abs[k] / cmp.scale);
    addValue(report, std::string("entries_") + kStateNames[k], cmp.state_count[k]);
  }
  if (cmp.max_rel > settings_.max_rel_warn) {
    ++counters_.over_warn;
    if (mp.pyramidal)  // an LCP with a unique solution: a difference means an inexact solve
      ROS_WARN_STREAM_THROTTLE(1.0, "Step at " << stampText(stamp) << ": our forces differ from MuJoCo's by "
                                               << cmp.max_rel << " (relative) on the pyramidal LCP");
  }
  report->level = cmp.max_rel > settings_.max_rel_warn && mp.pyramidal
                      ? diagnostic_msgs::DiagnosticStatus::WARN
                      : diagnostic_msgs::DiagnosticStatus::OK;
}

namespace {

// The geom pairs in contact, ordered.
std::vector<std::pair<int, int>> contactPairs(const mjData* d) {
  std::vector<std::pair<int, int>> pairs;
  for (int i = 0; i < d->ncon; ++i)
    pairs.emplace_back(std::min(d->contact[i].geom1, d->contact[i].geom2),
                       std::max(d->contact[i].geom1, d->contact[i].geom2));
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  return pairs;
}

}  // namespace

// Both copies are at the same step, before its constraint solve: where the bodies are, the
// energy, which geoms touch.
void MujocoBridgeNode::forwardReference() {
  mjModel* rm = reference_->model();
  mjData* rd = reference_->data();
  const mjData* d = world_->data();
  scene::forwardToConstraints(rm, rd, true);
  double worst = 0.0;
  for (int b = 1; b < rm->nbody; ++b) {
    double dist2 = 0.0;
    for (int k = 0; k < 3; ++k) dist2 += std::pow(d->xpos[3 * b + k] - rd->xpos[3 * b + k], 2);
    worst = std::max(worst, std::sqrt(dist2));
  }
  ref_position_diff_ = worst;
  ref_energy_ = scene::totalEnergy(rm, rd);
  ref_contacts_ = rd->ncon;
  const auto ours = contactPairs(d), theirs = contactPairs(rd);
  std::vector<std::pair<int, int>> differ;
  std::set_symmetric_difference(ours.begin(), ours.end(), theirs.begin(), theirs.end(),
                                std::back_inserter(differ));
  ref_pairs_differ_ = static_cast<int>(differ.size());
  totals_.max_ref_position_diff = std::max(totals_.max_ref_position_diff, worst);
  totals_.max_ref_energy_diff =
      std::max(totals_.max_ref_energy_diff, std::abs(totals_.last_energy - ref_energy_));
  if (ref_pairs_differ_ > 0) ++totals_.ref_contact_pair_steps_differ;
}

void MujocoBridgeNode::stepReference() {
  const std::string error = scene::integrateEuler(reference_->model(), reference_->data());
  if (!error.empty()) throw std::runtime_error(error);
}

}  // namespace lcp_contact_solver_ros
