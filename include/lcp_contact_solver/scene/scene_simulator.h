// The example simulator: steps a scene at a fixed dt with semi-implicit Euler.
//
// One step is split in two so the ROS simulator node can put the solver node in between:
//
//   const StepProblem& sp = sim.buildStep();   // contacts (FCL), free motion, W, d_free
//   ... publish sp.frames / sp.problem, receive forces λ (one per row, N) ...
//   sim.applyForces(lambda);                   // v_new = v_free + dt M⁻¹ Jᵀ λ, integrate
//
// step() does both with the ContactSolver inside (fully in-process: tests, benchmarks).
// buildStep() with no contacts gives an empty problem: applyForces() then takes an empty
// vector (the core refuses an empty problem, so nothing is solved).
#pragma once

#include "lcp_contact_solver/core/contact_solver.h"
#include "lcp_contact_solver/core/problem.h"
#include "lcp_contact_solver/core/solve_result.h"
#include "lcp_contact_solver/scene/compliance.h"
#include "lcp_contact_solver/scene/contact_generator.h"
#include "lcp_contact_solver/scene/scene.h"

#include <Eigen/Core>

#include <memory>
#include <string>
#include <vector>

namespace lcp_contact_solver {
namespace scene {

// What one step asks the solver.
struct StepProblem {
  core::Problem problem;             // contacts (id, type, rows, μ), W, d_free; rows in frame order
  std::vector<SceneContact> frames;  // one per problem contact, same order
  double dt = 0.0;                   // s
  double time = 0.0;                 // simulated time at the start of the step (s)
  long long step_index = 0;          // 0 for the first step
};

struct StepStats {
  long long step_index = 0;
  double time = 0.0;  // simulated time after the step (s)
  int contacts = 0;
  int rows = 0;
  int frictionless_contacts = 0;
  int impacts = 0;  // contacts that bounced this step (restitution)
  ContactGenerationStats generation;
  bool solved = false;  // the in-process solver ran (false without contacts or with applyForces)
  core::SolveStatus status = core::SolveStatus::kConverged;
  bool converged = true;
  int iterations = 0;
  double residual = 0.0;
  double max_penetration = 0.0;  // m, over this step's contacts before the step
  // Wall time (s) of the parts.
  double time_contacts = 0.0, time_problem = 0.0, time_solve = 0.0, time_integrate = 0.0;
};

class SceneSimulator {
 public:
  // Takes the scene; the in-process solver uses scene.params.solver.
  explicit SceneSimulator(Scene scene);
  ~SceneSimulator();
  SceneSimulator(const SceneSimulator&) = delete;
  SceneSimulator& operator=(const SceneSimulator&) = delete;

  // --- split step (ROS simulator node) ---
  // Contacts and problem at the current state for a step of dt (default: params.dt).
  // Throws SceneError when a step is already pending.
  const StepProblem& buildStep();
  const StepProblem& buildStep(double dt);
  bool stepPending() const { return pending_; }
  // Applies λ (size = problem rows, N) and integrates. Throws SceneError when no step is
  // pending or the size is wrong. Returns the step's statistics.
  StepStats applyForces(const Eigen::VectorXd& lambda);

  // --- in-process ---
  StepStats step();
  StepStats step(double dt);
  // Steps until `duration` of simulated time has passed (fixed dt = params.dt).
  void run(double duration);

  // --- state ---
  const Scene& scene() const { return scene_; }
  const SceneParams& params() const { return scene_.params; }
  int bodyCount() const { return static_cast<int>(scene_.bodies.size()); }
  const RigidBody& body(int index) const;
  const RigidBody& body(const std::string& name) const;
  // Sets a dynamic body's pose / velocities (throws SceneError for a static one).
  void setBodyPose(int index, const Eigen::Vector3d& position, const Eigen::Quaterniond& orientation);
  void setBodyVelocity(int index, const Eigen::Vector3d& linear, const Eigen::Vector3d& angular);
  // Adds a wrench at the body's COM (world frame) for the next step only.
  void addExternalWrench(int index, const Eigen::Vector3d& force, const Eigen::Vector3d& torque);

  double time() const { return time_; }
  long long stepCount() const { return step_index_; }
  double kineticEnergy() const;    // J
  double potentialEnergy() const;  // J, −m g·c relative to the world origin
  double energy() const { return kineticEnergy() + potentialEnergy(); }

  const StepProblem& lastProblem() const { return problem_; }         // the last built step
  const core::SolveResult& lastSolve() const { return last_solve_; }  // the in-process solve of step()
  const Eigen::VectorXd& lastForces() const { return last_forces_; }  // λ applied last
  const StepStats& lastStats() const { return last_stats_; }
  // Contact wrench [force; torque about the COM] on each body from the last applied forces.
  std::vector<Vector6d> lastContactWrenches() const;

  ContactGenerator& contactGenerator() { return *generator_; }
  core::ContactSolver& solver() { return solver_; }

 private:
  void applyRestitution(double dt);
  Scene scene_;
  std::unique_ptr<ContactGenerator> generator_;
  core::ContactSolver solver_;
  StepProblem problem_;
  std::unique_ptr<RigidContactModel> model_;
  std::vector<Vector6d> v_free_;
  bool pending_ = false;
  double time_ = 0.0;
  long long step_index_ = 0;
  Eigen::VectorXd last_forces_;
  core::SolveResult last_solve_;
  StepStats last_stats_;
  StepStats building_;  // stats of the pending step
};

}  // namespace scene
}  // namespace lcp_contact_solver
