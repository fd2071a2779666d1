// A solve's outcome → ConstraintForces and SolverStats (msg_conversion.h), and the checks
// before publishing them.
#include "lcp_contact_solver/ros/msg_conversion/msg_conversion.h"

#include "lcp_contact_solver/ros/msg_conversion/msg_primitives.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <unordered_map>
#include <utility>

namespace lcp_contact_solver_ros {

namespace {

// Up to three rows of a contact along (n, t1, t2); later bilateral rows have no direction.
Eigen::Vector3d directionalForce(const lcs::core::Contact& contact, const double* lambda) {
  Eigen::Vector3d components = Eigen::Vector3d::Zero();
  for (int k = 0; k < std::min(3, contact.rows); ++k) components[k] = lambda[k];
  return components;
}

}  // namespace

lcs::ConstraintForces toConstraintForcesMsg(const lcs::ContactArray& contacts,
                                            const std::vector<ContactFrame>& frames,
                                            const lcs::core::Problem& problem,
                                            const lcs::core::SolveResult& result) {
  lcs::ConstraintForces msg;
  msg.header = contacts.header;
  const std::vector<int> offsets = problem.rowOffsets();
  msg.forces.resize(problem.contacts.size());
  for (std::size_t i = 0; i < problem.contacts.size(); ++i) {
    const lcs::core::Contact& contact = problem.contacts[i];
    const ContactFrame& frame = frames[i];
    const double* lambda = result.forces.data() + offsets[i];
    const Eigen::Vector3d components = directionalForce(contact, lambda);
    lcs::ContactForce& out = msg.forces[i];
    out.id = contact.id;
    out.body_a = contacts.contacts[i].body_a;
    out.body_b = contacts.contacts[i].body_b;
    out.state = static_cast<std::uint8_t>(result.states[i]);
    out.normal_force = components[0];
    out.tangent1_force = components[1];
    out.tangent2_force = components[2];
    out.force = toVector3(frame.normal * components[0] + frame.tangent1 * components[1] +
                          frame.tangent2 * components[2]);
    out.position = toPoint(frame.position);
    out.normal = toVector3(frame.normal);
    out.tangent1 = toVector3(frame.tangent1);
    out.tangent2 = toVector3(frame.tangent2);
    out.lambda.assign(lambda, lambda + contact.rows);
    if (contact.type == lcs::core::ContactType::kTorsional ||
        contact.type == lcs::core::ContactType::kRolling) {
      Eigen::Vector3d torque = frame.normal * lambda[3];
      if (contact.rows == 6) torque += frame.tangent1 * lambda[4] + frame.tangent2 * lambda[5];
      out.torque = toVector3(torque);
    }
  }
  msg.wrenches = sumBodyPairWrenches(msg.forces);
  return msg;
}

std::vector<lcs::BodyPairWrench> sumBodyPairWrenches(const std::vector<lcs::ContactForce>& forces) {
  std::vector<lcs::BodyPairWrench> wrenches;
  // Pairs in order of first appearance; the lookup by hash, and the previous contact's pair
  // first (a simulator lists a pair's contacts together): no string copy per contact.
  struct PairHash {
    std::size_t operator()(const std::pair<const std::string*, const std::string*>& k) const {
      const std::size_t a = std::hash<std::string>()(*k.first);
      return a ^ (std::hash<std::string>()(*k.second) + 0x9e3779b97f4a7c15ULL + (a << 6) + (a >> 2));
    }
  };
  struct PairEqual {
    bool operator()(const std::pair<const std::string*, const std::string*>& x,
                    const std::pair<const std::string*, const std::string*>& y) const {
      return *x.first == *y.first && *x.second == *y.second;
    }
  };
  std::unordered_map<std::pair<const std::string*, const std::string*>, std::size_t, PairHash, PairEqual>
      index;
  std::vector<Eigen::Vector3d> force_sum, torque_sum;
  std::size_t last = 0;
  for (const lcs::ContactForce& f : forces) {
    std::size_t at;
    if (!wrenches.empty() && wrenches[last].body_a == f.body_a && wrenches[last].body_b == f.body_b) {
      at = last;
    } else {
      const auto found = index.find({&f.body_a, &f.body_b});  // keys point into `forces`
      if (found != index.end()) {
        at = found->second;
      } else {
        at = wrenches.size();
        index.emplace(std::make_pair(&f.body_a, &f.body_b), at);
        lcs::BodyPairWrench w;
        w.body_a = f.body_a;
        w.body_b = f.body_b;
        wrenches.push_back(w);
        force_sum.emplace_back(Eigen::Vector3d::Zero());
        torque_sum.emplace_back(Eigen::Vector3d::Zero());
      }
    }
    last = at;
    const Eigen::Vector3d force = toEigen(f.force);
    force_sum[at] += force;
    torque_sum[at] += toEigen(f.position).cross(force) + toEigen(f.torque);
  }
  for (std::size_t k = 0; k < wrenches.size(); ++k) {
    wrenches[k].wrench.force = toVector3(force_sum[k]);
    wrenches[k].wrench.torque = toVector3(torque_sum[k]);
  }
  return wrenches;
}

lcs::SolverStats toStatsMsg(const std_msgs::Header& header, const lcs::core::Problem& problem,
                            const lcs::core::SolveResult& result) {
  lcs::SolverStats stats;
  stats.header = header;
  stats.success = solveGaveForces(result);
  stats.status_code = static_cast<std::uint8_t>(result.status);
  stats.status = lcs::core::statusName(result.status);
  stats.message = result.message;
  stats.solver = result.solver;
  stats.friction_model = lcs::core::frictionModelName(result.friction_model);
  stats.iterations = result.iterations;
  stats.residual = result.residual;
  stats.solver_error = result.solver_error;
  stats.converged = result.converged;
  stats.solve_time = result.solve_time;
  stats.num_contacts = static_cast<std::int32_t>(problem.contacts.size());
  stats.num_rows = problem.rowCount();
  return stats;
}

lcs::SolverStats rejectedStatsMsg(const std_msgs::Header& header, std::uint8_t status_code,
                                  const std::string& message) {
  lcs::SolverStats stats;
  stats.header = header;
  stats.success = false;
  stats.status_code = status_code;
  stats.status = statusCodeName(status_code);
  stats.message = message;
  return stats;
}

std::string statusCodeName(std::uint8_t status_code) {
  if (status_code == lcs::SolverStats::NO_COMPLIANCE) return "no_compliance";
  if (status_code == lcs::SolverStats::DROPPED) return "dropped";
  if (status_code < lcs::SolverStats::NO_COMPLIANCE)
    return lcs::core::statusName(
        static_cast<lcs::core::SolveStatus>(status_code));  // "unknown" past the last
  return "unknown";
}

bool solveGaveForces(const lcs::core::SolveResult& result) {
  return result.status == lcs::core::SolveStatus::kConverged ||
         result.status == lcs::core::SolveStatus::kMaxIterations ||
         result.status == lcs::core::SolveStatus::kTimeBudget;
}

bool allFinite(const lcs::ConstraintForces& forces) {
  for (const lcs::ContactForce& f : forces.forces) {
    if (!std::isfinite(f.normal_force) || !std::isfinite(f.tangent1_force) ||
        !std::isfinite(f.tangent2_force) || !finite(f.force) || !finite(f.position) || !finite(f.normal) ||
        !finite(f.tangent1) || !finite(f.tangent2))
      return false;
    for (double v : f.lambda)
      if (!std::isfinite(v)) return false;
  }
  for (const lcs::BodyPairWrench& w : forces.wrenches)
    if (!finite(w.wrench.force) || !finite(w.wrench.torque)) return false;
  return true;
}

bool allFinite(const lcs::SolverStats& stats) {
  return std::isfinite(stats.residual) && std::isfinite(stats.solver_error) &&
         std::isfinite(stats.solve_time);
}

}  // namespace lcp_contact_solver_ros
