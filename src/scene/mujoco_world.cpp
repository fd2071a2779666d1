// The MuJoCo model and its step (mujoco_world.h). The MuJoCo 2.2 facts it relies on are
// checked by test/scene/test_mujoco_adapter.cpp:
//   - efc_b = J qacc_smooth − aref (mj_fwdConstraint computes it so; recomputed here when
//     MuJoCo's solver does not run);
//   - mj_projectConstraint fills efc_AR only for the dual solver (PGS), so it is called with
//     the solver switched to PGS for the duration of the call;
//   - qacc = qacc_smooth + M⁻¹ Jᵀ f (what MuJoCo's solvers leave).
#include "lcp_contact_solver/scene/mujoco_world.h"

#include <algorithm>
#include <chrono>
#include <vector>

namespace lcp_contact_solver {
namespace scene {

namespace {

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// One of MuJoCo's option values by its name.
struct NamedValue {
  const char* name;
  int value;
};
using NameTable = std::vector<NamedValue>;

const NameTable kCones = {{"pyramidal", mjCONE_PYRAMIDAL}, {"elliptic", mjCONE_ELLIPTIC}};
const NameTable kSolvers = {{"pgs", mjSOL_PGS}, {"cg", mjSOL_CG}, {"newton", mjSOL_NEWTON}};
const NameTable kJacobians = {{"dense", mjJAC_DENSE}, {"sparse", mjJAC_SPARSE}, {"auto", mjJAC_AUTO}};

// `name`'s value in `table`; false with "unknown <what> '<name>' (a, b or c)" in `error`
// (may be null) when the table has no such name.
bool parseNamed(const std::string& name, const NameTable& table, const char* what, int* value,
                std::string* error) {
  for (const NamedValue& entry : table) {
    if (name != entry.name) continue;
    *value = entry.value;
    return true;
  }
  if (error) {
    std::string choices;
    for (std::size_t k = 0; k < table.size(); ++k) {
      if (k > 0) choices += k + 1 == table.size() ? " or " : ", ";
      choices += table[k].name;
    }
    *error = "unknown " + std::string(what) + " '" + name + "' (" + choices + ")";
  }
  return false;
}

}  // namespace

// ---- options ----------------------------------------------------------------------------

bool parseMujocoCone(const std::string& name, int* cone, std::string* error) {
  return parseNamed(name, kCones, "cone", cone, error);
}

bool parseMujocoSolver(const std::string& name, int* solver, std::string* error) {
  return parseNamed(name, kSolvers, "MuJoCo solver", solver, error);
}

bool parseMujocoJacobian(const std::string& name, int* jacobian, std::string* error) {
  return parseNamed(name, kJacobians, "jacobian", jacobian, error);
}

const char* mujocoConeName(int cone) { return cone == mjCONE_ELLIPTIC ? "elliptic" : "pyramidal"; }

const char* mujocoSolverName(int solver) {
  for (const NamedValue& entry : kSolvers)
    if (entry.value == solver) return entry.name;
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
  mjModel* m = binary ? mj_loadModel(path.c_str(), nullptr)
                      : mj_loadXML(path.c_str(), nullptr, message, sizeof message);
  if (!m)
    return fail(path + ": " + (message[0] ? std::string(message) : std::string("cannot load the model")));
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

}  // namespace scene
}  // namespace lcp_contact_solver
