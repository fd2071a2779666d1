// The body form of the compliance and the unbuilt solve (build_lcp = false,
// core/body_compliance.h, BodyAccess in kernels/sweep_access.h): W λ without W equals the
// assembled W λ; the unbuilt Gauss-Seidel gives the forces of the built solve (dense and
// block-sparse W) for frictional, frictionless and bilateral contacts, with warm start,
// minW, maxF, regularization, softness, sor and the SOFA stopping rule; the other solvers
// assemble W and say so; malformed body forms are refused with a sentence.
#include "unbuilt_test_util.h"

namespace lcp_contact_solver::core {
namespace {

using namespace unbuilt_test;

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

}  // namespace
}  // namespace lcp_contact_solver::core
