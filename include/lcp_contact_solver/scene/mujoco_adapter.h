// MuJoCo as a source of contact problems (ROS-free; needs libmujoco-dev, MuJoCo 2.2.x).
//
// MuJoCo's constraint solver works in acceleration units with soft constraints. After the
// position and velocity stages it holds, for the nefc constraint rows of the step,
//
//   efc_J    the constraint Jacobian (nefc × nv),
//   efc_R    the regularizer (softness) of each row,
//   efc_AR   = J M⁻¹ Jᵀ + diag(R)             ("A + R", nefc × nefc, dense or CSR),
//   efc_b    = J qacc_smooth − aref            (aref: the rows' spring-damper reference),
//
// and its dual problem is   min_f ½ fᵀ AR f + fᵀ b   over the rows' feasible sets, after
// which qacc = qacc_smooth + M⁻¹ Jᵀ f. Its optimality conditions are the package's problem
//
//   d = W λ + d_free   with   W = AR,  d_free = b,  λ = f   (d: acceleration, m/s² or rad/s²)
//
// row by row:
//
//   frictionless contact (condim 1)      one unilateral row: 0 ≤ f ⟂ d ≥ 0
//   pyramidal contact, condim k          2(k−1) rows, one per pyramid edge n ± μ_j t_j, each
//                                        unilateral (the cone is their nonnegative span: for
//                                        condim 3 the diamond |f_t1|/μ1 + |f_t2|/μ2 ≤ f_n, not
//                                        the package's pyramid4 box); each edge is its own
//                                        one-row frictionless contact here
//   joint / tendon limit                 one unilateral row
//   equality (connect, weld, joint, ...)  bilateral rows (free sign, d = 0)
//   elliptic contact, condim 3           MuJoCo minimizes the quadratic over the cone: the
//                                        convex relaxation, whose sliding contacts separate
//                                        (d_n = μ |d_t|). Here it becomes one frictional
//                                        contact (normal, t1, t2; μ = friction[0]) of the
//                                        package's Coulomb problem (d_n = 0 while sliding).
//                                        Both agree on open-with-d_n≥μ|d_t| and sticking
//                                        contacts, not on sliding ones.
//   friction loss (dof, tendon)          box constraint |f| ≤ frictionloss: not representable,
//                                        dropped (see MujocoExtractOptions::fold_dropped)
//   elliptic condim 4 / 6                torsional / rolling rows dropped, the rest as above
//
// With the pyramidal cone every kept row is unilateral or bilateral and AR is positive
// definite (R > 0), so the problem is an LCP with a unique solution, which MuJoCo's PGS
// reaches as well: efc_force and the package's LCP solvers must agree.
//
// Rows may be rescaled: problem row p is MuJoCo row e(p) with λ_p = s_p f_e(p),
// W_pq = AR_{e(p)e(q)} / (s_p s_q), d_free_p = b_e(p) / s_p. Pyramid edges of the tangent
// directions use s = |n ± μ t| = √(1 + μ²), so the force of an edge is λ along the unit
// edge direction; an anisotropic elliptic contact scales its second tangent by μ1/μ2 so the
// cone is the disc of μ1. Every other row has s = 1. Positive row scaling leaves the
// solution unchanged.
//
// Conventions of the entries (world frame): a contact's body_a is geom2's body, body_b
// geom1's; MuJoCo's contact normal points from geom1 to geom2, i.e. from body_b towards
// body_a, and positive forces push body_a along it — the package's convention. A limit is
// an entry with body_a = the joint's body, body_b = its parent, position = the joint
// anchor and normal = the joint axis times the sign of the row (a generalized force: N·m for
// a hinge); an equality is an entry between its two bodies at body_a's origin.
//
// The model and its step: mujoco_world.h; comparisons of forces: mujoco_comparison.h.
#pragma once

#include "lcp_contact_solver/core/problem.h"
#include "lcp_contact_solver/scene/mujoco_world.h"

#include <mujoco/mujoco.h>

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

namespace lcp_contact_solver {
namespace scene {

// ---- the problem ------------------------------------------------------------------------

enum class MujocoRowKind : std::uint8_t {
  kFrictionless,  // condim-1 contact: one unilateral row
  kPyramidEdge,   // one edge of a pyramidal contact: one unilateral row
  kElliptic,      // elliptic contact: one frictional contact (normal, t1, t2)
  kLimit,         // joint or tendon limit: one unilateral row
  kEquality,      // equality constraint: bilateral rows
};
const char* mujocoRowKindName(MujocoRowKind kind);

// One core contact of the extracted problem and where it comes from.
struct MujocoEntry {
  MujocoRowKind kind = MujocoRowKind::kFrictionless;
  int efc_row = 0;      // its first MuJoCo row
  int mj_contact = -1;  // index into d->contact (contacts), else -1
  int edge = -1;        // pyramid edge 0 .. 2(condim−1)−1: direction edge/2, sign + for even
  int object = -1;      // joint / tendon / equality id (limits, equalities), else -1
  int body_a = 0;       // MuJoCo body ids: body_a receives +λ along the normal
  int body_b = 0;
  int geom1 = -1, geom2 = -1;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // world frame, m
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();   // unit
  Eigen::Vector3d tangent1 = Eigen::Vector3d::Zero();  // unit (elliptic), else zero
  Eigen::Vector3d tangent2 = Eigen::Vector3d::Zero();
  double mu = 0.0;    // elliptic: friction[0]; pyramid edge: μ of its direction
  double dist = 0.0;  // contacts: MuJoCo's distance (negative: penetration), m
};

struct MujocoExtractOptions {
  bool include_limits = true;      // limits as unilateral rows (else dropped)
  bool include_equalities = true;  // equalities as bilateral rows (else dropped)
  // Dropped rows (friction loss, excluded limits/equalities, elliptic torsion/rolling) are
  // coupled to the kept ones through AR. false: the coupling is ignored (the kept rows are
  // solved as if the dropped rows carried no force). true: MuJoCo's own efc_force of the
  // dropped rows is folded into d_free (d_free += AR_kd f_d), which is exact when MuJoCo's
  // solver ran and is what a cross-check of the kept rows needs.
  bool fold_dropped = false;
  bool scale_rows = true;  // the row scaling described at the top of this file
  // W storage: dense, block-sparse (one block per pair of coupled entries), or automatic:
  // block-sparse when the problem has more than `dense_max_rows` rows and fewer than
  // `dense_min_fill` of W's entries are nonzero.
  enum class Storage { kAuto, kDense, kBlockSparse } storage = Storage::kAuto;
  int dense_max_rows = 200;  // mujoco_bench: block-sparse wins from a few hundred rows
  // A W this full is dense whatever its size: a block per pair of coupled entries then costs
  // more than the entries themselves (soft bodies and composites, whose bodies share one
  // tree: composite/softbox's 735 rows are 100 % full, 461 041 blocks mostly 1 x 1).
  double dense_min_fill = 0.25;
};

struct MujocoProblem {
  core::Problem problem;             // contacts (id, type, rows, μ), W, d_free in problem order
  std::vector<MujocoEntry> entries;  // one per problem contact
  std::vector<int> efc_row;          // MuJoCo row of each problem row
  Eigen::VectorXd row_scale;         // s of each problem row (λ = s f)
  Eigen::VectorXd mujoco_lambda;     // MuJoCo's efc_force in problem units (s f)
  std::vector<int> dropped_rows;     // MuJoCo rows left out
  int nefc = 0;
  int ncon = 0;           // MuJoCo's contacts in the constraint problem
  bool pyramidal = true;  // the model's cone
  double time = 0.0;      // d->time of the step

  // Forces of every MuJoCo row (nefc) from problem forces λ; dropped rows get 0, or their
  // value in `dropped_source` (e.g. d->efc_force after MuJoCo's own solve) when given.
  Eigen::VectorXd toEfcForce(const Eigen::VectorXd& lambda, const double* dropped_source = nullptr) const;
  // Problem forces of MuJoCo's row forces.
  Eigen::VectorXd fromEfcForce(const double* efc_force) const;
};

// Persistent-ish ids: contacts key on (geom1, geom2, the contact's rank among this pair's
// contacts of the step, pyramid edge); limits on (type, joint/tendon); equalities on the id.
std::int64_t mujocoContactId(int geom1, int geom2, int rank, int edge);
std::int64_t mujocoLimitId(int constraint_type, int object);
std::int64_t mujocoEqualityId(int equality);

// Builds the problem of the step from the data forwardToConstraints left (efc_AR must be
// present). Empty string, or one sentence naming what cannot be converted. A step without
// rows gives an empty problem (no contacts).
std::string extractProblem(const mjModel* m, const mjData* d, const MujocoExtractOptions& options,
                           MujocoProblem* out);

}  // namespace scene
}  // namespace lcp_contact_solver
