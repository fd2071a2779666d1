// One ContactPoint's type code and geometry (msg_conversion.h): the type mapping and the
// contact frame read from a message.
#include "lcp_contact_solver/ros/msg_conversion/msg_conversion.h"

#include "lcp_contact_solver/ros/msg_conversion/msg_primitives.h"

#include <cmath>

namespace lcp_contact_solver_ros {

namespace {

// Directions closer to zero than this are "not given" (tangents) or invalid (normal).
constexpr double kZeroLength = 1e-9;
// Given tangents must be orthogonal to the normal and to each other within this cosine.
constexpr double kOrthogonalityTolerance = 1e-3;

// toMsgType / fromMsgType are casts because the numbers agree; this keeps them agreeing.
static_assert(static_cast<int>(lcs::core::ContactType::kFrictional) == lcs::ContactPoint::FRICTIONAL &&
                  static_cast<int>(lcs::core::ContactType::kFrictionless) ==
                      lcs::ContactPoint::FRICTIONLESS &&
                  static_cast<int>(lcs::core::ContactType::kBilateral) == lcs::ContactPoint::BILATERAL &&
                  static_cast<int>(lcs::core::ContactType::kTorsional) == lcs::ContactPoint::TORSIONAL &&
                  static_cast<int>(lcs::core::ContactType::kRolling) == lcs::ContactPoint::ROLLING,
              "ContactPoint's type constants must equal the core's ContactType values");

}  // namespace

std::uint8_t toMsgType(lcs::core::ContactType type) { return static_cast<std::uint8_t>(type); }

lcs::core::ContactType fromMsgType(std::uint8_t type) { return static_cast<lcs::core::ContactType>(type); }

void deriveTangents(const Eigen::Vector3d& normal, Eigen::Vector3d* tangent1, Eigen::Vector3d* tangent2) {
  lcs::core::tangentsFromNormal(normal, tangent1, tangent2);
}

std::string toContactFrame(const lcs::ContactPoint& contact, ContactFrame* frame) {
  if (!finite(contact.position)) return "has a non-finite position";
  if (!finite(contact.normal) || !finite(contact.tangent1) || !finite(contact.tangent2))
    return "has a non-finite direction";
  const Eigen::Vector3d n = toEigen(contact.normal);
  if (n.norm() < kZeroLength) return "has a zero normal";
  frame->position = toEigen(contact.position);
  frame->normal = n.normalized();
  const Eigen::Vector3d t1 = toEigen(contact.tangent1), t2 = toEigen(contact.tangent2);
  const bool has_t1 = t1.norm() >= kZeroLength, has_t2 = t2.norm() >= kZeroLength;
  if (!has_t1 && !has_t2) {
    deriveTangents(frame->normal, &frame->tangent1, &frame->tangent2);
    frame->derived_tangents = true;
    return "";
  }
  if (has_t1 != has_t2) return "gives one tangent only (give both or neither)";
  frame->tangent1 = t1.normalized();
  frame->tangent2 = t2.normalized();
  frame->derived_tangents = false;
  if (std::abs(frame->tangent1.dot(frame->normal)) > kOrthogonalityTolerance ||
      std::abs(frame->tangent2.dot(frame->normal)) > kOrthogonalityTolerance ||
      std::abs(frame->tangent1.dot(frame->tangent2)) > kOrthogonalityTolerance)
    return "has tangents that are not orthogonal to the normal and each other";
  return "";
}

}  // namespace lcp_contact_solver_ros
