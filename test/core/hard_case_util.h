// Generators and checks of the hard-case suite (test_hard_cases*.cpp): small rigid-body
// worlds turned into contact problems (W = dt² J M⁻¹ Jᵀ, d_free = gap + dt J v_free, the
// scene layer's convention, written again here so the core tests need no scene library),
// and the checks every hard case applies to every solver's result.
#pragma once

#include "lcp_contact_solver/core/contact_frame.h"
#include "lcp_contact_solver/core/contact_solver.h"
#include "lcp_contact_solver/core/residual.h"

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/Eigenvalues>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

namespace lcp_contact_solver::core {
namespace hard {

constexpr double kG = 9.81;

inline const std::vector<SolverKind>& allSolvers() {
  static const std::vector<SolverKind> kinds = {SolverKind::kPgs, SolverKind::kNlgs, SolverKind::kLemke,
                                                SolverKind::kApgd, SolverKind::kNewton};
  return kinds;
}

// ---- rigid-body worlds --------------------------------------------------------------------

struct Body {
  double mass = 1.0;
  Eigen::Matrix3d inv_inertia = Eigen::Matrix3d::Identity();
  Eigen::Vector3d com = Eigen::Vector3d::Zero();
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  Eigen::Vector3d w = Eigen::Vector3d::Zero();
};

// A solid box of full side lengths `size`.
inline Body box(double mass, const Eigen::Vector3d& size, const Eigen::Vector3d& com) {
  Body b;
  b.mass = mass;
  const Eigen::Vector3d s2 = size.cwiseProduct(size);
  const Eigen::Vector3d I = mass / 12.0 * Eigen::Vector3d(s2.y() + s2.z(), s2.x() + s2.z(), s2.x() + s2.y());
  b.inv_inertia = I.cwiseInverse().asDiagonal();
  b.com = com;
  return b;
}

struct ContactSpec {
  int a = 0;   // body the normal points into (λ_n n acts on it)
  int b = -1;  // the other body, -1 for the static world
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  double mu = 0.5;  // 0 with kFrictionless; Contact::kMuDefault allowed
  ContactType type = ContactType::kFrictional;
  double gap = 0.0;  // m; < 0 penetration
  std::int64_t id = 0;
};

class World {
 public:
  double dt = 0.01;
  Eigen::Vector3d gravity = Eigen::Vector3d(0.0, 0.0, -kG);
  std::vector<Body> bodies;
  std::vector<ContactSpec> contacts;

  int add(const Body& body) {
    bodies.push_back(body);
    return static_cast<int>(bodies.size()) - 1;
  }
  void contact(int a, int b, const Eigen::Vector3d& point, const Eigen::Vector3d& normal, double mu,
               double gap = 0.0) {
    ContactSpec c;
    c.a = a;
    c.b = b;
    c.point = point;
    c.normal = normal.normalized();
    c.mu = mu;
    c.type = mu == 0.0 ? ContactType::kFrictionless : ContactType::kFrictional;
    c.gap = gap;
    c.id = static_cast<std::int64_t>(contacts.size()) + 1;
    contacts.push_back(c);
  }

  int rows() const {
    int n = 0;
    for (const ContactSpec& c : contacts) n += c.type == ContactType::kFrictional ? 3 : 1;
    return n;
  }

  // Directions of a contact's rows: n, then t1, t2 for a frictional one.
  static std::vector<Eigen::Vector3d> directions(const ContactSpec& c) {
    std::vector<Eigen::Vector3d> dirs = {c.normal};
    if (c.type == ContactType::kFrictional) {
      Eigen::Vector3d t1, t2;
      tangentsFromNormal(c.normal, &t1, &t2);
      dirs.push_back(t1);
      dirs.push_back(t2);
    }
    return dirs;
  }

  // J (rows × 6 bodies): row u at p is [uᵀ, ((p - c_a) × u)ᵀ] on A, its negative on B.
  Eigen::MatrixXd jacobian() const {
    Eigen::MatrixXd J = Eigen::MatrixXd::Zero(rows(), 6 * static_cast<int>(bodies.size()));
    int row = 0;
    for (const ContactSpec& c : contacts) {
      for (const Eigen::Vector3d& u : directions(c)) {
        for (int side = 0; side < 2; ++side) {
          const int body = side == 0 ? c.a : c.b;
          if (body < 0) continue;
          const double sign = side == 0 ? 1.0 : -1.0;
          J.block<1, 3>(row, 6 * body) += sign * u.transpose();
          J.block<1, 3>(row, 6 * body + 3) += sign * (c.point - bodies[body].com).cross(u).transpose();
        }
        ++row;
      }
    }
    return J;
  }

  Eigen::MatrixXd inverseMass() const {
    const int n = 6 * static_cast<int>(bodies.size());
    Eigen::MatrixXd Minv = Eigen::MatrixXd::Zero(n, n);
    for (std::size_t i = 0; i < bodies.size(); ++i) {
      Minv.block<3, 3>(6 * i, 6 * i) = Eigen::Matrix3d::Identity() / bodies[i].mass;
      Minv.block<3, 3>(6 * i + 3, 6 * i + 3) = bodies[i].inv_inertia;
    }
    return Minv;
  }

  Eigen::VectorXd freeVelocity() const {
    Eigen::VectorXd v(6 * bodies.size());
    for (std::size_t i = 0; i < bodies.size(); ++i) {
      v.segment<3>(6 * i) = bodies[i].v + dt * gravity;
      v.segment<3>(6 * i + 3) = bodies[i].w;
    }
    return v;
  }

  Problem problem() const {
    const Eigen::MatrixXd J = jacobian();
    Problem p;
    p.W = Eigen::MatrixXd(dt * dt * J * inverseMass() * J.transpose());
    p.d_free = dt * J * freeVelocity();
    int row = 0;
    for (const ContactSpec& c : contacts) {
      Contact contact;
      contact.id = c.id;
      contact.type = c.type;
      contact.rows = c.type == ContactType::kFrictional ? 3 : 1;
      contact.mu = c.type == ContactType::kFrictional ? c.mu : 0.0;
      p.contacts.push_back(contact);
      p.d_free[row] += c.gap;
      row += contact.rows;
    }
    p.name = "world";
    return p;
  }

  // Net contact force on a body from λ (world frame), N.
  Eigen::Vector3d netForce(int body, const Eigen::VectorXd& lambda) const {
    Eigen::Vector3d f = Eigen::Vector3d::Zero();
    int row = 0;
    for (const ContactSpec& c : contacts) {
      for (const Eigen::Vector3d& u : directions(c)) {
        if (c.a == body) f += lambda[row] * u;
        if (c.b == body) f -= lambda[row] * u;
        ++row;
      }
    }
    return f;
  }

  // Sum of the normal forces of the contacts between a and b (either order).
  double normalSum(int a, int b, const Eigen::VectorXd& lambda) const {
    double sum = 0.0;
    int row = 0;
    for (const ContactSpec& c : contacts) {
      if ((c.a == a && c.b == b) || (c.a == b && c.b == a)) sum += lambda[row];
      row += c.type == ContactType::kFrictional ? 3 : 1;
    }
    return sum;
  }
};

// k contact points on the bottom face (z = com.z - h/2) of a box: a √k × √k grid for
// k = 4, 16; k = 8 is the 3 × 3 grid without its centre.
inline std::vector<Eigen::Vector3d> bottomPoints(const Eigen::Vector3d& com, const Eigen::Vector3d& size,
                                                 int k) {
  std::vector<Eigen::Vector3d> points;
  const double z = com.z() - 0.5 * size.z();
  auto grid = [&](int n, bool skip_centre) {
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        if (skip_centre && i == n / 2 && j == n / 2) continue;
        const double x = com.x() + size.x() * (-0.5 + static_cast<double>(i) / (n - 1));
        const double y = com.y() + size.y() * (-0.5 + static_cast<double>(j) / (n - 1));
        points.emplace_back(x, y, z);
      }
  };
  if (k == 4)
    grid(2, false);
  else if (k == 8)
    grid(3, true);
  else if (k == 16)
    grid(4, false);
  else
    ADD_FAILURE() << "bottomPoints: k = " << k;
  return points;
}

// A stack of boxes resting face on face, k points per face, alternate boxes `ratio` times
// heavier, pushed sideways and spun: 3k rows per face against 6 DoF per box, so W is
// rank-deficient, and the mass ratio makes it ill-conditioned as well.
inline Problem boxStack(int boxes, int k, double ratio, double push, double mu) {
  World w;
  const Eigen::Vector3d size(1.0, 1.0, 0.5);
  for (int i = 0; i < boxes; ++i) {
    Body b = hard::box(i % 2 ? ratio : 1.0, size, Eigen::Vector3d(0.0, 0.0, 0.25 + 0.5 * i));
    b.v = Eigen::Vector3d(push * (i % 2 ? 1 : -1), 0.3 * push, 0.0);
    b.w = Eigen::Vector3d(0.0, 0.0, push);
    w.add(b);
  }
  for (int i = 0; i < boxes; ++i)
    for (const Eigen::Vector3d& p : hard::bottomPoints(w.bodies[i].com, size, k))
      w.contact(i, i - 1, p, Eigen::Vector3d::UnitZ(), mu);
  return w.problem();
}

// The same W as a BlockSparseMatrix with a block for every nonzero contact pair.
inline Problem toBlockSparse(const Problem& dense_problem) {
  Problem p = dense_problem;
  const Eigen::MatrixXd W = toDense(dense_problem.W);
  const std::vector<int> off = dense_problem.rowOffsets();
  std::vector<int> sizes;
  for (const Contact& c : dense_problem.contacts) sizes.push_back(c.rows);
  BlockSparseMatrix S = BlockSparseMatrix::withBlockSizes(sizes);
  for (std::size_t i = 0; i < sizes.size(); ++i) {
    S.beginRow();
    for (std::size_t j = 0; j < sizes.size(); ++j) {
      const Eigen::MatrixXd block = W.block(off[i], off[j], sizes[i], sizes[j]);
      if (i == j || block.cwiseAbs().maxCoeff() > 0.0) S.addBlock(static_cast<int>(j), block);
    }
  }
  p.W = S;
  return p;
}

// ---- checks -------------------------------------------------------------------------------

inline SolverParams paramsFor(SolverKind kind, double tolerance = 1e-6, int max_it = 1000) {
  SolverParams params;
  params.solver = kind;
  params.tolerance = tolerance;
  params.maxIt = max_it;
  params.initial_guess = false;
  return params;
}

inline bool bitIdentical(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return a.size() == b.size() &&
         (a.size() == 0 ||
          std::memcmp(a.data(), b.data(), sizeof(double) * static_cast<std::size_t>(a.size())) == 0);
}

inline bool isFailureStatus(SolveStatus s) {
  return s == SolveStatus::kMaxIterations || s == SolveStatus::kZeroDiagonal ||
         s == SolveStatus::kNotApplicable || s == SolveStatus::kRayTermination ||
         s == SolveStatus::kNumericalFailure || s == SolveStatus::kTimeBudget;
}

// Energy the contact forces add over one step, in the units of λ·d (J at position level):
// ΔKE = λᵀ d_free + ½ λᵀ (W + rI) λ = λᵀ d − ½ λᵀ (W + rI) λ. For an exact Coulomb solution
// λᵀ d = −Σ μ λ_n |d_t| ≤ 0, so ΔKE ≤ −½ λᵀ W λ ≤ 0: contacts never inject energy. (Exact
// only with gap = 0 rows; a gap makes d_free differ from dt J v_free by a constant.)
inline double energyGain(const Problem& p, double regularization, const Eigen::VectorXd& lambda) {
  Eigen::VectorXd Wl;
  multiply(p.W, lambda, Wl);
  Wl += regularization * lambda;
  return lambda.dot(p.d_free) + 0.5 * lambda.dot(Wl);
}

// What every hard case asserts about every result, whatever the solver and status:
//   - every number finite, sizes right;
//   - honest: converged ⟺ status converged ⟹ residual ≤ tolerance; otherwise a named
//     failure status with a message; `d` and `residual` are the true ones of the returned
//     forces (recomputed here);
//   - forces feasible: λ_n ≥ 0 and |λ_t| ≤ μ λ_n (slack: rounding, and for newton, whose
//     iterates are not projected, the residual), ignored contacts carry no force.
// Returns a one-line summary for the case's table.
inline std::string expectHonest(const Problem& p, const SolverParams& params, const SolveResult& r,
                                const std::string& label) {
  const int n = p.rowCount();
  EXPECT_NE(r.status, SolveStatus::kInvalidInput) << label << ": " << r.message;
  EXPECT_EQ(r.forces.size(), n) << label;
  EXPECT_EQ(r.d.size(), n) << label;
  EXPECT_EQ(r.states.size(), p.contacts.size()) << label;
  if (r.forces.size() != n || r.d.size() != n || r.states.size() != p.contacts.size())
    return label + ": bad sizes";
  EXPECT_TRUE(r.forces.allFinite()) << label;
  EXPECT_TRUE(r.d.allFinite()) << label;
  EXPECT_TRUE(std::isfinite(r.residual)) << label;
  EXPECT_TRUE(std::isfinite(r.solver_error)) << label;
  EXPECT_TRUE(std::isfinite(r.solve_time)) << label;
  EXPECT_EQ(r.converged, r.status == SolveStatus::kConverged) << label;
  if (r.converged) {
    if (params.stopping_rule == StoppingRule::kResidual && r.friction_model == FrictionModel::kCoulombDisc) {
      EXPECT_LE(r.residual, params.tolerance) << label << ": claims converged";
    }
  } else {
    EXPECT_TRUE(isFailureStatus(r.status)) << label << ": status " << statusName(r.status);
    EXPECT_FALSE(r.message.empty()) << label << ": a failure must say why";
  }
  // d and the residual are those of the returned forces.
  Eigen::VectorXd d;
  multiply(p.W, r.forces, d);
  d += p.d_free + params.regularizationTerm * r.forces;
  const double scale =
      toDense(p.W).cwiseAbs().maxCoeff() * r.forces.cwiseAbs().sum() + p.d_free.cwiseAbs().maxCoeff();
  EXPECT_LE((d - r.d).cwiseAbs().maxCoeff(), 1e-12 * scale) << label;
  std::vector<bool> ignored(p.contacts.size());
  for (std::size_t i = 0; i < p.contacts.size(); ++i) ignored[i] = r.states[i] == ContactState::kIgnored;
  const std::vector<double> mu = effectiveMu(p, params.mu);
  const double true_residual = naturalMapResidual(p, mu, r.forces, r.d, ignored);
  EXPECT_NEAR(r.residual, true_residual, 1e-12 * std::max(1.0, true_residual)) << label;
  // Feasibility. Gauss-Seidel, Lemke and apgd keep their iterates feasible; newton's are not
  // projected, but the natural map bounds their distance to the cone: Proj_K(λ − d') ∈ K,
  // so dist(λ_c, K) <= |e_c| <= residual · |d_free|, and |λ_t| − μ λ_n <= √(1 + μ²) dist.
  const std::vector<int> off = p.rowOffsets();
  const double force_scale = r.forces.cwiseAbs().maxCoeff();
  const double distance = r.residual * (p.d_free.norm() > 0.0 ? p.d_free.norm() : 1.0);
  for (std::size_t i = 0; i < p.contacts.size(); ++i) {
    const double* l = r.forces.data() + off[i];
    if (ignored[i]) {
      for (int k = 0; k < p.contacts[i].rows; ++k) EXPECT_EQ(l[k], 0.0) << label << " contact " << i;
      continue;
    }
    if (p.contacts[i].type == ContactType::kBilateral) continue;
    if (r.friction_model != FrictionModel::kCoulombDisc) continue;
    const double slack = 1e-9 * force_scale + (1.0 + 1e-9) * std::sqrt(1.0 + mu[i] * mu[i]) * distance;
    EXPECT_GE(l[0], -slack) << label << " " << r.solver << " contact " << i;
    if (p.contacts[i].type == ContactType::kFrictional) {
      EXPECT_LE(std::hypot(l[1], l[2]), mu[i] * l[0] + slack) << label << " " << r.solver << " contact " << i;
    }
  }
  char line[256];
  std::snprintf(line, sizeof(line), "%-28s %-7s %-18s it %6d  residual %9.3g", label.c_str(),
                r.solver.c_str(), statusName(r.status), r.iterations, r.residual);
  return line;
}

// Solves twice with fresh solvers; the two results must be bit-identical.
inline SolveResult solveTwiceChecked(const Problem& p, const SolverParams& params, const std::string& label,
                                     bool print = true) {
  const SolveResult r = solveProblem(p, params);
  const SolveResult again = solveProblem(p, params);
  EXPECT_TRUE(bitIdentical(r.forces, again.forces)) << label << ": forces differ between two runs";
  EXPECT_TRUE(bitIdentical(r.d, again.d)) << label;
  EXPECT_EQ(r.status, again.status) << label;
  EXPECT_EQ(r.iterations, again.iterations) << label;
  EXPECT_EQ(std::memcmp(&r.residual, &again.residual, sizeof(double)), 0) << label;
  const std::string line = expectHonest(p, params, r, label);
  if (print) std::printf("  %s\n", line.c_str());
  return r;
}

// A box (0.2 m cube, 1 kg unless given) resting on the static ground with k contacts.
inline World boxOnPlane(int k, double mu, double mass = 1.0, double side = 0.2) {
  World world;
  const Eigen::Vector3d size(side, side, side);
  const Eigen::Vector3d com(0.0, 0.0, 0.5 * side);
  world.add(box(mass, size, com));
  for (const Eigen::Vector3d& p : bottomPoints(com, size, k))
    world.contact(0, -1, p, Eigen::Vector3d::UnitZ(), mu);
  return world;
}

// Solvers that apply to a problem: pgs and lemke need μ = 0 (disc model) everywhere.
inline bool applies(SolverKind kind, const Problem& p, double default_mu = 0.6) {
  if (kind != SolverKind::kPgs && kind != SolverKind::kLemke) return true;
  for (const Contact& c : p.contacts)
    if (c.type == ContactType::kFrictional && (c.mu < 0.0 ? default_mu : c.mu) > 0.0) return false;
  return true;
}

}  // namespace hard
}  // namespace lcp_contact_solver::core
