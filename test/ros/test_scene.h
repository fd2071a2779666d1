// A small known contact problem as messages, shared by the unit tests and the rostests:
// two frictional contacts (one with the default μ), a frictionless one and a 2-row
// bilateral one, 9 rows coupled through a symmetric positive definite W.
#pragma once

#include "lcp_contact_solver/ros/msg_conversion/msg_conversion.h"

#include <lcp_contact_solver/Compliance.h>
#include <lcp_contact_solver/ContactArray.h>

#include <Eigen/Core>

#include <cmath>
#include <string>

namespace lcp_contact_solver_test {

using lcp_contact_solver::Compliance;
using lcp_contact_solver::ContactArray;
using lcp_contact_solver::ContactPoint;

struct Scene {
  ContactArray contacts;
  Compliance compliance;
};

inline geometry_msgs::Vector3 vec(double x, double y, double z) {
  geometry_msgs::Vector3 v;
  v.x = x;
  v.y = y;
  v.z = z;
  return v;
}

inline geometry_msgs::Point point(double x, double y, double z) {
  geometry_msgs::Point p;
  p.x = x;
  p.y = y;
  p.z = z;
  return p;
}

inline ContactPoint contact(std::int64_t id, const std::string& a, const std::string& b, std::uint8_t type,
                            std::vector<double> d_free, double mu) {
  ContactPoint c;
  c.id = id;
  c.body_a = a;
  c.body_b = b;
  c.type = type;
  c.rows = type == ContactPoint::BILATERAL ? d_free.size() : 0;
  c.d_free = std::move(d_free);
  c.mu = mu;
  c.normal = vec(0.0, 0.0, 1.0);
  return c;
}

// W = B Bᵀ + I/2 with a fixed, dense B (m/N): symmetric positive definite and coupled, so
// Gauss-Seidel needs several sweeps from zero.
inline Eigen::MatrixXd coupledCompliance(int rows) {
  Eigen::MatrixXd B(rows, rows);
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < rows; ++j) B(i, j) = 0.3 * std::sin(1.0 + i * rows + j);
  return B * B.transpose() + 0.5 * Eigen::MatrixXd::Identity(rows, rows);
}

// Contact ids are first_id .. first_id + 3, so tests can keep their warm starts apart.
inline Scene makeScene(std::int64_t first_id, const ros::Time& stamp, bool block_sparse = false) {
  Scene s;
  s.contacts.header.stamp = stamp;
  s.contacts.header.frame_id = "world";
  s.contacts.contacts = {
      contact(first_id, "box", "ground", ContactPoint::FRICTIONAL, {-0.02, 0.01, 0.0},
              ContactPoint::MU_DEFAULT),
      contact(first_id + 1, "box", "ground", ContactPoint::FRICTIONAL, {-0.01, -0.02, 0.005}, 0.2),
      contact(first_id + 2, "ball", "box", ContactPoint::FRICTIONLESS, {-0.015}, ContactPoint::MU_DEFAULT),
      contact(first_id + 3, "arm", "box", ContactPoint::BILATERAL, {0.01, -0.01}, ContactPoint::MU_DEFAULT),
  };
  s.contacts.contacts[0].position = point(0.1, 0.0, 0.0);
  s.contacts.contacts[1].position = point(-0.1, 0.0, 0.0);
  s.contacts.contacts[1].normal = vec(0.0, 0.6, 0.8);  // tangents given, orthonormal
  s.contacts.contacts[1].tangent1 = vec(1.0, 0.0, 0.0);
  s.contacts.contacts[1].tangent2 = vec(0.0, 0.8, -0.6);
  s.contacts.contacts[2].position = point(0.0, 0.2, 0.1);
  s.contacts.contacts[2].normal = vec(0.0, 0.0, 2.0);  // not unit: normalized
  s.contacts.contacts[3].position = point(0.0, -0.2, 0.3);
  s.contacts.contacts[3].normal = vec(1.0, 0.0, 0.0);

  const Eigen::MatrixXd W = coupledCompliance(9);
  if (!block_sparse) {
    s.compliance = lcp_contact_solver_ros::toComplianceMsg(W);
  } else {
    // The same W as blocks; (3, 2) comes before (0, 0) to check that order does not matter.
    const int offsets[] = {0, 3, 6, 7, 9};
    s.compliance.storage = Compliance::STORAGE_BLOCK_SPARSE;
    s.compliance.rows = 9;
    for (int i : {3, 0, 1, 2}) {
      for (int j = 0; j < 4; ++j) {
        s.compliance.block_rows.push_back(i);
        s.compliance.block_cols.push_back(j);
        for (int r = offsets[i]; r < offsets[i + 1]; ++r)
          for (int c = offsets[j]; c < offsets[j + 1]; ++c) s.compliance.block_data.push_back(W(r, c));
      }
    }
  }
  s.compliance.header = s.contacts.header;
  return s;
}

// The same contacts with the compliance in body form (STORAGE_BODIES): three bodies (box 0,
// ball 1, arm 2; the ground is static), C_b = B_b B_bᵀ + I/2, fixed Jacobian rows on each
// side. W = Σ J C Jᵀ is symmetric positive definite (9 rows, 18 body coordinates).
inline Scene makeBodyFormScene(std::int64_t first_id, const ros::Time& stamp) {
  Scene s = makeScene(first_id, stamp);
  Compliance& c = s.compliance;
  c = Compliance();
  c.header = s.contacts.header;
  c.storage = Compliance::STORAGE_BODIES;
  c.rows = 9;
  for (int b = 0; b < 3; ++b) {
    Eigen::Matrix<double, 6, 6> B;
    for (int i = 0; i < 6; ++i)
      for (int j = 0; j < 6; ++j) B(i, j) = 0.4 * std::sin(2.0 + 7.0 * b + 6 * i + j);
    const Eigen::Matrix<double, 6, 6> C = B * B.transpose() + 0.5 * Eigen::Matrix<double, 6, 6>::Identity();
    for (int i = 0; i < 6; ++i)
      for (int j = 0; j < 6; ++j) c.body_compliance.push_back(C(i, j));
  }
  c.contact_bodies = {0, -1, 0, -1, 1, 0, 2, 0};
  const int rows[] = {3, 3, 1, 2};
  int value = 0;
  for (int i = 0; i < 4; ++i)
    for (int side = 0; side < 2; ++side) {
      if (c.contact_bodies[2 * i + side] < 0) continue;
      for (int k = 0; k < 6 * rows[i]; ++k)
        c.jacobian.push_back(std::cos(0.7 * value++) * (side == 0 ? 1.0 : -0.8));
    }
  return s;
}

}  // namespace lcp_contact_solver_test
