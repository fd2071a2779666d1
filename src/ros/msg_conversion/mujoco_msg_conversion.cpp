#include "lcp_contact_solver/ros/msg_conversion/mujoco_msg_conversion.h"

#include "lcp_contact_solver/core/residual.h"
#include "lcp_contact_solver/ros/msg_conversion/msg_conversion.h"

#include <cmath>
#include <vector>

namespace lcp_contact_solver_ros {

namespace {

namespace scene = lcs::scene;
using lcp_contact_solver::ContactPoint;

}  // namespace

// ---- messages -------------------------------------------------------------------------------

lcp_contact_solver::ContactArray toContactArrayMsg(const scene::MujocoProblem& problem,
                                                   const scene::MujocoWorld& world,
                                                   const std_msgs::Header& header) {
  std::vector<ContactFrame> frames(problem.entries.size());
  std::vector<ContactBodies> bodies(problem.entries.size());
  for (std::size_t i = 0; i < problem.entries.size(); ++i) {
    const scene::MujocoEntry& e = problem.entries[i];
    // Elliptic contacts keep MuJoCo's own frame, so the rows stay its rows; the other
    // entries (pyramid edges, limits, equalities) leave the tangents to the reader's rule.
    if (e.kind == scene::MujocoRowKind::kElliptic) {
      frames[i].position = e.position;
      frames[i].normal = e.normal;
      frames[i].tangent1 = e.tangent1;
      frames[i].tangent2 = e.tangent2;
    } else {
      frames[i] = lcs::core::frameFromNormal(e.position, e.normal);
    }
    bodies[i] = {world.bodyName(e.body_a), world.bodyName(e.body_b)};
  }
  lcp_contact_solver::ContactArray msg = toContactArrayMsg(problem.problem, frames, bodies, header);
  // MuJoCo's reference acceleration (solref) is already in d_free: no Baumgarte correction
  // or softness on top, whatever the node's ~erp / ~softness (the adapter's contacts keep
  // the core's "use the default" there, so in-process solves are unchanged).
  for (ContactPoint& p : msg.contacts) p.erp = p.softness = 0.0;
  return msg;
}

lcp_contact_solver::Compliance toComplianceMsg(const scene::MujocoProblem& problem,
                                               const std_msgs::Header& header) {
  lcp_contact_solver::Compliance msg = toComplianceMsg(problem.problem.W);
  msg.header = header;
  return msg;
}

std::string toReferenceForcesMsg(const scene::MujocoProblem& problem,
                                 const lcp_contact_solver::ContactArray& contacts,
                                 const lcp_contact_solver::Compliance& compliance,
                                 lcp_contact_solver::ConstraintForces* forces) {
  lcs::core::Problem read;
  std::vector<ContactFrame> frames;
  if (std::string error = toProblem(contacts, compliance, 0, &read, &frames); !error.empty()) return error;
  if (read.rowCount() != problem.mujoco_lambda.size())
    return std::to_string(problem.mujoco_lambda.size()) + " MuJoCo forces for " +
           std::to_string(read.rowCount()) + " rows";
  lcs::core::SolveResult mujoco;
  mujoco.forces = problem.mujoco_lambda;
  // Every contact of the bridge carries its own mu (pyramid edges and limits none): the
  // default is never used.
  mujoco.states = lcs::core::classifyContacts(
      read, lcs::core::effectiveMu(read, lcs::core::SolverParams().mu), mujoco.forces);
  *forces = toConstraintForcesMsg(contacts, frames, read, mujoco);
  return "";
}

std::string toProblemForces(const lcp_contact_solver::ConstraintForces& forces,
                            const scene::MujocoProblem& problem, Eigen::VectorXd* lambda) {
  const std::size_t n = problem.problem.contacts.size();
  if (forces.forces.size() != n)
    return std::to_string(forces.forces.size()) + " forces for " + std::to_string(n) + " contacts";
  const std::vector<int> offsets = problem.problem.rowOffsets();
  lambda->resize(offsets.back());
  for (std::size_t i = 0; i < n; ++i) {
    const auto& f = forces.forces[i];
    if (f.id != problem.problem.contacts[i].id)
      return "force " + std::to_string(i) + " has id " + std::to_string(f.id) + ", the contact " +
             std::to_string(problem.problem.contacts[i].id);
    const int rows = offsets[i + 1] - offsets[i];
    if (static_cast<int>(f.lambda.size()) != rows)
      return "force " + std::to_string(i) + " has " + std::to_string(f.lambda.size()) +
             " rows, the contact " + std::to_string(rows);
    for (int r = 0; r < rows; ++r) {
      if (!std::isfinite(f.lambda[r])) return "force " + std::to_string(i) + " is not finite";
      (*lambda)[offsets[i] + r] = f.lambda[r];
    }
  }
  return "";
}

}  // namespace lcp_contact_solver_ros
