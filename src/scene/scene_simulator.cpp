// Fixed-step semi-implicit Euler simulator around the core solver (see scene_simulator.h).
#include "lcp_contact_solver/scene/scene_simulator.h"

#include <chrono>
#include <cmath>

namespace lcp_contact_solver {
namespace scene {

namespace {

double seconds(std::chrono::steady_clock::time_point a, std::chrono::steady_clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

// q ← exp(ω dt / 2) ⊗ q: exact rotation for a constant world angular velocity over the step.
Eigen::Quaterniond integrateOrientation(const Eigen::Quaterniond& q, const Eigen::Vector3d& w, double dt) {
  const double angle = w.norm() * dt;
  if (angle < 1e-300) return q;
  const Eigen::Quaterniond dq(Eigen::AngleAxisd(angle, w.normalized()));
  return (dq * q).normalized();
}

}  // namespace

SceneSimulator::SceneSimulator(Scene scene) : scene_(std::move(scene)), solver_(scene_.params.solver) {
  if (std::string err = validateSceneParams(scene_.params); !err.empty())
    throw SceneError("scene '" + scene_.name + "': " + err);
  generator_ = std::make_unique<ContactGenerator>(scene_);
}

SceneSimulator::~SceneSimulator() = default;

const RigidBody& SceneSimulator::body(int index) const {
  if (index < 0 || index >= bodyCount())
    throw SceneError("scene '" + scene_.name + "': no body with index " + std::to_string(index));
  return scene_.bodies[index];
}

const RigidBody& SceneSimulator::body(const std::string& name) const {
  return scene_.bodies[scene_.requireBody(name)];
}

void SceneSimulator::setBodyPose(int index, const Eigen::Vector3d& position,
                                 const Eigen::Quaterniond& orientation) {
  const RigidBody& b = body(index);
  if (b.is_static) throw SceneError("body '" + b.name + "' is static: its pose cannot change");
  if (pending_) throw SceneError("setBodyPose during a pending step");
  scene_.bodies[index].position = position;
  scene_.bodies[index].orientation = orientation.normalized();
}

void SceneSimulator::setBodyVelocity(int index, const Eigen::Vector3d& linear,
                                     const Eigen::Vector3d& angular) {
  const RigidBody& b = body(index);
  if (b.is_static) throw SceneError("body '" + b.name + "' is static: it cannot move");
  if (pending_) throw SceneError("setBodyVelocity during a pending step");
  scene_.bodies[index].linear_velocity = linear;
  scene_.bodies[index].angular_velocity = angular;
}

void SceneSimulator::addExternalWrench(int index, const Eigen::Vector3d& force,
                                       const Eigen::Vector3d& torque) {
  const RigidBody& b = body(index);
  if (b.is_static) return;  // static bodies do not move
  if (pending_) throw SceneError("addExternalWrench during a pending step (add it before buildStep)");
  scene_.bodies[index].external_force += force;
  scene_.bodies[index].external_torque += torque;
}

const StepProblem& SceneSimulator::buildStep() { return buildStep(scene_.params.dt); }

// Newton restitution at impact: a contact approaching faster than restitution_threshold
// that would close within the step asks for v_n,new ≥ −e v_n,pre instead of "close the gap
// and stop": d_free_n = dt (J_n v_free + e v_n,pre), the speculative gap dropped (so the
// bounce starts up to one step's travel early, and a resting contact, slower than the
// threshold, never bounces). Contacts with e = 0 and scenes without restitution: untouched.
void SceneSimulator::applyRestitution(double dt) {
  const std::vector<SceneContact>& frames = problem_.frames;
  bool any = false;
  for (const SceneContact& f : frames) any = any || f.restitution > 0.0;
  if (!any) return;
  std::vector<Vector6d> v_now(scene_.bodies.size(), Vector6d::Zero());
  for (std::size_t i = 0; i < scene_.bodies.size(); ++i) {
    const RigidBody& b = scene_.bodies[i];
    if (!b.is_static) v_now[i] << b.linear_velocity, b.angular_velocity;
  }
  const Eigen::VectorXd vn = model_->normalVelocities(v_now);
  const std::vector<int>& offsets = model_->rowOffsets();
  core::Problem& p = problem_.problem;
  for (std::size_t c = 0; c < frames.size(); ++c) {
    const SceneContact& f = frames[c];
    if (f.restitution <= 0.0 || vn[c] >= -scene_.params.restitution_threshold) continue;
    if (f.gap() + dt * vn[c] >= 0.0) continue;  // does not reach the other body this step
    p.d_free[offsets[c]] += f.restitution * dt * vn[c] - gapTerm(f.gap());
    ++building_.impacts;
  }
}

const StepProblem& SceneSimulator::buildStep(double dt) {
  if (pending_) throw SceneError("buildStep: a step is pending; call applyForces first");
  if (!std::isfinite(dt) || dt <= 0.0) throw SceneError("buildStep: dt must be > 0");
  building_ = StepStats();
  building_.step_index = step_index_;
  const auto t0 = std::chrono::steady_clock::now();
  problem_ = StepProblem();
  problem_.dt = dt;
  problem_.time = time_;
  problem_.step_index = step_index_;
  problem_.frames = generator_->generate();
  building_.generation = generator_->lastStats();
  const auto t1 = std::chrono::steady_clock::now();

  v_free_ = freeVelocities(scene_, dt);
  model_ = std::make_unique<RigidContactModel>(scene_, problem_.frames);
  core::Problem& p = problem_.problem;
  p.name = scene_.name;
  p.contacts = problemContacts(scene_, problem_.frames);
  for (const SceneContact& f : problem_.frames) {
    building_.max_penetration = std::max(building_.max_penetration, f.depth);
    if (f.type == core::ContactType::kFrictionless) ++building_.frictionless_contacts;
  }
  if (scene_.params.compliance == ComplianceStorage::kBodies) {
    p.bodies = std::make_shared<const core::BodyCompliance>(model_->bodyCompliance(dt));
  } else {
    p.W = model_->compliance(dt, scene_.params.compliance);
  }
  p.d_free = model_->freeViolation(v_free_, dt);
  applyRestitution(dt);
  building_.contacts = static_cast<int>(p.contacts.size());
  building_.rows = p.rowCount();
  building_.time_contacts = seconds(t0, t1);
  building_.time_problem = seconds(t1, std::chrono::steady_clock::now());
  pending_ = true;
  return problem_;
}

StepStats SceneSimulator::applyForces(const Eigen::VectorXd& lambda) {
  if (!pending_) throw SceneError("applyForces: no step pending; call buildStep first");
  if (lambda.size() != model_->rowCount())
    throw SceneError("applyForces: " + std::to_string(lambda.size()) + " forces given, the step has " +
                     std::to_string(model_->rowCount()) + " rows");
  if (!lambda.allFinite()) throw SceneError("applyForces: a force is not finite");
  const auto t0 = std::chrono::steady_clock::now();
  const double dt = problem_.dt;
  std::vector<Vector6d> v = v_free_;
  model_->applyForces(lambda, dt, &v);
  for (std::size_t i = 0; i < scene_.bodies.size(); ++i) {
    RigidBody& b = scene_.bodies[i];
    if (b.is_static) continue;
    b.linear_velocity = v[i].head<3>();
    b.angular_velocity = v[i].tail<3>();
    // Semi-implicit Euler: the COM moves with the new velocity, the orientation turns with
    // the new angular velocity, and the link frame follows the COM.
    const Eigen::Vector3d com = b.comWorld() + dt * b.linear_velocity;
    b.orientation = integrateOrientation(b.orientation, b.angular_velocity, dt);
    b.position = com - b.orientation * b.com_local;
    b.external_force.setZero();
    b.external_torque.setZero();
  }
  last_forces_ = lambda;
  time_ += dt;
  ++step_index_;
  pending_ = false;
  building_.time = time_;
  building_.time_integrate = seconds(t0, std::chrono::steady_clock::now());
  last_stats_ = building_;
  return last_stats_;
}

StepStats SceneSimulator::step() { return step(scene_.params.dt); }

StepStats SceneSimulator::step(double dt) {
  const StepProblem& sp = buildStep(dt);
  Eigen::VectorXd lambda = Eigen::VectorXd::Zero(sp.problem.rowCount());
  core::SolveResult result;
  double solve_time = 0.0;
  const bool solve = !sp.problem.contacts.empty();
  if (solve) {
    const auto t0 = std::chrono::steady_clock::now();
    result = solver_.solve(sp.problem);
    solve_time = seconds(t0, std::chrono::steady_clock::now());
    if (result.forces.size() == lambda.size()) lambda = result.forces;
  }
  building_.solved = solve;
  if (solve) {
    building_.status = result.status;
    building_.converged = result.converged;
    building_.iterations = result.iterations;
    building_.residual = result.residual;
  }
  building_.time_solve = solve_time;
  last_solve_ = std::move(result);
  return applyForces(lambda);
}

void SceneSimulator::run(double duration) {
  const long long n = static_cast<long long>(std::llround(duration / scene_.params.dt));
  for (long long i = 0; i < n; ++i) step();
}

double SceneSimulator::kineticEnergy() const {
  double e = 0.0;
  for (const RigidBody& b : scene_.bodies) {
    if (b.is_static) continue;
    e += 0.5 * b.mass * b.linear_velocity.squaredNorm();
    e += 0.5 * b.angular_velocity.dot(b.inertiaWorld() * b.angular_velocity);
  }
  return e;
}

double SceneSimulator::potentialEnergy() const {
  double e = 0.0;
  for (const RigidBody& b : scene_.bodies)
    if (!b.is_static) e -= b.mass * scene_.params.gravity.dot(b.comWorld());
  return e;
}

std::vector<Vector6d> SceneSimulator::lastContactWrenches() const {
  if (!model_ || last_forces_.size() != model_->rowCount())
    return std::vector<Vector6d>(scene_.bodies.size(), Vector6d::Zero());
  return model_->bodyWrenches(last_forces_);
}

}  // namespace scene
}  // namespace lcp_contact_solver
