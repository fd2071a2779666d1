// Conversions between the package's messages and the ROS-free core, as free functions.
// Every function that reads a message validates it and returns an empty string on
// success or one sentence naming the first fault, so a malformed message never reaches
// the solver.
#pragma once

#include "lcp_contact_solver/core/problem.h"
#include "lcp_contact_solver/core/solve_result.h"

#include <lcp_contact_solver/Compliance.h>
#include <lcp_contact_solver/ConstraintForces.h>
#include <lcp_contact_solver/ContactArray.h>
#include <lcp_contact_solver/SolverStats.h>

#include <Eigen/Core>

#include <string>
#include <vector>

namespace lcp_contact_solver_ros {

namespace lcs = ::lcp_contact_solver;

// Where a contact is and its unit directions, in the contact array's header frame.
struct ContactFrame {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d tangent1 = Eigen::Vector3d::UnitX();
  Eigen::Vector3d tangent2 = Eigen::Vector3d::UnitY();
  bool derived_tangents = false;
};

// Deterministic tangents of a unit normal: the core's rule (core/contact_frame.h), shared
// with the scene layer so both derive the same friction rows.
void deriveTangents(const Eigen::Vector3d& normal, Eigen::Vector3d* tangent1,
                    Eigen::Vector3d* tangent2);

// Reads one contact's geometry, normalizing the directions and deriving missing tangents.
std::string toContactFrame(const lcs::ContactPoint& contact, ContactFrame* frame);

// Builds the core problem and the contact frames from a contact array and its
// compliance. Sizes are checked against the contacts before anything is allocated;
// `max_rows` > 0 refuses larger problems. Stamps are not compared here.
std::string toProblem(const lcs::ContactArray& contacts, const lcs::Compliance& compliance,
                      int max_rows, lcs::Problem* problem, std::vector<ContactFrame>* frames);

// The compliance message of a core matrix (dense, or block-sparse with the core's blocks).
lcs::Compliance toComplianceMsg(const lcs::ComplianceMatrix& W);
// The compliance message of a problem: its body form (STORAGE_BODIES) when it has one,
// otherwise its W as above. `header` is left to the caller.
lcs::Compliance toComplianceMsg(const lcs::Problem& problem);

// Forces of a solved problem: per contact and summed per body pair. `frames` and
// `problem` come from toProblem on `contacts`.
lcs::ConstraintForces toConstraintForcesMsg(const lcs::ContactArray& contacts,
                                            const std::vector<ContactFrame>& frames,
                                            const lcs::Problem& problem,
                                            const lcs::SolveResult& result);

// The summed wrench on body_a per (body_a, body_b) pair, torques about the frame origin.
std::vector<lcs::BodyPairWrench> sumBodyPairWrenches(const std::vector<lcs::ContactForce>& forces);

// Stats of a solve that ran.
lcs::SolverStats toStatsMsg(const std_msgs::Header& header, const lcs::Problem& problem,
                            const lcs::SolveResult& result);

// Stats of an input that was not solved (malformed, unpaired, refused by the core).
lcs::SolverStats rejectedStatsMsg(const std_msgs::Header& header, std::uint8_t status_code,
                                  const std::string& message);

// The status name the node uses for a SolverStats status code.
std::string statusCodeName(std::uint8_t status_code);

// True when the solve gave forces worth applying: converged, or the best iterate at the
// iteration cap (SOFA's behaviour) or time budget. Other statuses publish no forces.
bool solveGaveForces(const lcs::SolveResult& result);

// Last guard before publishing: every number in the message is finite.
bool allFinite(const lcs::ConstraintForces& forces);
bool allFinite(const lcs::SolverStats& stats);

}  // namespace lcp_contact_solver_ros
