// ContactSolver::solveInPlace: erp and softness applied to the problem itself instead of a
// copy of W. Its results must equal solve()'s (the copying path) and the problem must come
// back bit for bit, on every storage (dense, block-sparse with and without stored diagonal
// blocks, the body form), at both constraint levels, with μ = 0 compaction and on errors.
#include "lcp_contact_solver/core/body_compliance.h"
#include "lcp_contact_solver/core/contact_solver.h"
#include "lcp_contact_solver/core/stabilization.h"

#include <gtest/gtest.h>

#include <random>

namespace lcp_contact_solver::core {
namespace {

// Mixed contacts (frictional, μ = 0 frictional, frictionless, bilateral, torsional), some
// penetrating, some with their own erp/softness; W = J C Jᵀ of random bodies, so the
// problem has a body form too.
Problem mixedProblem(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const int nbodies = 4, nc = 10;
  auto bodies = std::make_shared<BodyCompliance>();
  for (int b = 0; b < nbodies; ++b) {
    BodyMatrix A;
    for (int r = 0; r < 6; ++r)
      for (int c = 0; c < 6; ++c) A(r, c) = u(rng);
    bodies->body_compliance.push_back(A * A.transpose() + 0.5 * BodyMatrix::Identity());
  }
  Problem p;
  const ContactType types[] = {ContactType::kFrictional, ContactType::kFrictionless, ContactType::kBilateral,
                               ContactType::kTorsional};
  for (int i = 0; i < nc; ++i) {
    Contact c;
    c.id = 100 + i;
    c.type = types[i % 4];
    c.rows = c.type == ContactType::kBilateral ? 2 : rowsForType(c.type);
    c.mu = i == 4 ? 0.0 : 0.4;  // contact 4: frictional with μ = 0 (compacted to one row)
    c.mu_torsional = c.type == ContactType::kTorsional ? 0.01 : 0.0;
    c.gap = i % 3 == 0 ? -0.01 * (i + 1) : 0.002;
    if (i == 6) c.erp = 0.5;
    if (i == 8) c.softness = 0.05;
    p.contacts.push_back(c);
    ContactJacobian J;
    J.rows = c.rows;
    J.body_a = i % nbodies;
    J.body_b = i % 3 == 1 ? -1 : (i + 1) % nbodies;
    J.jacobian_a.resize(c.rows, 6);
    for (int k = 0; k < c.rows * 6; ++k) J.jacobian_a.data()[k] = u(rng);
    if (J.body_b >= 0) {
      J.jacobian_b.resize(c.rows, 6);
      for (int k = 0; k < c.rows * 6; ++k) J.jacobian_b.data()[k] = u(rng);
    }
    bodies->contacts.push_back(J);
  }
  p.bodies = bodies;
  p.d_free = Eigen::VectorXd(bodies->rowCount());
  for (int r = 0; r < p.d_free.size(); ++r) p.d_free[r] = 0.1 * u(rng);
  return p;
}

Problem assembled(const Problem& body_form, bool dense) {
  Problem p = body_form;
  p.bodies.reset();
  if (dense)
    p.W = body_form.bodies->toDense();
  else
    p.W = body_form.bodies->assemble();
  return p;
}

// The block-sparse W without the stored diagonal block of contact `skip`.
Problem withoutDiagonalBlock(const Problem& p, int skip) {
  const auto& W = std::get<BlockSparseMatrix>(p.W);
  std::vector<int> sizes;
  for (const Contact& c : p.contacts) sizes.push_back(c.rows);
  BlockSparseMatrix out = BlockSparseMatrix::withBlockSizes(sizes);
  for (int i = 0; i < W.blockCount(); ++i) {
    out.beginRow();
    for (int b = W.row_start[i]; b < W.row_start[i + 1]; ++b) {
      const int j = W.block_col[b];
      if (i == skip && j == skip) continue;
      out.addBlock(j,
                   Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
                       W.values.data() + W.value_start[b], sizes[i], sizes[j]));
    }
  }
  Problem q = p;
  q.W = std::move(out);
  return q;
}

void expectSameProblem(const Problem& a, const Problem& b) {
  ASSERT_EQ(a.W.index(), b.W.index());
  if (const auto* dense = std::get_if<Eigen::MatrixXd>(&a.W)) {
    EXPECT_TRUE(*dense == std::get<Eigen::MatrixXd>(b.W));  // bit for bit
  } else {
    const auto& x = std::get<BlockSparseMatrix>(a.W);
    const auto& y = std::get<BlockSparseMatrix>(b.W);
    EXPECT_EQ(x.values, y.values);
    EXPECT_EQ(x.block_col, y.block_col);
    EXPECT_EQ(x.row_start, y.row_start);
  }
  EXPECT_TRUE(a.d_free == b.d_free);
  EXPECT_EQ(a.bodies, b.bodies);  // the same body form object, not a modified copy
}

void expectSameResult(const SolveResult& a, const SolveResult& b, const std::string& what) {
  ASSERT_EQ(a.status, b.status) << what << ": " << a.message << " / " << b.message;
  EXPECT_EQ(a.message, b.message) << what;
  EXPECT_EQ(a.iterations, b.iterations) << what;
  ASSERT_EQ(a.forces.size(), b.forces.size()) << what;
  EXPECT_LE((a.forces - b.forces).lpNorm<Eigen::Infinity>(), 1e-12) << what;
  EXPECT_LE((a.d - b.d).lpNorm<Eigen::Infinity>(), 1e-12) << what;
  EXPECT_NEAR(a.residual, b.residual, 1e-12) << what;
  EXPECT_EQ(a.states, b.states) << what;
}

struct Setting {
  const char* name;
  SolverParams params;
};

std::vector<Setting> settings() {
  SolverParams base;
  base.tolerance = 1e-10;
  base.maxIt = 2000;
  base.initial_guess = false;
  std::vector<Setting> out;
  SolverParams erp = base;
  erp.erp = 0.2;
  out.push_back({"erp", erp});
  SolverParams soft = erp;
  soft.softness = 0.01;
  out.push_back({"erp+softness", soft});
  SolverParams velocity = soft;
  velocity.constraint_level = ConstraintLevel::kVelocity;
  velocity.time_step = 0.01;
  out.push_back({"velocity level", velocity});
  SolverParams own = base;  // only the contacts' own erp/softness (contacts 6 and 8)
  out.push_back({"per-contact values only", own});
  return out;
}

TEST(SolveInPlace, EqualsTheCopyingSolveAndRestoresTheProblem) {
  const Problem body_form = mixedProblem(7);
  struct Storage {
    const char* name;
    Problem problem;
  };
  const std::vector<Storage> storages = {{"dense", assembled(body_form, true)},
                                         {"block-sparse", assembled(body_form, false)},
                                         {"body form (unbuilt)", body_form}};
  for (const Storage& storage : storages) {
    for (const Setting& setting : settings()) {
      // nlgs: the only kernel for torsional rows and on the body form; the stabilization
      // stage before it is the same for every kernel.
      for (SolverKind kind : {SolverKind::kNlgs}) {
        SolverParams params = setting.params;
        params.solver = kind;
        params.build_lcp = !storage.problem.bodies;
        const std::string what = std::string(storage.name) + ", " + setting.name + ", " + solverName(kind);
        ASSERT_TRUE(needsStabilization(storage.problem, params)) << what;
        ContactSolver copying(params), in_place(params);
        Problem borrowed = storage.problem;
        const SolveResult expected = copying.solve(storage.problem);
        ASSERT_TRUE(expected.status == SolveStatus::kConverged ||
                    expected.status == SolveStatus::kMaxIterations)
            << what << ": " << expected.message;
        const SolveResult got = in_place.solveInPlace(borrowed);
        expectSameResult(got, expected, what);
        expectSameProblem(borrowed, storage.problem);
        // And again warm-started: the remembered forces are the same.
        params.initial_guess = true;
        copying.setParams(params);
        in_place.setParams(params);
        expectSameResult(in_place.solveInPlace(borrowed), copying.solve(storage.problem), what + ", warm");
        expectSameProblem(borrowed, storage.problem);
      }
    }
  }
}

TEST(SolveInPlace, AMissingDiagonalBlockFallsBackToTheCopy) {
  // Contact 8 has its own softness; without a stored (8, 8) block the softness needs a new
  // block, which only the copying path can add.
  const Problem p = withoutDiagonalBlock(assembled(mixedProblem(11), false), 8);
  for (const Setting& setting : settings()) {
    const std::string what = setting.name;
    ContactSolver copying(setting.params), in_place(setting.params);
    Problem borrowed = p;
    expectSameResult(in_place.solveInPlace(borrowed), copying.solve(p), what);
    expectSameProblem(borrowed, p);
  }
}

TEST(SolveInPlace, ARefusedProblemIsLeftAsItWas) {
  const Problem p = assembled(mixedProblem(3), false);
  SolverParams params;
  params.erp = 0.2;
  params.constraint_level = ConstraintLevel::kVelocity;
  params.time_step = 0.0;  // erp at velocity level without a step: refused
  ContactSolver copying(params), in_place(params);
  Problem borrowed = p;
  const SolveResult refused = in_place.solveInPlace(borrowed);
  EXPECT_EQ(refused.status, SolveStatus::kInvalidInput);
  EXPECT_NE(refused.message.find("time_step"), std::string::npos) << refused.message;
  EXPECT_EQ(refused.message, copying.solve(p).message);
  expectSameProblem(borrowed, p);
}

TEST(SolveInPlace, WithoutStabilizationItIsTheSolve) {
  SolverParams params;
  params.tolerance = 1e-10;
  const Problem p = assembled(mixedProblem(5), true);
  Problem plain = p;
  for (Contact& c : plain.contacts) c.erp = c.softness = 0.0;
  ASSERT_FALSE(needsStabilization(plain, params));
  ContactSolver copying(params), in_place(params);
  Problem borrowed = plain;
  expectSameResult(in_place.solveInPlace(borrowed), copying.solve(plain), "no erp, no softness");
  expectSameProblem(borrowed, plain);
}

}  // namespace
}  // namespace lcp_contact_solver::core
