// The MuJoCo bridge's messages (ros/sim/mujoco_bridge_node.h): a step's problem
// (scene/mujoco_adapter.h) as the node's ContactArray and Compliance, MuJoCo's own forces as
// the node's ConstraintForces, and the node's forces back in the problem's rows. Written
// through msg_conversion.h like every simulator's.
#pragma once

#include "lcp_contact_solver/scene/mujoco_adapter.h"

#include <lcp_contact_solver/Compliance.h>
#include <lcp_contact_solver/ConstraintForces.h>
#include <lcp_contact_solver/ContactArray.h>
#include <std_msgs/Header.h>

#include <Eigen/Core>

#include <string>

namespace lcp_contact_solver_ros {

namespace lcs = ::lcp_contact_solver;

// The messages of one step's problem (positions and directions in MuJoCo's world frame).
lcp_contact_solver::ContactArray toContactArrayMsg(const lcs::scene::MujocoProblem& problem,
                                                   const lcs::scene::MujocoWorld& world,
                                                   const std_msgs::Header& header);
lcp_contact_solver::Compliance toComplianceMsg(const lcs::scene::MujocoProblem& problem,
                                               const std_msgs::Header& header);
// MuJoCo's own forces of the step (problem.mujoco_lambda: efc_force in problem rows) as the
// node would publish them for `contacts` and `compliance` (toProblem, then
// toConstraintForcesMsg with the states classifyContacts gives): same ids, rows and layout,
// so they compare with the node's row by row. Empty string, or why the messages do not
// convert (they came from `problem`, so only for a bug).
std::string toReferenceForcesMsg(const lcs::scene::MujocoProblem& problem,
                                 const lcp_contact_solver::ContactArray& contacts,
                                 const lcp_contact_solver::Compliance& compliance,
                                 lcp_contact_solver::ConstraintForces* forces);
// λ (problem rows) from the solver's forces for this problem; empty string or why they do not fit.
std::string toProblemForces(const lcp_contact_solver::ConstraintForces& forces,
                            const lcs::scene::MujocoProblem& problem, Eigen::VectorXd* lambda);

}  // namespace lcp_contact_solver_ros
