// Lemke on every shared reference LCP (/work/shared/problems/lcp, from Siconos' test data).
// Needs the .dat reader, so it belongs to test_problem_io (which links lcp_contact_solver_io).
#include "lcp_contact_solver/core/contact_solver.h"
#include "lcp_contact_solver/core/problem_io.h"

#include <gtest/gtest.h>

#include <Eigen/Core>

#include <algorithm>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace lcp_contact_solver::core {
namespace {

struct Expected {
  SolveStatus status;
  int pivots;
};

// What lexicographic Lemke (covering vector e, pivot cap 1000) does on each file. The pivot
// counts are those of the same rule run in exact rational arithmetic, so a change here
// means the floating-point path left the exact one.
const std::map<std::string, Expected>& expectations() {
  static const std::map<std::string, Expected> table = {
      {"lcp_CPS_1.dat", {SolveStatus::kConverged, 2}},  // degenerate: solutions z1 + z2 = 1
      {"lcp_CPS_2.dat", {SolveStatus::kConverged, 5}},
      // Bimatrix game [[0, A], [B, 0]], A, B > 0: M is copositive but not copositive-plus,
      // and Lemke with covering vector e ends on a ray after its first pivot whichever row
      // leaves (every w_r leaving makes z_r's column nonpositive), although the game has
      // equilibria. Lemke-Howson (a different covering) would be needed; not a bug.
      {"lcp_CPS_3.dat", {SolveStatus::kRayTermination, 1}},
      {"lcp_CPS_4.dat", {SolveStatus::kConverged, 5}},
      {"lcp_CPS_4bis.dat", {SolveStatus::kConverged, 5}},
      {"lcp_CPS_5.dat", {SolveStatus::kConverged, 2}},
      {"lcp_Pang_isolated_sol.dat", {SolveStatus::kConverged, 3}},
      // Infeasible: w1 = -z2 - z3 - 1e-4 < 0 for every z >= 0. The ray is the right answer.
      {"lcp_Pang_isolated_sol_perturbed.dat", {SolveStatus::kRayTermination, 4}},
      {"lcp_deudeu.dat", {SolveStatus::kConverged, 3}},
      {"lcp_deudeu_block.dat", {SolveStatus::kConverged, 3}},
      {"lcp_enum_fails.dat", {SolveStatus::kConverged, 8}},
      {"lcp_exp_murty.dat", {SolveStatus::kConverged, 2}},    // q = -1: the easy variant
      {"lcp_exp_murty2.dat", {SolveStatus::kConverged, 64}},  // Murty's 2^n path, n = 6
      {"lcp_inf_sol_perturbed.dat", {SolveStatus::kConverged, 5}},
      {"lcp_mmc.dat", {SolveStatus::kConverged, 23}},
      {"lcp_ortiz.dat", {SolveStatus::kConverged, 3}},
      {"lcp_ortiz_block.dat", {SolveStatus::kConverged, 3}},
      // q is zero on 32 of 40 rows: degenerate at nearly every pivot. Without treating
      // rounding-level tableau entries as the zeros they are, the lexicographic choice is
      // decided by noise and the method cycles until the cap.
      {"lcp_tobenna.dat", {SolveStatus::kConverged, 127}},
      {"lcp_trivial.dat", {SolveStatus::kConverged, 10}},
      {"lcp_trivial_block.dat", {SolveStatus::kConverged, 10}},
  };
  return table;
}

std::string lcpDir() { return std::string(LCS_PROBLEMS_DIR) + "/lcp"; }

std::vector<std::string> sharedLcpFiles() {
  std::vector<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(lcpDir())) {
    if (entry.path().extension() == ".dat") names.push_back(entry.path().filename().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

SolveResult solveWithLemke(const Problem& problem) {
  SolverParams params;
  params.solver = SolverKind::kLemke;
  params.maxIt = 1000;
  params.islands = false;  // the pivot counts below are those of one tableau
  return solveProblem(problem, params);
}

TEST(LemkeShared, EveryFileHasAnExpectation) {
  const std::vector<std::string> names = sharedLcpFiles();
  EXPECT_EQ(names.size(), expectations().size());
  for (const std::string& name : names) EXPECT_TRUE(expectations().count(name)) << name;
}

TEST(LemkeShared, EveryLcpEndsAsExpected) {
  for (const std::string& name : sharedLcpFiles()) {
    SCOPED_TRACE(name);
    const auto expected = expectations().find(name);
    if (expected == expectations().end()) continue;  // reported by the test above
    const Problem problem = readSiconosDat(lcpDir() + "/" + name);
    const SolveResult result = solveWithLemke(problem);
    EXPECT_EQ(result.status, expected->second.status) << statusName(result.status) << ": " << result.message;
    EXPECT_EQ(result.iterations, expected->second.pivots);
    ASSERT_TRUE(result.forces.allFinite());
    ASSERT_TRUE(result.d.allFinite());
    EXPECT_TRUE(std::isfinite(result.residual));
    if (expected->second.status == SolveStatus::kConverged) {
      // Exact up to rounding. The largest figures are tobenna (~5e-14) and mmc (~1e-15).
      EXPECT_LE(result.residual, 1e-10);
      EXPECT_GE(result.forces.minCoeff(), 0.0);
      EXPECT_GE(result.d.minCoeff(), -1e-10 * std::max(1.0, problem.d_free.norm()));
    } else {
      EXPECT_FALSE(result.converged);
      EXPECT_FALSE(result.message.empty());
    }
  }
}

TEST(LemkeShared, KnownSolutions) {
  {
    const SolveResult r = solveWithLemke(readSiconosDat(lcpDir() + "/lcp_deudeu.dat"));
    ASSERT_EQ(r.status, SolveStatus::kConverged);
    EXPECT_NEAR(r.forces[0], 4.0 / 3.0, 1e-14);
    EXPECT_NEAR(r.forces[1], 7.0 / 3.0, 1e-14);
  }
  {
    // Murty's exponential example: the unique solution is z = (0, ..., 0, 64).
    const SolveResult r = solveWithLemke(readSiconosDat(lcpDir() + "/lcp_exp_murty2.dat"));
    ASSERT_EQ(r.status, SolveStatus::kConverged);
    Eigen::VectorXd expected = Eigen::VectorXd::Zero(6);
    expected[5] = 64.0;
    EXPECT_LE((r.forces - expected).cwiseAbs().maxCoeff(), 1e-12);
  }
  {
    // The isolated solution z = (1, 0, 0).
    const SolveResult r = solveWithLemke(readSiconosDat(lcpDir() + "/lcp_Pang_isolated_sol.dat"));
    ASSERT_EQ(r.status, SolveStatus::kConverged);
    EXPECT_NEAR(r.forces[0], 1.0, 1e-15);
    EXPECT_EQ(r.forces[1], 0.0);
    EXPECT_EQ(r.forces[2], 0.0);
  }
}

TEST(LemkeShared, BlockAndDenseStorageAgree) {
  for (const char* base : {"lcp_deudeu", "lcp_ortiz", "lcp_trivial"}) {
    SCOPED_TRACE(base);
    const SolveResult dense = solveWithLemke(readSiconosDat(lcpDir() + "/" + base + ".dat"));
    const SolveResult block = solveWithLemke(readSiconosDat(lcpDir() + "/" + base + "_block.dat"));
    ASSERT_EQ(dense.status, SolveStatus::kConverged);
    ASSERT_EQ(block.status, SolveStatus::kConverged);
    EXPECT_LE((dense.forces - block.forces).cwiseAbs().maxCoeff(), 1e-12);
  }
}

}  // namespace
}  // namespace lcp_contact_solver::core
