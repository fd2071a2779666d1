// A MuJoCo model and its step (ROS-free; needs libmujoco-dev, MuJoCo 2.2.x): loading with
// option overrides, the forward pipeline up to the constraint problem, external constraint
// forces applied, Euler integration, energy and penetration. What the constraint problem
// becomes for the package's solvers is mujoco_adapter.h; our forces against MuJoCo's,
// mujoco_comparison.h.
#pragma once

#include <mujoco/mujoco.h>

#include <Eigen/Core>

#include <memory>
#include <string>

namespace lcp_contact_solver {
namespace scene {

// ---- model, options ----------------------------------------------------------------------

// Overrides of the model's mjOption, applied after loading. Empty / negative = keep the model's.
struct MujocoOptions {
  std::string cone;       // "pyramidal" or "elliptic"
  std::string solver;     // MuJoCo's own solver: "pgs", "cg" or "newton"
  std::string jacobian;   // "dense", "sparse" or "auto"
  int iterations = -1;    // MuJoCo's solver iterations
  double tolerance = -1;  // MuJoCo's solver tolerance (0: run every iteration)
  double timestep = -1;   // s
};

// Parses the names above ("" keeps the model's). False with a sentence for an unknown one.
bool parseMujocoCone(const std::string& name, int* cone, std::string* error);
bool parseMujocoSolver(const std::string& name, int* solver, std::string* error);
bool parseMujocoJacobian(const std::string& name, int* jacobian, std::string* error);
const char* mujocoConeName(int cone);
const char* mujocoSolverName(int solver);

// An mjModel and its mjData, freed together.
class MujocoWorld {
 public:
  // Loads an MJCF (or MJB) file and applies the option overrides; nullptr with a sentence in
  // `error` when the file does not load or an override is invalid.
  static std::unique_ptr<MujocoWorld> load(const std::string& path, const MujocoOptions& options,
                                           std::string* error);
  ~MujocoWorld();
  MujocoWorld(const MujocoWorld&) = delete;
  MujocoWorld& operator=(const MujocoWorld&) = delete;

  mjModel* model() const { return model_; }
  mjData* data() const { return data_; }
  const std::string& path() const { return path_; }

  // Copies the full state and the step's data of `other` (same model) into this world.
  void copyDataFrom(const MujocoWorld& other);
  // A second world on the same file and options, with this one's data copied.
  std::unique_ptr<MujocoWorld> clone() const;

  // Body name (or "body<N>"; body 0 is "world").
  std::string bodyName(int body) const;

 private:
  MujocoWorld() = default;
  mjModel* model_ = nullptr;
  mjData* data_ = nullptr;
  std::string path_;
  MujocoOptions options_;
};

// ---- the step --------------------------------------------------------------------------

// Runs MuJoCo's forward pipeline on the current state up to its constraint problem (the
// sequence of mj_step: MuJoCo's position/velocity checks, then positions (collisions,
// constraints, efc_J, efc_R) and their sensors, velocities (efc_aref) and theirs, actuation,
// smooth accelerations (qacc_smooth) and efc_b = J qacc_smooth − aref; computes efc_AR also
// when the model's solver is primal (CG, Newton do not need it). With `run_solver` MuJoCo's
// own solver runs too (mj_fwdConstraint: efc_force, qfrc_constraint, qacc — together this
// is mj_forward without the acceleration sensors), and its wall time is returned through
// `solver_seconds` (may be null).
void forwardToConstraints(mjModel* m, mjData* d, bool run_solver, double* solver_seconds = nullptr);

// Computes efc_AR for the current constraints whatever the model's solver (MuJoCo 2.2 fills
// it only for its dual solver, PGS). Returns its wall time in s.
double computeConstraintAR(mjModel* m, mjData* d);

// Constraint forces of every MuJoCo row (nefc) → qfrc_constraint = Jᵀ f and
// qacc = qacc_smooth + M⁻¹ Jᵀ f, replacing what MuJoCo's solver left (efc_force too).
void applyConstraintForces(const mjModel* m, mjData* d, const Eigen::VectorXd& efc_force);

// Finishes the step from d->qacc as mj_step does: acceleration sensors, MuJoCo's check of
// qacc, then semi-implicit Euler (mj_Euler, with its implicit joint damping). Empty string,
// or why not (only the Euler integrator is supported: RK4 re-evaluates the dynamics at
// substeps, which would bypass the forces).
std::string integrateEuler(const mjModel* m, mjData* d);

// Kinetic + potential energy (gravity, springs) of the current state after the position
// stage, J (MuJoCo's mj_energyPos + mj_energyVel, with its energy flag set for the call).
double totalEnergy(mjModel* m, mjData* d);
// Deepest penetration over the active contacts (−min dist, 0 when none penetrates), m.
double maxPenetration(const mjData* d);

}  // namespace scene
}  // namespace lcp_contact_solver
