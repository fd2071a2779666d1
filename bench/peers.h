// Peer solvers measured by the benchmark (bench/work_precision.cpp; runPeer in
// work_precision_runs.cpp times them): solvers of other projects installed from Debian,
// behind one small interface so the driver times them the way it times ours. Each adapter converts our Problem once (prepare, not timed) and then
// solves from zero (solve, timed). Their answers are judged by our residual, never by their
// own report (kept in PeerOutcome::self_error for the CSV).
#pragma once

#include "lcp_contact_solver/core/problem.h"

#include <Eigen/Core>

#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace lcs_bench {

// One point of a sweep: a tolerance for iterative methods, an iteration count for methods
// without a residual-based stopping rule, or a single "direct" setting.
struct Setting {
  std::string label;  // as written in the CSV "setting" column
  double tolerance = std::numeric_limits<double>::quiet_NaN();
  int max_iterations = 0;  // the cap handed to the method
};

struct PeerOutcome {
  Eigen::VectorXd forces;       // one per row of our Problem, in our row order and sign
  std::string status;           // "converged", "max_iterations", "failed", ...
  bool claims_success = false;  // the method's own verdict
  int iterations = -1;          // as reported by the method (-1: none)
  double self_error = std::numeric_limits<double>::quiet_NaN();  // its own error measure
};

enum class SweepKind { kTolerance, kIterations, kDirect };

class Peer {
 public:
  virtual ~Peer() = default;
  virtual std::string name() const = 0;
  virtual SweepKind sweep() const = 0;
  // Whether the method treats this problem at all (e.g. an LCP solver needs no friction).
  virtual bool applies(const lcp_contact_solver::core::Problem& problem) const = 0;
  // Converts the problem into the method's own data; not timed.
  virtual void prepare(const lcp_contact_solver::core::Problem& problem) = 0;
  // Called before every solve, not timed: a peer whose data a solve may change rebuilds it.
  virtual void beforeSolve() {}
  // Solves the prepared problem from a zero initial guess; timed by the caller.
  virtual PeerOutcome solve(const Setting& setting) = 0;
  // Frees what prepare() built.
  virtual void release() = 0;
};

// Siconos numerics (libsiconos-numerics-dev): fc3d NSGS, NSN_AC, PROX; LCP Lemke and PGS.
std::vector<std::unique_ptr<Peer>> makeSiconosPeers();
// Bullet's MLCP solvers (libbullet-dev, float64 libraries): Dantzig and projected Gauss-Seidel,
// friction as a box whose bounds follow the normal force (limitDependency).
std::vector<std::unique_ptr<Peer>> makeBulletPeers();

// True when every contact is a 3-row frictional contact (what an fc3d solver accepts).
bool isFc3d(const lcp_contact_solver::core::Problem& problem);
// True when every contact is a 1-row frictionless contact (an LCP).
bool isLcp(const lcp_contact_solver::core::Problem& problem);

}  // namespace lcs_bench
