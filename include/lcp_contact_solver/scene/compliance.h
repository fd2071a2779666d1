// Rigid-body contact mechanics of one step: Jacobians, the compliance W, the free-motion
// violation d_free, and applying the solved forces.
//
// Units and formulation (position level, SOFA's convention, λ in newtons). For a step dt:
//   v_free = v + dt M⁻¹ f_ext                       (gravity, external wrenches)
//   W      = dt² J M⁻¹ Jᵀ                            (m/N)
//   d_free = gapTerm(gap) + dt (J v_free)  normal row (m); the contact also carries gap,
//            the scene's erp and softness, which the solver applies (core/stabilization.h)
//            dt (J v_free)                  tangent rows (m)
//   λ      = the contact forces over the step (N), from d = W λ + d_free, 0 ≤ λ_n ⟂ d_n ≥ 0
//   v_new  = v_free + dt M⁻¹ Jᵀ λ,  then x_new from v_new (semi-implicit Euler).
// so d_n = gapTerm(gap) + dt (J v_new): the gap left after the step (with a penetration the
// solver adds erp·gap, so d_n ≥ 0 removes the fraction erp of it per step).
//
// J: one row per contact row (normal, t1, t2), two 6-dof blocks (body A, body B), each in
// the body's [linear; angular] velocity coordinates (COM velocity, world angular velocity):
//   J_A,u = [ uᵀ, ((p − c_A) × u)ᵀ ],   J_B,u = −[ uᵀ, ((p − c_B) × u)ᵀ ]
// so J v is the velocity of A relative to B at the contact point along u. Torsional and
// rolling rows are angular only: J_A,ω = [ 0, ωᵀ ], J_B,ω = −[ 0, ωᵀ ] for ω = n (spin),
// t1, t2 (rolling): the relative angular velocity about those axes, λ a torque (N·m, the
// row's "d" in rad). Static bodies have no block (M⁻¹ = 0).
#pragma once

#include "lcp_contact_solver/core/body_compliance.h"
#include "lcp_contact_solver/core/problem.h"
#include "lcp_contact_solver/scene/contact_generator.h"
#include "lcp_contact_solver/scene/scene.h"

#include <Eigen/Core>

#include <vector>

namespace lcp_contact_solver {
namespace scene {

using Vector6d = Eigen::Matrix<double, 6, 1>;

// The gap in d_free: gap when gap > 0 (speculative contact: no force unless the bodies
// would meet within the step), 0 when gap < 0: the penetration is corrected by the solver's
// Baumgarte term from Contact::gap and Contact::erp, the same in-process and through the node.
double gapTerm(double gap);

// Free velocities [v; ω] of every body after dt under gravity and external wrenches
// (zero for static bodies).
std::vector<Vector6d> freeVelocities(const Scene& scene, double dt);

// Jacobians of a set of contacts and the adjacency body → contacts; builds W and d_free and
// maps forces back to body velocities. Cost O(contacts × neighbours).
class RigidContactModel {
 public:
  RigidContactModel(const Scene& scene, const std::vector<SceneContact>& frames);

  int contactCount() const { return static_cast<int>(contacts_.size()); }
  int rowCount() const { return offsets_.empty() ? 0 : offsets_.back(); }
  const std::vector<int>& rowOffsets() const { return offsets_; }

  // dt² J M⁻¹ Jᵀ; block-sparse holds one block per pair of contacts sharing a dynamic body
  // (both (i, j) and (j, i)), columns ascending.
  // kBodies gives the block-sparse W (the body form is bodyCompliance).
  core::ComplianceMatrix compliance(double dt, ComplianceStorage storage) const;
  // The body form of the same W (core/body_compliance.h): C_b = dt² M_b⁻¹ for every scene
  // body (zero for static ones, which no contact names: their side is -1) and each
  // contact's J_A, J_B. O(bodies + rows).
  core::BodyCompliance bodyCompliance(double dt) const;
  // gapTerm + dt J v_free.
  Eigen::VectorXd freeViolation(const std::vector<Vector6d>& v_free, double dt) const;
  // Relative normal velocity J_n v of each contact (m/s; < 0 approaching).
  Eigen::VectorXd normalVelocities(const std::vector<Vector6d>& v) const;
  // v += dt M⁻¹ Jᵀ λ for every dynamic body (λ one entry per row).
  void applyForces(const Eigen::VectorXd& lambda, double dt, std::vector<Vector6d>* velocities) const;
  // Jᵀ λ per body: the contact wrench [force; torque about the COM] on each body (world).
  std::vector<Vector6d> bodyWrenches(const Eigen::VectorXd& lambda) const;
  // The full J (rows × 6·bodies), for tests.
  Eigen::MatrixXd denseJacobian() const;
  // The full M⁻¹ (6·bodies square), for tests.
  Eigen::MatrixXd denseInverseMass() const;

 private:
  struct Side {
    int body = -1;                       // -1: static (no block)
    Eigen::Matrix<double, 6, 6> J;       // first `rows` rows used
    Eigen::Matrix<double, 6, 6> MinvJt;  // M⁻¹ Jᵀ
  };
  struct ContactData {
    int rows = 3;
    double gap = 0.0;
    Side side[2];
  };

  // Contacts sharing a dynamic body with contact i (i included), ascending.
  std::vector<int> neighbours(int i) const;

  int body_count_ = 0;
  std::vector<ContactData> contacts_;
  std::vector<int> offsets_;
  std::vector<std::vector<int>> body_contacts_;            // dynamic body → contacts, ascending
  std::vector<Eigen::Matrix<double, 6, 6>> inverse_mass_;  // per body (zero for static)
};

// The core contacts of the frames: id, type, rows, μ, gap, and the scene's erp and softness.
std::vector<core::Contact> problemContacts(const Scene& scene, const std::vector<SceneContact>& frames);

// Problem (contacts, W, d_free) of the given frames; frames.size() == contacts. With
// kBodies the problem carries the body form (Problem::bodies) and no W.
core::Problem buildProblem(const Scene& scene, const std::vector<SceneContact>& frames,
                           const std::vector<Vector6d>& v_free, double dt, ComplianceStorage storage);

}  // namespace scene
}  // namespace lcp_contact_solver
