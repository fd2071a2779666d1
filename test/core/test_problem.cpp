// Problem structure and validation: bad input gets a sentence, never a crash.
#include "lcp_contact_solver/core/contact_solver.h"
#include "lcp_contact_solver/core/problem.h"

#include <gtest/gtest.h>

#include <limits>
#include <string>

namespace lcp_contact_solver::core {
namespace {

Problem twoContacts() {
  Problem p;
  p.contacts = {Contact{1, ContactType::kFrictional, 3, 0.5}, Contact{2, ContactType::kFrictionless, 1, 0.0}};
  p.W = Eigen::MatrixXd(Eigen::MatrixXd::Identity(4, 4));
  p.d_free = Eigen::Vector4d(-1, 0, 0, -1);
  return p;
}

TEST(Problem, RowOffsetsFollowContactTypes) {
  const Problem p = twoContacts();
  EXPECT_EQ(p.rowCount(), 4);
  EXPECT_EQ(p.rowOffsets(), (std::vector<int>{0, 3, 4}));
  EXPECT_EQ(validateProblem(p), "");
}

TEST(Problem, ValidationNamesTheFault) {
  Problem p = twoContacts();
  p.d_free[2] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(validateProblem(p).find("d_free"), std::string::npos);

  p = twoContacts();
  std::get<Eigen::MatrixXd>(p.W)(1, 2) = std::numeric_limits<double>::infinity();
  EXPECT_NE(validateProblem(p).find("non-finite"), std::string::npos);

  p = twoContacts();
  p.W = Eigen::MatrixXd(Eigen::MatrixXd::Identity(5, 5));
  EXPECT_NE(validateProblem(p).find("W is 5x5"), std::string::npos);

  p = twoContacts();
  p.contacts[0].mu = -0.3;
  EXPECT_NE(validateProblem(p).find("negative mu"), std::string::npos);

  p = twoContacts();
  p.contacts[1].rows = 3;
  EXPECT_NE(validateProblem(p).find("frictionless"), std::string::npos);

  EXPECT_NE(validateProblem(Problem()).find("no contacts"), std::string::npos);
  EXPECT_NE(validateProblem(twoContacts(), 2).find("limit"), std::string::npos);
}

TEST(Problem, InvalidProblemGivesInvalidInputStatusAndNoNumbers) {
  Problem p = twoContacts();
  p.d_free.resize(2);
  const SolveResult r = solveProblem(p, SolverParams());
  EXPECT_EQ(r.status, SolveStatus::kInvalidInput);
  EXPECT_FALSE(r.converged);
  EXPECT_EQ(r.forces.size(), 0);
  EXPECT_FALSE(r.message.empty());
}

TEST(Problem, BlockSparseRoundTripsThroughDense) {
  Eigen::MatrixXd W = Eigen::MatrixXd::Zero(4, 4);
  W << 2, 0, 0, 1, 0, 1, 0, 0, 0, 0, 1, 0, 1, 0, 0, 3;
  BlockSparseMatrix B = BlockSparseMatrix::withBlockSizes({3, 1});
  B.beginRow();
  B.addBlock(0, W.block(0, 0, 3, 3));
  B.addBlock(1, W.block(0, 3, 3, 1));
  B.beginRow();
  B.addBlock(0, W.block(3, 0, 1, 3));
  B.addBlock(1, W.block(3, 3, 1, 1));
  EXPECT_EQ(B.validate(), "");
  EXPECT_EQ(B.toDense(), W);
  Eigen::VectorXd x(4), y;
  x << 1, 2, 3, 4;
  B.multiply(x, y);
  EXPECT_EQ(y, W * x);
  ComplianceMatrix C = B;
  EXPECT_EQ(diagonalBlock(C, 0, 3), W.block(0, 0, 3, 3));
  EXPECT_EQ(diagonalBlock(C, 3, 1), W.block(3, 3, 1, 1));

  Problem p = twoContacts();
  p.W = B;
  EXPECT_EQ(validateProblem(p), "");
  B.values.pop_back();
  p.W = B;
  EXPECT_NE(validateProblem(p), "");
}

// multiply's unrolled three-row path against the dense product, with every pairing of block
// heights it meets (contacts, scalar rows, a two-row block) and an absent block.
TEST(Problem, BlockSparseMultiplyMatchesDenseForMixedBlockSizes) {
  const std::vector<int> sizes = {3, 1, 3, 2, 3};
  BlockSparseMatrix B = BlockSparseMatrix::withBlockSizes(sizes);
  std::vector<int> offset = {0};
  for (int s : sizes) offset.push_back(offset.back() + s);
  const int n = offset.back();
  std::srand(7);
  const Eigen::MatrixXd full = Eigen::MatrixXd::Random(n, n);
  Eigen::MatrixXd W = Eigen::MatrixXd::Zero(n, n);
  for (int i = 0; i < static_cast<int>(sizes.size()); ++i) {
    B.beginRow();
    for (int j = 0; j < static_cast<int>(sizes.size()); ++j) {
      if ((i + 2 * j) % 5 == 1) continue;  // some blocks absent
      const Eigen::MatrixXd block = full.block(offset[i], offset[j], sizes[i], sizes[j]);
      B.addBlock(j, block);
      W.block(offset[i], offset[j], sizes[i], sizes[j]) = block;
    }
  }
  ASSERT_EQ(B.validate(), "");
  const Eigen::VectorXd x = Eigen::VectorXd::Random(n);
  Eigen::VectorXd y;
  B.multiply(x, y);
  EXPECT_LE((y - W * x).cwiseAbs().maxCoeff(), 1e-14 * n);
}

// Every block 1 x 1 (an LCP's or MuJoCo's pyramid edges' storage): multiply's compressed-row
// path against the dense product, with absent blocks, an empty row and a stored zero.
TEST(Problem, BlockSparseMultiplyOfScalarBlocksMatchesDense) {
  const int n = 9;
  BlockSparseMatrix B = BlockSparseMatrix::withBlockSizes(std::vector<int>(n, 1));
  std::srand(11);
  const Eigen::MatrixXd full = Eigen::MatrixXd::Random(n, n);
  Eigen::MatrixXd W = Eigen::MatrixXd::Zero(n, n);
  for (int i = 0; i < n; ++i) {
    B.beginRow();
    if (i == 4) continue;  // a row with no stored block
    for (int j = 0; j < n; ++j) {
      if ((3 * i + j) % 4 == 1) continue;
      const double v = i == 2 && j == 2 ? 0.0 : full(i, j);
      B.addBlock(j, Eigen::MatrixXd::Constant(1, 1, v));
      W(i, j) = v;
    }
  }
  ASSERT_EQ(B.validate(), "");
  ASSERT_EQ(B.toDense(), W);
  const Eigen::VectorXd x = Eigen::VectorXd::Random(n);
  Eigen::VectorXd y;
  B.multiply(x, y);
  EXPECT_LE((y - W * x).cwiseAbs().maxCoeff(), 1e-14 * n);
  EXPECT_EQ(y[4], 0.0);
}

TEST(Problem, SolverNamesRoundTrip) {
  for (const std::string& name : solverNames()) {
    SolverKind kind;
    ASSERT_TRUE(parseSolverName(name, &kind));
    EXPECT_EQ(name, solverName(kind));
  }
  SolverKind kind;
  EXPECT_FALSE(parseSolverName("nope", &kind));
}

// The symmetry test read in W's own storage agrees with the definition on the dense copy:
// a symmetric W (blocks of 1, 2 and 3 rows, some pairs stored both ways), one entry moved,
// and a block whose mirror is not stored.
TEST(Problem, SymmetryIsReadInEitherStorage) {
  // 9 rows (compared dense) and 20 times as many (read in the blocks).
  for (int copies : {1, 20}) {
    std::vector<int> sizes;
    for (int k = 0; k < copies; ++k) sizes.insert(sizes.end(), {3, 1, 2, 3});
    std::vector<int> start = {0};
    for (int size : sizes) start.push_back(start.back() + size);
    const int n = start.back(), nb = static_cast<int>(sizes.size());
    Eigen::MatrixXd A = Eigen::MatrixXd::Random(n, n);
    Eigen::MatrixXd S = A + A.transpose();
    for (int i = 0; i < nb; ++i)  // some pairs of contacts not coupled: no blocks stored there
      for (int j = 0; j < nb; ++j)
        if ((i + 2 * j) % 5 == 0 && i != j) S.block(start[i], start[j], sizes[i], sizes[j]).setZero();
    S = 0.5 * (S + S.transpose()).eval();
    for (int i = 0; i < nb; ++i)
      for (int j = 0; j < nb; ++j)
        if ((i + 2 * j) % 5 == 0 && i != j) {
          S.block(start[i], start[j], sizes[i], sizes[j]).setZero();
          S.block(start[j], start[i], sizes[j], sizes[i]).setZero();
        }
    // Blocks in column order or in reverse: the block path must not depend on the order.
    const auto blocked = [&](const Eigen::MatrixXd& M, bool reverse) {
      BlockSparseMatrix B = BlockSparseMatrix::withBlockSizes(sizes);
      for (int i = 0; i < nb; ++i) {
        B.beginRow();
        for (int c = 0; c < nb; ++c) {
          const int j = reverse ? nb - 1 - c : c;
          const Eigen::MatrixXd block = M.block(start[i], start[j], sizes[i], sizes[j]);
          if (block.cwiseAbs().maxCoeff() > 0.0) B.addBlock(j, block);
        }
      }
      return B;
    };
    Eigen::MatrixXd moved = S;
    moved(7, 2) += 1e-6;
    Eigen::MatrixXd one_sided = S;  // a block stored whose mirror is not
    for (int i = 0; i < nb && one_sided == S; ++i)
      for (int j = 0; j < nb; ++j)
        if (S.block(start[i], start[j], sizes[i], sizes[j]).isZero(0.0) && i != j) {
          one_sided(start[i], start[j]) = 0.5;
          break;
        }
    ASSERT_NE(one_sided, S);
    EXPECT_TRUE(isSymmetric(ComplianceMatrix(S), 1e-12));
    EXPECT_FALSE(isSymmetric(ComplianceMatrix(moved), 1e-12));
    EXPECT_FALSE(isSymmetric(ComplianceMatrix(one_sided), 1e-12));
    for (bool reverse : {false, true}) {
      SCOPED_TRACE(std::to_string(n) + " rows, blocks in " + (reverse ? "reverse " : "") + "column order");
      EXPECT_TRUE(isSymmetric(ComplianceMatrix(blocked(S, reverse)), 1e-12));
      EXPECT_FALSE(isSymmetric(ComplianceMatrix(blocked(moved, reverse)), 1e-12));
      EXPECT_TRUE(isSymmetric(ComplianceMatrix(blocked(moved, reverse)), 1e-3));  // a looser tolerance
      EXPECT_FALSE(isSymmetric(ComplianceMatrix(blocked(one_sided, reverse)), 1e-12));
    }
  }
}

}  // namespace
}  // namespace lcp_contact_solver::core
