// The entry point of the core: validates a problem, applies SOFA's parameters (warm start,
// regularization, minW, maxF), runs the chosen kernel and reports a SolveResult that never
// holds a non-finite number.
#pragma once

#include "lcp_contact_solver/core/problem.h"
#include "lcp_contact_solver/core/solve_result.h"
#include "lcp_contact_solver/core/solver_params.h"

#include <Eigen/Core>

#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

namespace lcp_contact_solver::core {

struct KernelReport;

class ContactSolver {
 public:
  explicit ContactSolver(const SolverParams& params = SolverParams());

  // Returns an empty string on success, otherwise why the parameters were refused (the
  // previous ones stay in force).
  std::string setParams(const SolverParams& params);
  const SolverParams& params() const { return params_; }

  // Solves `problem` with its erp/softness applied (stabilization.h); the result's d and
  // residual are those of the problem as solved.
  SolveResult solve(const Problem& problem);
  // The same solve and result without copying W for erp/softness: they are applied to
  // `problem` itself (d_free's normal rows, W's normal diagonal) and undone bit for bit
  // before this returns. Nothing else may read `problem` meanwhile.
  SolveResult solveInPlace(Problem& problem);

  // Forgets the forces remembered for warm starting.
  void resetWarmStart() {
    remembered_.clear();
    remembered_forces_.clear();
  }
  std::size_t warmStartSize() const { return remembered_.size(); }

 private:
  using Clock = std::chrono::steady_clock;
  struct Prepared;  // what the kernels solve and what the result reports on

  // After validation and stabilization: `stated` is the problem as solved. The stages below
  // in order (contact_solver.cpp): prepare, solvePrepared, expandForces, measureResult,
  // explainResult.
  SolveResult solveStated(const Problem& stated, Clock::time_point start);
  void prepare(const Problem& stated, Clock::time_point start, Prepared& p) const;
  bool refusesExtendedFriction(const Prepared& p, Clock::time_point start, SolveResult& result) const;
  KernelReport solvePrepared(Prepared& p, Eigen::VectorXd& lambda, SolveResult& result) const;
  void expandForces(const Prepared& p, Eigen::VectorXd lambda, KernelReport& report,
                    SolveResult& result) const;
  void measureResult(const Prepared& p, KernelReport& report, SolveResult& result) const;
  void explainResult(const Prepared& p, SolveResult& result) const;
  SolveResult invalidInput(const std::string& error) const;
  Eigen::VectorXd initialGuess(const Problem& problem, const std::vector<int>& offsets) const;
  void rememberForces(const Problem& problem, const std::vector<int>& offsets, const Eigen::VectorXd& lambda);

  SolverParams params_;
  // The forces of the latest solve by contact id, flat so that a cycle allocates nothing
  // per contact: entries sorted by id, each naming its rows of remembered_forces_.
  struct RememberedContact {
    std::int64_t id;
    int offset;
    int rows;
  };
  std::vector<RememberedContact> remembered_;
  std::vector<double> remembered_forces_;
};

// One-off solve without warm start memory.
SolveResult solveProblem(const Problem& problem, const SolverParams& params);

}  // namespace lcp_contact_solver::core
