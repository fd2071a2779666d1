// The body form of the compliance and the unbuilt solve (build_lcp = false,
// core/body_compliance.h, BodyAccess in kernels/sweep_access.h): W λ without W equals the
// assembled W λ; the unbuilt Gauss-Seidel gives the forces of the built solve (dense and
// block-sparse W) for frictional, frictionless and bilateral contacts, with warm start,
// minW, maxF, regularization, softness, sor and the SOFA stopping rule; the other solvers
// assemble W and say so; malformed body forms are refused with a sentence.
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
namespace {

// Relative difference of two force vectors (max norm), with a floor for all-zero answers.
double relDiff(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
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

RandomScene randomScene(int nbodies, int ncontacts, unsigned seed, const Mix& mix = Mix(), double mu = 0.5) {
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
Problem builtDense(const Problem& p) {
  Problem out = p;
  out.bodies.reset();
  out.W = p.bodies->toDense();
  return out;
}
Problem builtSparse(const Problem& p) {
  Problem out = p;
  out.bodies.reset();
  out.W = p.bodies->assemble();
  return out;
}

SolverParams tight(SolverKind kind = SolverKind::kNlgs) {
  SolverParams params;
  params.solver = kind;
  params.tolerance = 1e-10;
  params.maxIt = 200000;
  params.initial_guess = false;
  return params;
}

SolverParams unbuilt(SolverParams params) {
  params.build_lcp = false;
  return params;
}

// Solves the body-form problem unbuilt and the same problem built (dense and block-sparse)
// with the same parameters; expects the same forces and statuses.
void expectSameAsBuilt(const Problem& p, const SolverParams& params, double tol = 1e-8,
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

// ---- the body form itself -----------------------------------------------------------------

TEST(BodyCompliance, MultiplyEqualsTheAssembledW) {
  for (unsigned seed : {1u, 2u, 3u}) {
    Mix mix;
    mix.bilateral = 0.2;
    RandomScene s = randomScene(6, 15, seed, mix);
    s.bodies.diagonal = Eigen::VectorXd::Random(s.bodies.rowCount()).cwiseAbs() * 1e-6;
    ASSERT_EQ(s.bodies.validate(), "");
    const BlockSparseMatrix W = s.bodies.assemble();
    ASSERT_EQ(W.validate(), "");
    EXPECT_EQ(W.block_offset, s.problem.rowOffsets());
    const Eigen::MatrixXd dense = W.toDense();
    // W = J C Jᵀ formed the long way.
    const int rows = s.bodies.rowCount(), nb = s.bodies.bodyCount();
    Eigen::MatrixXd J = Eigen::MatrixXd::Zero(rows, 6 * nb), C = Eigen::MatrixXd::Zero(6 * nb, 6 * nb);
    const std::vector<int> off = s.bodies.rowOffsets();
    for (int i = 0; i < s.bodies.contactCount(); ++i) {
      const ContactJacobian& c = s.bodies.contacts[i];
      J.block(off[i], 6 * c.body_a, c.rows, 6) += c.jacobian_a;
      if (c.body_b >= 0) J.block(off[i], 6 * c.body_b, c.rows, 6) += c.jacobian_b;
    }
    for (int b = 0; b < nb; ++b) C.block<6, 6>(6 * b, 6 * b) = s.bodies.body_compliance[b];
    Eigen::MatrixXd reference = J * C * J.transpose();
    reference.diagonal() += s.bodies.diagonal;
    EXPECT_LT((dense - reference).cwiseAbs().maxCoeff(), 1e-14 * reference.cwiseAbs().maxCoeff());
    for (int trial = 0; trial < 3; ++trial) {
      const Eigen::VectorXd x = Eigen::VectorXd::Random(rows);
      Eigen::VectorXd y, y_built;
      s.bodies.multiply(x, y);
      W.multiply(x, y_built);
      EXPECT_LT((y - y_built).norm(), 1e-13 * y_built.norm());
      EXPECT_LT((y - reference * x).norm(), 1e-13 * y_built.norm());
    }
    // A block exists exactly when the contacts share a body (or on the diagonal).
    for (int i = 0; i < W.blockCount(); ++i) {
      for (int k = W.row_start[i]; k < W.row_start[i + 1]; ++k) {
        const int j = W.block_col[k];
        const ContactJacobian &a = s.bodies.contacts[i], &b = s.bodies.contacts[j];
        const bool share = a.body_a == b.body_a || a.body_a == b.body_b ||
                           (a.body_b >= 0 && (a.body_b == b.body_a || a.body_b == b.body_b));
        EXPECT_TRUE(share || i == j) << i << ", " << j;
      }
    }
  }
}

TEST(BodyCompliance, AContactOnTheSameBodyTwiceCountsBothSides) {
  // body_a == body_b: W = (J_a + J_b) C (J_a + J_b)ᵀ, the cross terms included.
  BodyCompliance bc;
  bc.body_compliance.push_back(BodyMatrix::Identity() * 2.0);
  ContactJacobian c;
  c.rows = 1;
  c.body_a = 0;
  c.body_b = 0;
  c.jacobian_a.resize(1, 6);
  c.jacobian_b.resize(1, 6);
  c.jacobian_a << 1, 0, 0, 0, 0, 0;
  c.jacobian_b << 1, 0, 0, 0, 0, 0;
  bc.contacts.push_back(c);
  EXPECT_DOUBLE_EQ(bc.block(0, 0)(0, 0), 8.0);
  EXPECT_DOUBLE_EQ(bc.toDense()(0, 0), 8.0);
  Eigen::VectorXd y;
  bc.multiply(Eigen::VectorXd::Ones(1), y);
  EXPECT_DOUBLE_EQ(y[0], 8.0);
}

TEST(BodyCompliance, MalformedBodyFormsAreRefusedWithASentence) {
  const RandomScene good = randomScene(3, 4, 7);
  ASSERT_EQ(validateProblem(good.problem), "");
  struct Case {
    const char* expect;
    std::function<void(Problem&, BodyCompliance&)> spoil;
  };
  const std::vector<Case> cases = {
      {"both an assembled W and the body form",
       [](Problem& p, BodyCompliance&) { p.W = Eigen::MatrixXd::Identity(p.rowCount(), p.rowCount()); }},
      {"contacts, the problem has", [](Problem&, BodyCompliance& b) { b.contacts.pop_back(); }},
      {"rows, the contact has",
       [](Problem& p, BodyCompliance&) {
         p.contacts[0].type = ContactType::kBilateral;
         p.contacts[0].rows = p.contacts[0].rows == 3 ? 2 : 3;
         p.d_free.resize(p.rowCount());
         p.d_free.setZero();
       }},
      {"outside -1..2", [](Problem&, BodyCompliance& b) { b.contacts[1].body_a = 3; }},
      {"outside -1..2", [](Problem&, BodyCompliance& b) { b.contacts[1].body_b = -2; }},
      {"Jacobian on body_a",
       [](Problem&, BodyCompliance& b) {
         b.contacts[2].jacobian_a.resize(b.contacts[2].rows == 3 ? 2 : 3, 6);
       }},
      {"non-finite Jacobian",
       [](Problem&, BodyCompliance& b) { b.contacts[0].jacobian_a(0, 4) = std::nan(""); }},
      {"non-finite compliance", [](Problem&, BodyCompliance& b) { b.body_compliance[1](2, 2) = INFINITY; }},
      {"diagonal has", [](Problem&, BodyCompliance& b) { b.diagonal = Eigen::VectorXd::Zero(2); }},
      {"diagonal holds a non-finite",
       [](Problem&, BodyCompliance& b) {
         b.diagonal = Eigen::VectorXd::Zero(b.rowCount());
         b.diagonal[1] = std::nan("");
       }},
  };
  for (const Case& c : cases) {
    Problem p = good.problem;
    BodyCompliance b = good.bodies;
    c.spoil(p, b);
    p.bodies = std::make_shared<const BodyCompliance>(b);
    const std::string err = validateProblem(p);
    EXPECT_NE(err.find(c.expect), std::string::npos) << "expected '" << c.expect << "', got '" << err << "'";
    const SolveResult r = solveProblem(p, unbuilt(tight()));
    EXPECT_EQ(r.status, SolveStatus::kInvalidInput) << c.expect;
    EXPECT_EQ(r.message, err);
    EXPECT_TRUE(std::isfinite(r.residual));
  }
}

// ---- the unbuilt solve against the built one -------------------------------------------------

TEST(Unbuilt, FrictionalAndFrictionlessGiveTheBuiltForces) {
  for (unsigned seed : {11u, 12u, 13u, 14u}) {
    SCOPED_TRACE(seed);
    const RandomScene s = randomScene(10, 14, seed);
    expectSameAsBuilt(s.problem, tight());
  }
}

TEST(Unbuilt, BilateralContactsGiveTheBuiltForces) {
  Mix mix;
  mix.bilateral = 0.4;
  mix.frictionless = 0.2;
  for (unsigned seed : {21u, 22u}) {
    SCOPED_TRACE(seed);
    const RandomScene s = randomScene(10, 12, seed, mix);
    expectSameAsBuilt(s.problem, tight());
  }
}

TEST(Unbuilt, TorsionalAndRollingContactsGiveTheBuiltForces) {
  // 4-row (spin) and 6-row (spin + rolling) contacts: angular rows J = ±[0, ωᵀ].
  RandomScene s = randomScene(8, 10, 17);
  std::mt19937 rng(18);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (std::size_t i = 0; i < s.problem.contacts.size(); ++i) {
    Contact& c = s.problem.contacts[i];
    ContactJacobian& j = s.bodies.contacts[i];
    if (c.type != ContactType::kFrictional) continue;
    c.type = i % 2 ? ContactType::kTorsional : ContactType::kRolling;
    c.rows = rowsForType(c.type);
    c.mu_torsional = 0.01;
    c.mu_rolling = 0.005;
    const int old_rows = j.rows;
    j.rows = c.rows;
    for (JacobianBlock* J : {&j.jacobian_a, &j.jacobian_b}) {
      if (J->rows() == 0) continue;
      const double sign = J == &j.jacobian_a ? 1.0 : -1.0;
      const JacobianBlock linear = *J;
      J->setZero(c.rows, 6);
      J->topRows(old_rows) = linear;
      for (int k = 3; k < c.rows; ++k) J->row(k).tail<3>() = sign * linear.row(k - 3).head<3>();
    }
  }
  s.problem.d_free.resize(s.bodies.rowCount());
  int row = 0;
  for (const Contact& c : s.problem.contacts) {
    for (int k = 0; k < c.rows; ++k)
      s.problem.d_free[row + k] = k == 0 ? -1e-3 * (1.2 + u(rng)) : 3e-4 * u(rng);
    row += c.rows;
  }
  s.problem.bodies = std::make_shared<const BodyCompliance>(s.bodies);
  ASSERT_EQ(validateProblem(s.problem), "");
  expectSameAsBuilt(s.problem, tight());
}

TEST(Unbuilt, FrictionlessProblemsRunPgsUnbuilt) {
  Mix mix;
  mix.frictionless = 1.0;
  const RandomScene s = randomScene(8, 20, 31, mix);
  for (SolverKind kind : {SolverKind::kPgs, SolverKind::kAuto}) {
    const SolveResult r = solveProblem(s.problem, unbuilt(tight(kind)));
    EXPECT_EQ(r.solver, kind == SolverKind::kAuto ? "auto:pgs" : "pgs");
    EXPECT_TRUE(r.unbuilt);
    // Built, auto may start elsewhere (Lemke on a coupled LCP); its unbuilt path is pgs.
    expectSameAsBuilt(s.problem, tight(SolverKind::kPgs));
  }
}

TEST(Unbuilt, AutoStaysGaussSeidelAtTightTolerances) {
  // Unbuilt, auto starts with Gauss-Seidel (W is not formed unless a fallback needs it);
  // built block-sparse with a moderate normal coupling (κ < 2) it starts with nlgs as well.
  const RandomScene s = randomScene(10, 14, 41);
  const SolveResult u = solveProblem(s.problem, unbuilt(tight(SolverKind::kAuto)));
  EXPECT_EQ(u.solver, "auto:nlgs");
  EXPECT_TRUE(u.unbuilt);
  EXPECT_EQ(u.status, SolveStatus::kConverged) << u.message;
  EXPECT_NE(u.message.find("unbuilt solve on the body form (10 bodies)"), std::string::npos) << u.message;
  const SolveResult b = solveProblem(builtSparse(s.problem), tight(SolverKind::kAuto));
  EXPECT_EQ(b.solver, "auto:nlgs");
  EXPECT_LT(relDiff(u.forces, b.forces), 1e-7);
}

TEST(Unbuilt, SameSweepsBeforeConvergence) {
  // maxIt = 3: not converged, and still the same iterate: it is the same iteration.
  const RandomScene s = randomScene(10, 14, 51);
  SolverParams params = tight();
  params.maxIt = 3;
  expectSameAsBuilt(s.problem, params, 1e-10, false);
  EXPECT_EQ(solveProblem(s.problem, unbuilt(params)).iterations, 3);
}

TEST(Unbuilt, WarmStartMinWMaxFRegularizationSorAndSofaRule) {
  const RandomScene s = randomScene(10, 16, 61);
  {
    SCOPED_TRACE("regularization");
    SolverParams params = tight();
    params.regularizationTerm = 1e-6;
    expectSameAsBuilt(s.problem, params);
  }
  {
    SCOPED_TRACE("sor");
    SolverParams params = tight();
    params.sor = 1.3;
    expectSameAsBuilt(s.problem, params);
  }
  {
    SCOPED_TRACE("sofa stopping rule");
    SolverParams params = tight();
    params.stopping_rule = StoppingRule::kSofa;
    params.tolerance = 1e-14;
    expectSameAsBuilt(s.problem, params, 1e-8, false);
  }
  {
    SCOPED_TRACE("minW");
    // Between the smallest and the largest W_nn: some contacts are ignored.
    const Eigen::MatrixXd W = s.bodies.toDense();
    const std::vector<int> off = s.problem.rowOffsets();
    std::vector<double> wnn;
    for (std::size_t i = 0; i < s.problem.contacts.size(); ++i) wnn.push_back(W(off[i], off[i]));
    std::sort(wnn.begin(), wnn.end());
    SolverParams params = tight();
    params.minW = 0.5 * (wnn[2] + wnn[3]);
    const SolveResult u = solveProblem(s.problem, unbuilt(params));
    EXPECT_EQ(std::count(u.states.begin(), u.states.end(), ContactState::kIgnored), 3);
    expectSameAsBuilt(s.problem, params);
  }
  {
    SCOPED_TRACE("maxF");
    const SolveResult free = solveProblem(s.problem, unbuilt(tight()));
    double largest = 0.0;
    const std::vector<int> off = s.problem.rowOffsets();
    for (std::size_t i = 0; i < s.problem.contacts.size(); ++i)
      largest = std::max(largest, free.forces.segment(off[i], s.problem.contacts[i].rows).norm());
    SolverParams params = tight();
    params.maxF = 0.7 * largest;
    const SolveResult u = solveProblem(s.problem, unbuilt(params));
    EXPECT_GE(u.resolves, 1);
    expectSameAsBuilt(s.problem, params);
  }
  {
    SCOPED_TRACE("warm start over three solves");
    SolverParams params = tight();
    params.initial_guess = true;
    params.maxIt = 40;  // warm start visible in the forces when the sweeps are capped
    ContactSolver unbuilt_solver(unbuilt(params)), built_solver(params);
    Problem u_problem = s.problem;
    Problem b_problem = builtSparse(s.problem);
    for (int step = 0; step < 3; ++step) {
      const SolveResult u = unbuilt_solver.solve(u_problem);
      const SolveResult b = built_solver.solve(b_problem);
      EXPECT_TRUE(u.unbuilt);
      EXPECT_EQ(u.iterations, b.iterations) << "step " << step;
      EXPECT_LT(relDiff(u.forces, b.forces), 1e-9) << "step " << step;
      u_problem.d_free *= 0.9;
      b_problem.d_free *= 0.9;
    }
    EXPECT_EQ(unbuilt_solver.warmStartSize(), s.problem.contacts.size());
  }
}

TEST(Unbuilt, SoftnessAndErpJoinTheBodyForm) {
  RandomScene s = randomScene(10, 14, 71);
  Problem p = s.problem;
  for (std::size_t i = 0; i < p.contacts.size(); ++i) {
    p.contacts[i].gap = i % 3 == 0 ? -0.002 : 0.0;
    p.contacts[i].erp = 0.2;
    p.contacts[i].softness = i % 2 == 0 ? 1e-6 : 0.0;
  }
  expectSameAsBuilt(p, tight());
  // The input's body form is shared and must stay as given.
  EXPECT_EQ(p.bodies->diagonal.size(), 0);
}

TEST(Unbuilt, ZeroSelfComplianceIsAZeroDiagonalUnlessMinW) {
  // A contact between two static bodies has W_cc = 0: Gauss-Seidel refuses it, built or not.
  RandomScene s = randomScene(4, 5, 81);
  BodyCompliance b = s.bodies;
  b.contacts[2].body_a = -1;
  b.contacts[2].body_b = -1;
  Problem p = s.problem;
  p.bodies = std::make_shared<const BodyCompliance>(b);
  const SolveResult u = solveProblem(p, unbuilt(tight()));
  EXPECT_EQ(u.status, SolveStatus::kZeroDiagonal);
  EXPECT_NE(u.message.find("contact 2"), std::string::npos) << u.message;
  SolverParams params = tight();
  params.minW = 1e-300;
  expectSameAsBuilt(p, params);
  EXPECT_EQ(solveProblem(p, unbuilt(params)).states[2], ContactState::kIgnored);
}

TEST(Unbuilt, OtherSolversAssembleWAndSaySo) {
  Mix mix;
  mix.frictionless = 1.0;
  const RandomScene s = randomScene(6, 10, 91, mix);
  for (SolverKind kind : {SolverKind::kLemke, SolverKind::kNewton, SolverKind::kApgd}) {
    const SolveResult u = solveProblem(s.problem, unbuilt(tight(kind)));
    const SolveResult b = solveProblem(builtSparse(s.problem), tight(kind));
    EXPECT_FALSE(u.unbuilt) << solverName(kind);
    EXPECT_NE(u.message.find(std::string("build_lcp=false: ") + solverName(kind) +
                             " needs the assembled W; assembled it from the body form"),
              std::string::npos)
        << u.message;
    EXPECT_EQ(u.status, b.status) << solverName(kind);
    EXPECT_EQ(u.forces, b.forces) << solverName(kind) << ": the very same assembled problem";
  }
  // build_lcp = true on a body form: assembled, no note.
  const SolveResult built = solveProblem(s.problem, tight(SolverKind::kPgs));
  EXPECT_FALSE(built.unbuilt);
  EXPECT_EQ(built.message, "");
  // build_lcp = false without a body form: the built solve, with SOFA's note.
  const SolveResult no_bodies = solveProblem(builtDense(s.problem), unbuilt(tight(SolverKind::kPgs)));
  EXPECT_FALSE(no_bodies.unbuilt);
  EXPECT_NE(no_bodies.message.find("needs the body form"), std::string::npos);
}

TEST(Unbuilt, TimeBudgetAndMaxIterationsAreHonest) {
  const RandomScene s = randomScene(40, 80, 101);
  SolverParams params = tight();
  params.tolerance = 1e-300;  // never reached
  params.maxIt = 5;
  const SolveResult capped = solveProblem(s.problem, unbuilt(params));
  EXPECT_EQ(capped.status, SolveStatus::kMaxIterations);
  EXPECT_EQ(capped.iterations, 5);
  EXPECT_TRUE(capped.forces.allFinite());
  params.maxIt = 100000000;
  params.time_budget = 0.02;
  const SolveResult budget = solveProblem(s.problem, unbuilt(params));
  EXPECT_EQ(budget.status, SolveStatus::kTimeBudget) << budget.message;
  EXPECT_LT(budget.solve_time, 1.0);
  // The residual is the true one of the returned forces (computed through W λ).
  Problem built = builtDense(s.problem);
  Eigen::VectorXd d = toDense(built.W) * budget.forces + built.d_free;
  EXPECT_LT((d - budget.d).norm(), 1e-12 * (1.0 + d.norm()));
}

TEST(Unbuilt, DisplayDebugHistoryMatches) {
  const RandomScene s = randomScene(10, 14, 111);
  SolverParams params = tight();
  params.displayDebug = true;
  params.maxIt = 20;
  const SolveResult u = solveProblem(s.problem, unbuilt(params));
  const SolveResult b = solveProblem(builtDense(s.problem), params);
  ASSERT_EQ(u.residual_history.size(), b.residual_history.size());
  for (std::size_t k = 0; k < u.residual_history.size(); ++k)
    EXPECT_NEAR(u.residual_history[k], b.residual_history[k], 1e-9 * (b.residual_history[k] + 1e-300));
}

}  // namespace
}  // namespace lcp_contact_solver::core
