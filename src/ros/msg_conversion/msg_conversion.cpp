#include "lcp_contact_solver/ros/msg_conversion/msg_conversion.h"

#include "lcp_contact_solver/core/body_compliance.h"
#include "lcp_contact_solver/core/contact_solver.h"
#include "lcp_contact_solver/ros/msg_conversion/msg_primitives.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <numeric>
#include <unordered_map>
#include <unordered_set>
#include <utility>

namespace lcp_contact_solver_ros {

namespace {

// Directions closer to zero than this are "not given" (tangents) or invalid (normal).
constexpr double kZeroLength = 1e-9;
// Given tangents must be orthogonal to the normal and to each other within this cosine.
constexpr double kOrthogonalityTolerance = 1e-3;
// Bounds the allocation a hostile message can cause when max_rows is 0 (no limit).
constexpr std::int64_t kHardRowLimit = 1000000;

// toMsgType / fromMsgType are casts because the numbers agree; this keeps them agreeing.
static_assert(static_cast<int>(lcs::core::ContactType::kFrictional) == lcs::ContactPoint::FRICTIONAL &&
                  static_cast<int>(lcs::core::ContactType::kFrictionless) == lcs::ContactPoint::FRICTIONLESS &&
                  static_cast<int>(lcs::core::ContactType::kBilateral) == lcs::ContactPoint::BILATERAL &&
                  static_cast<int>(lcs::core::ContactType::kTorsional) == lcs::ContactPoint::TORSIONAL &&
                  static_cast<int>(lcs::core::ContactType::kRolling) == lcs::ContactPoint::ROLLING,
              "ContactPoint's type constants must equal the core's ContactType values");

std::string contactName(std::size_t index, std::int64_t id) {
  return "contact " + std::to_string(index) + " (id " + std::to_string(id) + ")";
}

// Row count of a contact message, or -1 with `error` set.
int contactRows(const lcs::ContactPoint& c, std::string* error) {
  switch (c.type) {
    case lcs::ContactPoint::FRICTIONAL:
    case lcs::ContactPoint::FRICTIONLESS:
    case lcs::ContactPoint::TORSIONAL:
    case lcs::ContactPoint::ROLLING: {
      const int fixed = lcs::core::rowsForType(fromMsgType(c.type));  // the core's count: 3, 1, 4, 6
      if (c.rows != 0 && static_cast<int>(c.rows) != fixed) {
        *error = "has rows=" + std::to_string(c.rows) + " but its type has " + std::to_string(fixed);
        return -1;
      }
      return fixed;
    }
    case lcs::ContactPoint::BILATERAL:
      if (c.rows < 1 || c.rows > 6) {
        *error = "is bilateral with rows=" + std::to_string(c.rows) + " (1..6 expected)";
        return -1;
      }
      return static_cast<int>(c.rows);
    default:
      *error = "has an unknown type " + std::to_string(c.type);
      return -1;
  }
}

std::string checkMu(double mu) {
  if (!std::isfinite(mu)) return "has a non-finite mu";
  if (mu < 0.0 && mu != lcs::ContactPoint::MU_DEFAULT)
    return "has a negative mu " + std::to_string(mu) + " (use MU_DEFAULT=-1 for the node's mu)";
  return "";
}

std::string checkStabilization(const lcs::ContactPoint& msg) {
  if (!std::isfinite(msg.gap)) return "has a non-finite gap";
  if (!std::isfinite(msg.erp) || (msg.erp != lcs::ContactPoint::USE_DEFAULT && (msg.erp < 0.0 || msg.erp > 1.0)))
    return "has erp " + std::to_string(msg.erp) + " outside [0, 1] (use USE_DEFAULT=-1 for the node's erp)";
  if (!std::isfinite(msg.softness) || (msg.softness != lcs::ContactPoint::USE_DEFAULT && msg.softness < 0.0))
    return "has a negative or non-finite softness " + std::to_string(msg.softness) +
           " (use USE_DEFAULT=-1 for the node's softness)";
  return "";
}

std::string toCoreContact(const lcs::ContactPoint& msg, lcs::core::Contact* contact) {
  std::string error;
  const int rows = contactRows(msg, &error);
  if (rows < 0) return error;
  if (static_cast<int>(msg.d_free.size()) != rows)
    return "has " + std::to_string(msg.d_free.size()) + " d_free values for " + std::to_string(rows) + " rows";
  error = checkMu(msg.mu);
  if (error.empty() && (!std::isfinite(msg.mu_torsional) || msg.mu_torsional < 0.0))
    error = "has a negative or non-finite mu_torsional";
  if (error.empty() && (!std::isfinite(msg.mu_rolling) || msg.mu_rolling < 0.0))
    error = "has a negative or non-finite mu_rolling";
  if (error.empty()) error = checkStabilization(msg);
  if (!error.empty()) return error;
  contact->id = msg.id;
  contact->type = fromMsgType(msg.type);
  contact->rows = rows;
  contact->mu = msg.mu;
  contact->mu_torsional = msg.mu_torsional;
  contact->mu_rolling = msg.mu_rolling;
  contact->gap = msg.gap;
  contact->erp = msg.erp;
  contact->softness = msg.softness;
  return "";
}

std::string readContacts(const lcs::ContactArray& msg, int max_rows, lcs::core::Problem* problem,
                         std::vector<ContactFrame>* frames) {
  if (msg.contacts.empty()) return "the contact array is empty";
  // Every contact has at least one row: refuse an array over the limit before allocating
  // anything per contact (a hostile array of 10⁶ contacts costs one comparison).
  const std::int64_t limit = max_rows > 0 ? max_rows : kHardRowLimit;
  if (static_cast<std::int64_t>(msg.contacts.size()) > limit)
    return "the array has " + std::to_string(msg.contacts.size()) + " contacts, more than the row limit of " +
           std::to_string(limit);
  problem->contacts.resize(msg.contacts.size());
  frames->resize(msg.contacts.size());
  // Repeated ids: one sorted copy finds whether there is any; only then does a set name
  // the first contact that repeats one (no tree node per contact on the normal path).
  std::vector<std::int64_t> sorted(msg.contacts.size());
  for (std::size_t i = 0; i < sorted.size(); ++i) sorted[i] = msg.contacts[i].id;
  std::sort(sorted.begin(), sorted.end());
  const bool repeats = std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end();
  std::unordered_set<std::int64_t> ids;
  std::int64_t rows = 0;
  for (std::size_t i = 0; i < msg.contacts.size(); ++i) {
    const lcs::ContactPoint& c = msg.contacts[i];
    std::string error = toCoreContact(c, &problem->contacts[i]);
    if (error.empty()) error = toContactFrame(c, &(*frames)[i]);
    if (error.empty() && repeats && !ids.insert(c.id).second) error = "repeats an id used by an earlier contact";
    if (!error.empty()) return contactName(i, c.id) + " " + error;
    rows += problem->contacts[i].rows;
  }
  if (rows > limit)
    return "the contacts have " + std::to_string(rows) + " rows, more than the limit of " + std::to_string(limit);
  problem->d_free.resize(rows);
  double* out = problem->d_free.data();
  for (const lcs::ContactPoint& c : msg.contacts) out = std::copy(c.d_free.begin(), c.d_free.end(), out);
  return "";
}

std::string readDense(const lcs::Compliance& msg, int rows, lcs::core::ComplianceMatrix* W) {
  const std::size_t expected = static_cast<std::size_t>(rows) * static_cast<std::size_t>(rows);
  if (msg.data.size() != expected)
    return "dense compliance has " + std::to_string(msg.data.size()) + " values, " +
           std::to_string(rows) + "x" + std::to_string(rows) + " expected";
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  *W = Eigen::MatrixXd(Eigen::Map<const RowMajor>(msg.data.data(), rows, rows));
  return "";
}

std::string readBlockSparse(const lcs::Compliance& msg, const std::vector<int>& offsets,
                            lcs::core::ComplianceMatrix* W) {
  const std::size_t nb = offsets.size() - 1;
  const std::size_t blocks = msg.block_rows.size();
  if (msg.block_cols.size() != blocks)
    return "block-sparse compliance has " + std::to_string(blocks) + " block_rows but " +
           std::to_string(msg.block_cols.size()) + " block_cols";
  std::vector<int> sizes(nb);
  for (std::size_t i = 0; i < nb; ++i) sizes[i] = offsets[i + 1] - offsets[i];
  // Where each block's values start in block_data, in message order.
  std::vector<std::size_t> start(blocks + 1, 0);
  for (std::size_t k = 0; k < blocks; ++k) {
    const std::uint32_t i = msg.block_rows[k], j = msg.block_cols[k];
    if (i >= nb || j >= nb)
      return "block " + std::to_string(k) + " (" + std::to_string(i) + ", " + std::to_string(j) +
             ") names a contact beyond the " + std::to_string(nb) + " contacts";
    start[k + 1] = start[k] + static_cast<std::size_t>(sizes[i]) * sizes[j];
  }
  auto key = [&msg](std::size_t k) { return std::make_pair(msg.block_rows[k], msg.block_cols[k]); };
  // Blocks in (row, column) order; a repeated block is two equal neighbours there. A
  // message written in that order (toComplianceMsg, the scene layer) is checked in one pass
  // and needs no permutation.
  bool in_order = true;
  for (std::size_t k = 1; k < blocks && in_order; ++k) in_order = key(k - 1) < key(k);
  std::vector<std::size_t> order;
  if (!in_order) {
    order.resize(blocks);
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&key](std::size_t a, std::size_t b) { return key(a) < key(b); });
    for (std::size_t k = 1; k < blocks; ++k)
      if (key(order[k - 1]) == key(order[k]))
        return "block (" + std::to_string(msg.block_rows[order[k]]) + ", " + std::to_string(msg.block_cols[order[k]]) +
               ") is given twice";
  }
  if (msg.block_data.size() != start[blocks])
    return "block-sparse compliance has " + std::to_string(msg.block_data.size()) +
           " block_data values, its blocks need " + std::to_string(start[blocks]);
  // The CSR arrays written in place: one copy of each block's values, no per-value append;
  // in message order that copy is the whole of block_data at once (no zero fill first).
  lcs::core::BlockSparseMatrix sparse = lcs::core::BlockSparseMatrix::withBlockSizes(sizes);
  sparse.row_start.assign(nb + 1, 0);
  sparse.block_col.resize(blocks);
  sparse.value_start.resize(blocks);
  if (in_order) {
    sparse.values.assign(msg.block_data.begin(), msg.block_data.end());
    for (std::size_t k = 0; k < blocks; ++k) {
      ++sparse.row_start[msg.block_rows[k] + 1];
      sparse.block_col[k] = static_cast<int>(msg.block_cols[k]);
      sparse.value_start[k] = static_cast<int>(start[k]);
    }
  } else {
    sparse.values.resize(start[blocks]);
    std::size_t value = 0;
    for (std::size_t n = 0; n < blocks; ++n) {
      const std::size_t k = order[n];
      const std::size_t size = start[k + 1] - start[k];
      ++sparse.row_start[msg.block_rows[k] + 1];
      sparse.block_col[n] = static_cast<int>(msg.block_cols[k]);
      sparse.value_start[n] = static_cast<int>(value);
      std::copy(msg.block_data.begin() + start[k], msg.block_data.begin() + start[k] + size,
                sparse.values.begin() + value);
      value += size;
    }
  }
  for (std::size_t i = 0; i < nb; ++i) sparse.row_start[i + 1] += sparse.row_start[i];
  *W = std::move(sparse);
  return "";
}

// The body form: every size is checked against the contacts before anything is allocated;
// finiteness is checked by validateProblem (BodyCompliance::validate) afterwards.
std::string readBodies(const lcs::Compliance& msg, const std::vector<int>& offsets,
                       std::shared_ptr<const lcs::core::BodyCompliance>* out) {
  const std::size_t nc = offsets.size() - 1;
  if (msg.body_compliance.size() % 36 != 0)
    return "the body form has " + std::to_string(msg.body_compliance.size()) +
           " body_compliance values, not 36 (a 6x6 block) per body";
  const std::size_t nb = msg.body_compliance.size() / 36;
  if (msg.contact_bodies.size() != 2 * nc)
    return "the body form has " + std::to_string(msg.contact_bodies.size()) + " contact_bodies, " +
           std::to_string(2 * nc) + " expected (body_a and body_b per contact)";
  std::size_t jacobian_values = 0;
  for (std::size_t i = 0; i < nc; ++i) {
    for (int s = 0; s < 2; ++s) {
      const std::int32_t b = msg.contact_bodies[2 * i + s];
      if (b < -1 || (b >= 0 && static_cast<std::size_t>(b) >= nb))
        return "the body form's contact " + std::to_string(i) + " names " + (s == 0 ? "body_a " : "body_b ") +
               std::to_string(b) + ", outside -1.." + std::to_string(static_cast<long long>(nb) - 1) + " (-1 = static)";
      if (b >= 0) jacobian_values += static_cast<std::size_t>(offsets[i + 1] - offsets[i]) * 6;
    }
  }
  if (msg.jacobian.size() != jacobian_values)
    return "the body form has " + std::to_string(msg.jacobian.size()) + " jacobian values, its contacts need " +
           std::to_string(jacobian_values) + " (rows x 6 per side with a body)";
  if (!msg.body_diagonal.empty() && msg.body_diagonal.size() != static_cast<std::size_t>(offsets.back()))
    return "the body form has " + std::to_string(msg.body_diagonal.size()) + " body_diagonal values, " +
           std::to_string(offsets.back()) + " rows (or none) expected";
  auto bodies = std::make_shared<lcs::core::BodyCompliance>();
  bodies->body_compliance.resize(nb);
  using RowMajor6 = Eigen::Matrix<double, 6, 6, Eigen::RowMajor>;
  for (std::size_t b = 0; b < nb; ++b) bodies->body_compliance[b] = Eigen::Map<const RowMajor6>(msg.body_compliance.data() + 36 * b);
  bodies->contacts.resize(nc);
  std::size_t next = 0;
  for (std::size_t i = 0; i < nc; ++i) {
    lcs::core::ContactJacobian& c = bodies->contacts[i];
    c.rows = offsets[i + 1] - offsets[i];
    c.body_a = msg.contact_bodies[2 * i];
    c.body_b = msg.contact_bodies[2 * i + 1];
    for (lcs::core::JacobianBlock* J : {&c.jacobian_a, &c.jacobian_b}) {
      if ((J == &c.jacobian_a ? c.body_a : c.body_b) < 0) continue;
      J->resize(c.rows, 6);
      for (int k = 0; k < c.rows * 6; ++k) J->data()[k] = msg.jacobian[next++];  // row-major, as stored
    }
  }
  if (!msg.body_diagonal.empty())
    bodies->diagonal = Eigen::Map<const Eigen::VectorXd>(msg.body_diagonal.data(), msg.body_diagonal.size());
  *out = std::move(bodies);
  return "";
}

std::string readCompliance(const lcs::Compliance& msg, const std::vector<int>& offsets,
                           lcs::core::ComplianceMatrix* W, std::shared_ptr<const lcs::core::BodyCompliance>* bodies) {
  const int rows = offsets.back();
  if (static_cast<std::int64_t>(msg.rows) != rows)
    return "the compliance has rows=" + std::to_string(msg.rows) + ", the contacts have " + std::to_string(rows);
  switch (msg.storage) {
    case lcs::Compliance::STORAGE_DENSE: return readDense(msg, rows, W);
    case lcs::Compliance::STORAGE_BLOCK_SPARSE: return readBlockSparse(msg, offsets, W);
    case lcs::Compliance::STORAGE_BODIES: return readBodies(msg, offsets, bodies);
    default: return "the compliance has an unknown storage " + std::to_string(msg.storage);
  }
}

// Up to three rows of a contact along (n, t1, t2); later bilateral rows have no direction.
Eigen::Vector3d directionalForce(const lcs::core::Contact& contact, const double* lambda) {
  Eigen::Vector3d components = Eigen::Vector3d::Zero();
  for (int k = 0; k < std::min(3, contact.rows); ++k) components[k] = lambda[k];
  return components;
}

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

std::string toProblem(const lcs::ContactArray& contacts, const lcs::Compliance& compliance,
                      int max_rows, lcs::core::Problem* problem, std::vector<ContactFrame>* frames, bool validate) {
  *problem = lcs::core::Problem();
  std::string error = readContacts(contacts, max_rows, problem, frames);
  if (error.empty()) error = readCompliance(compliance, problem->rowOffsets(), &problem->W, &problem->bodies);
  if (error.empty() && validate) error = lcs::core::validateProblem(*problem, max_rows);  // non-finite W, d_free
  problem->name = contacts.header.frame_id;
  return error;
}

lcs::ContactArray toContactArrayMsg(const lcs::core::Problem& problem, const std::vector<ContactFrame>& frames,
                                    const std::vector<ContactBodies>& bodies, const std_msgs::Header& header) {
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
    if (c.body_a >= 0) msg.jacobian.insert(msg.jacobian.end(), c.jacobian_a.data(), c.jacobian_a.data() + 6 * c.rows);
    if (c.body_b >= 0) msg.jacobian.insert(msg.jacobian.end(), c.jacobian_b.data(), c.jacobian_b.data() + 6 * c.rows);
  }
  msg.body_diagonal.assign(bodies.diagonal.data(), bodies.diagonal.data() + bodies.diagonal.size());
  return msg;
}

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
    if (contact.type == lcs::core::ContactType::kTorsional || contact.type == lcs::core::ContactType::kRolling) {
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
  std::unordered_map<std::pair<const std::string*, const std::string*>, std::size_t, PairHash, PairEqual> index;
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
    return lcs::core::statusName(static_cast<lcs::core::SolveStatus>(status_code));  // "unknown" past the last
  return "unknown";
}

bool solveGaveForces(const lcs::core::SolveResult& result) {
  return result.status == lcs::core::SolveStatus::kConverged || result.status == lcs::core::SolveStatus::kMaxIterations ||
         result.status == lcs::core::SolveStatus::kTimeBudget;
}

bool allFinite(const lcs::ConstraintForces& forces) {
  for (const lcs::ContactForce& f : forces.forces) {
    if (!std::isfinite(f.normal_force) || !std::isfinite(f.tangent1_force) || !std::isfinite(f.tangent2_force) ||
        !finite(f.force) || !finite(f.position) || !finite(f.normal) || !finite(f.tangent1) || !finite(f.tangent2))
      return false;
    for (double v : f.lambda)
      if (!std::isfinite(v)) return false;
  }
  for (const lcs::BodyPairWrench& w : forces.wrenches)
    if (!finite(w.wrench.force) || !finite(w.wrench.torque)) return false;
  return true;
}

bool allFinite(const lcs::SolverStats& stats) {
  return std::isfinite(stats.residual) && std::isfinite(stats.solver_error) && std::isfinite(stats.solve_time);
}

}  // namespace lcp_contact_solver_ros
