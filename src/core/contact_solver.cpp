#include "lcp_contact_solver/core/contact_solver.h"

#include "lcp_contact_solver/core/body_compliance.h"
#include "lcp_contact_solver/core/islands.h"
#include "lcp_contact_solver/core/kernels.h"
#include "lcp_contact_solver/core/residual.h"
#include "lcp_contact_solver/core/stabilization.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <sstream>

namespace lcp_contact_solver {

// ---- SolveContext ---------------------------------------------------------------------------

void SolveContext::computeD(const Eigen::VectorXd& lambda, Eigen::VectorXd& d) const {
  multiplyCompliance(*problem, lambda, d);  // the body form (unbuilt solve) without forming W
  d += problem->d_free;
  if (regularization != 0.0) d += regularization * lambda;
}

double SolveContext::residual(const Eigen::VectorXd& lambda) const {
  Eigen::VectorXd d;
  computeD(lambda, d);
  return naturalMapResidual(*problem, mu, lambda, d, ignored);
}

bool SolveContext::hasFriction() const {
  for (std::size_t i = 0; i < problem->contacts.size(); ++i)
    if ((ignored.empty() || !ignored[i]) && hasSlidingFriction(problem->contacts[i].type) && mu[i] > 0.0)
      return true;
  return false;
}

// ---- ContactSolver --------------------------------------------------------------------------

namespace {

using Clock = std::chrono::steady_clock;

bool pyramidModel(const SolverParams& params) {
  return params.friction_model != FrictionModel::kCoulombDisc;
}

// auto: a pyramid makes friction an LCP, solved by (boxed) pgs; no friction: pgs. The disc,
// from the work-precision study (docs/BENCHMARKS.md: cold solves of the fc3d set and of the
// scene problems): nlgs is the fastest down to a residual of 1e-4; from 1e-5 on, nlgs stalls
// on rank-deficient stacks (BoxesStack, OneObject, box pyramids) where newton reaches 1e-8
// in milliseconds on up to a few hundred rows, while on larger problems newton's
// factorizations cost more than apgd's matrix-vector products.
constexpr double kAutoTightTolerance = 1e-4;  // tolerance below this: newton or apgd
constexpr int kAutoNewtonMaxRows = 200;       // newton up to this many rows, apgd above

// Torsional or rolling contacts: only nlgs has their local step.
bool hasExtendedFriction(const Problem& problem) {
  for (const Contact& c : problem.contacts)
    if (c.type == ContactType::kTorsional || c.type == ContactType::kRolling) return true;
  return false;
}

SolverKind resolveKind(SolverKind kind, const SolveContext& ctx) {
  if (kind != SolverKind::kAuto) return kind;
  if (hasExtendedFriction(*ctx.problem)) return SolverKind::kNlgs;
  if (!ctx.hasFriction() || pyramidModel(*ctx.params)) return SolverKind::kPgs;
  // The unbuilt solve (body form, build_lcp = false) is Gauss-Seidel, as in SOFA: nlgs at
  // any tolerance (newton and apgd would need the assembled W).
  if (ctx.problem->bodies) return SolverKind::kNlgs;
  const SolverParams& p = *ctx.params;
  if (p.stopping_rule == StoppingRule::kResidual && p.tolerance < kAutoTightTolerance)
    return ctx.problem->rowCount() <= kAutoNewtonMaxRows ? SolverKind::kNewton : SolverKind::kApgd;
  return SolverKind::kNlgs;
}

// Lemke ends when z0 leaves the basis: exact in exact arithmetic, but on an ill-conditioned
// W (mass ratios of 1e6, rank deficiency) the basic solution can miss the tolerance by
// round-off. "converged" means the residual reached the tolerance, for every solver, so
// that is a numerical failure (the pyramid variant does the same in pyramid.cpp).
KernelReport honestLemke(KernelReport report, const SolverParams& params) {
  if (report.status == SolveStatus::kConverged && params.stopping_rule == StoppingRule::kResidual &&
      report.solver_error > params.tolerance) {
    report.status = SolveStatus::kNumericalFailure;
    std::ostringstream message;
    message << "Lemke's final basis leaves a residual of " << report.solver_error << " > tolerance "
            << params.tolerance << " (round-off over " << report.iterations
            << " pivots on an ill-conditioned W); the forces are that basic solution";
    report.message = message.str();
  }
  return report;
}

KernelReport runKernel(SolverKind kind, const SolveContext& ctx, Eigen::VectorXd& lambda) {
  const bool pyramid = pyramidModel(*ctx.params) && ctx.hasFriction();
  switch (kind) {
    case SolverKind::kPgs:
      return pyramid ? runBoxedGaussSeidel(ctx, lambda) : runProjectedGaussSeidel(ctx, lambda);
    case SolverKind::kLemke:
      return pyramid ? runPyramidLemke(ctx, lambda) : honestLemke(runLemke(ctx, lambda), *ctx.params);
    case SolverKind::kApgd: return runApgd(ctx, lambda);
    case SolverKind::kNewton: return runNewton(ctx, lambda);
    case SolverKind::kNlgs:
    case SolverKind::kAuto: break;
  }
  return runNonlinearGaussSeidel(ctx, lambda);
}

// minW: a contact whose normal self-compliance (regularized) is at most minW gets no force.
std::vector<bool> contactsBelowMinW(const Problem& problem, const std::vector<int>& offsets,
                                    double min_w, double regularization) {
  std::vector<bool> ignored(problem.contacts.size(), false);
  if (min_w <= 0.0) return ignored;
  for (std::size_t i = 0; i < problem.contacts.size(); ++i) {
    const double w_nn = contactDiagonalBlock(problem, offsets, static_cast<int>(i))(0, 0) + regularization;
    ignored[i] = w_nn <= min_w;
  }
  return ignored;
}

// Rows the kernels must leave at zero: ignored contacts, tangents of μ = 0 contacts.
void zeroInactiveRows(const SolveContext& ctx, Eigen::VectorXd& lambda) {
  const Problem& problem = *ctx.problem;
  for (std::size_t i = 0; i < problem.contacts.size(); ++i) {
    const int off = ctx.offsets[i];
    const Contact& c = problem.contacts[i];
    if (ctx.ignored[i]) {
      lambda.segment(off, c.rows).setZero();
    } else if (hasSlidingFriction(c.type) && ctx.mu[i] == 0.0) {
      lambda.segment(off + 1, 2).setZero();
    }
  }
}

// maxF: marks contacts whose force norm exceeds the limit; returns how many.
int dropContactsAboveMaxF(SolveContext& ctx, const Eigen::VectorXd& lambda, double max_f) {
  int dropped = 0;
  for (std::size_t i = 0; i < ctx.problem->contacts.size(); ++i) {
    if (ctx.ignored[i]) continue;
    const double force = lambda.segment(ctx.offsets[i], ctx.problem->contacts[i].rows).norm();
    if (force > max_f) {
      ctx.ignored[i] = true;
      ++dropped;
    }
  }
  return dropped;
}

// Solvers that run on the body form without assembling W (build_lcp = false).
bool runsUnbuilt(SolverKind kind) {
  return kind == SolverKind::kAuto || kind == SolverKind::kPgs || kind == SolverKind::kNlgs;
}

// The problem with the body form replaced by its assembled, block-sparse W.
Problem assembledProblem(const Problem& problem) {
  Problem out;
  out.contacts = problem.contacts;
  out.d_free = problem.d_free;
  out.name = problem.name;
  out.W = problem.bodies->assemble();
  return out;
}

// The kernel could not run, or ended on something that is not an approximate solution:
// its forces must not drive maxF drops nor seed the next warm start.
bool failedToRun(SolveStatus status) {
  return status == SolveStatus::kZeroDiagonal || status == SolveStatus::kNotApplicable ||
         status == SolveStatus::kRayTermination || status == SolveStatus::kNumericalFailure;
}

}  // namespace

ContactSolver::ContactSolver(const SolverParams& params) : params_(params) {}

std::string ContactSolver::setParams(const SolverParams& params) {
  std::string err = validateParams(params);
  if (err.empty()) params_ = params;
  return err;
}

Eigen::VectorXd ContactSolver::initialGuess(const Problem& problem, const std::vector<int>& offsets) const {
  Eigen::VectorXd lambda = Eigen::VectorXd::Zero(offsets.back());
  if (!params_.initial_guess) return lambda;
  for (std::size_t i = 0; i < problem.contacts.size(); ++i) {
    const auto it = warm_start_.find(problem.contacts[i].id);
    // Leading rows (normal first) also seed a contact that lost rows, e.g. μ set to 0.
    if (it == warm_start_.end() || static_cast<int>(it->second.size()) < problem.contacts[i].rows) continue;
    for (int k = 0; k < problem.contacts[i].rows; ++k) lambda[offsets[i] + k] = it->second[k];
  }
  return lambda;
}

void ContactSolver::rememberForces(const Problem& problem, const std::vector<int>& offsets,
                                   const Eigen::VectorXd& lambda) {
  // Only the contacts of the latest solve are kept: ids that vanished do not pile up.
  warm_start_.clear();
  for (std::size_t i = 0; i < problem.contacts.size(); ++i) {
    const int rows = problem.contacts[i].rows;
    warm_start_[problem.contacts[i].id].assign(lambda.data() + offsets[i], lambda.data() + offsets[i] + rows);
  }
}

namespace {

// A frictional contact whose μ is 0 has two tangent rows that can never carry force.
bool zeroFriction(const Contact& c, double default_mu) {
  return c.type == ContactType::kFrictional && (c.mu == 0.0 || (c.mu == Contact::kMuDefault && default_mu == 0.0));
}

// The problem without those rows: each such contact becomes a 1-row frictionless one, W and
// d_free keep its normal row only. `kept` maps each reduced row to its row in `p`.
struct Compaction {
  Problem reduced;
  std::vector<int> kept;
};

Compaction compactZeroFriction(const Problem& p, double default_mu) {
  Compaction out;
  out.reduced.name = p.name;
  out.reduced.contacts = p.contacts;
  const std::vector<int> offsets = p.rowOffsets();
  std::vector<std::vector<int>> local(p.contacts.size());  // kept rows of each contact, local index
  for (std::size_t i = 0; i < p.contacts.size(); ++i) {
    Contact& c = out.reduced.contacts[i];
    if (zeroFriction(c, default_mu)) {
      c.type = ContactType::kFrictionless;
      c.rows = 1;
    }
    for (int k = 0; k < c.rows; ++k) {
      local[i].push_back(k);
      out.kept.push_back(offsets[i] + k);
    }
  }
  out.reduced.d_free = p.d_free(out.kept);
  if (const auto* dense = std::get_if<Eigen::MatrixXd>(&p.W)) {
    out.reduced.W = Eigen::MatrixXd((*dense)(out.kept, out.kept));
    return out;
  }
  const auto& W = std::get<BlockSparseMatrix>(p.W);
  std::vector<int> sizes;
  for (const Contact& c : out.reduced.contacts) sizes.push_back(c.rows);
  BlockSparseMatrix R = BlockSparseMatrix::withBlockSizes(sizes);
  for (int i = 0; i < W.blockCount(); ++i) {
    R.beginRow();
    for (int b = W.row_start[i]; b < W.row_start[i + 1]; ++b) {
      const int j = W.block_col[b];
      const int cols = p.contacts[j].rows;
      const Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> block(
          W.values.data() + W.value_start[b], p.contacts[i].rows, cols);
      R.addBlock(j, Eigen::MatrixXd(block(local[i], local[j])));
    }
  }
  out.reduced.W = std::move(R);
  return out;
}

}  // namespace

SolveResult ContactSolver::solve(const Problem& input) {
  const Clock::time_point start = Clock::now();
  SolveResult result;
  result.solver = solverName(params_.solver);
  std::string err = validateParams(params_);
  if (err.empty()) err = validateProblem(input, params_.max_rows);
  // Baumgarte and softness change d_free and W: solve a copy, only when they are used.
  Problem stabilized;
  const bool stabilize = err.empty() && needsStabilization(input, params_);
  if (stabilize) {
    stabilized = input;
    err = applyStabilization(params_, &stabilized);
  }
  if (!err.empty()) {
    result.status = SolveStatus::kInvalidInput;
    result.message = err;
    return result;
  }
  const Problem& stated = stabilize ? stabilized : input;
  // build_lcp with the body form: Gauss-Seidel runs unbuilt on it (false); every other case
  // assembles the block-sparse W once and solves as usual.
  const bool unbuilt = stated.bodies && !params_.build_lcp && runsUnbuilt(params_.solver);
  Problem assembled;
  if (stated.bodies && !unbuilt) assembled = assembledProblem(stated);
  const Problem& base = stated.bodies && !unbuilt ? assembled : stated;
  // μ = 0 contacts cost one row (README "Contact models"): the kernels run without their
  // tangent rows; forces, d, residual and states are reported on every row of `base`.
  const bool compact = !unbuilt && std::any_of(base.contacts.begin(), base.contacts.end(), [this](const Contact& c) {
    return zeroFriction(c, params_.mu);
  });
  Compaction compaction;
  if (compact) compaction = compactZeroFriction(base, params_.mu);
  const Problem& problem = compact ? compaction.reduced : base;

  SolveContext ctx;
  ctx.problem = &problem;
  ctx.params = &params_;
  ctx.offsets = problem.rowOffsets();
  ctx.mu = effectiveMu(problem, params_.mu);
  ctx.regularization = params_.regularizationTerm;
  ctx.ignored = contactsBelowMinW(problem, ctx.offsets, params_.minW, ctx.regularization);
  if (params_.time_budget > 0.0) {
    ctx.has_deadline = true;
    ctx.deadline = start + std::chrono::duration_cast<Clock::duration>(
                               std::chrono::duration<double>(std::min(params_.time_budget, 1e7)));
  }

  const SolverKind kind = resolveKind(params_.solver, ctx);
  result.solver = solverName(kind);
  if (kind != SolverKind::kNlgs && hasExtendedFriction(problem)) {
    result.status = SolveStatus::kNotApplicable;
    result.message = std::string(solverName(kind)) +
                     " does not solve torsional or rolling friction (4- and 6-row contacts); use nlgs or auto";
    result.forces = Eigen::VectorXd::Zero(base.rowCount());
    result.d = base.d_free;
    result.states.assign(base.contacts.size(), ContactState::kOpen);
    result.solve_time = std::chrono::duration<double>(Clock::now() - start).count();
    return result;
  }
  // Independent islands of W are solved apart (islands.h), built once for every maxF pass.
  std::unique_ptr<IslandSolver> islands;
  // Newton on the disc stays whole: its globalisation (nlgs warm-up and bursts, ε from the
  // residual) reaches 1e-8 on Capsules-i101-404 whole but not on one of its 32 islands alone.
  const bool split = kind != SolverKind::kNewton || !ctx.hasFriction();
  if (params_.islands && split && !unbuilt && !params_.displayDebug && problem.contacts.size() > 1) {
    Islands found = findIslands(problem);
    if (found.count() > 1) islands = std::make_unique<IslandSolver>(ctx, std::move(found));
  }
  const int threads = params_.threads > 0 ? params_.threads : defaultThreadCount();
  Eigen::VectorXd lambda = initialGuess(problem, ctx.offsets);
  KernelReport report;
  // maxF: drop the contacts above the limit and solve the rest again, so the remaining
  // forces are consistent with the contacts that are left. Each pass drops at least one
  // contact, so this ends.
  for (;;) {
    zeroInactiveRows(ctx, lambda);
    const KernelReport pass =
        islands ? islands->run(ctx, [kind](const SolveContext& c, Eigen::VectorXd& l) { return runKernel(kind, c, l); },
                               lambda, threads)
                : runKernel(kind, ctx, lambda);
    report.status = pass.status;
    report.message = pass.message;
    report.solver_error = pass.solver_error;
    report.iterations += pass.iterations;
    report.history.insert(report.history.end(), pass.history.begin(), pass.history.end());
    report.friction_model = pass.friction_model;
    if (failedToRun(pass.status) || pass.status == SolveStatus::kTimeBudget || params_.maxF <= 0.0) break;
    if (dropContactsAboveMaxF(ctx, lambda, params_.maxF) == 0) break;
    ++result.resolves;
  }
  zeroInactiveRows(ctx, lambda);

  if (!lambda.allFinite()) {  // kernels promise finite output; this is the last guard
    lambda.setZero();
    report.status = SolveStatus::kNumericalFailure;
    report.message = "the solver produced a non-finite force; forces reset to zero";
  }
  result.forces = lambda;
  ctx.computeD(lambda, result.d);
  if (!result.d.allFinite()) {
    result.d.setZero();
    result.forces.setZero();
    report.status = SolveStatus::kNumericalFailure;
    report.message = "W λ overflowed; forces reset to zero";
  }
  if (compact) {  // back to every row: the dropped tangent rows carry no force
    Eigen::VectorXd forces = Eigen::VectorXd::Zero(base.rowCount());
    forces(compaction.kept) = result.forces;
    Eigen::VectorXd d;
    multiply(base.W, forces, d);
    d += base.d_free;
    d(compaction.kept) = result.d;  // the solved rows as solved (regularization included)
    if (!d.allFinite()) {
      d.setZero();
      forces.setZero();
      report.status = SolveStatus::kNumericalFailure;
      report.message = "W λ overflowed; forces reset to zero";
    }
    result.forces = std::move(forces);
    result.d = std::move(d);
  }
  const std::vector<double> reported_mu = compact ? effectiveMu(base, params_.mu) : ctx.mu;
  result.residual = naturalMapResidual(base, reported_mu, result.forces, result.d, ctx.ignored);
  result.states = classifyContacts(base, reported_mu, result.forces, ctx.ignored);
  result.status = report.status;
  result.converged = report.status == SolveStatus::kConverged;
  result.iterations = report.iterations;
  result.solver_error = std::isfinite(report.solver_error) ? report.solver_error : 0.0;
  result.message = report.message;
  result.friction_model = report.friction_model;
  if (pyramidModel(params_) && report.friction_model == FrictionModel::kCoulombDisc && ctx.hasFriction() &&
      !failedToRun(result.status)) {
    result.message += std::string(result.message.empty() ? "" : "; ") + "friction_model " +
                      frictionModelName(params_.friction_model) + " applies to pgs and lemke; " +
                      result.solver + " solved the Coulomb disc";
  }
  result.residual_history = std::move(report.history);
  result.unbuilt = unbuilt;
  if (!params_.build_lcp) {
    std::string note;
    if (unbuilt) {
      note = "unbuilt solve on the body form (" + std::to_string(stated.bodies->bodyCount()) + " bodies)";
    } else if (stated.bodies) {
      note = std::string("build_lcp=false: ") + solverName(params_.solver) +
             " needs the assembled W; assembled it from the body form (block-sparse)";
    } else {
      note = "build_lcp=false needs the body form of the compliance; solved on the assembled W";
    }
    result.message += std::string(result.message.empty() ? "" : "; ") + note;
  }
  if (!failedToRun(result.status)) rememberForces(base, base.rowOffsets(), result.forces);
  result.solve_time = std::chrono::duration<double>(Clock::now() - start).count();
  return result;
}

SolveResult solveProblem(const Problem& problem, const SolverParams& params) {
  ContactSolver solver(params);
  SolverParams no_warm_start = params;
  no_warm_start.initial_guess = false;
  solver.setParams(no_warm_start);
  return solver.solve(problem);
}

// ---- names ----------------------------------------------------------------------------------

const char* statusName(SolveStatus status) {
  switch (status) {
    case SolveStatus::kConverged: return "converged";
    case SolveStatus::kMaxIterations: return "max_iterations";
    case SolveStatus::kZeroDiagonal: return "zero_diagonal";
    case SolveStatus::kNotApplicable: return "not_applicable";
    case SolveStatus::kRayTermination: return "ray_termination";
    case SolveStatus::kNumericalFailure: return "numerical_failure";
    case SolveStatus::kInvalidInput: return "invalid_input";
    case SolveStatus::kTimeBudget: return "time_budget";
  }
  return "unknown";
}

const char* stateName(ContactState state) {
  switch (state) {
    case ContactState::kOpen: return "open";
    case ContactState::kStick: return "stick";
    case ContactState::kSlip: return "slip";
    case ContactState::kIgnored: return "ignored";
  }
  return "unknown";
}

}  // namespace lcp_contact_solver
