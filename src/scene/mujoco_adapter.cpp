// MuJoCo's constraint rows → core problem (mujoco_adapter.h has the mapping). The MuJoCo 2.2
// fact it relies on, checked by test/scene/test_mujoco_adapter.cpp: a pyramidal contact of
// condim k owns rows efc_address .. efc_address + 2(k−1) − 1, edge 2j is n + μ_j t_j and edge
// 2j+1 is n − μ_j t_j (mju_decodePyramid's layout).
#include "lcp_contact_solver/scene/mujoco_adapter.h"

#include "mujoco_matrix.h"

#include <map>
#include <sstream>
#include <utility>

namespace lcp_contact_solver {
namespace scene {

namespace {

Eigen::Vector3d vec3(const mjtNum* v) { return Eigen::Vector3d(v[0], v[1], v[2]); }

// Entry (e, col) of the Jacobian.
double jacobianAt(const mjModel* m, const mjData* d, int e, int col) {
  if (mj_isSparse(m)) {
    const int adr = d->efc_J_rowadr[e];
    for (int k = 0; k < d->efc_J_rownnz[e]; ++k)
      if (d->efc_J_colind[adr + k] == col) return d->efc_J[adr + k];
    return 0.0;
  }
  return d->efc_J[static_cast<std::size_t>(e) * m->nv + col];
}

int bodyOfEqualityObject(const mjModel* m, int eq, int object) {
  if (object < 0) return 0;
  switch (m->eq_type[eq]) {
    case mjEQ_CONNECT:
    case mjEQ_WELD: return object;
    case mjEQ_JOINT: return m->jnt_bodyid[object];
    case mjEQ_DISTANCE: return m->geom_bodyid[object];
    default: return 0;  // tendons have no body
  }
}

// A core contact of `rows` rows and friction `mu`.
core::Contact coreContact(std::int64_t id, core::ContactType type, int rows, double mu) {
  core::Contact contact;
  contact.id = id;
  contact.type = type;
  contact.rows = rows;
  contact.mu = mu;
  return contact;
}

// Walks MuJoCo's rows once, one method per constraint type, collecting the problem's
// entries and contacts, the MuJoCo row of each problem row and its scale.
class RowWalker {
 public:
  RowWalker(const mjModel* m, const mjData* d, const MujocoExtractOptions& options, MujocoProblem* out)
      : m_(m), d_(d), options_(options), out_(out), rank_(d->ncon, 0), counted_(d->ncon, 0) {
    // Rank of each contact among the contacts of its geom pair (for persistent ids).
    std::map<std::pair<int, int>, int> seen;
    for (int c = 0; c < d->ncon; ++c) rank_[c] = seen[{d->contact[c].geom1, d->contact[c].geom2}]++;
  }

  // Every row kept or dropped: empty string, or why a row does not convert.
  std::string walk() {
    int e = 0;
    while (e < d_->nefc) {
      int next = e + 1;  // the first row after the entry at e
      std::string error;
      switch (d_->efc_type[e]) {
        case mjCNSTR_EQUALITY: error = equality(e, &next); break;
        case mjCNSTR_FRICTION_DOF:
        case mjCNSTR_FRICTION_TENDON: out_->dropped_rows.push_back(e); break;
        case mjCNSTR_LIMIT_JOINT:
        case mjCNSTR_LIMIT_TENDON: limit(e); break;
        case mjCNSTR_CONTACT_FRICTIONLESS: error = frictionless(e); break;
        case mjCNSTR_CONTACT_PYRAMIDAL: error = pyramidal(e, &next); break;
        case mjCNSTR_CONTACT_ELLIPTIC: error = elliptic(e, &next); break;
        default:
          return "efc row " + std::to_string(e) + " has an unknown constraint type " +
                 std::to_string(d_->efc_type[e]);
      }
      if (!error.empty()) return error;
      e = next;
    }
    return "";
  }

  const std::vector<double>& scales() const { return scale_of_row_; }

 private:
  void add(const MujocoEntry& entry, const core::Contact& contact, const std::vector<int>& efc_rows,
           const std::vector<double>& scales) {
    out_->entries.push_back(entry);
    out_->problem.contacts.push_back(contact);
    for (std::size_t k = 0; k < efc_rows.size(); ++k) {
      out_->efc_row.push_back(efc_rows[k]);
      scale_of_row_.push_back(scales[k]);
    }
  }

  // The entry of MuJoCo contact c starting at row e; counts the contact once.
  MujocoEntry contactEntry(int c, MujocoRowKind kind, int e) {
    const mjContact& con = d_->contact[c];
    MujocoEntry entry;
    entry.kind = kind;
    entry.efc_row = e;
    entry.mj_contact = c;
    entry.geom1 = con.geom1;
    entry.geom2 = con.geom2;
    entry.body_a = m_->geom_bodyid[con.geom2];
    entry.body_b = m_->geom_bodyid[con.geom1];
    entry.position = vec3(con.pos);
    entry.normal = vec3(con.frame);
    entry.dist = con.dist;
    if (!counted_[c]) {
      counted_[c] = 1;
      ++out_->ncon;
    }
    return entry;
  }

  // The contact that row e names: empty string, or why it names none.
  std::string checkContactId(int e) const {
    const int id = d_->efc_id[e];
    if (id < 0 || id >= d_->ncon)
      return "efc row " + std::to_string(e) + " names contact " + std::to_string(id) + " of " +
             std::to_string(d_->ncon);
    return "";
  }

  std::string equality(int e, int* next) {
    const int id = d_->efc_id[e];
    int k = 1;
    while (e + k < d_->nefc && d_->efc_type[e + k] == mjCNSTR_EQUALITY && d_->efc_id[e + k] == id) ++k;
    *next = e + k;
    if (!options_.include_equalities) {
      for (int r = 0; r < k; ++r) out_->dropped_rows.push_back(e + r);
      return "";
    }
    if (k > 6)
      return "equality " + std::to_string(id) + " has " + std::to_string(k) +
             " rows (at most 6 fit a bilateral contact)";
    MujocoEntry entry;
    entry.kind = MujocoRowKind::kEquality;
    entry.efc_row = e;
    entry.object = id;
    entry.body_a = bodyOfEqualityObject(m_, id, m_->eq_obj1id[id]);
    entry.body_b = bodyOfEqualityObject(m_, id, m_->eq_obj2id[id]);
    entry.position = vec3(d_->xpos + 3 * entry.body_a);
    std::vector<int> efc_rows;
    for (int r = 0; r < k; ++r) efc_rows.push_back(e + r);
    add(entry, coreContact(mujocoEqualityId(id), core::ContactType::kBilateral, k, 0.0), efc_rows,
        std::vector<double>(k, 1.0));
    return "";
  }

  void limit(int e) {
    if (!options_.include_limits) {
      out_->dropped_rows.push_back(e);
      return;
    }
    const int type = d_->efc_type[e], id = d_->efc_id[e];
    MujocoEntry entry;
    entry.kind = MujocoRowKind::kLimit;
    entry.efc_row = e;
    entry.object = id;
    if (type == mjCNSTR_LIMIT_JOINT) {
      entry.body_a = m_->jnt_bodyid[id];
      entry.body_b = m_->body_parentid[entry.body_a];
      entry.position = vec3(d_->xanchor + 3 * id);
      const int jtype = m_->jnt_type[id];
      if (jtype == mjJNT_HINGE || jtype == mjJNT_SLIDE) {
        const double sign = jacobianAt(m_, d_, e, m_->jnt_dofadr[id]) < 0.0 ? -1.0 : 1.0;
        Eigen::Vector3d axis = vec3(d_->xaxis + 3 * id);
        if (axis.norm() > 0.0) entry.normal = sign * axis.normalized();
      }
    }
    add(entry, coreContact(mujocoLimitId(type, id), core::ContactType::kFrictionless, 1, 0.0), {e}, {1.0});
  }

  std::string frictionless(int e) {
    if (std::string error = checkContactId(e); !error.empty()) return error;
    const int id = d_->efc_id[e];
    const MujocoEntry entry = contactEntry(id, MujocoRowKind::kFrictionless, e);
    add(entry,
        coreContact(mujocoContactId(entry.geom1, entry.geom2, rank_[id], -1),
                    core::ContactType::kFrictionless, 1, 0.0),
        {e}, {1.0});
    return "";
  }

  // One one-row entry per pyramid edge.
  std::string pyramidal(int e, int* next) {
    if (std::string error = checkContactId(e); !error.empty()) return error;
    const int id = d_->efc_id[e];
    const mjContact& con = d_->contact[id];
    const int edges = 2 * (con.dim - 1);
    if (con.efc_address != e || con.dim < 2 || e + edges > d_->nefc)
      return "pyramidal contact " + std::to_string(id) + " does not own rows " + std::to_string(e) + ".." +
             std::to_string(e + edges - 1);
    const Eigen::Vector3d n = vec3(con.frame);
    for (int k = 0; k < edges; ++k) {
      MujocoEntry entry = contactEntry(id, MujocoRowKind::kPyramidEdge, e + k);
      const int j = k / 2;
      const double sign = k % 2 == 0 ? 1.0 : -1.0;
      entry.edge = k;
      entry.mu = con.friction[j];
      double s = 1.0;
      if (j < 2) {  // tangent directions: the edge is the force direction n ± μ t
        const Eigen::Vector3d edge = n + sign * con.friction[j] * vec3(con.frame + 3 * (j + 1));
        if (options_.scale_rows) s = edge.norm();
        entry.normal = edge.normalized();
      }  // torsion / rolling edges: a normal force with a torque; the normal is n
      add(entry,
          coreContact(mujocoContactId(entry.geom1, entry.geom2, rank_[id], k),
                      core::ContactType::kFrictionless, 1, 0.0),
          {e + k}, {s});
    }
    *next = e + edges;
    return "";
  }

  // One frictional entry (normal, t1, t2); torsion and rolling rows dropped.
  std::string elliptic(int e, int* next) {
    if (std::string error = checkContactId(e); !error.empty()) return error;
    const int id = d_->efc_id[e];
    const mjContact& con = d_->contact[id];
    if (con.efc_address != e || con.dim < 3 || e + con.dim > d_->nefc)
      return "elliptic contact " + std::to_string(id) + " does not own rows " + std::to_string(e) + ".." +
             std::to_string(e + con.dim - 1);
    MujocoEntry entry = contactEntry(id, MujocoRowKind::kElliptic, e);
    entry.tangent1 = vec3(con.frame + 3);
    entry.tangent2 = vec3(con.frame + 6);
    entry.mu = con.friction[0];
    double s2 = 1.0;  // anisotropy: scale the second tangent so the cone is the disc of μ1
    if (options_.scale_rows && con.friction[1] > 0.0 && con.friction[1] != con.friction[0])
      s2 = con.friction[0] / con.friction[1];
    add(entry,
        coreContact(mujocoContactId(entry.geom1, entry.geom2, rank_[id], -1), core::ContactType::kFrictional,
                    3, con.friction[0]),
        {e, e + 1, e + 2}, {1.0, 1.0, s2});
    for (int r = 3; r < con.dim; ++r) out_->dropped_rows.push_back(e + r);  // torsion, rolling
    *next = e + con.dim;
    return "";
  }

  const mjModel* m_;
  const mjData* d_;
  const MujocoExtractOptions& options_;
  MujocoProblem* out_;
  std::vector<int> rank_;
  std::vector<char> counted_;  // per MuJoCo contact: counted in out_->ncon
  std::vector<double> scale_of_row_;
};

}  // namespace

const char* mujocoRowKindName(MujocoRowKind kind) {
  switch (kind) {
    case MujocoRowKind::kFrictionless: return "frictionless";
    case MujocoRowKind::kPyramidEdge: return "pyramid_edge";
    case MujocoRowKind::kElliptic: return "elliptic";
    case MujocoRowKind::kLimit: return "limit";
    case MujocoRowKind::kEquality: return "equality";
  }
  return "unknown";
}

// ---- ids ---------------------------------------------------------------------------------

std::int64_t mujocoContactId(int geom1, int geom2, int rank, int edge) {
  return (static_cast<std::int64_t>(geom1 & 0xFFFFF) << 36) |
         (static_cast<std::int64_t>(geom2 & 0xFFFFF) << 16) | (static_cast<std::int64_t>(rank & 0x3FF) << 6) |
         static_cast<std::int64_t>((edge + 1) & 0x3F);
}

std::int64_t mujocoLimitId(int constraint_type, int object) {
  return (std::int64_t{1} << 60) | (static_cast<std::int64_t>(constraint_type & 0xFF) << 32) |
         static_cast<std::int64_t>(object & 0x7FFFFFFF);
}

std::int64_t mujocoEqualityId(int equality) {
  return (std::int64_t{2} << 60) | static_cast<std::int64_t>(equality & 0x7FFFFFFF);
}

// ---- extraction --------------------------------------------------------------------------

std::string extractProblem(const mjModel* m, const mjData* d, const MujocoExtractOptions& options,
                           MujocoProblem* out) {
  *out = MujocoProblem();
  out->nefc = d->nefc;
  out->pyramidal = m->opt.cone == mjCONE_PYRAMIDAL;
  out->time = d->time;
  std::ostringstream name;
  name << "mujoco t=" << d->time;
  out->problem.name = name.str();

  RowWalker walker(m, d, options, out);
  if (std::string error = walker.walk(); !error.empty()) return error;
  const std::vector<int> row_of_efc = detail::fillRows(m, d, options, walker.scales(), out);
  const int n = static_cast<int>(out->efc_row.size());
  const bool block_sparse =
      options.storage == MujocoExtractOptions::Storage::kBlockSparse ||
      (options.storage == MujocoExtractOptions::Storage::kAuto && n > options.dense_max_rows &&
       detail::fillOfW(m, d, *out, row_of_efc) < options.dense_min_fill);
  if (block_sparse)
    out->problem.W = detail::blockSparseW(m, d, *out, row_of_efc);
  else
    out->problem.W = detail::denseW(m, d, *out, row_of_efc);
  return "";
}

Eigen::VectorXd MujocoProblem::toEfcForce(const Eigen::VectorXd& lambda, const double* dropped_source) const {
  Eigen::VectorXd f = Eigen::VectorXd::Zero(nefc);
  for (int p = 0; p < static_cast<int>(efc_row.size()) && p < lambda.size(); ++p)
    f[efc_row[p]] = lambda[p] / row_scale[p];
  if (dropped_source)
    for (int r : dropped_rows) f[r] = dropped_source[r];
  return f;
}

Eigen::VectorXd MujocoProblem::fromEfcForce(const double* efc_force) const {
  Eigen::VectorXd lambda(efc_row.size());
  for (std::size_t p = 0; p < efc_row.size(); ++p) lambda[p] = efc_force[efc_row[p]] * row_scale[p];
  return lambda;
}

}  // namespace scene
}  // namespace lcp_contact_solver
