// Random rigid-body scenes in the body form and the built-vs-unbuilt comparison shared by
// the test_unbuilt*.cpp files.
#pragma once

#include "lcp_contact_solver/core/body_compliance.h"
#include "lcp_contact_solver/core/contact_solver.h"

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <random>

namespace lcp_contact_solver::core {
namespace unbuilt_test {

// Relative difference of two force vectors (max norm), with a floor for all-zero answers.
inline double relDiff(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  if (a.size() != b.size()) return std::numeric_limits<double>::infinity();
  const double scale = std::max({a.cwiseAbs().maxCoeff(), b.cwiseAbs().maxCoeff(), 1e-300});
  return (a - b).cwiseAbs().maxCoeff() / scale;
}

struct Mix {
  double frictionless = 0.2;  // fraction of one-row contacts
  double bilateral = 0.0;     // fraction of bilateral contacts (1..3 rows)
  double world = 0.4;         // fraction of contacts against the static world (body_b = -1)
};

// Rigid bodies (random mass 0.5..5 kg, random inertia) and contacts between them or with
// the world, in the scene's convention: per row u (normal, t1, t2), J_a = [uᵀ, (r_a × u)ᵀ],
// J_b = -[uᵀ, (r_b × u)ᵀ], C_b = dt² M_b⁻¹. Normals pushed together (d_free_n < 0 for
// most), tangential drift, so contacts stick, slide and open.
struct RandomScene {
  BodyCompliance bodies;
  Problem problem;  // contacts, d_free and `bodies`; W empty
};

inline RandomScene randomScene(int nbodies, int ncontacts, unsigned seed, const Mix& mix = Mix(),
                               double mu = 0.5) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0), pos(0.0, 1.0);
  auto vec3 = [&] { return Eigen::Vector3d(u(rng), u(rng), u(rng)); };
  const double dt = 0.01;
  RandomScene s;
  for (int b = 0; b < nbodies; ++b) {
    const double mass = 0.5 + 4.5 * pos(rng);
    Eigen::Matrix3d A;
    A << vec3(), vec3(), vec3();
    const Eigen::Matrix3d R = A.householderQr().householderQ();
    const Eigen::Vector3d inertia = mass * (0.05 + 0.1 * vec3().cwiseAbs().array()).matrix();
    BodyMatrix C = BodyMatrix::Zero();
    C.topLeftCorner<3, 3>() = Eigen::Matrix3d::Identity() / mass;
    C.bottomRightCorner<3, 3>() = R * inertia.cwiseInverse().asDiagonal() * R.transpose();
    s.bodies.body_compliance.push_back(dt * dt * C);
  }
  for (int c = 0; c < ncontacts; ++c) {
    ContactJacobian cj;
    Contact contact;
    contact.id = 1000 + c;
    const double kind = pos(rng);
    if (kind < mix.bilateral) {
      contact.type = ContactType::kBilateral;
      contact.rows = 1 + static_cast<int>(3 * pos(rng)) % 3;
    } else if (kind < mix.bilateral + mix.frictionless) {
      contact.type = ContactType::kFrictionless;
      contact.rows = 1;
    } else {
      contact.type = ContactType::kFrictional;
      contact.rows = 3;
      contact.mu = mu * (0.5 + pos(rng));
    }
    cj.rows = contact.rows;
    cj.body_a = static_cast<int>(rng() % nbodies);
    cj.body_b = pos(rng) < mix.world ? -1 : static_cast<int>(rng() % nbodies);
    if (cj.body_b == cj.body_a) cj.body_b = (cj.body_a + 1) % nbodies;
    const Eigen::Vector3d n = vec3().normalized();
    Eigen::Vector3d t1 = n.unitOrthogonal();
    const Eigen::Vector3d t2 = n.cross(t1);
    const Eigen::Vector3d dirs[3] = {n, t1, t2};
    const Eigen::Vector3d ra = 0.2 * vec3(), rb = 0.2 * vec3();
    cj.jacobian_a.resize(cj.rows, 6);
    cj.jacobian_b.resize(cj.body_b >= 0 ? cj.rows : 0, 6);
    for (int k = 0; k < cj.rows; ++k) {
      cj.jacobian_a.row(k) << dirs[k].transpose(), ra.cross(dirs[k]).transpose();
      if (cj.body_b >= 0) cj.jacobian_b.row(k) << -dirs[k].transpose(), -rb.cross(dirs[k]).transpose();
    }
    s.bodies.contacts.push_back(cj);
    s.problem.contacts.push_back(contact);
  }
  const int rows = s.bodies.rowCount();
  s.problem.d_free.resize(rows);
  int row = 0;
  for (const Contact& c : s.problem.contacts) {
    for (int k = 0; k < c.rows; ++k) {
      const bool normal = k == 0 && c.type != ContactType::kBilateral;
      s.problem.d_free[row + k] =
          normal ? -1e-3 * (0.2 + pos(rng)) + (pos(rng) < 0.15 ? 3e-3 : 0.0) : 4e-4 * u(rng);
    }
    row += c.rows;
  }
  s.problem.bodies = std::make_shared<const BodyCompliance>(s.bodies);
  return s;
}

// The same problem with an assembled W (no body form).
inline Problem builtDense(const Problem& p) {
  Problem out = p;
  out.bodies.reset();
  out.W = p.bodies->toDense();
  return out;
}
inline Problem builtSparse(const Problem& p) {
  Problem out = p;
  out.bodies.reset();
  out.W = p.bodies->assemble();
  return out;
}

inline SolverParams tight(SolverKind kind = SolverKind::kNlgs) {
  SolverParams params;
  params.solver = kind;
  params.tolerance = 1e-10;
  params.maxIt = 200000;
  params.initial_guess = false;
  return params;
}

inline SolverParams unbuilt(SolverParams params) {
  params.build_lcp = false;
  return params;
}

// Solves the body-form problem unbuilt and the same problem built (dense and block-sparse)
// with the same parameters; expects the same forces and statuses.
inline void expectSameAsBuilt(const Problem& p, const SolverParams& params, double tol = 1e-8,
                              bool expect_converged = true) {
  // Both split into the same islands (contacts sharing a body; W's nonzero blocks).
  const SolveResult u = solveProblem(p, unbuilt(params));
  const SolveResult d = solveProblem(builtDense(p), params);
  const SolveResult s = solveProblem(builtSparse(p), params);
  EXPECT_TRUE(u.unbuilt) << u.message;
  EXPECT_FALSE(d.unbuilt);
  EXPECT_FALSE(s.unbuilt);
  if (expect_converged) {
    ASSERT_EQ(u.status, SolveStatus::kConverged) << u.message;
    ASSERT_EQ(d.status, SolveStatus::kConverged) << d.message;
    ASSERT_EQ(s.status, SolveStatus::kConverged) << s.message;
    EXPECT_LE(u.residual, params.tolerance);
  } else {
    EXPECT_EQ(u.status, d.status);
    EXPECT_EQ(u.status, s.status);
  }
  EXPECT_EQ(u.solver, d.solver);
  EXPECT_LT(relDiff(u.forces, d.forces), tol) << "unbuilt vs dense\n"
                                              << u.forces.transpose() << "\n"
                                              << d.forces.transpose();
  EXPECT_LT(relDiff(u.forces, s.forces), tol) << "unbuilt vs block-sparse";
  EXPECT_LT(relDiff(u.d, d.d), 1e-6) << "d = W λ + d_free through the body form";
  EXPECT_EQ(u.states, d.states);
  EXPECT_EQ(u.resolves, d.resolves);
  // The same iteration: the sweep counts agree (round-off may move the exit by one sweep).
  EXPECT_LE(std::abs(u.iterations - d.iterations), 1) << u.iterations << " vs " << d.iterations;
}

}  // namespace unbuilt_test
}  // namespace lcp_contact_solver::core
