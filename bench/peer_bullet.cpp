// Bullet's MLCP solvers as peers (Debian libbullet-dev 3.24, the float64 libraries, built
// with BT_USE_DOUBLE_PRECISION): btDantzigSolver (ODE's Dantzig pivoting) and
// btSolveProjectedGaussSeidel, both through btMLCPSolverInterface::solveMLCP(A, b, x, lo, hi,
// limitDependency, numIterations, useSparsity).
//
// Bullet's MLCP is boxed: find x with lo_i <= x_i <= hi_i and w = A x - b, where w_i >= 0 at
// the lower bound, <= 0 at the upper bound, = 0 in between. With A = W and b = -d_free,
// w = W x + d_free = d, our convention. A frictional contact becomes
//   normal row:   [0, +inf)                         (limitDependency -1)
//   tangent rows: [-mu * x_n, +mu * x_n], each alone (limitDependency = the normal row)
// i.e. Bullet solves the BOX friction model (|x_t1|, |x_t2| <= mu x_n separately), not the
// Coulomb disc: its answers are measured with our disc residual like every other solver's,
// and the box residual of that model is reported beside it (model_residual in the CSV).
// A frictionless row is [0, +inf); a bilateral row (-inf, +inf).
//
// Dantzig is direct (numIterations unused). Bullet's PGS has no residual-based stopping
// rule (only a threshold on the squared change of x, 0 by default), so its sweep is over
// the iteration count.
#include "peers.h"

#include <BulletDynamics/MLCPSolvers/btDantzigSolver.h>
#include <BulletDynamics/MLCPSolvers/btSolveProjectedGaussSeidel.h>
#include <LinearMath/btMatrixX.h>

#include <cmath>

#ifndef BT_USE_DOUBLE_PRECISION
#error "the Bullet peer must be built against Bullet's float64 libraries (BT_USE_DOUBLE_PRECISION)"
#endif

namespace lcs_bench {
namespace {

namespace lcs = lcp_contact_solver;

class BulletPeer : public Peer {
 public:
  BulletPeer(std::string name, bool dantzig) : name_(std::move(name)), dantzig_(dantzig) {}
  std::string name() const override { return name_; }
  SweepKind sweep() const override { return dantzig_ ? SweepKind::kDirect : SweepKind::kIterations; }
  bool applies(const lcs::core::Problem& problem) const override { return problem.rowCount() > 0; }

  void prepare(const lcs::core::Problem& problem) override {
    const int n = problem.rowCount();
    const Eigen::MatrixXd W = lcs::core::toDense(problem.W);
    A_.resize(n, n);
    A_.setZero();
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j)
        if (W(i, j) != 0.0) A_.setElem(i, j, W(i, j));
    b_.resize(n);
    lo_.resize(n);
    hi_.resize(n);
    x_.resize(n);
    dependency_.resize(n);
    const std::vector<int> offsets = problem.rowOffsets();
    for (std::size_t c = 0; c < problem.contacts.size(); ++c) {
      const lcs::core::Contact& contact = problem.contacts[c];
      const int off = offsets[c];
      for (int k = 0; k < contact.rows; ++k) {
        const int i = off + k;
        b_[i] = -problem.d_free[i];
        dependency_[i] = -1;
        if (contact.type == lcs::core::ContactType::kBilateral) {
          lo_[i] = -BT_LARGE_FLOAT;
          hi_[i] = BT_LARGE_FLOAT;
        } else if (k == 0) {
          lo_[i] = 0.0;
          hi_[i] = BT_LARGE_FLOAT;
        } else {
          const double mu = contact.mu < 0 ? 0.6 : contact.mu;
          lo_[i] = -mu;
          hi_[i] = mu;
          dependency_[i] = off;
        }
      }
    }
  }

  PeerOutcome solve(const Setting& setting) override {
    const int n = b_.rows();
    for (int i = 0; i < n; ++i) x_[i] = 0.0;
    bool ok = false;
    double self_error = std::nan("");
    if (dantzig_) {
      btDantzigSolver solver;
      ok = solver.solveMLCP(A_, b_, x_, lo_, hi_, dependency_, 1, true);
    } else {
      btSolveProjectedGaussSeidel solver;
      ok = solver.solveMLCP(A_, b_, x_, lo_, hi_, dependency_, setting.max_iterations, true);
      self_error = solver.m_leastSquaresResidual;  // squared change of x in the last sweep
    }
    PeerOutcome out;
    out.forces.resize(n);
    for (int i = 0; i < n; ++i) out.forces[i] = x_[i];
    out.claims_success = ok;
    out.self_error = self_error;
    out.iterations = dantzig_ ? -1 : setting.max_iterations;
    // PGS always says true and always runs numIterations sweeps (threshold 0): "done".
    out.status = !ok ? "failed" : (dantzig_ ? "converged" : "done");
    return out;
  }

  void release() override {
    A_.resize(0, 0);
    b_.resize(0);
  }

 private:
  std::string name_;
  bool dantzig_;
  btMatrixXu A_;
  btVectorXu b_, x_, lo_, hi_;
  btAlignedObjectArray<int> dependency_;
};

}  // namespace

std::vector<std::unique_ptr<Peer>> makeBulletPeers() {
  std::vector<std::unique_ptr<Peer>> peers;
  peers.push_back(std::make_unique<BulletPeer>("bullet-dantzig", true));
  peers.push_back(std::make_unique<BulletPeer>("bullet-pgs", false));
  return peers;
}

}  // namespace lcs_bench
