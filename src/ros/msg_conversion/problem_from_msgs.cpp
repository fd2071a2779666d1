// ContactArray + Compliance → core Problem (toProblem, msg_conversion.h): every field
// validated before it is used, every size before anything is allocated.
#include "lcp_contact_solver/ros/msg_conversion/msg_conversion.h"

#include "lcp_contact_solver/core/body_compliance.h"

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <numeric>
#include <unordered_set>
#include <utility>

namespace lcp_contact_solver_ros {

namespace {

// Bounds the allocation a hostile message can cause when max_rows is 0 (no limit).
constexpr std::int64_t kHardRowLimit = 1000000;

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
    default: *error = "has an unknown type " + std::to_string(c.type); return -1;
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
  if (!std::isfinite(msg.erp) ||
      (msg.erp != lcs::ContactPoint::USE_DEFAULT && (msg.erp < 0.0 || msg.erp > 1.0)))
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
    return "has " + std::to_string(msg.d_free.size()) + " d_free values for " + std::to_string(rows) +
           " rows";
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
    if (error.empty() && repeats && !ids.insert(c.id).second)
      error = "repeats an id used by an earlier contact";
    if (!error.empty()) return contactName(i, c.id) + " " + error;
    rows += problem->contacts[i].rows;
  }
  if (rows > limit)
    return "the contacts have " + std::to_string(rows) + " rows, more than the limit of " +
           std::to_string(limit);
  problem->d_free.resize(rows);
  double* out = problem->d_free.data();
  for (const lcs::ContactPoint& c : msg.contacts) out = std::copy(c.d_free.begin(), c.d_free.end(), out);
  return "";
}

std::string readDense(const lcs::Compliance& msg, int rows, lcs::core::ComplianceMatrix* W) {
  const std::size_t expected = static_cast<std::size_t>(rows) * static_cast<std::size_t>(rows);
  if (msg.data.size() != expected)
    return "dense compliance has " + std::to_string(msg.data.size()) + " values, " + std::to_string(rows) +
           "x" + std::to_string(rows) + " expected";
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
        return "block (" + std::to_string(msg.block_rows[order[k]]) + ", " +
               std::to_string(msg.block_cols[order[k]]) + ") is given twice";
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
               std::to_string(b) + ", outside -1.." + std::to_string(static_cast<long long>(nb) - 1) +
               " (-1 = static)";
      if (b >= 0) jacobian_values += static_cast<std::size_t>(offsets[i + 1] - offsets[i]) * 6;
    }
  }
  if (msg.jacobian.size() != jacobian_values)
    return "the body form has " + std::to_string(msg.jacobian.size()) +
           " jacobian values, its contacts need " + std::to_string(jacobian_values) +
           " (rows x 6 per side with a body)";
  if (!msg.body_diagonal.empty() && msg.body_diagonal.size() != static_cast<std::size_t>(offsets.back()))
    return "the body form has " + std::to_string(msg.body_diagonal.size()) + " body_diagonal values, " +
           std::to_string(offsets.back()) + " rows (or none) expected";
  auto bodies = std::make_shared<lcs::core::BodyCompliance>();
  bodies->body_compliance.resize(nb);
  using RowMajor6 = Eigen::Matrix<double, 6, 6, Eigen::RowMajor>;
  for (std::size_t b = 0; b < nb; ++b)
    bodies->body_compliance[b] = Eigen::Map<const RowMajor6>(msg.body_compliance.data() + 36 * b);
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
                           lcs::core::ComplianceMatrix* W,
                           std::shared_ptr<const lcs::core::BodyCompliance>* bodies) {
  const int rows = offsets.back();
  if (static_cast<std::int64_t>(msg.rows) != rows)
    return "the compliance has rows=" + std::to_string(msg.rows) + ", the contacts have " +
           std::to_string(rows);
  switch (msg.storage) {
    case lcs::Compliance::STORAGE_DENSE: return readDense(msg, rows, W);
    case lcs::Compliance::STORAGE_BLOCK_SPARSE: return readBlockSparse(msg, offsets, W);
    case lcs::Compliance::STORAGE_BODIES: return readBodies(msg, offsets, bodies);
    default: return "the compliance has an unknown storage " + std::to_string(msg.storage);
  }
}

}  // namespace

std::string toProblem(const lcs::ContactArray& contacts, const lcs::Compliance& compliance, int max_rows,
                      lcs::core::Problem* problem, std::vector<ContactFrame>* frames, bool validate) {
  *problem = lcs::core::Problem();
  std::string error = readContacts(contacts, max_rows, problem, frames);
  if (error.empty()) error = readCompliance(compliance, problem->rowOffsets(), &problem->W, &problem->bodies);
  if (error.empty() && validate)
    error = lcs::core::validateProblem(*problem, max_rows);  // non-finite W, d_free
  problem->name = contacts.header.frame_id;
  return error;
}

}  // namespace lcp_contact_solver_ros
