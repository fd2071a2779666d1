// Every problem in ../shared/problems (Siconos test data, written by others) is read and
// solved by every solver; each assertion states what that solver must reach there, or the
// explicit failure it must report where it cannot apply.
#include "lcp_contact_solver/core/contact_solver.h"
#include "lcp_contact_solver/core/problem_io.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <set>

namespace lcp_contact_solver::core {
namespace {

namespace fs = std::filesystem;

std::vector<std::string> problemFiles(const std::string& family) {
  std::vector<std::string> files;
  for (const auto& entry : fs::directory_iterator(fs::path(LCS_PROBLEMS_DIR) / family))
    if (entry.is_regular_file()) files.push_back(entry.path().string());
  std::sort(files.begin(), files.end());
  return files;
}

std::string baseName(const std::string& path) { return fs::path(path).filename().string(); }

void expectFinite(const SolveResult& r, const std::string& what) {
  EXPECT_TRUE(r.forces.allFinite()) << what;
  EXPECT_TRUE(r.d.allFinite()) << what;
  EXPECT_TRUE(std::isfinite(r.residual)) << what;
  EXPECT_TRUE(std::isfinite(r.solver_error)) << what;
}

SolverParams params(SolverKind kind, double tolerance, int max_it) {
  SolverParams p;
  p.solver = kind;
  p.tolerance = tolerance;
  p.maxIt = max_it;
  p.initial_guess = false;
  return p;
}

bool hasNonPositiveDiagonal(const Problem& p) { return (toDense(p.W).diagonal().array() <= 0.0).any(); }

TEST(SharedProblemSolves, AllFilesArePresent) {
  EXPECT_EQ(problemFiles("lcp").size(), 20u);
  EXPECT_EQ(problemFiles("fc3d").size(), 26u);
}

// NLGS at SOFA's default tolerance solves every frictional problem.
TEST(SharedProblemSolves, NlgsReachesTheDefaultToleranceOnEveryFc3dProblem) {
  for (const std::string& file : problemFiles("fc3d")) {
    const Problem p = readProblemFile(file);
    SolverParams nlgs;
    nlgs.solver = SolverKind::kNlgs;
    const SolveResult r = solveProblem(p, nlgs);
    expectFinite(r, file);
    EXPECT_EQ(r.solver, "nlgs") << file;
    EXPECT_EQ(r.status, SolveStatus::kConverged) << file << ": " << r.message;
    EXPECT_LE(r.residual, 1e-3) << file;
    // auto (the default, a portfolio since #14) as well, whatever its path.
    const SolveResult a = solveProblem(p, SolverParams());
    expectFinite(a, file);
    EXPECT_EQ(a.solver.rfind("auto:", 0), 0u) << file;
    EXPECT_EQ(a.status, SolveStatus::kConverged) << file << ": " << a.solver << " " << a.message;
    EXPECT_LE(a.residual, 1e-3) << file;
  }
}

// At 1e-6 Gauss-Seidel stalls where W is rank deficient (more contact rows than body
// degrees of freedom: BoxesStack, OneObject-i100000): it must say so, not claim success.
TEST(SharedProblemSolves, NlgsAtOneMicroOrAnHonestStall) {
  const std::set<std::string> rank_deficient_stalls = {"BoxesStack1-i100000-32.hdf5.dat",
                                                       "OneObject-i100000-316.hdf5.dat"};
  for (const std::string& file : problemFiles("fc3d")) {
    const Problem p = readProblemFile(file);
    const SolveResult r = solveProblem(p, params(SolverKind::kNlgs, 1e-6, 20000));
    expectFinite(r, file);
    if (rank_deficient_stalls.count(baseName(file))) {
      EXPECT_EQ(r.status, SolveStatus::kMaxIterations) << file;
      EXPECT_FALSE(r.converged);
      EXPECT_GT(r.residual, 1e-6) << file;
      EXPECT_LT(r.residual, 1e-4) << file;  // the best iterate is still a usable answer
    } else {
      EXPECT_EQ(r.status, SolveStatus::kConverged) << file << ": " << r.message;
      EXPECT_LE(r.residual, 1e-6) << file;
    }
  }
}

// Friction makes PGS and Lemke inapplicable: an explicit status, finite zero output.
TEST(SharedProblemSolves, LcpSolversRefuseFrictionalProblems) {
  for (const std::string& file : problemFiles("fc3d")) {
    const Problem p = readProblemFile(file);
    for (SolverKind kind : {SolverKind::kPgs, SolverKind::kLemke}) {
      const SolveResult r = solveProblem(p, params(kind, 1e-6, 1000));
      expectFinite(r, file);
      EXPECT_EQ(r.status, SolveStatus::kNotApplicable) << file << " " << solverName(kind);
      EXPECT_EQ(r.forces.norm(), 0.0);
    }
  }
}

// PGS solves every LCP whose diagonal is positive to 1e-10; on a zero or negative
// diagonal (CPS_2/3/4, Pang, enum_fails, tobenna) it cannot even start and says so
// (SOFA divides by it and returns NaN).
TEST(SharedProblemSolves, PgsOnLcpsConvergesOrReportsTheZeroDiagonal) {
  for (const std::string& file : problemFiles("lcp")) {
    const Problem p = readProblemFile(file);
    const SolveResult r = solveProblem(p, params(SolverKind::kPgs, 1e-10, 100000));
    expectFinite(r, file);
    if (hasNonPositiveDiagonal(p)) {
      EXPECT_EQ(r.status, SolveStatus::kZeroDiagonal) << file;
      EXPECT_FALSE(r.message.empty());
    } else {
      EXPECT_EQ(r.status, SolveStatus::kConverged) << file << ": " << r.message;
      EXPECT_LE(r.residual, 1e-10) << file;
    }
  }
}

TEST(SharedProblemSolves, SameInputGivesBitIdenticalOutput) {
  for (const std::string& file : problemFiles("fc3d")) {
    const Problem p = readProblemFile(file);
    const SolveResult a = solveProblem(p, SolverParams());
    const SolveResult b = solveProblem(p, SolverParams());
    EXPECT_EQ(a.iterations, b.iterations) << file;
    EXPECT_TRUE(a.forces == b.forces) << file;
  }
}

}  // namespace
}  // namespace lcp_contact_solver::core
