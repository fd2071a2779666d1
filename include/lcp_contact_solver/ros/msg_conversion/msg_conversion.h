// Conversions between the package's messages and the ROS-free core, as free functions:
// the one home of message conversion (the simulators' scene_msg_conversion and the MuJoCo
// bridge write their ContactArray through toContactArrayMsg here; Eigen ↔ geometry_msgs is
// msg_primitives.h). Every function that reads a message validates it and returns an empty
// string on success or one sentence naming the first fault, so a malformed message never
// reaches the solver.
//
// Implemented in src/ros/msg_conversion/ by what is converted: contact_point.cpp (one
// contact's type and frame), problem_from_msgs.cpp (ContactArray + Compliance → Problem),
// problem_to_msgs.cpp (Problem → ContactArray, Compliance), result_msgs.cpp (SolveResult →
// ConstraintForces, SolverStats).
#pragma once

#include "lcp_contact_solver/core/contact_frame.h"
#include "lcp_contact_solver/core/problem.h"
#include "lcp_contact_solver/core/solve_result.h"

#include <lcp_contact_solver/Compliance.h>
#include <lcp_contact_solver/ConstraintForces.h>
#include <lcp_contact_solver/ContactArray.h>
#include <lcp_contact_solver/SolverStats.h>

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

namespace lcp_contact_solver_ros {

namespace lcs = ::lcp_contact_solver;

// The core's contact frame (core/contact_frame.h), in the contact array's header frame.
// Named here too because the node, the markers and this layer's users spell it
// lcp_contact_solver_ros::ContactFrame; it is the same type, not a second one.
using lcs::core::ContactFrame;

// The one mapping between the core's contact types and ContactPoint's type constants (the
// numbers agree by design; contact_point.cpp asserts it at compile time).
std::uint8_t toMsgType(lcs::core::ContactType type);
// Only for a type code that contactRows-style validation accepted (0..4).
lcs::core::ContactType fromMsgType(std::uint8_t type);

// Deterministic tangents of a unit normal: the core's rule (core/contact_frame.h), shared
// with the scene layer so both derive the same friction rows.
void deriveTangents(const Eigen::Vector3d& normal, Eigen::Vector3d* tangent1, Eigen::Vector3d* tangent2);

// Reads one contact's geometry, normalizing the directions and deriving missing tangents.
std::string toContactFrame(const lcs::ContactPoint& contact, ContactFrame* frame);

// Builds the core problem and the contact frames from a contact array and its
// compliance. Sizes are checked against the contacts before anything is allocated;
// `max_rows` > 0 refuses larger problems. Stamps are not compared here. `validate` false
// leaves out lcs::validateProblem (non-finite values in W and d_free): for a caller whose
// next step is ContactSolver::solve, which runs the same check (CycleSolver).
std::string toProblem(const lcs::ContactArray& contacts, const lcs::Compliance& compliance, int max_rows,
                      lcs::core::Problem* problem, std::vector<ContactFrame>* frames, bool validate = true);

// Body names of one contact, for toContactArrayMsg.
struct ContactBodies {
  std::string body_a, body_b;
};

// The ContactArray of a problem, written one way for every simulator: per contact (problem
// order) its id, type, rows, μ, μ_torsional, μ_rolling, gap, erp, softness and its rows'
// d_free from `problem`; position, normal and tangents from `frames` (tangents zero where
// derived_tangents: the reader derives the same); body names from `bodies`. `frames` and
// `bodies` have one entry per contact.
lcs::ContactArray toContactArrayMsg(const lcs::core::Problem& problem,
                                    const std::vector<ContactFrame>& frames,
                                    const std::vector<ContactBodies>& bodies, const std_msgs::Header& header);

// The compliance message of a core matrix (dense, or block-sparse with the core's blocks).
lcs::Compliance toComplianceMsg(const lcs::core::ComplianceMatrix& W);
// The compliance message of a problem: its body form (STORAGE_BODIES) when it has one,
// otherwise its W as above. `header` is left to the caller.
lcs::Compliance toComplianceMsg(const lcs::core::Problem& problem);

// Forces of a solved problem: per contact and summed per body pair. `frames` and
// `problem` come from toProblem on `contacts`.
lcs::ConstraintForces toConstraintForcesMsg(const lcs::ContactArray& contacts,
                                            const std::vector<ContactFrame>& frames,
                                            const lcs::core::Problem& problem,
                                            const lcs::core::SolveResult& result);

// The summed wrench on body_a per (body_a, body_b) pair, torques about the frame origin.
std::vector<lcs::BodyPairWrench> sumBodyPairWrenches(const std::vector<lcs::ContactForce>& forces);

// Stats of a solve that ran.
lcs::SolverStats toStatsMsg(const std_msgs::Header& header, const lcs::core::Problem& problem,
                            const lcs::core::SolveResult& result);

// Stats of an input that was not solved (malformed, unpaired, refused by the core).
lcs::SolverStats rejectedStatsMsg(const std_msgs::Header& header, std::uint8_t status_code,
                                  const std::string& message);

// The status name the node uses for a SolverStats status code.
std::string statusCodeName(std::uint8_t status_code);

// True when the solve gave forces worth applying: converged, or the best iterate at the
// iteration cap (SOFA's behaviour) or time budget. Other statuses publish no forces.
bool solveGaveForces(const lcs::core::SolveResult& result);

// Last guard before publishing: every number in the message is finite.
bool allFinite(const lcs::ConstraintForces& forces);
bool allFinite(const lcs::SolverStats& stats);

}  // namespace lcp_contact_solver_ros
