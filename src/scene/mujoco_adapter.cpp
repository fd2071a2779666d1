// MuJoCo → core problem. See include/lcp_contact_solver/scene/mujoco_adapter.h for the
// mapping; the MuJoCo 2.2 facts it relies on are checked by test/scene/test_mujoco_adapter.cpp:
//   - efc_b = J qacc_smooth − aref (mj_fwdConstraint computes it so; recomputed here when
//     MuJoCo's solver does not run);
//   - mj_projectConstraint fills efc_AR only for the dual solver (PGS), so it is called with
//     the solver switched to PGS for the duration of the call;
//   - a pyramidal contact of condim k owns rows efc_address .. efc_address + 2(k−1) − 1,
//     edge 2j is n + μ_j t_j and edge 2j+1 is n − μ_j t_j (mju_decodePyramid's layout);
//   - qacc = qacc_smooth + M⁻¹ Jᵀ f (what MuJoCo's solvers leave).
#include "lcp_contact_solver/scene/mujoco_adapter.h"

#include "lcp_contact_solver/core/residual.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <sstream>
#include <utility>

namespace lcp_contact_solver {
namespace scene {

namespace {

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

Eigen::Vector3d vec3(const mjtNum* v) { return Eigen::Vector3d(v[0], v[1], v[2]); }

// Row e of AR as (column, value) pairs, dense or CSR.
template <typename F>
void forEachARInRow(const mjModel* m, const mjData* d, int e, F&& f) {
  const int n = d->nefc;
  if (mj_isSparse(m)) {
    const int adr = d->efc_AR_rowadr[e];
    for (int k = 0; k < d->efc_AR_rownnz[e]; ++k) f(d->efc_AR_colind[adr + k], d->efc_AR[adr + k]);
  } else {
    const mjtNum* row = d->efc_AR + static_cast<std::size_t>(e) * n;
    for (int c = 0; c < n; ++c)
      if (row[c] != 0.0) f(c, row[c]);
  }
}

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

}  // namespace

// ---- options ----------------------------------------------------------------------------

bool parseMujocoCone(const std::string& name, int* cone, std::string* error) {
  if (name == "pyramidal") *cone = mjCONE_PYRAMIDAL;
  else if (name == "elliptic") *cone = mjCONE_ELLIPTIC;
  else {
    if (error) *error = "unknown cone '" + name + "' (pyramidal or elliptic)";
    return false;
  }
  return true;
}

bool parseMujocoSolver(const std::string& name, int* solver, std::string* error) {
  if (name == "pgs") *solver = mjSOL_PGS;
  else if (name == "cg") *solver = mjSOL_CG;
  else if (name == "newton") *solver = mjSOL_NEWTON;
  else {
    if (error) *error = "unknown MuJoCo solver '" + name + "' (pgs, cg or newton)";
    return false;
  }
  return true;
}

bool parseMujocoJacobian(const std::string& name, int* jacobian, std::string* error) {
  if (name == "dense") *jacobian = mjJAC_DENSE;
  else if (name == "sparse") *jacobian = mjJAC_SPARSE;
  else if (name == "auto") *jacobian = mjJAC_AUTO;
  else {
    if (error) *error = "unknown jacobian '" + name + "' (dense, sparse or auto)";
    return false;
  }
  return true;
}

const char* mujocoConeName(int cone) { return cone == mjCONE_ELLIPTIC ? "elliptic" : "pyramidal"; }

const char* mujocoSolverName(int solver) {
  switch (solver) {
    case mjSOL_PGS: return "pgs";
    case mjSOL_CG: return "cg";
    case mjSOL_NEWTON: return "newton";
  }
  return "unknown";
}

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

// ---- MujocoWorld --------------------------------------------------------------------------

std::unique_ptr<MujocoWorld> MujocoWorld::load(const std::string& path, const MujocoOptions& options,
                                               std::string* error) {
  auto fail = [error](const std::string& message) {
    if (error) *error = message;
    return std::unique_ptr<MujocoWorld>();
  };
  int cone = -1, solver = -1, jacobian = -1;
  std::string why;
  if (!options.cone.empty() && !parseMujocoCone(options.cone, &cone, &why)) return fail(why);
  if (!options.solver.empty() && !parseMujocoSolver(options.solver, &solver, &why)) return fail(why);
  if (!options.jacobian.empty() && !parseMujocoJacobian(options.jacobian, &jacobian, &why)) return fail(why);
  if (options.iterations == 0) return fail("MuJoCo iterations must be > 0 (negative keeps the model's)");

  char message[1000] = "";
  const bool binary = path.size() > 4 && path.compare(path.size() - 4, 4, ".mjb") == 0;
  mjModel* m = binary ? mj_loadModel(path.c_str(), nullptr) : mj_loadXML(path.c_str(), nullptr, message, sizeof message);
  if (!m) return fail(path + ": " + (message[0] ? std::string(message) : std::string("cannot load the model")));
  if (cone >= 0) m->opt.cone = cone;
  if (solver >= 0) m->opt.solver = solver;
  if (jacobian >= 0) m->opt.jacobian = jacobian;
  if (options.iterations > 0) m->opt.iterations = options.iterations;
  if (options.tolerance >= 0.0) m->opt.tolerance = options.tolerance;
  if (options.timestep > 0.0) m->opt.timestep = options.timestep;
  mjData* d = mj_makeData(m);
  if (!d) {
    mj_deleteModel(m);
    return fail(path + ": MuJoCo could not allocate its data (nstack/njmax too large?)");
  }
  std::unique_ptr<MujocoWorld> world(new MujocoWorld());
  world->model_ = m;
  world->data_ = d;
  world->path_ = path;
  world->options_ = options;
  return world;
}

MujocoWorld::~MujocoWorld() {
  if (data_) mj_deleteData(data_);
  if (model_) mj_deleteModel(model_);
}

void MujocoWorld::copyDataFrom(const MujocoWorld& other) { mj_copyData(data_, model_, other.data_); }

std::unique_ptr<MujocoWorld> MujocoWorld::clone() const {
  std::unique_ptr<MujocoWorld> world(new MujocoWorld());
  world->model_ = mj_copyModel(nullptr, model_);
  world->data_ = mj_makeData(world->model_);
  world->path_ = path_;
  world->options_ = options_;
  mj_copyData(world->data_, world->model_, data_);
  return world;
}

std::string MujocoWorld::bodyName(int body) const {
  const char* name = mj_id2name(model_, mjOBJ_BODY, body);
  if (name && name[0]) return name;
  return body == 0 ? "world" : "body" + std::to_string(body);
}

// ---- the step ---------------------------------------------------------------------------

double computeConstraintAR(mjModel* m, mjData* d) {
  const auto start = std::chrono::steady_clock::now();
  const int saved = m->opt.solver;
  m->opt.solver = mjSOL_PGS;  // mj_projectConstraint fills efc_AR only for the dual solver
  mj_projectConstraint(m, d);
  m->opt.solver = saved;
  return secondsSince(start);
}

void forwardToConstraints(mjModel* m, mjData* d, bool run_solver, double* solver_seconds) {
  // mj_step's sequence (mj_step1, then mj_step2 up to the solver), sensors included.
  mj_checkPos(m, d);  // MuJoCo's reset on bad numbers, with its warning
  mj_checkVel(m, d);
  mj_fwdPosition(m, d);  // collisions, constraints (J, R), and efc_AR for PGS
  mj_sensorPos(m, d);
  if (mjENABLED(mjENBL_ENERGY)) mj_energyPos(m, d);
  mj_fwdVelocity(m, d);  // efc_aref
  mj_sensorVel(m, d);
  if (mjENABLED(mjENBL_ENERGY)) mj_energyVel(m, d);
  if (mjcb_control) mjcb_control(m, d);  // a user's controller, as mj_step calls it
  mj_fwdActuation(m, d);
  mj_fwdAcceleration(m, d);  // qacc_smooth
  if (run_solver) {
    const auto start = std::chrono::steady_clock::now();
    mj_fwdConstraint(m, d);
    if (solver_seconds) *solver_seconds = secondsSince(start);
  } else {
    const int nefc = d->nefc;
    if (nefc > 0) {
      mj_mulJacVec(m, d, d->efc_b, d->qacc_smooth);
      mju_subFrom(d->efc_b, d->efc_aref, nefc);
      mju_zero(d->efc_force, nefc);
    }
    mju_zero(d->qfrc_constraint, m->nv);
    mju_copy(d->qacc, d->qacc_smooth, m->nv);
    if (solver_seconds) *solver_seconds = 0.0;
  }
  if (d->nefc > 0 && !mj_isDual(m)) computeConstraintAR(m, d);
}

void applyConstraintForces(const mjModel* m, mjData* d, const Eigen::VectorXd& efc_force) {
  const int nefc = d->nefc, nv = m->nv;
  for (int i = 0; i < nefc; ++i) d->efc_force[i] = i < efc_force.size() ? efc_force[i] : 0.0;
  if (nefc > 0) {
    mj_mulJacTVec(m, d, d->qfrc_constraint, d->efc_force);
  } else {
    mju_zero(d->qfrc_constraint, nv);
  }
  mj_solveM(m, d, d->qacc, d->qfrc_constraint, 1);
  mju_addTo(d->qacc, d->qacc_smooth, nv);
}

std::string integrateEuler(const mjModel* m, mjData* d) {
  if (m->opt.integrator != mjINT_EULER)
    return "only MuJoCo's Euler integrator can take external constraint forces (the model uses " +
           std::string(m->opt.integrator == mjINT_RK4 ? "RK4" : "implicit") + ")";
  mj_sensorAcc(m, d);  // the rest of mj_step: acceleration sensors, MuJoCo's check, Euler
  mj_checkAcc(m, d);
  mj_Euler(m, d);
  return "";
}

double totalEnergy(mjModel* m, mjData* d) {
  const int saved = m->opt.enableflags;
  m->opt.enableflags |= mjENBL_ENERGY;  // MuJoCo 2.2 computes energy only with the flag set
  mj_energyPos(m, d);
  mj_energyVel(m, d);
  m->opt.enableflags = saved;
  return d->energy[0] + d->energy[1];
}

double maxPenetration(const mjData* d) {
  double depth = 0.0;
  for (int i = 0; i < d->ncon; ++i)
    if (d->contact[i].exclude == 0) depth = std::max(depth, -d->contact[i].dist);
  return depth;
}

// ---- ids ---------------------------------------------------------------------------------

std::int64_t mujocoContactId(int geom1, int geom2, int rank, int edge) {
  return (static_cast<std::int64_t>(geom1 & 0xFFFFF) << 36) | (static_cast<std::int64_t>(geom2 & 0xFFFFF) << 16) |
         (static_cast<std::int64_t>(rank & 0x3FF) << 6) | static_cast<std::int64_t>((edge + 1) & 0x3F);
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
  const int nefc = d->nefc;
  out->nefc = nefc;
  out->pyramidal = m->opt.cone == mjCONE_PYRAMIDAL;
  out->time = d->time;
  std::ostringstream name;
  name << "mujoco t=" << d->time;
  out->problem.name = name.str();

  // Rank of each contact among the contacts of its geom pair (for persistent ids).
  std::vector<int> rank(d->ncon, 0);
  {
    std::map<std::pair<int, int>, int> seen;
    for (int c = 0; c < d->ncon; ++c) rank[c] = seen[{d->contact[c].geom1, d->contact[c].geom2}]++;
  }

  std::vector<double> scale_of_row;
  std::vector<char> contact_counted(d->ncon, 0);
  auto addEntry = [&](const MujocoEntry& entry, const core::Contact& contact, const std::vector<int>& efc_rows,
                      const std::vector<double>& scales) {
    out->entries.push_back(entry);
    out->problem.contacts.push_back(contact);
    for (std::size_t k = 0; k < efc_rows.size(); ++k) {
      out->efc_row.push_back(efc_rows[k]);
      scale_of_row.push_back(scales[k]);
    }
  };
  auto contactEntry = [&](int c, MujocoRowKind kind, int e) {
    const mjContact& con = d->contact[c];
    MujocoEntry entry;
    entry.kind = kind;
    entry.efc_row = e;
    entry.mj_contact = c;
    entry.geom1 = con.geom1;
    entry.geom2 = con.geom2;
    entry.body_a = m->geom_bodyid[con.geom2];
    entry.body_b = m->geom_bodyid[con.geom1];
    entry.position = vec3(con.pos);
    entry.normal = vec3(con.frame);
    entry.dist = con.dist;
    if (!contact_counted[c]) {
      contact_counted[c] = 1;
      ++out->ncon;
    }
    return entry;
  };

  int e = 0;
  while (e < nefc) {
    const int type = d->efc_type[e];
    const int id = d->efc_id[e];
    switch (type) {
      case mjCNSTR_EQUALITY: {
        int k = 1;
        while (e + k < nefc && d->efc_type[e + k] == mjCNSTR_EQUALITY && d->efc_id[e + k] == id) ++k;
        if (!options.include_equalities) {
          for (int r = 0; r < k; ++r) out->dropped_rows.push_back(e + r);
        } else {
          if (k > 6)
            return "equality " + std::to_string(id) + " has " + std::to_string(k) + " rows (at most 6 fit a bilateral contact)";
          MujocoEntry entry;
          entry.kind = MujocoRowKind::kEquality;
          entry.efc_row = e;
          entry.object = id;
          entry.body_a = bodyOfEqualityObject(m, id, m->eq_obj1id[id]);
          entry.body_b = bodyOfEqualityObject(m, id, m->eq_obj2id[id]);
          entry.position = vec3(d->xpos + 3 * entry.body_a);
          core::Contact contact;
          contact.id = mujocoEqualityId(id);
          contact.type = core::ContactType::kBilateral;
          contact.rows = k;
          contact.mu = 0.0;
          std::vector<int> efc_rows;
          for (int r = 0; r < k; ++r) efc_rows.push_back(e + r);
          addEntry(entry, contact, efc_rows, std::vector<double>(k, 1.0));
        }
        e += k;
        break;
      }
      case mjCNSTR_FRICTION_DOF:
      case mjCNSTR_FRICTION_TENDON:
        out->dropped_rows.push_back(e);
        e += 1;
        break;
      case mjCNSTR_LIMIT_JOINT:
      case mjCNSTR_LIMIT_TENDON: {
        if (!options.include_limits) {
          out->dropped_rows.push_back(e);
          e += 1;
          break;
        }
        MujocoEntry entry;
        entry.kind = MujocoRowKind::kLimit;
        entry.efc_row = e;
        entry.object = id;
        if (type == mjCNSTR_LIMIT_JOINT) {
          entry.body_a = m->jnt_bodyid[id];
          entry.body_b = m->body_parentid[entry.body_a];
          entry.position = vec3(d->xanchor + 3 * id);
          const int jtype = m->jnt_type[id];
          if (jtype == mjJNT_HINGE || jtype == mjJNT_SLIDE) {
            const double sign = jacobianAt(m, d, e, m->jnt_dofadr[id]) < 0.0 ? -1.0 : 1.0;
            Eigen::Vector3d axis = vec3(d->xaxis + 3 * id);
            if (axis.norm() > 0.0) entry.normal = sign * axis.normalized();
          }
        }
        core::Contact contact;
        contact.id = mujocoLimitId(type, id);
        contact.type = core::ContactType::kFrictionless;
        contact.rows = 1;
        contact.mu = 0.0;
        addEntry(entry, contact, {e}, {1.0});
        e += 1;
        break;
      }
      case mjCNSTR_CONTACT_FRICTIONLESS: {
        if (id < 0 || id >= d->ncon) return "efc row " + std::to_string(e) + " names contact " + std::to_string(id) + " of " + std::to_string(d->ncon);
        MujocoEntry entry = contactEntry(id, MujocoRowKind::kFrictionless, e);
        core::Contact contact;
        contact.id = mujocoContactId(entry.geom1, entry.geom2, rank[id], -1);
        contact.type = core::ContactType::kFrictionless;
        contact.rows = 1;
        contact.mu = 0.0;
        addEntry(entry, contact, {e}, {1.0});
        e += 1;
        break;
      }
      case mjCNSTR_CONTACT_PYRAMIDAL: {
        if (id < 0 || id >= d->ncon) return "efc row " + std::to_string(e) + " names contact " + std::to_string(id) + " of " + std::to_string(d->ncon);
        const mjContact& con = d->contact[id];
        const int edges = 2 * (con.dim - 1);
        if (con.efc_address != e || con.dim < 2 || e + edges > nefc)
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
            if (options.scale_rows) s = edge.norm();
            entry.normal = edge.normalized();
          }  // torsion / rolling edges: a normal force with a torque; the normal is n
          core::Contact contact;
          contact.id = mujocoContactId(entry.geom1, entry.geom2, rank[id], k);
          contact.type = core::ContactType::kFrictionless;
          contact.rows = 1;
          contact.mu = 0.0;
          addEntry(entry, contact, {e + k}, {s});
        }
        e += edges;
        break;
      }
      case mjCNSTR_CONTACT_ELLIPTIC: {
        if (id < 0 || id >= d->ncon) return "efc row " + std::to_string(e) + " names contact " + std::to_string(id) + " of " + std::to_string(d->ncon);
        const mjContact& con = d->contact[id];
        if (con.efc_address != e || con.dim < 3 || e + con.dim > nefc)
          return "elliptic contact " + std::to_string(id) + " does not own rows " + std::to_string(e) + ".." +
                 std::to_string(e + con.dim - 1);
        MujocoEntry entry = contactEntry(id, MujocoRowKind::kElliptic, e);
        entry.tangent1 = vec3(con.frame + 3);
        entry.tangent2 = vec3(con.frame + 6);
        entry.mu = con.friction[0];
        double s2 = 1.0;  // anisotropy: scale the second tangent so the cone is the disc of μ1
        if (options.scale_rows && con.friction[1] > 0.0 && con.friction[1] != con.friction[0])
          s2 = con.friction[0] / con.friction[1];
        core::Contact contact;
        contact.id = mujocoContactId(entry.geom1, entry.geom2, rank[id], -1);
        contact.type = core::ContactType::kFrictional;
        contact.rows = 3;
        contact.mu = con.friction[0];
        addEntry(entry, contact, {e, e + 1, e + 2}, {1.0, 1.0, s2});
        for (int r = 3; r < con.dim; ++r) out->dropped_rows.push_back(e + r);  // torsion, rolling
        e += con.dim;
        break;
      }
      default:
        return "efc row " + std::to_string(e) + " has an unknown constraint type " + std::to_string(type);
    }
  }

  // Rows, scaling, d_free, MuJoCo's forces.
  const int n = static_cast<int>(out->efc_row.size());
  out->row_scale = Eigen::Map<const Eigen::VectorXd>(scale_of_row.data(), n);
  std::vector<int> row_of_efc(nefc, -1);
  for (int p = 0; p < n; ++p) row_of_efc[out->efc_row[p]] = p;
  out->problem.d_free.resize(n);
  out->mujoco_lambda.resize(n);
  for (int p = 0; p < n; ++p) {
    const int ep = out->efc_row[p];
    out->problem.d_free[p] = d->efc_b[ep] / out->row_scale[p];
    out->mujoco_lambda[p] = d->efc_force[ep] * out->row_scale[p];
  }
  if (options.fold_dropped && !out->dropped_rows.empty()) {
    std::vector<char> dropped(nefc, 0);
    for (int r : out->dropped_rows) dropped[r] = 1;
    for (int p = 0; p < n; ++p) {
      double coupling = 0.0;
      forEachARInRow(m, d, out->efc_row[p], [&](int col, double value) {
        if (dropped[col]) coupling += value * d->efc_force[col];
      });
      out->problem.d_free[p] += coupling / out->row_scale[p];
    }
  }

  // W: AR restricted to the kept rows, scaled.
  const bool block_sparse =
      options.storage == MujocoExtractOptions::Storage::kBlockSparse ||
      (options.storage == MujocoExtractOptions::Storage::kAuto && n > options.dense_max_rows);
  if (!block_sparse) {
    Eigen::MatrixXd W = Eigen::MatrixXd::Zero(n, n);
    for (int p = 0; p < n; ++p) {
      forEachARInRow(m, d, out->efc_row[p], [&](int col, double value) {
        const int q = row_of_efc[col];
        if (q >= 0) W(p, q) = value / (out->row_scale[p] * out->row_scale[q]);
      });
    }
    out->problem.W = std::move(W);
  } else {
    const std::vector<int> offsets = out->problem.rowOffsets();
    const int nb = static_cast<int>(out->entries.size());
    std::vector<int> entry_of_row(n);
    std::vector<int> sizes(nb);
    for (int i = 0; i < nb; ++i) {
      sizes[i] = offsets[i + 1] - offsets[i];
      for (int p = offsets[i]; p < offsets[i + 1]; ++p) entry_of_row[p] = i;
    }
    core::BlockSparseMatrix W = core::BlockSparseMatrix::withBlockSizes(sizes);
    std::vector<int> slot(nb, -1);  // block index of entry j within the current block row
    std::vector<int> cols;
    std::vector<Eigen::MatrixXd> blocks;
    for (int i = 0; i < nb; ++i) {
      cols.clear();
      blocks.clear();
      for (int p = offsets[i]; p < offsets[i + 1]; ++p) {
        forEachARInRow(m, d, out->efc_row[p], [&](int col, double value) {
          const int q = row_of_efc[col];
          if (q < 0) return;
          const int j = entry_of_row[q];
          if (slot[j] < 0) {
            slot[j] = static_cast<int>(cols.size());
            cols.push_back(j);
            blocks.push_back(Eigen::MatrixXd::Zero(sizes[i], sizes[j]));
          }
          blocks[slot[j]](p - offsets[i], q - offsets[j]) = value / (out->row_scale[p] * out->row_scale[q]);
        });
      }
      std::vector<int> order(cols.size());
      for (std::size_t k = 0; k < order.size(); ++k) order[k] = static_cast<int>(k);
      std::sort(order.begin(), order.end(), [&](int a, int b) { return cols[a] < cols[b]; });
      W.beginRow();
      for (int k : order) W.addBlock(cols[k], blocks[k]);
      for (int j : cols) slot[j] = -1;
    }
    out->problem.W = std::move(W);
  }
  return "";
}

Eigen::VectorXd MujocoProblem::toEfcForce(const Eigen::VectorXd& lambda, const double* dropped_source) const {
  Eigen::VectorXd f = Eigen::VectorXd::Zero(nefc);
  for (int p = 0; p < static_cast<int>(efc_row.size()) && p < lambda.size(); ++p) f[efc_row[p]] = lambda[p] / row_scale[p];
  if (dropped_source)
    for (int r : dropped_rows) f[r] = dropped_source[r];
  return f;
}

Eigen::VectorXd MujocoProblem::fromEfcForce(const double* efc_force) const {
  Eigen::VectorXd lambda(efc_row.size());
  for (std::size_t p = 0; p < efc_row.size(); ++p) lambda[p] = efc_force[efc_row[p]] * row_scale[p];
  return lambda;
}

Eigen::Vector3d contactFrameForce(const MujocoProblem& problem, const Eigen::VectorXd& lambda, int mj_contact,
                                  const mjData* d) {
  Eigen::Vector3d force = Eigen::Vector3d::Zero();
  const std::vector<int> offsets = problem.problem.rowOffsets();
  for (std::size_t i = 0; i < problem.entries.size(); ++i) {
    const MujocoEntry& entry = problem.entries[i];
    if (entry.mj_contact != mj_contact) continue;
    const int p = offsets[i];
    switch (entry.kind) {
      case MujocoRowKind::kFrictionless: force[0] += lambda[p]; break;
      case MujocoRowKind::kPyramidEdge: {
        const double f = lambda[p] / problem.row_scale[p];
        const int j = entry.edge / 2;
        force[0] += f;
        if (j < 2) force[1 + j] += (entry.edge % 2 == 0 ? 1.0 : -1.0) * d->contact[mj_contact].friction[j] * f;
        break;
      }
      case MujocoRowKind::kElliptic:
        for (int r = 0; r < 3; ++r) force[r] += lambda[p + r] / problem.row_scale[p + r];
        break;
      default: break;
    }
  }
  return force;
}

// ---- comparison --------------------------------------------------------------------------

ForceComparison compareForces(const MujocoProblem& problem, const Eigen::VectorXd& lambda,
                              const std::vector<core::ContactState>& states) {
  ForceComparison cmp;
  const std::vector<int> offsets = problem.problem.rowOffsets();
  cmp.rows = static_cast<int>(problem.efc_row.size());
  double scale = 0.0;
  for (int p = 0; p < cmp.rows; ++p) scale = std::max(scale, std::abs(problem.mujoco_lambda[p] / problem.row_scale[p]));
  for (std::size_t i = 0; i < problem.entries.size(); ++i) {
    double entry_max = 0.0;
    for (int p = offsets[i]; p < offsets[i + 1]; ++p) {
      const double ours = p < lambda.size() ? lambda[p] / problem.row_scale[p] : 0.0;
      const double theirs = problem.mujoco_lambda[p] / problem.row_scale[p];
      entry_max = std::max(entry_max, std::abs(ours - theirs));
    }
    cmp.max_abs = std::max(cmp.max_abs, entry_max);
    if (i < states.size()) {
      const int s = static_cast<int>(states[i]);
      if (s >= 0 && s < core::kContactStateCount) {
        ++cmp.state_count[s];
        cmp.state_max_abs[s] = std::max(cmp.state_max_abs[s], entry_max);
      }
    }
  }
  cmp.scale = scale > 0.0 ? scale : 1.0;
  cmp.max_rel = cmp.max_abs / cmp.scale;
  return cmp;
}

double problemResidual(const MujocoProblem& problem, const Eigen::VectorXd& lambda) {
  if (problem.problem.contacts.empty()) return 0.0;
  Eigen::VectorXd d;
  core::multiply(problem.problem.W, lambda, d);
  d += problem.problem.d_free;
  return core::naturalMapResidual(problem.problem, core::effectiveMu(problem.problem, 0.0), lambda, d);
}

}  // namespace scene
}  // namespace lcp_contact_solver
