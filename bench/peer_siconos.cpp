// Siconos numerics as a peer (Debian libsiconos-numerics-dev 4.4): fc3d NSGS, NSN_AC and
// PROX through fc3d_driver, LCP Lemke and PGS through linearComplementarity_driver.
//
// Conversion (prepare, not timed): our dense W becomes an NM_DENSE matrix (column-major),
// our block-sparse W an NM_SPARSE_BLOCK matrix with 3x3 blocks (the storage the .dat file
// had), built from a triplet matrix by Siconos' own SBM_from_csparse so that Siconos
// allocates and frees everything itself. Siconos' convention u = M r + q is ours
// (d = W λ + d_free) with the same row order (normal, tangent, tangent), so forces need no
// conversion. Every solve starts from r = 0 with Siconos' default options except the
// tolerance and the iteration cap; fatal errors inside Siconos come back through its
// setjmp hook and are reported as "failed".
#include "peers.h"

#include <cmath>
#include <csetjmp>
#include <cstdlib>
#include <cstring>

extern "C" {
#include <FrictionContactProblem.h>
#include <Friction_cst.h>
#include <LinearComplementarityProblem.h>
#include <NumericsMatrix.h>
#include <NumericsVerbose.h>
#include <SiconosNumerics.h>
#include <SolverOptions.h>
#include <SparseBlockMatrix.h>
#include <lcp_cst.h>
#include <sn_error_handling.h>
}

namespace lcs_bench {
namespace {

namespace lcs = lcp_contact_solver;

// Builds a Siconos matrix with W's storage. Returns nullptr when a block-sparse W has
// blocks that are not 3x3 (Siconos' SBM fc3d path needs uniform blocks).
NumericsMatrix* toNumericsMatrix(const lcs::core::ComplianceMatrix& W, int block_size, bool csc = false) {
  const int n = lcs::core::complianceRows(W);
  if (const auto* dense = std::get_if<Eigen::MatrixXd>(&W)) {
    NumericsMatrix* M = NM_create(NM_DENSE, n, n);
    // Eigen's default storage is column-major, like Siconos' matrix0.
    std::memcpy(M->matrix0, dense->data(), sizeof(double) * static_cast<std::size_t>(n) * n);
    return M;
  }
  const auto& S = std::get<lcs::core::BlockSparseMatrix>(W);
  for (int b = 0; b < S.blockCount(); ++b)
    if (S.block_offset[b + 1] - S.block_offset[b] != block_size) return nullptr;
  NumericsMatrix* T = NM_create(NM_SPARSE, n, n);
  NM_triplet_alloc(T, static_cast<CS_INT>(S.values.size()));
  for (int br = 0; br < S.blockCount(); ++br) {
    const int r0 = S.block_offset[br];
    const int rows = S.block_offset[br + 1] - r0;
    for (int k = S.row_start[br]; k < S.row_start[br + 1]; ++k) {
      const int bc = S.block_col[k];
      const int c0 = S.block_offset[bc];
      const int cols = S.block_offset[bc + 1] - c0;
      const double* v = S.values.data() + S.value_start[k];
      for (int i = 0; i < rows; ++i)
        for (int j = 0; j < cols; ++j) NM_entry(T, r0 + i, c0 + j, v[i * cols + j]);
    }
  }
  if (csc) {
    NM_csc(T);
    return T;
  }
  SparseBlockStructuredMatrix* sbm = SBM_new();
  if (SBM_from_csparse(block_size, NM_csc(T), sbm) != 0) {
    SBM_clear(sbm);
    NM_free(T);
    return nullptr;
  }
  NM_free(T);
  return NM_new_SBM(n, n, sbm);
}

double* copyToMalloc(const Eigen::VectorXd& v) {
  double* p = static_cast<double*>(std::malloc(sizeof(double) * std::max<Eigen::Index>(v.size(), 1)));
  for (Eigen::Index i = 0; i < v.size(); ++i) p[i] = v[i];
  return p;
}

// The driver calls, guarded by Siconos' error hook (a fatal error longjmps back here).
// Plain C data only in these frames.
int guardedFc3d(FrictionContactProblem* p, double* r, double* u, SolverOptions* o, int* fatal) {
  *fatal = 0;
  if (setjmp(*sn_get_jmp_buf()) != 0) {
    sn_release_jmp_buf();
    *fatal = 1;
    return 1;
  }
  const int info = fc3d_driver(p, r, u, o);
  sn_release_jmp_buf();
  return info;
}

int guardedLcp(LinearComplementarityProblem* p, double* z, double* w, SolverOptions* o, int* fatal) {
  *fatal = 0;
  if (setjmp(*sn_get_jmp_buf()) != 0) {
    sn_release_jmp_buf();
    *fatal = 1;
    return 1;
  }
  const int info = linearComplementarity_driver(p, z, w, o);
  sn_release_jmp_buf();
  return info;
}

PeerOutcome outcome(int info, int fatal, const SolverOptions* options, const std::vector<double>& r,
                    bool iterative, const Setting& setting) {
  PeerOutcome out;
  out.forces = Eigen::Map<const Eigen::VectorXd>(r.data(), static_cast<Eigen::Index>(r.size()));
  out.iterations = options->iparam[SICONOS_IPARAM_ITER_DONE];
  out.self_error = options->dparam[SICONOS_DPARAM_RESIDU];
  out.claims_success = fatal == 0 && info == 0;
  if (fatal)
    out.status = "failed";
  else if (info == 0)
    out.status = "converged";
  else if (iterative && out.iterations >= setting.max_iterations)
    out.status = "max_iterations";
  else
    out.status = "failed";
  return out;
}

class SiconosFc3d : public Peer {
 public:
  // csc: hand a block-sparse W over as NM_SPARSE (compressed columns) instead of
  // NM_SPARSE_BLOCK; Siconos 4.4's PROX stops at once on a sparse-block matrix.
  SiconosFc3d(std::string name, int solver_id, bool csc = false)
      : name_(std::move(name)), id_(solver_id), csc_(csc) {}
  ~SiconosFc3d() override { release(); }
  std::string name() const override { return name_; }
  SweepKind sweep() const override { return SweepKind::kTolerance; }
  bool applies(const lcs::core::Problem& problem) const override { return isFc3d(problem); }

  // Siconos keeps state in the problem's matrix between calls (factorizations, work
  // arrays): a second PROX call on the same problem stops at once. So every solve gets a
  // fresh copy, built outside the timed region.
  void prepare(const lcs::core::Problem& problem) override { source_ = &problem; }
  void beforeSolve() override { build(*source_); }

  void build(const lcs::core::Problem& problem) {
    release();
    NumericsMatrix* M = toNumericsMatrix(problem.W, 3, csc_);
    if (M == nullptr) return;
    const std::vector<double> mu = [&] {
      std::vector<double> m;
      for (const lcs::core::Contact& c : problem.contacts) m.push_back(c.mu < 0 ? 0.6 : c.mu);
      return m;
    }();
    Eigen::VectorXd mu_v = Eigen::Map<const Eigen::VectorXd>(mu.data(), static_cast<Eigen::Index>(mu.size()));
    problem_ = frictionContactProblem_new_with_data(3, static_cast<int>(problem.contacts.size()), M,
                                                    copyToMalloc(problem.d_free), copyToMalloc(mu_v));
    n_ = problem.rowCount();
  }

  PeerOutcome solve(const Setting& setting) override {
    if (problem_ == nullptr) {
      PeerOutcome out;
      out.status = "not_applicable";
      return out;
    }
    SolverOptions* options = solver_options_create(id_);
    options->dparam[SICONOS_DPARAM_TOL] = setting.tolerance;
    options->iparam[SICONOS_IPARAM_MAX_ITER] = setting.max_iterations;
    std::vector<double> r(n_, 0.0), u(n_, 0.0);
    int fatal = 0;
    const int info = guardedFc3d(problem_, r.data(), u.data(), options, &fatal);
    PeerOutcome out = outcome(info, fatal, options, r, true, setting);
    solver_options_delete(options);
    return out;
  }

  void release() override {
    if (problem_ != nullptr) frictionContactProblem_free(problem_);
    problem_ = nullptr;
  }

 private:
  std::string name_;
  int id_;
  bool csc_;
  const lcs::core::Problem* source_ = nullptr;
  FrictionContactProblem* problem_ = nullptr;
  int n_ = 0;
};

class SiconosLcp : public Peer {
 public:
  SiconosLcp(std::string name, int solver_id, bool direct)
      : name_(std::move(name)), id_(solver_id), direct_(direct) {}
  ~SiconosLcp() override { release(); }
  std::string name() const override { return name_; }
  SweepKind sweep() const override { return direct_ ? SweepKind::kDirect : SweepKind::kTolerance; }
  bool applies(const lcs::core::Problem& problem) const override { return isLcp(problem); }

  void prepare(const lcs::core::Problem& problem) override { source_ = &problem; }
  void beforeSolve() override { build(*source_); }

  void build(const lcs::core::Problem& problem) {
    release();
    problem_ = newLCP();
    problem_->size = problem.rowCount();
    problem_->M = toNumericsMatrix(lcs::core::ComplianceMatrix(lcs::core::toDense(problem.W)), 1);
    problem_->q = copyToMalloc(problem.d_free);
    n_ = problem.rowCount();
  }

  PeerOutcome solve(const Setting& setting) override {
    SolverOptions* options = solver_options_create(id_);
    if (!std::isnan(setting.tolerance)) options->dparam[SICONOS_DPARAM_TOL] = setting.tolerance;
    if (setting.max_iterations > 0) options->iparam[SICONOS_IPARAM_MAX_ITER] = setting.max_iterations;
    std::vector<double> z(n_, 0.0), w(n_, 0.0);
    int fatal = 0;
    const int info = guardedLcp(problem_, z.data(), w.data(), options, &fatal);
    PeerOutcome out = outcome(info, fatal, options, z, !direct_, setting);
    solver_options_delete(options);
    return out;
  }

  void release() override {
    if (problem_ != nullptr) freeLinearComplementarityProblem(problem_);
    problem_ = nullptr;
  }

 private:
  std::string name_;
  int id_;
  bool direct_;
  const lcs::core::Problem* source_ = nullptr;
  LinearComplementarityProblem* problem_ = nullptr;
  int n_ = 0;
};

}  // namespace

std::vector<std::unique_ptr<Peer>> makeSiconosPeers() {
  numerics_set_verbose(std::getenv("LCS_SICONOS_VERBOSE") ? 1 : 0);
  std::vector<std::unique_ptr<Peer>> peers;
  peers.push_back(std::make_unique<SiconosFc3d>("siconos-nsgs", SICONOS_FRICTION_3D_NSGS));
  peers.push_back(std::make_unique<SiconosFc3d>("siconos-nsn-ac", SICONOS_FRICTION_3D_NSN_AC));
  peers.push_back(std::make_unique<SiconosFc3d>("siconos-prox", SICONOS_FRICTION_3D_PROX, true));
  peers.push_back(std::make_unique<SiconosLcp>("siconos-lemke", SICONOS_LCP_LEMKE, true));
  peers.push_back(std::make_unique<SiconosLcp>("siconos-pgs", SICONOS_LCP_PGS, false));
  return peers;
}

}  // namespace lcs_bench
