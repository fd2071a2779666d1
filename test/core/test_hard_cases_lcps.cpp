// Hard cases: Murty's LCP, the shared degenerate LCPs, maxF and regressions the hard cases found.
#include "hard_case_util.h"

#include "lcp_contact_solver/core/problem_io.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <map>

namespace lcp_contact_solver::core {
namespace {

using namespace hard;

// ---- Murty's exponential LCP and the shared degenerate LCPs ---------------------------------

Eigen::MatrixXd murtyMatrix(int n) {
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(n, n);
  for (int i = 0; i < n; ++i) {
    M(i, i) = 1.0;
    for (int j = i + 1; j < n; ++j) M(i, j) = 2.0;
  }
  return M;
}

Eigen::VectorXd murtyVector(int n) {
  Eigen::VectorXd q(n);
  for (int i = 0; i < n; ++i) q[i] = -(std::ldexp(1.0, n + 1) - std::ldexp(1.0, i + 1));
  return q;
}

// Murty's LCP (Lemke visits 2^n bases) at n = 16..24 through ContactSolver: lemke stops at
// its pivot cap (maxIt = 1000) and says so (max_iterations, "pivot cap"), with finite,
// nonnegative forces and their true residual. Gauss-Seidel solves the triangular M in n
// sweeps and newton in a few steps; apgd assumes a symmetric W and may stop at maxIt.
// Unique solution (P-matrix): z = (0, ..., 0, 2^(n+1) - 2^n).
TEST(HardCases, MurtyThroughEverySolver) {
  for (int n = 16; n <= 24; n += 4) {
    const Problem p = makeLcpProblem(murtyMatrix(n), murtyVector(n));
    Eigen::VectorXd solution = Eigen::VectorXd::Zero(n);
    solution[n - 1] = std::ldexp(1.0, n + 1) - std::ldexp(1.0, n);
    for (SolverKind kind : allSolvers()) {
      const std::string label = "murty n=" + std::to_string(n);
      const SolveResult r = solveTwiceChecked(p, paramsFor(kind, 1e-8, 1000), label);
      if (kind == SolverKind::kLemke) {
        EXPECT_EQ(r.status, SolveStatus::kMaxIterations) << label;
        EXPECT_EQ(r.iterations, 1000) << label;
        EXPECT_NE(r.message.find("pivot cap"), std::string::npos) << r.message;
        EXPECT_GE(r.forces.minCoeff(), 0.0) << label;
      } else if (kind != SolverKind::kApgd) {
        ASSERT_TRUE(r.converged) << label << " " << r.solver << ": " << r.message;
      }
      if (r.converged) {
        EXPECT_LE((r.forces - solution).cwiseAbs().maxCoeff(), 1e-6 * solution.norm())
            << label << " " << r.solver;
      }
    }
  }
}

// Every LCP in ../shared/problems/lcp (degenerate, zero diagonals, non-symmetric, Murty)
// through every solver: finite, honest, bit-identical; some solver solves each one, except
// the infeasible Pang_isolated_sol_perturbed, which nobody may report solved. (Lemke's own
// outcome per file is asserted in test_lemke_shared.cpp.)
TEST(HardCases, SharedLcpsThroughEverySolver) {
  namespace fs = std::filesystem;
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(std::string(LCS_PROBLEMS_DIR) + "/lcp"))
    if (entry.path().extension() == ".dat") files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  ASSERT_EQ(files.size(), 20u);
  for (const fs::path& file : files) {
    const Problem p = readSiconosDat(file.string());
    int converged = 0;
    for (SolverKind kind : allSolvers()) {
      const SolveResult r = solveTwiceChecked(p, paramsFor(kind, 1e-8, 2000), file.filename().string());
      converged += r.converged ? 1 : 0;
    }
    // Pang_isolated_sol_perturbed is infeasible (w1 = -z2 - z3 - 1e-4 < 0 for all z >= 0).
    if (file.filename() == "lcp_Pang_isolated_sol_perturbed.dat") {
      EXPECT_EQ(converged, 0) << file.filename() << ": an infeasible LCP was reported solved";
    } else {
      EXPECT_GE(converged, 1) << file.filename() << ": no solver found a solution";
    }
  }
}

// The frictional reference problems of ../shared/problems/fc3d up to 400 rows (Rover*,
// FC3D_Example1, Confeti, NESpheres, OneObject, BoxesStack1: the last two rank-deficient)
// through every solver at 1e-6, 2000 iterations: finite, honest, bit-identical; pgs and
// lemke are not_applicable (friction); newton solves every one of them.
TEST(HardCases, SharedFc3dThroughEverySolver) {
  namespace fs = std::filesystem;
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(std::string(LCS_PROBLEMS_DIR) + "/fc3d"))
    if (entry.path().extension() == ".dat") files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  int tried = 0;
  for (const fs::path& file : files) {
    const Problem p = readSiconosDat(file.string());
    if (p.rowCount() > 400) continue;
    ++tried;
    for (SolverKind kind : allSolvers()) {
      const SolveResult r =
          solveTwiceChecked(p, paramsFor(kind, 1e-6, 2000), file.filename().string(), false);
      if (!applies(kind, p)) {
        EXPECT_EQ(r.status, SolveStatus::kNotApplicable) << file.filename();
      }
      if (kind == SolverKind::kNewton) {
        EXPECT_TRUE(r.converged) << file.filename() << ": " << r.message;
      }
    }
  }
  EXPECT_GE(tried, 15);
}

// ---- maxF -----------------------------------------------------------------------------------

// A box whose centre of mass sits over one corner region carries most of its weight on
// that corner. maxF below that corner's force drops it; the rest is solved again (and
// again, while another contact exceeds maxF). Asserted for every applicable solver: at
// least one drop (resolves >= 1), the dropped contacts are ignored with zero force, every
// remaining force is <= maxF, the result converged, and it equals a fresh solve of the
// problem without the dropped contacts (the re-solve is consistent, unlike SOFA's).
TEST(HardCases, MaxFDropsAndResolves) {
  for (double mu : {0.0, 0.5}) {
    World world;
    const Eigen::Vector3d size(0.2, 0.2, 0.2);
    world.add(box(10.0, size, Eigen::Vector3d(0.06, 0.06, 0.1)));
    for (const Eigen::Vector3d& pt : bottomPoints(Eigen::Vector3d(0, 0, 0.1), size, 4))
      world.contact(0, -1, pt, Eigen::Vector3d::UnitZ(), mu);
    const Problem p = world.problem();
    for (SolverKind kind : allSolvers()) {
      if (!applies(kind, p)) continue;
      SolverParams params = paramsFor(kind, 1e-9, 20000);
      params.regularizationTerm = 1e-6;  // 4 contacts on 3 freedoms: make the forces unique
      const SolveResult full = solveProblem(p, params);
      ASSERT_TRUE(full.converged) << full.solver << ": " << full.message;
      const double max_force = full.forces.cwiseAbs().maxCoeff();
      params.maxF = 0.8 * max_force;
      const std::string label = "maxF mu=" + std::to_string(mu).substr(0, 3);
      const SolveResult r = solveTwiceChecked(p, params, label);
      ASSERT_TRUE(r.converged) << label << " " << r.solver << ": " << r.message;
      EXPECT_GE(r.resolves, 1) << label;
      Problem rest = p;
      rest.contacts.clear();
      std::vector<int> keep_rows;
      const std::vector<int> off = p.rowOffsets();
      for (std::size_t i = 0; i < p.contacts.size(); ++i) {
        const double norm = r.forces.segment(off[i], p.contacts[i].rows).norm();
        if (r.states[i] == ContactState::kIgnored) {
          EXPECT_EQ(norm, 0.0) << label;
          continue;
        }
        EXPECT_LE(norm, params.maxF) << label << " contact " << i;
        rest.contacts.push_back(p.contacts[i]);
        for (int k = 0; k < p.contacts[i].rows; ++k) keep_rows.push_back(off[i] + k);
      }
      ASSERT_LT(rest.contacts.size(), p.contacts.size()) << label;
      const Eigen::MatrixXd W = toDense(p.W);
      Eigen::MatrixXd Wr(keep_rows.size(), keep_rows.size());
      Eigen::VectorXd qr(keep_rows.size()), expected_rows(keep_rows.size());
      for (std::size_t a = 0; a < keep_rows.size(); ++a) {
        qr[a] = p.d_free[keep_rows[a]];
        expected_rows[a] = r.forces[keep_rows[a]];
        for (std::size_t b = 0; b < keep_rows.size(); ++b) Wr(a, b) = W(keep_rows[a], keep_rows[b]);
      }
      rest.W = Wr;
      rest.d_free = qr;
      SolverParams fresh = params;
      fresh.maxF = 0.0;
      const SolveResult again = solveProblem(rest, fresh);
      ASSERT_TRUE(again.converged) << again.message;
      EXPECT_LE((again.forces - expected_rows).cwiseAbs().maxCoeff(), 1e-6 * max_force)
          << label << " " << r.solver;
    }
  }
}

// ---- regressions of faults the hard cases found ---------------------------------------------

// The natural map of a row, λ − max(0, λ − d), cancels to exactly 0 in floating point when
// |d| is below λ's rounding (λ = 2.45e6 N, d = 2e-10 m: the heavy-on-light stack), which
// made a solver report "residual 0" for an error of 2e-7. residual.cpp now computes it as
// min(λ, d) (frictionless) and as the modified velocity itself inside the cone.
TEST(HardCases, ResidualDoesNotCancelOnLargeForces) {
  for (ContactType type : {ContactType::kFrictionless, ContactType::kFrictional}) {
    Problem p;
    const int rows = type == ContactType::kFrictional ? 3 : 1;
    p.contacts.push_back(Contact{1, type, rows, 0.5});
    p.W = Eigen::MatrixXd(Eigen::MatrixXd::Identity(rows, rows));
    p.d_free = Eigen::VectorXd::Zero(rows);
    p.d_free[0] = -1e-3;
    Eigen::VectorXd lambda = Eigen::VectorXd::Zero(rows), d = Eigen::VectorXd::Zero(rows);
    lambda[0] = 2.45e6;
    d[0] = 2e-10;  // the contact still closes at 2e-10 m per step
    const double r = naturalMapResidual(p, {0.5}, lambda, d);
    EXPECT_NEAR(r, 2e-10 / 1e-3, 1e-12) << (type == ContactType::kFrictional ? "frictional" : "frictionless");
  }
}

// Lemke's dense tableau is 3 × 8 n² bytes: a large problem (or a hostile message with
// solver=lemke and max_rows = 30000, 21 GB) must be refused, not end in an allocation
// failure. 5000 frictionless rows (block-sparse diagonal W, so the test itself is cheap),
// and a pyramid4 problem of 1000 frictional contacts (6000 LCP variables).
TEST(HardCases, LemkeRefusesProblemsTooLargeForItsTableau) {
  for (bool pyramid : {false, true}) {
    const int contacts = pyramid ? 1000 : 5000;
    Problem p;
    std::vector<int> sizes;
    for (int i = 0; i < contacts; ++i) {
      p.contacts.push_back(pyramid ? Contact{i, ContactType::kFrictional, 3, 0.5}
                                   : Contact{i, ContactType::kFrictionless, 1, 0.0});
      sizes.push_back(p.contacts.back().rows);
    }
    BlockSparseMatrix W = BlockSparseMatrix::withBlockSizes(sizes);
    for (int i = 0; i < contacts; ++i) {
      W.beginRow();
      W.addBlock(i, Eigen::MatrixXd::Identity(sizes[i], sizes[i]));
    }
    p.W = W;
    p.d_free = -Eigen::VectorXd::Ones(p.rowCount());
    SolverParams params = paramsFor(SolverKind::kLemke, 1e-8, 100000);
    if (pyramid) params.friction_model = FrictionModel::kPyramid4;
    // W is diagonal: by island (the default) every contact is its own small tableau.
    const SolveResult split = solveProblem(p, params);
    EXPECT_EQ(split.status, SolveStatus::kConverged) << split.message;
    params.islands = false;  // one tableau for the whole problem
    const SolveResult r =
        solveTwiceChecked(p, params, pyramid ? "lemke pyramid4 6000 vars" : "lemke 5000 rows");
    EXPECT_EQ(r.status, SolveStatus::kNotApplicable) << r.message;
    EXPECT_NE(r.message.find("limited to 4096"), std::string::npos) << r.message;
    EXPECT_LT(r.solve_time, 1.0);
  }
}

}  // namespace
}  // namespace lcp_contact_solver::core
