// Core Problem → ContactArray and Compliance (msg_conversion.h): how every simulator
// writes the messages the node reads.
#include "lcp_contact_solver/ros/msg_conversion/msg_conversion.h"

#include "lcp_contact_solver/core/body_compliance.h"
#include "lcp_contact_solver/ros/msg_conversion/msg_primitives.h"

#include <cstdint>
#include <variant>

namespace lcp_contact_solver_ros {

lcs::ContactArray toContactArrayMsg(const lcs::core::Problem& problem,
                                    const std::vector<ContactFrame>& frames,
                                    const std::vector<ContactBodies>& bodies,
                                    const std_msgs::Header& header) {
  lcs::ContactArray msg;
  msg.header = header;
  const std::vector<int> offsets = problem.rowOffsets();
  msg.contacts.resize(problem.contacts.size());
  for (std::size_t i = 0; i < problem.contacts.size(); ++i) {
    const lcs::core::Contact& c = problem.contacts[i];
    const ContactFrame& f = frames[i];
    lcs::ContactPoint& out = msg.contacts[i];
    out.id = c.id;
    out.body_a = bodies[i].body_a;
    out.body_b = bodies[i].body_b;
    out.position = toPoint(f.position);
    out.normal = toVector3(f.normal);
    if (!f.derived_tangents) {
      out.tangent1 = toVector3(f.tangent1);
      out.tangent2 = toVector3(f.tangent2);
    }
    out.d_free.assign(problem.d_free.data() + offsets[i], problem.d_free.data() + offsets[i + 1]);
    out.mu = c.mu;
    out.mu_torsional = c.mu_torsional;
    out.mu_rolling = c.mu_rolling;
    out.gap = c.gap;
    out.erp = c.erp;
    out.softness = c.softness;
    out.type = toMsgType(c.type);
    out.rows = static_cast<std::uint32_t>(c.rows);
  }
  return msg;
}

lcs::Compliance toComplianceMsg(const lcs::core::ComplianceMatrix& W) {
  lcs::Compliance msg;
  msg.rows = static_cast<std::uint32_t>(lcs::core::complianceRows(W));
  if (const auto* dense = std::get_if<Eigen::MatrixXd>(&W)) {
    msg.storage = lcs::Compliance::STORAGE_DENSE;
    msg.data.reserve(dense->size());
    for (Eigen::Index r = 0; r < dense->rows(); ++r)
      for (Eigen::Index c = 0; c < dense->cols(); ++c) msg.data.push_back((*dense)(r, c));
    return msg;
  }
  const auto& sparse = std::get<lcs::core::BlockSparseMatrix>(W);
  msg.storage = lcs::Compliance::STORAGE_BLOCK_SPARSE;
  for (int i = 0; i < sparse.blockCount(); ++i) {
    for (int k = sparse.row_start[i]; k < sparse.row_start[i + 1]; ++k) {
      msg.block_rows.push_back(static_cast<std::uint32_t>(i));
      msg.block_cols.push_back(static_cast<std::uint32_t>(sparse.block_col[k]));
    }
  }
  msg.block_data = sparse.values;  // stored in the same (block-row) order
  return msg;
}

lcs::Compliance toComplianceMsg(const lcs::core::Problem& problem) {
  if (!problem.bodies) return toComplianceMsg(problem.W);
  const lcs::core::BodyCompliance& bodies = *problem.bodies;
  lcs::Compliance msg;
  msg.storage = lcs::Compliance::STORAGE_BODIES;
  msg.rows = static_cast<std::uint32_t>(bodies.rowCount());
  msg.body_compliance.reserve(36 * bodies.body_compliance.size());
  for (const lcs::core::BodyMatrix& C : bodies.body_compliance)
    for (int r = 0; r < 6; ++r)
      for (int c = 0; c < 6; ++c) msg.body_compliance.push_back(C(r, c));
  for (const lcs::core::ContactJacobian& c : bodies.contacts) {
    msg.contact_bodies.push_back(c.body_a);
    msg.contact_bodies.push_back(c.body_b);
    if (c.body_a >= 0)
      msg.jacobian.insert(msg.jacobian.end(), c.jacobian_a.data(), c.jacobian_a.data() + 6 * c.rows);
    if (c.body_b >= 0)
      msg.jacobian.insert(msg.jacobian.end(), c.jacobian_b.data(), c.jacobian_b.data() + 6 * c.rows);
  }
  msg.body_diagonal.assign(bodies.diagonal.data(), bodies.diagonal.data() + bodies.diagonal.size());
  return msg;
}

}  // namespace lcp_contact_solver_ros
