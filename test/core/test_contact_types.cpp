// Torsional (4-row) and rolling (6-row) contacts in the core: the local laws on problems
// with a known answer, the residual, which solvers take them, and validation.
#include "lcp_contact_solver/core/contact_solver.h"
#include "lcp_contact_solver/core/residual.h"

#include <gtest/gtest.h>

namespace lcp_contact_solver::core {
namespace {

// One contact with a diagonal W: every row decoupled, so each law can be checked alone.
Problem oneContact(ContactType type, const Eigen::VectorXd& w, const Eigen::VectorXd& d_free) {
  Problem p;
  Contact c;
  c.id = 3;
  c.type = type;
  c.rows = rowsForType(type);
  c.mu = 0.5;
  c.mu_torsional = 0.02;
  c.mu_rolling = 0.01;
  p.contacts.push_back(c);
  p.W = Eigen::MatrixXd(w.asDiagonal());
  p.d_free = d_free;
  return p;
}

SolverParams tight() {
  SolverParams params;
  params.tolerance = 1e-13;
  params.maxIt = 1000;
  params.initial_guess = false;
  return params;
}

TEST(ContactTypes, TorsionalRowSticksBelowItsBoundAndSlipsAtIt) {
  // λ_n = 10 (d_free_n = -10 w_n): the spin torque is bounded by μ_tor λ_n = 0.2.
  Eigen::VectorXd w(4), d(4);
  w << 0.1, 0.1, 0.1, 0.5;
  d << -1.0, 0.0, 0.0, -0.05;  // a small spin drive: sticks at λ_s = 0.05 / 0.5
  SolveResult r = solveProblem(oneContact(ContactType::kTorsional, w, d), tight());
  ASSERT_EQ(r.status, SolveStatus::kConverged) << r.message;
  EXPECT_EQ(r.solver, std::string("auto:nlgs"));  // auto: only nlgs has the local step
  EXPECT_NEAR(r.forces[0], 10.0, 1e-10);
  EXPECT_NEAR(r.forces[3], 0.1, 1e-10);
  EXPECT_NEAR(r.d[3], 0.0, 1e-12);
  d[3] = 3.0;  // a large drive the other way: slips at the bound, opposing the spin
  r = solveProblem(oneContact(ContactType::kTorsional, w, d), tight());
  ASSERT_EQ(r.status, SolveStatus::kConverged) << r.message;
  EXPECT_NEAR(r.forces[3], -0.02 * 10.0, 1e-10);
  EXPECT_GT(r.d[3], 0.0);
  EXPECT_LE(r.residual, 1e-13);
}

TEST(ContactTypes, RollingPairIsADiscOfRadiusMuRollingLambdaN) {
  Eigen::VectorXd w(6), d(6);
  w << 0.1, 0.1, 0.1, 0.5, 0.2, 0.2;
  d << -1.0, 0.0, 0.0, 0.0, 0.3, 0.4;  // rolling drive |(0.3, 0.4)| / 0.2 = 2.5 > 0.1: slips
  const SolveResult r = solveProblem(oneContact(ContactType::kRolling, w, d), tight());
  ASSERT_EQ(r.status, SolveStatus::kConverged) << r.message;
  const double bound = 0.01 * 10.0;
  EXPECT_NEAR(r.forces[4], -bound * 0.6, 1e-10);  // opposite to the drive, on the disc's rim
  EXPECT_NEAR(r.forces[5], -bound * 0.8, 1e-10);
  EXPECT_NEAR(r.forces[3], 0.0, 1e-12);
  EXPECT_LE(r.residual, 1e-13);
}

TEST(ContactTypes, CoupledRowsConvergeToTheNaturalMapZero) {
  // A coupled 6×6 block (a ball on a plane couples tangents and rolling): the residual
  // says whether every law holds at once.
  Eigen::MatrixXd A = Eigen::MatrixXd::Random(6, 6);
  Problem p = oneContact(ContactType::kRolling, Eigen::VectorXd::Ones(6), Eigen::VectorXd::Zero(6));
  p.W = Eigen::MatrixXd(A * A.transpose() + 0.5 * Eigen::MatrixXd::Identity(6, 6));
  p.d_free << -1.0, 0.3, -0.2, 0.5, -0.4, 0.1;
  const SolveResult r = solveProblem(p, tight());
  ASSERT_EQ(r.status, SolveStatus::kConverged) << r.message;
  EXPECT_LE(r.residual, 1e-13);
  EXPECT_LE(std::abs(r.forces[3]), 0.02 * r.forces[0] * (1 + 1e-12));
  EXPECT_LE(r.forces.segment<2>(4).norm(), 0.01 * r.forces[0] * (1 + 1e-12));
}

TEST(ContactTypes, OtherSolversSayTheyDoNotApply) {
  Eigen::VectorXd w = Eigen::VectorXd::Ones(4), d = -Eigen::VectorXd::Ones(4);
  for (SolverKind kind : {SolverKind::kPgs, SolverKind::kLemke, SolverKind::kApgd, SolverKind::kNewton}) {
    SolverParams params = tight();
    params.solver = kind;
    const SolveResult r = solveProblem(oneContact(ContactType::kTorsional, w, d), params);
    EXPECT_EQ(r.status, SolveStatus::kNotApplicable) << solverName(kind);
    EXPECT_NE(r.message.find("torsional"), std::string::npos) << r.message;
    EXPECT_TRUE(r.forces.allFinite());
    // The residual is that of the zero forces returned (a pressed contact: far from 0).
    EXPECT_GT(r.residual, 0.1) << solverName(kind);
    const Problem p = oneContact(ContactType::kTorsional, w, d);
    EXPECT_EQ(r.residual, naturalMapResidual(p, effectiveMu(p, params.mu), r.forces, r.d, {}));
  }
}

TEST(ContactTypes, ValidationNamesTheFault) {
  Problem p = oneContact(ContactType::kTorsional, Eigen::VectorXd::Ones(4), Eigen::VectorXd::Zero(4));
  p.contacts[0].rows = 3;
  EXPECT_NE(validateProblem(p).find("torsional but has 3 rows"), std::string::npos) << validateProblem(p);
  p = oneContact(ContactType::kRolling, Eigen::VectorXd::Ones(6), Eigen::VectorXd::Zero(6));
  p.contacts[0].mu_rolling = -0.1;
  EXPECT_NE(validateProblem(p).find("rolling friction"), std::string::npos) << validateProblem(p);
  EXPECT_EQ(rowsForType(ContactType::kTorsional), 4);
  EXPECT_EQ(rowsForType(ContactType::kRolling), 6);
}

// μ = 0 frictional contacts are solved as one row: the same forces, iterations and residual as
// the problem that declares them frictionless, tangent forces zero, d on every row, and the
// warm start kept across solves (dense and block-sparse W).
TEST(ContactTypes, ZeroFrictionContactsAreSolvedAsOneRow) {
  // Four contacts: 0 and 2 frictional with μ = 0, 1 with μ = 0.5, 3 with the default μ = 0.
  Problem three;
  for (int i = 0; i < 4; ++i)
    three.contacts.push_back(Contact{10 + i, ContactType::kFrictional, 3, i == 1 ? 0.5 : 0.0});
  three.contacts[3].mu = Contact::kMuDefault;
  Eigen::MatrixXd A = Eigen::MatrixXd::Random(12, 12);
  const Eigen::MatrixXd W = A * A.transpose() + 0.2 * Eigen::MatrixXd::Identity(12, 12);
  three.W = W;
  three.d_free = Eigen::VectorXd::Random(12);
  three.d_free[0] = three.d_free[3] = three.d_free[6] = three.d_free[9] = -1.0;  // all pressed
  // The same problem written with frictionless contacts.
  Problem one = three;
  std::vector<int> rows = {0, 3, 4, 5, 6, 9};
  for (int i : {0, 2, 3}) {
    one.contacts[i].type = ContactType::kFrictionless;
    one.contacts[i].rows = 1;
  }
  one.W = Eigen::MatrixXd(W(rows, rows));
  one.d_free = three.d_free(rows);
  SolverParams params;
  params.mu = 0.0;
  params.tolerance = 1e-12;
  params.solver = SolverKind::kNlgs;
  params.initial_guess = false;
  for (bool sparse : {false, true}) {
    SCOPED_TRACE(sparse ? "block-sparse" : "dense");
    Problem p = three;
    if (sparse) {
      BlockSparseMatrix m = BlockSparseMatrix::withBlockSizes({3, 3, 3, 3});
      for (int i = 0; i < 4; ++i) {
        m.beginRow();
        for (int j = 0; j < 4; ++j) m.addBlock(j, W.block(3 * i, 3 * j, 3, 3));
      }
      p.W = m;
    }
    const SolveResult full = solveProblem(p, params), reduced = solveProblem(one, params);
    ASSERT_EQ(full.status, SolveStatus::kConverged) << full.message;
    ASSERT_EQ(full.forces.size(), 12);
    EXPECT_EQ(full.iterations, reduced.iterations);
    EXPECT_LE((full.forces(rows) - reduced.forces).lpNorm<Eigen::Infinity>(), 1e-12);
    for (int r : {1, 2, 7, 8, 10, 11}) EXPECT_EQ(full.forces[r], 0.0) << "row " << r;
    const Eigen::VectorXd d = W * full.forces + three.d_free;
    EXPECT_LE((full.d - d).lpNorm<Eigen::Infinity>(), 1e-12);
    // The same errors, normalised by the full d_free (tangent rows included).
    EXPECT_NEAR(full.residual, reduced.residual * one.d_free.norm() / three.d_free.norm(), 1e-15);
    EXPECT_EQ(full.states, reduced.states);
  }
  // Warm start by id survives: the second solve of the same problem starts where it ended.
  params.initial_guess = true;
  params.tolerance = 1e-8;
  ContactSolver solver(params);
  const SolveResult cold = solver.solve(three);
  const SolveResult warm = solver.solve(three);
  ASSERT_TRUE(cold.converged && warm.converged);
  EXPECT_LT(warm.iterations, cold.iterations);
}

}  // namespace
}  // namespace lcp_contact_solver::core
