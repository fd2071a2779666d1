// Islands (core/islands.h) and the symmetric active-set Newton (newton_symmetric.cpp, its
// LCP and sticking paths):
// the islands of a W made of independent groups are found (contacts interleaved across
// groups); solving by island gives the whole problem's forces (exactly for a fixed number
// of Gauss-Seidel sweeps, to 1e-10 for unique solutions at tight tolerance), and the same
// forces bit for bit whatever the thread count; the symmetric Newton path returns forces
// whose residual, recomputed here from W, d_free and the forces, meets the tolerance.
#include "hard_case_util.h"
#include "solvers_test_util.h"
#include "lcp_contact_solver/core/body_compliance.h"
#include "lcp_contact_solver/core/contact_solver.h"
#include "lcp_contact_solver/core/islands.h"
#include "lcp_contact_solver/core/residual.h"

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include <algorithm>
#include <memory>
#include <numeric>
#include <random>

namespace lcp_contact_solver::core {
namespace {

enum class Kinds { kFrictionless, kFrictional, kMixed };

// `groups` independent groups of `per_group` contacts. Within a group W = J Jᵀ / m + δ I
// (J random, rank limited by `dof` so that W can be singular when δ = 0), groups do not
// touch; the contacts of all groups are shuffled together so that islands are not
// contiguous ranges.
struct Generated {
  Problem problem;
  std::vector<int> group_of;  // per contact
};

Generated generate(int groups, int per_group, Kinds kinds, unsigned seed, double delta = 1e-3, int dof = 12) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0), pos(0.0, 1.0);
  const int nc = groups * per_group;
  std::vector<int> order(nc);
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), rng);
  Generated g;
  g.group_of.resize(nc);
  for (int i = 0; i < nc; ++i) {
    g.group_of[i] = order[i] % groups;
    Contact c;
    c.id = 100 + i;
    const bool frictional = kinds == Kinds::kFrictional || (kinds == Kinds::kMixed && pos(rng) < 0.5);
    c.type = frictional ? ContactType::kFrictional : ContactType::kFrictionless;
    c.rows = frictional ? 3 : 1;
    c.mu = frictional ? 0.3 + 0.5 * pos(rng) : -1.0;
    g.problem.contacts.push_back(c);
  }
  const std::vector<int> off = g.problem.rowOffsets();
  const int n = off.back();
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(n, groups * dof);
  for (int i = 0; i < nc; ++i)
    for (int r = off[i]; r < off[i + 1]; ++r)
      for (int k = 0; k < dof; ++k) J(r, g.group_of[i] * dof + k) = u(rng);
  Eigen::MatrixXd W = J * J.transpose() * 0.1;
  W.diagonal().array() += delta;
  g.problem.W = W;
  g.problem.d_free.resize(n);
  for (int i = 0; i < nc; ++i)
    for (int r = off[i]; r < off[i + 1]; ++r)
      g.problem.d_free[r] = r == off[i] ? -0.5 + 0.8 * pos(rng) : 0.3 * u(rng);
  return g;
}

SolverParams paramsFor(SolverKind kind, double tolerance, int max_it, bool islands, int threads = 1) {
  SolverParams p;
  p.solver = kind;
  p.tolerance = tolerance;
  p.maxIt = max_it;
  p.initial_guess = false;
  p.islands = islands;
  p.threads = threads;
  return p;
}

double maxDiff(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return a.size() == b.size() ? (a - b).cwiseAbs().maxCoeff() : 1e300;
}

using solvers_test::recomputedResidual;

TEST(Islands, FindsTheGroupsOfInterleavedContacts) {
  for (bool sparse : {false, true}) {
    Generated g = generate(5, 6, Kinds::kMixed, 3);
    const Problem p = sparse ? hard::toBlockSparse(g.problem) : g.problem;
    const Islands islands = findIslands(p);
    ASSERT_EQ(islands.count(), 5) << (sparse ? "block-sparse" : "dense");
    for (std::size_t i = 0; i < p.contacts.size(); ++i)
      for (std::size_t j = 0; j < p.contacts.size(); ++j)
        EXPECT_EQ(islands.island_of[i] == islands.island_of[j], g.group_of[i] == g.group_of[j]);
    int total = 0;
    for (const auto& c : islands.contacts) {
      EXPECT_TRUE(std::is_sorted(c.begin(), c.end()));
      total += static_cast<int>(c.size());
    }
    EXPECT_EQ(total, 30);
  }
}

// Random couplings, some in one triangle of W only (a non-symmetric W): the islands are the
// connected components of the graph whose edges are W's nonzero blocks, found here by a
// breadth-first search, one entry at a time, independent of findIslands' pair-wise pass.
// Every third trial has one-row contacts only (an LCP, MuJoCo's pyramid edges), which the
// dense pass reads without a loop over rows.
TEST(Islands, MatchAGraphSearchOverTheNonzeroBlocks) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 60; ++trial) {
    const int nc = 2 + static_cast<int>(rng() % 30);
    const bool one_row_each = trial % 3 == 0;
    Problem p;
    for (int i = 0; i < nc; ++i) {
      Contact c;
      c.type = one_row_each || rng() % 3 == 0 ? ContactType::kFrictionless : ContactType::kFrictional;
      c.rows = c.type == ContactType::kFrictionless ? 1 : 3;
      c.mu = 0.5;
      p.contacts.push_back(c);
    }
    const std::vector<int> off = p.rowOffsets();
    const int n = off.back();
    Eigen::MatrixXd W = Eigen::MatrixXd::Identity(n, n);
    const double density = 0.02 + 0.1 * (trial % 4);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int i = 0; i < nc; ++i)
      for (int j = 0; j < nc; ++j)
        if (i != j && u(rng) < density)  // one entry of block (i, j): maybe not of (j, i)
          W(off[i] + static_cast<int>(rng() % p.contacts[i].rows), off[j] + static_cast<int>(rng() % p.contacts[j].rows)) = 0.1;
    p.W = W;
    p.d_free = Eigen::VectorXd::Zero(n);
    std::vector<int> component(nc, -1);
    int components = 0;
    for (int s = 0; s < nc; ++s) {
      if (component[s] >= 0) continue;
      std::vector<int> queue{s};
      component[s] = components;
      for (std::size_t q = 0; q < queue.size(); ++q)
        for (int r = 0; r < n; ++r)
          for (int c = 0; c < n; ++c) {
            if (W(r, c) == 0.0) continue;
            const int a = static_cast<int>(std::upper_bound(off.begin(), off.end(), r) - off.begin()) - 1;
            const int b = static_cast<int>(std::upper_bound(off.begin(), off.end(), c) - off.begin()) - 1;
            const int other = a == queue[q] ? b : b == queue[q] ? a : -1;
            if (other >= 0 && component[other] < 0) {
              component[other] = components;
              queue.push_back(other);
            }
          }
      ++components;
    }
    for (const Problem& form : {p, hard::toBlockSparse(p)}) {
      const Islands islands = findIslands(form);
      ASSERT_EQ(islands.count(), components) << "trial " << trial;
      for (int i = 0; i < nc; ++i)
        for (int j = 0; j < nc; ++j)
          EXPECT_EQ(islands.island_of[i] == islands.island_of[j], component[i] == component[j]) << "trial " << trial;
    }
  }
}

TEST(Islands, OneGroupIsOneIsland) {
  Generated g = generate(1, 12, Kinds::kFrictional, 4);
  EXPECT_EQ(findIslands(g.problem).count(), 1);
  EXPECT_EQ(findIslands(hard::toBlockSparse(g.problem)).count(), 1);
}

TEST(Islands, IslandProblemKeepsTheRowsOfItsContacts) {
  Generated g = generate(3, 4, Kinds::kMixed, 5);
  const Islands islands = findIslands(g.problem);
  const std::vector<int> off = g.problem.rowOffsets();
  const Eigen::MatrixXd W = toDense(g.problem.W);
  for (const Problem& p : {g.problem, hard::toBlockSparse(g.problem)}) {
    const Problem sub = islandProblem(p, off, islands.contacts[1]);
    std::vector<int> rows;
    for (int i : islands.contacts[1])
      for (int r = off[i]; r < off[i + 1]; ++r) rows.push_back(r);
    EXPECT_EQ(Eigen::MatrixXd(W(rows, rows)), toDense(sub.W));
    EXPECT_EQ(Eigen::VectorXd(g.problem.d_free(rows)), sub.d_free);
    EXPECT_EQ(validateProblem(sub), "");
  }
}

// A fixed number of sweeps (tolerance out of reach): each island's Gauss-Seidel iterates
// are the whole problem's, whose other islands contribute exact zeros. The work reported is
// those sweeps on every island (iterations: the most one island took).
TEST(Islands, GaussSeidelSweepsEqualTheWholeProblem) {
  for (bool sparse : {false, true}) {
    for (SolverKind kind : {SolverKind::kNlgs, SolverKind::kPgs}) {
      Generated g = generate(4, 10, kind == SolverKind::kPgs ? Kinds::kFrictionless : Kinds::kMixed, 6);
      ASSERT_GE(g.problem.rowCount(), kMinRowsForIslands);  // else both solves are whole
      const Problem p = sparse ? hard::toBlockSparse(g.problem) : g.problem;
      const SolveResult whole = solveProblem(p, paramsFor(kind, 1e-300, 37, false));
      const SolveResult split = solveProblem(p, paramsFor(kind, 1e-300, 37, true));
      EXPECT_EQ(whole.iterations, 37);
      EXPECT_EQ(split.iterations, 37);
      EXPECT_EQ(whole.total_iterations, 37);
      const int islands = findIslands(p).count();
      ASSERT_GT(islands, 1);
      EXPECT_EQ(split.total_iterations, 37 * islands);
      EXPECT_LE(maxDiff(whole.forces, split.forces), 1e-12)
          << solverName(kind) << (sparse ? " sparse" : " dense");
      EXPECT_LE(maxDiff(whole.d, split.d), 1e-12);
      EXPECT_NEAR(whole.residual, split.residual, 1e-12 * std::max(1.0, whole.residual));
    }
  }
}

// Unique solutions (W positive definite, no friction) at tight tolerance: every solver on
// islands reaches the whole problem's solution, and the tolerance on the whole problem.
TEST(Islands, UniqueSolutionsEqualTheWholeProblem) {
  for (bool sparse : {false, true}) {
    Generated g = generate(6, 6, Kinds::kFrictionless, 7, 0.05);
    ASSERT_GE(g.problem.rowCount(), kMinRowsForIslands);
    const Problem p = sparse ? hard::toBlockSparse(g.problem) : g.problem;
    const SolveResult reference = solveProblem(p, paramsFor(SolverKind::kLemke, 1e-12, 100000, false));
    ASSERT_TRUE(reference.converged) << reference.message;
    for (SolverKind kind : {SolverKind::kPgs, SolverKind::kLemke, SolverKind::kNewton, SolverKind::kApgd}) {
      const SolveResult split = solveProblem(p, paramsFor(kind, 1e-12, 200000, true));
      EXPECT_TRUE(split.converged) << solverName(kind) << ": " << split.message;
      EXPECT_LE(split.residual, 1e-12) << solverName(kind);
      EXPECT_LE(maxDiff(split.forces, reference.forces), 1e-10)
          << solverName(kind) << (sparse ? " sparse" : " dense");
    }
  }
}

// The per-island tolerances add up to the whole problem's: converged means the whole
// residual meets the tolerance, also with islands whose d_free is zero.
TEST(Islands, ConvergedMeansTheWholeResidualMeetsTheTolerance) {
  Generated g = generate(5, 8, Kinds::kMixed, 8);
  ASSERT_GE(g.problem.rowCount(), kMinRowsForIslands);
  const std::vector<int> off = g.problem.rowOffsets();
  for (int i = 0; i < static_cast<int>(g.problem.contacts.size()); ++i)
    if (g.group_of[i] == 2)
      for (int r = off[i]; r < off[i + 1]; ++r) g.problem.d_free[r] = 0.0;
  for (double tol : {1e-3, 1e-6}) {
    const SolveResult r = solveProblem(g.problem, paramsFor(SolverKind::kNlgs, tol, 100000, true));
    ASSERT_TRUE(r.converged) << r.message;
    EXPECT_LE(r.residual, tol);
    EXPECT_LE(recomputedResidual(g.problem, r.forces), tol);
  }
}

// auto checks a zero start on the whole problem before it splits it: each island alone is
// held to its share of the tolerance, and the island whose start is worst would iterate.
// The independent check: the residual of the returned (zero) forces, recomputed from W.
TEST(Islands, AutoAcceptsAZeroStartThatMeetsTheToleranceAsAWhole) {
  for (unsigned seed : {3u, 4u, 5u}) {
    const Generated g = generate(4, 4, Kinds::kFrictional, seed);
    ASSERT_GE(g.problem.rowCount(), kMinRowsForIslands);
    const Eigen::VectorXd zero = Eigen::VectorXd::Zero(g.problem.rowCount());
    const double start = recomputedResidual(g.problem, zero);
    ASSERT_GT(start, 0.0);
    const double tol = 1.01 * start;  // the whole start meets it, not every island's alone
    const SolveResult r = solveProblem(g.problem, paramsFor(SolverKind::kAuto, tol, 100000, true));
    ASSERT_TRUE(r.converged) << r.message;
    EXPECT_EQ(r.solver, "auto") << "a member ran although the start was an answer";
    EXPECT_EQ(r.iterations, 0);
    EXPECT_EQ(r.forces, zero);
    EXPECT_LE(recomputedResidual(g.problem, r.forces), tol);
    EXPECT_NEAR(r.residual, start, 1e-12 * start);
  }
}

// Each island alone is held to its share of the tolerance, stricter than the whole problem's
// test, so from a start within a digit of the tolerance auto first sweeps the whole problem a
// few times (autoWholeSweepsEnd). Where those sweeps meet the tolerance they are the answer:
// nlgs's own three sweeps on the whole problem, not one run per island. Where they do not (the
// start two digits above it, or W coupled too strongly for three sweeps) the islands are
// solved as before and the sweeps are counted. Checked by the residual recomputed from W.
TEST(Islands, AutoEndsWithWholeSweepsWhereTheyMeetTheToleranceFirst) {
  for (unsigned seed : {21u, 22u, 23u}) {
    Generated g = generate(8, 5, Kinds::kFrictional, seed, 0.05);
    ASSERT_GE(g.problem.rowCount(), kMinRowsForIslands);
    const int count = findIslands(g.problem).count();
    ASSERT_GT(count, 3);
    const Eigen::VectorXd zero = Eigen::VectorXd::Zero(g.problem.rowCount());
    const double start = recomputedResidual(g.problem, zero);
    const SolveResult three = solveProblem(g.problem, paramsFor(SolverKind::kNlgs, 1e-300, 3, false));
    // a tolerance within a digit of the start that three whole sweeps meet
    const double tol = std::max(three.residual * 1.01, start / 9.0);
    ASSERT_LT(tol, start);
    const SolveResult whole = solveProblem(g.problem, paramsFor(SolverKind::kNlgs, tol, 3, false));
    ASSERT_TRUE(whole.converged) << "seed " << seed;
    const SolveResult r = solveProblem(g.problem, paramsFor(SolverKind::kAuto, tol, 100000, true));
    ASSERT_TRUE(r.converged) << r.message;
    EXPECT_EQ(r.solver, "auto:nlgs");
    EXPECT_EQ(r.iterations, whole.iterations);
    EXPECT_EQ(r.total_iterations, whole.iterations) << "one run on the whole problem, not one per island";
    EXPECT_EQ(r.forces, whole.forces);
    EXPECT_LE(recomputedResidual(g.problem, r.forces), tol);
    solvers_test::expectPath(r);
    // Two digits below the start: no whole sweeps, every island solved on its own.
    const double tight = 1e-2 * start;
    const SolveResult split = solveProblem(g.problem, paramsFor(SolverKind::kAuto, tight, 100000, true));
    ASSERT_TRUE(split.converged) << split.message;
    EXPECT_GE(split.total_iterations, count);
    EXPECT_LE(recomputedResidual(g.problem, split.forces), tight);
  }
}

// Where three whole sweeps fall short of a tolerance within a digit of the start, their iterate
// is dropped and the islands are solved as before, each from the start: the same forces as the
// same solve without the sweeps (a maxF that binds no contact leaves them out), three more
// iterations, and three more sweeps per island in the work. maxIt bounds both together.
TEST(Islands, WholeSweepsThatFallShortAreCountedAndTheIslandsGoOn) {
  const Generated g = generate(4, 12, Kinds::kFrictional, 31, 1e-2, 12);  // coupled groups: slower sweeps
  const int count = findIslands(g.problem).count();
  ASSERT_GT(count, 1);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(g.problem.rowCount());
  const double tol = recomputedResidual(g.problem, zero) / 9.0;
  const SolveResult three = solveProblem(g.problem, paramsFor(SolverKind::kNlgs, 1e-300, 3, false));
  ASSERT_GT(three.residual, tol) << "three sweeps would end it";
  const SolveResult r = solveProblem(g.problem, paramsFor(SolverKind::kAuto, tol, 100000, true));
  ASSERT_TRUE(r.converged) << r.message;
  EXPECT_LE(recomputedResidual(g.problem, r.forces), tol);
  solvers_test::expectPath(r);
  EXPECT_EQ(r.solver.rfind("auto:nlgs", 0), 0u) << r.solver;  // the sweeps are its first stage
  SolverParams without = paramsFor(SolverKind::kAuto, tol, 100000, true);
  without.maxF = 1e300;
  const SolveResult islands_alone = solveProblem(g.problem, without);
  ASSERT_TRUE(islands_alone.converged);
  EXPECT_EQ(r.forces, islands_alone.forces);
  EXPECT_EQ(r.iterations, islands_alone.iterations + 3);
  EXPECT_EQ(r.total_iterations, islands_alone.total_iterations + 3 * count);
  for (int max_it : {7, 9, 12}) {
    const SolveResult bounded = solveProblem(g.problem, paramsFor(SolverKind::kAuto, tol, max_it, true));
    EXPECT_LE(bounded.iterations, max_it) << "maxIt bounds the sweeps and the islands together";
  }
}

// auto on islands reports one island's path (the one that took longest): "auto:" and its
// stages' names, each stage's time within the solve's own.
TEST(Islands, AutoReportsThePathOfOneIslandWithItsTimes) {
  const Generated g = generate(6, 6, Kinds::kFrictional, 11);
  ASSERT_GE(g.problem.rowCount(), kMinRowsForIslands);
  for (double tol : {1e-4, 1e-8}) {
    const SolveResult r = solveProblem(g.problem, paramsFor(SolverKind::kAuto, tol, 100000, true));
    ASSERT_TRUE(r.converged) << r.message;
    EXPECT_LE(recomputedResidual(g.problem, r.forces), tol);
    solvers_test::expectPath(r);
  }
}

TEST(Islands, ResultsDoNotDependOnTheThreadCount) {
  for (bool sparse : {false, true}) {
    Generated g = generate(40, 4, Kinds::kMixed, 9);  // > 200 rows: the pool runs
    const Problem p = sparse ? hard::toBlockSparse(g.problem) : g.problem;
    for (SolverKind kind : {SolverKind::kNlgs, SolverKind::kNewton, SolverKind::kApgd, SolverKind::kAuto}) {
      const SolveResult one = solveProblem(p, paramsFor(kind, 1e-8, 100000, true, 1));
      for (int threads : {2, 3, 8, 0}) {
        const SolveResult many = solveProblem(p, paramsFor(kind, 1e-8, 100000, true, threads));
        EXPECT_EQ(one.forces, many.forces) << solverName(kind) << " threads " << threads;
        EXPECT_EQ(one.iterations, many.iterations);
        EXPECT_EQ(one.status, many.status);
      }
    }
  }
}

// One island with more rows than all the others together is solved last, with the part of
// the tolerance the others left unused. Here 60 coupled frictional contacts and 30 one-row
// contacts alone (W_ii = 1, d_free_i = -0.5: solved exactly by one sweep, residual 0), so the
// big island may use the whole problem's error budget: its sweeps are those of the big
// island alone at tol |d_free| / |d_free_big|, fewer than at its own share of the tolerance
// (√(½ s² + ½ / k) / s of it, s = |d_free_big| / |d_free|, k islands), which is what it was
// held to before. The same forces with the pool's threads; the whole residual, recomputed from
// W, meets the tolerance.
TEST(Islands, TheDominantIslandTakesTheToleranceTheOthersLeft) {
  const Generated big = generate(1, 60, Kinds::kFrictional, 41, 0.05);
  const int nb = big.problem.rowCount();
  const int singles = 30;
  Problem p = big.problem;
  Eigen::MatrixXd W = Eigen::MatrixXd::Zero(nb + singles, nb + singles);
  W.topLeftCorner(nb, nb) = std::get<Eigen::MatrixXd>(big.problem.W);
  p.d_free.conservativeResize(nb + singles);
  for (int k = 0; k < singles; ++k) {
    Contact c;
    c.id = 1000 + k;
    c.type = ContactType::kFrictionless;
    c.rows = 1;
    p.contacts.push_back(c);
    W(nb + k, nb + k) = 1.0;
    p.d_free[nb + k] = -0.5;
  }
  p.W = W;
  ASSERT_GT(p.rowCount(), 200) << "the pool runs with threads > 1";
  ASSERT_EQ(findIslands(p).count(), 1 + singles);
  const double s = big.problem.d_free.stableNorm() / p.d_free.stableNorm();
  const double own_share = std::sqrt(0.5 * s * s + 0.5 / (1 + singles)) / s;
  for (double tol : {1e-3, 1e-6}) {
    const SolveResult budget = solveProblem(big.problem, paramsFor(SolverKind::kNlgs, tol / s, 100000, false));
    const SolveResult share = solveProblem(big.problem, paramsFor(SolverKind::kNlgs, tol * own_share, 100000, false));
    ASSERT_TRUE(budget.converged && share.converged);
    ASSERT_LT(budget.iterations, share.iterations) << "the test needs a share that costs sweeps";
    const SolveResult r = solveProblem(p, paramsFor(SolverKind::kNlgs, tol, 100000, true, 1));
    ASSERT_TRUE(r.converged) << r.message;
    EXPECT_EQ(r.iterations, budget.iterations) << tol;
    EXPECT_EQ(r.forces.head(nb), budget.forces) << tol;
    EXPECT_LE(recomputedResidual(p, r.forces), tol);
    for (int threads : {2, 0}) {
      const SolveResult many = solveProblem(p, paramsFor(SolverKind::kNlgs, tol, 100000, true, threads));
      EXPECT_EQ(many.forces, r.forces) << "threads " << threads;
    }
    const SolveResult a = solveProblem(p, paramsFor(SolverKind::kAuto, tol, 100000, true));
    ASSERT_TRUE(a.converged) << a.message;
    EXPECT_LE(recomputedResidual(p, a.forces), tol) << a.solver;
  }
}

// Warm start and maxF with islands: a second solve from the first one's forces converges at
// once; maxF drops contacts and re-solves per island as on the whole problem.
TEST(Islands, WarmStartAndMaxFWork) {
  Generated g = generate(4, 10, Kinds::kFrictionless, 10, 0.05);
  ASSERT_GE(g.problem.rowCount(), kMinRowsForIslands);
  SolverParams p = paramsFor(SolverKind::kPgs, 1e-10, 100000, true);
  p.initial_guess = true;
  ContactSolver solver(p);
  const SolveResult first = solver.solve(g.problem);
  ASSERT_TRUE(first.converged);
  const SolveResult second = solver.solve(g.problem);
  EXPECT_TRUE(second.converged);
  EXPECT_LE(second.iterations, 1);
  const double limit = 0.5 * first.forces.maxCoeff();
  SolverParams capped = paramsFor(SolverKind::kLemke, 1e-12, 100000, true);
  capped.maxF = limit;
  SolverParams capped_whole = capped;
  capped_whole.islands = false;
  const SolveResult a = solveProblem(g.problem, capped), b = solveProblem(g.problem, capped_whole);
  EXPECT_GE(a.resolves, 1);
  EXPECT_EQ(a.states, b.states);
  EXPECT_LE(maxDiff(a.forces, b.forces), 1e-10);
}

// A kernel's message names the contact by its index in the whole problem, not in its island.
TEST(Islands, MessagesNameContactsOfTheWholeProblem) {
  Generated g = generate(3, 12, Kinds::kFrictionless, 71);
  ASSERT_GE(g.problem.rowCount(), kMinRowsForIslands);
  Eigen::MatrixXd W = std::get<Eigen::MatrixXd>(g.problem.W);
  const int k = 9;  // its own island, with no self-compliance
  W.row(k).setZero();
  W.col(k).setZero();
  g.problem.W = W;
  for (const Problem& p : {g.problem, hard::toBlockSparse(g.problem)}) {
    const SolveResult r = solveProblem(p, paramsFor(SolverKind::kPgs, 1e-8, 1000, true));
    EXPECT_EQ(r.status, SolveStatus::kZeroDiagonal);
    EXPECT_NE(r.message.find("contact 9 (id 109)"), std::string::npos) << r.message;
  }
}

// The body form: `groups` groups of 3 bodies; each contact joins two bodies of one group or
// one body and the world; contacts of all groups interleaved.
Problem bodyForm(int groups, int per_group, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0), pos(0.0, 1.0);
  auto bodies = std::make_shared<BodyCompliance>();
  for (int b = 0; b < 3 * groups; ++b) {
    BodyMatrix C = BodyMatrix::Zero();
    for (int k = 0; k < 6; ++k) C(k, k) = 1e-4 * (0.5 + pos(rng));
    bodies->body_compliance.push_back(C);
  }
  Problem p;
  for (int i = 0; i < groups * per_group; ++i) {
    const int g = static_cast<int>(rng() % groups);
    Contact c;
    c.id = 500 + i;
    c.type = pos(rng) < 0.7 ? ContactType::kFrictional : ContactType::kFrictionless;
    c.rows = c.type == ContactType::kFrictional ? 3 : 1;
    c.mu = c.type == ContactType::kFrictional ? 0.5 : -1.0;
    ContactJacobian cj;
    cj.rows = c.rows;
    cj.body_a = 3 * g + static_cast<int>(rng() % 3);
    cj.body_b = pos(rng) < 0.4 ? -1 : 3 * g + (cj.body_a - 3 * g + 1) % 3;
    cj.jacobian_a.resize(c.rows, 6);
    cj.jacobian_b.resize(cj.body_b >= 0 ? c.rows : 0, 6);
    for (int r = 0; r < c.rows; ++r)
      for (int k = 0; k < 6; ++k) {
        cj.jacobian_a(r, k) = u(rng);
        if (cj.body_b >= 0) cj.jacobian_b(r, k) = u(rng);
      }
    bodies->contacts.push_back(cj);
    p.contacts.push_back(c);
  }
  p.d_free.resize(bodies->rowCount());
  for (int r = 0; r < p.d_free.size(); ++r) p.d_free[r] = -1e-3 * pos(rng) + 2e-4 * u(rng);
  p.bodies = bodies;
  return p;
}

TEST(Islands, TheBodyFormSplitsByBodyAndEqualsTheWholeUnbuiltSolve) {
  const Problem p = bodyForm(6, 5, 61);
  ASSERT_EQ(validateProblem(p), "");
  ASSERT_GE(p.rowCount(), kMinRowsForIslands);
  Problem assembled = p;
  assembled.bodies.reset();
  assembled.W = p.bodies->assemble();
  const Islands by_body = findIslands(p), by_w = findIslands(assembled);
  EXPECT_GT(by_body.count(), 1);
  EXPECT_EQ(by_body.contacts, by_w.contacts);
  const std::vector<int> off = p.rowOffsets();
  for (const auto& island : by_body.contacts) {  // an island's body form is its rows of W
    const Problem sub = islandProblem(p, off, island);
    ASSERT_EQ(validateProblem(sub), "");
    EXPECT_LE(
        (sub.bodies->toDense() - toDense(islandProblem(assembled, off, island).W)).cwiseAbs().maxCoeff(),
        1e-15);
  }
  for (SolverKind kind : {SolverKind::kNlgs, SolverKind::kPgs}) {
    SolverParams whole = paramsFor(kind, 1e-300, 25, false), split = paramsFor(kind, 1e-300, 25, true);
    whole.build_lcp = split.build_lcp = false;
    const SolveResult a = solveProblem(p, whole), b = solveProblem(p, split);
    EXPECT_TRUE(a.unbuilt);
    EXPECT_TRUE(b.unbuilt);
    EXPECT_LE(maxDiff(a.forces, b.forces), 1e-12) << solverName(kind);
    for (int threads : {2, 5}) {
      split.threads = threads;
      EXPECT_EQ(solveProblem(p, split).forces, b.forces) << threads;
    }
  }
}

// ---- the symmetric active-set Newton ----------------------------------------------------

// An LCP's answer, checked independently of the solver: the residual recomputed from W,
// λ >= 0, d = W λ + d_free >= 0 and λ_i d_i = 0 to `tol`, and Lemke's pivoting (exact,
// another method) to 1e-8.
void expectLcpSolution(const Problem& p, const SolveResult& r, double tol) {
  EXPECT_LE(recomputedResidual(p, r.forces), tol);
  Eigen::VectorXd d;
  multiply(p.W, r.forces, d);
  d += p.d_free;
  const double scale = p.d_free.norm();
  EXPECT_GE(r.forces.minCoeff(), 0.0);
  EXPECT_GE(d.minCoeff(), -tol * scale);
  EXPECT_LE(r.forces.cwiseProduct(d).cwiseAbs().maxCoeff(), tol * scale * (1.0 + r.forces.maxCoeff()));
  const SolveResult lemke = solveProblem(p, paramsFor(SolverKind::kLemke, 1e-13, 100000, false));
  ASSERT_TRUE(lemke.converged) << lemke.message;
  EXPECT_LE(maxDiff(r.forces, lemke.forces), 1e-8);
}

TEST(SymmetricNewton, SolvesLcpsAndTheResidualOfItsForcesIsTheTolerance) {
  for (int groups : {1, 3, 40}) {  // 40 × 5 rows > the dense limit: the sparse LDLT path
    for (bool sparse : {false, true}) {
      Generated g = generate(groups, 5, Kinds::kFrictionless, 11 + groups, 1e-3);
      const Problem p = sparse ? hard::toBlockSparse(g.problem) : g.problem;
      const SolveResult r = solveProblem(p, paramsFor(SolverKind::kNewton, 1e-10, 1000, false));
      ASSERT_TRUE(r.converged) << r.message;
      EXPECT_NE(r.message.find("active-set"), std::string::npos) << r.message;
      expectLcpSolution(p, r, 1e-10);
    }
  }
}

// Dense LCPs of 60-250 rows whose active set moves by a few rows per step: from the second
// step on the Cholesky factor is updated (rows dropped by rank-1 updates, new rows appended)
// instead of computed again. The answer is checked as above (expectLcpSolution).
TEST(SymmetricNewton, UpdatedFactorsGiveTheSameSolutionAsLemke) {
  int steps_checked = 0;
  for (int n : {60, 150, 250}) {
    for (unsigned seed : {91u, 92u}) {
      Generated g = generate(1, n, Kinds::kFrictionless, seed, 1e-2, 3 * n);
      const Problem& p = g.problem;
      const SolveResult r = solveProblem(p, paramsFor(SolverKind::kNewton, 1e-12, 1000, false));
      ASSERT_TRUE(r.converged) << r.message;
      EXPECT_NE(r.message.find("active-set"), std::string::npos) << r.message;
      if (r.iterations >= 2) ++steps_checked;
      SCOPED_TRACE(testing::Message() << n << " rows, seed " << seed);
      expectLcpSolution(p, r, 1e-12);
    }
  }
  EXPECT_GE(steps_checked, 4) << "most of these need more than one Newton step";
}

TEST(SymmetricNewton, BilateralAndZeroFrictionRows) {
  Generated g = generate(2, 6, Kinds::kMixed, 21, 1e-2);
  for (Contact& c : g.problem.contacts) {
    if (c.type == ContactType::kFrictional) c.mu = 0.0;  // compacted to one row
  }
  g.problem.contacts[1].type = ContactType::kBilateral;
  g.problem.contacts[1].mu = -1.0;
  const SolveResult r = solveProblem(g.problem, paramsFor(SolverKind::kNewton, 1e-10, 1000, false));
  ASSERT_TRUE(r.converged) << r.message;
  EXPECT_NE(r.message.find("active-set"), std::string::npos) << r.message;
  EXPECT_LE(recomputedResidual(g.problem, r.forces), 1e-10);
}

// Warm started from the previous solve's forces (its active set): one step or none.
TEST(SymmetricNewton, WarmStartNeedsAtMostOneStep) {
  Generated g = generate(3, 8, Kinds::kFrictionless, 31, 1e-3);
  SolverParams p = paramsFor(SolverKind::kNewton, 1e-10, 1000, false);
  p.initial_guess = true;
  ContactSolver solver(p);
  ASSERT_TRUE(solver.solve(g.problem).converged);
  g.problem.d_free *= 1.01;  // the next step: same active set, slightly other values
  const SolveResult next = solver.solve(g.problem);
  ASSERT_TRUE(next.converged);
  EXPECT_LE(next.iterations, 1);
  EXPECT_LE(recomputedResidual(g.problem, next.forces), 1e-10);
}

// Not the symmetric path: friction, or a non-symmetric W; newton still solves them.
TEST(SymmetricNewton, OtherProblemsTakeTheGeneralNewton) {
  Generated g = generate(2, 5, Kinds::kFrictional, 41, 1e-2);
  const SolveResult friction = solveProblem(g.problem, paramsFor(SolverKind::kNewton, 1e-9, 1000, false));
  EXPECT_TRUE(friction.converged) << friction.message;
  EXPECT_EQ(friction.message.find("active-set"), std::string::npos);
  Generated h = generate(2, 5, Kinds::kFrictionless, 42, 0.5);
  Eigen::MatrixXd W = std::get<Eigen::MatrixXd>(h.problem.W);
  W(0, 1) += 0.01;  // a P-matrix still, not symmetric
  h.problem.W = W;
  const SolveResult skew = solveProblem(h.problem, paramsFor(SolverKind::kNewton, 1e-10, 1000, false));
  EXPECT_TRUE(skew.converged) << skew.message;
  EXPECT_EQ(skew.message.find("active-set"), std::string::npos) << skew.message;
  EXPECT_LE(recomputedResidual(h.problem, skew.forces), 1e-10);
}

// Singular W (more rows than degrees of freedom, no diagonal shift): the forces are not
// unique; the active-set path solves the semidefinite W_AA by a pivoted LDLᵀ without its
// zero pivots, and the residual of the forces is the tolerance.
TEST(SymmetricNewton, RankDeficientWStillSolved) {
  Generated g = generate(2, 10, Kinds::kFrictionless, 51, 0.0, 4);
  // A solvable one: d_free = -W λ* + s with λ* >= 0, s >= 0, λ*ᵀ s = 0.
  const Eigen::MatrixXd W = std::get<Eigen::MatrixXd>(g.problem.W);
  Eigen::VectorXd star = Eigen::VectorXd::Zero(W.rows()), slack = Eigen::VectorXd::Zero(W.rows());
  for (int i = 0; i < W.rows(); ++i) (i % 3 == 0 ? star[i] : slack[i]) = 0.1 + 0.01 * i;
  g.problem.d_free = -W * star + slack;
  const SolveResult r = solveProblem(g.problem, paramsFor(SolverKind::kNewton, 1e-8, 5000, false));
  EXPECT_TRUE(r.converged) << r.message;
  EXPECT_NE(r.message.find("active-set"), std::string::npos) << r.message;
  EXPECT_LE(recomputedResidual(g.problem, r.forces), 1e-8);
  // W = [1 1; 1 1] (rank one), q = -1: every λ >= 0 on λ1 + λ2 = 1 solves it, in one step.
  Problem line;
  line.W = Eigen::MatrixXd::Ones(2, 2);
  line.d_free = -Eigen::VectorXd::Ones(2);
  for (int i = 0; i < 2; ++i) {
    Contact c;
    c.id = i;
    c.type = ContactType::kFrictionless;
    c.rows = 1;
    line.contacts.push_back(c);
  }
  const SolveResult one = solveProblem(line, paramsFor(SolverKind::kNewton, 1e-10, 100, false));
  ASSERT_TRUE(one.converged) << one.message;
  EXPECT_NE(one.message.find("active-set"), std::string::npos) << one.message;
  EXPECT_EQ(one.iterations, 1);
  EXPECT_LE(recomputedResidual(line, one.forces), 1e-10);
  EXPECT_NEAR(one.forces.sum(), 1.0, 1e-12);
  EXPECT_GE(one.forces.minCoeff(), 0.0);
}

// ---- the sticking active-set path ---------------------------------------------------------

// Frictional contacts at rest: d_free = u - W λ* with every λ* pressed and strictly inside
// its cone and u = 0 (every contact sticks), except `sliding`, whose force is on the cone's
// edge against a tangential velocity it keeps (u_t opposite λ_t): it slides. Both are the
// conditions Coulomb's law states, so λ* solves the problem by construction.
struct Resting {
  Problem problem;
  Eigen::VectorXd star;
};

Resting resting(int contacts, unsigned seed, double delta, int dof, int sliding = -1) {
  Resting r;
  r.problem = generate(1, contacts, Kinds::kFrictional, seed, delta, dof).problem;
  const std::vector<int> off = r.problem.rowOffsets();
  const Eigen::MatrixXd W = std::get<Eigen::MatrixXd>(r.problem.W);
  r.star.resize(off.back());
  Eigen::VectorXd u = Eigen::VectorXd::Zero(off.back());
  for (int i = 0; i < contacts; ++i) {
    const double normal = 0.5 + 0.1 * i, angle = 0.7 * i;
    const double mu = r.problem.contacts[i].mu;
    const double t = (i == sliding ? 1.0 : 0.5) * mu * normal;
    r.star.segment<3>(off[i]) << normal, t * std::cos(angle), t * std::sin(angle);
    if (i == sliding) u.segment<2>(off[i] + 1) << -0.2 * std::cos(angle), -0.2 * std::sin(angle);
  }
  r.problem.d_free = u - W * r.star;
  return r;
}

// Resting contacts: the sticking path, one Cholesky step after the warm-up. A contact that
// slides: the answer cannot be that path's (u_t = 0 on every contact), and the general
// Newton reaches the constructed solution.
TEST(StickingNewton, RestingContactsTakeTheStickingPathASlidingOneDoesNot) {
  struct Case {
    unsigned seed;
    int sliding;
  };
  for (const Case c : {Case{61, -1}, Case{62, -1}, Case{63, -1}, Case{64, 2}}) {
    SCOPED_TRACE(c.seed);
    const bool sticks = c.sliding < 0;
    const Resting r = resting(6, c.seed, 1e-3, 24, c.sliding);
    const SolveResult s = solveProblem(r.problem, paramsFor(SolverKind::kNewton, 1e-10, 1000, false));
    ASSERT_TRUE(s.converged) << s.message;
    EXPECT_EQ(s.message.find("sticking active-set") != std::string::npos, sticks) << s.message;
    EXPECT_LE(recomputedResidual(r.problem, s.forces), 1e-10);
    EXPECT_LE(maxDiff(s.forces, r.star), sticks ? 1e-8 : 1e-6);
  }
}

// Sticking rows beyond the bodies' degrees of freedom with no diagonal shift (18 rows, 12
// DoF): the forces are not unique (W_AA singular, which the sticking path declines), and
// newton still reaches the tolerance.
TEST(StickingNewton, SingularStickingRowsAreStillSolved) {
  const Resting r = resting(6, 65, 0.0, 12);
  const SolveResult s = solveProblem(r.problem, paramsFor(SolverKind::kNewton, 1e-9, 5000, false));
  ASSERT_TRUE(s.converged) << s.message;
  EXPECT_LE(recomputedResidual(r.problem, s.forces), 1e-9);
}

// auto tries the path after its Gauss-Seidel probe where the probe's iterate sticks and the
// tolerance is out of the sweeps' cheap reach; not at a loose tolerance.
TEST(StickingNewton, AutoEndsARestingProblemWithIt) {
  const Resting r = resting(8, 66, 1e-3, 30);
  SolverParams tight = paramsFor(SolverKind::kAuto, 1e-10, 100000, false);
  const SolveResult s = solveProblem(r.problem, tight);
  ASSERT_TRUE(s.converged) << s.message;
  EXPECT_EQ(s.solver, "auto:nlgs->active-set");
  EXPECT_LE(recomputedResidual(r.problem, s.forces), 1e-10);
  EXPECT_LE(maxDiff(s.forces, r.star), 1e-8);
  const SolveResult loose = solveProblem(r.problem, paramsFor(SolverKind::kAuto, 1e-1, 100000, false));
  ASSERT_TRUE(loose.converged) << loose.message;
  EXPECT_EQ(loose.solver.find("active-set"), std::string::npos) << loose.solver;
  EXPECT_LE(recomputedResidual(r.problem, loose.forces), 1e-1);
  const Resting slide = resting(8, 67, 1e-3, 30, 5);
  const SolveResult slid = solveProblem(slide.problem, tight);
  ASSERT_TRUE(slid.converged) << slid.message;
  EXPECT_LE(recomputedResidual(slide.problem, slid.forces), 1e-10);
}

// The next step of a scene at rest, warm-started from the last: the warm start sticks
// everywhere, so auto tries its active set first and ends in one step, before any sweep.
// With u = 0 on every row the forces scale with d_free: 1.01 λ*.
TEST(StickingNewton, AWarmStartThatSticksIsTriedFirst) {
  Resting r = resting(8, 68, 1e-3, 30);
  SolverParams p = paramsFor(SolverKind::kAuto, 1e-10, 100000, false);
  p.initial_guess = true;
  ContactSolver solver(p);
  ASSERT_TRUE(solver.solve(r.problem).converged);
  r.problem.d_free *= 1.01;
  const SolveResult next = solver.solve(r.problem);
  ASSERT_TRUE(next.converged) << next.message;
  EXPECT_EQ(next.solver, "auto:active-set");
  EXPECT_EQ(next.iterations, 1);
  EXPECT_LE(recomputedResidual(r.problem, next.forces), 1e-10);
  EXPECT_LE(maxDiff(next.forces, 1.01 * r.star), 1e-8);
}

}  // namespace
}  // namespace lcp_contact_solver::core
