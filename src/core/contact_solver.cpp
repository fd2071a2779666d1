// ContactSolver: validation, SOFA's parameters and the stages of one solve around a kernel.
#include "lcp_contact_solver/core/contact_solver.h"

#include "kernel_dispatch.h"
#include "portfolio.h"
#include "zero_friction.h"

#include "lcp_contact_solver/core/body_compliance.h"
#include "lcp_contact_solver/core/islands.h"
#include "lcp_contact_solver/core/kernels/kernels.h"
#include "lcp_contact_solver/core/residual.h"
#include "lcp_contact_solver/core/stabilization.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <sstream>

namespace lcp_contact_solver::core {

using Clock = std::chrono::steady_clock;

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
    const std::int64_t id = problem.contacts[i].id;
    const auto it = std::lower_bound(remembered_.begin(), remembered_.end(), id,
                                     [](const RememberedContact& r, std::int64_t key) { return r.id < key; });
    // Leading rows (normal first) also seed a contact that lost rows, e.g. μ set to 0.
    if (it == remembered_.end() || it->id != id || it->rows < problem.contacts[i].rows) continue;
    for (int k = 0; k < problem.contacts[i].rows; ++k) lambda[offsets[i] + k] = remembered_forces_[it->offset + k];
  }
  return lambda;
}

void ContactSolver::rememberForces(const Problem& problem, const std::vector<int>& offsets,
                                   const Eigen::VectorXd& lambda) {
  // Only the contacts of the latest solve are kept: ids that vanished do not pile up.
  remembered_forces_.assign(lambda.data(), lambda.data() + lambda.size());
  remembered_.clear();
  remembered_.reserve(problem.contacts.size());
  for (std::size_t i = 0; i < problem.contacts.size(); ++i)
    remembered_.push_back({problem.contacts[i].id, offsets[i], problem.contacts[i].rows});
  // Ids usually arrive in order: the sort (and its buffer) only when they do not.
  const auto by_id = [](const RememberedContact& a, const RememberedContact& b) { return a.id < b.id; };
  if (!std::is_sorted(remembered_.begin(), remembered_.end(), by_id))
    std::stable_sort(remembered_.begin(), remembered_.end(), by_id);
  // A repeated id keeps its last contact, as an assignment by id would.
  std::size_t kept = 0;
  for (std::size_t i = 0; i < remembered_.size(); ++i) {
    if (i + 1 < remembered_.size() && remembered_[i + 1].id == remembered_[i].id) continue;
    remembered_[kept++] = remembered_[i];
  }
  remembered_.resize(kept);
}

SolveResult ContactSolver::invalidInput(const std::string& error) const {
  SolveResult result;
  result.solver = solverName(params_.solver);
  result.status = SolveStatus::kInvalidInput;
  result.message = error;
  return result;
}

SolveResult ContactSolver::solve(const Problem& input) {
  const Clock::time_point start = Clock::now();
  std::string err = validateParams(params_);
  if (err.empty()) err = validateProblem(input, params_.max_rows);
  if (!err.empty()) return invalidInput(err);
  if (!needsStabilization(input, params_)) return solveStated(input, start);
  // Baumgarte and softness change d_free and W: solve a copy (solveInPlace does without).
  Problem stabilized = input;
  err = applyStabilization(params_, &stabilized);
  if (!err.empty()) return invalidInput(err);
  return solveStated(stabilized, start);
}

SolveResult ContactSolver::solveInPlace(Problem& problem) {
  const Clock::time_point start = Clock::now();
  std::string err = validateParams(params_);
  if (err.empty()) err = validateProblem(problem, params_.max_rows);
  if (!err.empty()) return invalidInput(err);
  if (!needsStabilization(problem, params_)) return solveStated(problem, start);
  StabilizationUndo undo;
  if (!applyStabilizationInPlace(params_, &problem, &undo, &err)) {  // rare: W needs a block added
    Problem stabilized = problem;
    err = applyStabilization(params_, &stabilized);
    if (!err.empty()) return invalidInput(err);
    return solveStated(stabilized, start);
  }
  if (!err.empty()) return invalidInput(err);
  struct Restore {  // also when the solve throws (bad_alloc)
    const StabilizationUndo& undo;
    Problem& problem;
    ~Restore() { undo.restore(&problem); }
  } restore{undo, problem};
  return solveStated(problem, start);
}

// ---- The stages of one solve --------------------------------------------------------------
//
// prepare: assemble the body form or stay unbuilt, compact μ = 0 rows, and form the context
//          the kernels read (row offsets, μ per contact, minW, the deadline);
// solve:   the kernel, by islands where W splits, again without the contacts maxF drops;
// finish:  expand the compacted rows, guard against non-finite output, residual and states
//          recomputed from the returned forces, the messages, and the warm-start memory.
// (Validation and erp/softness come before, in solve / solveInPlace.)

// What the kernels solve, and what the result reports on. Holds pointers into itself: built
// in place by prepare, never copied.
struct ContactSolver::Prepared {
  const Problem* stated = nullptr;  // after validation and stabilization
  bool unbuilt = false;             // Gauss-Seidel on the body form, W never assembled
  Problem assembled;                // the body form's W, when the kernel needs it
  const Problem* base = nullptr;    // reported on: `stated` or `assembled`
  bool compact = false;             // μ = 0 tangent rows left out of `problem`
  Compaction compaction;
  const Problem* problem = nullptr;  // solved: `base` or `compaction.reduced`
  SolveContext ctx;

  Prepared() = default;
  Prepared(const Prepared&) = delete;
  Prepared& operator=(const Prepared&) = delete;
};

namespace {

// Solvers that run on the body form without assembling W (build_lcp = false).
bool runsUnbuilt(SolverKind kind) {
  return kind == SolverKind::kAuto || kind == SolverKind::kPgs || kind == SolverKind::kNlgs;
}

// minW: a contact whose normal self-compliance (regularized) is at most minW gets no force.
std::vector<bool> contactsBelowMinW(const Problem& problem, const std::vector<int>& offsets, double min_w,
                                    double regularization) {
  std::vector<bool> ignored(problem.contacts.size(), false);
  if (min_w <= 0.0) return ignored;
  for (std::size_t i = 0; i < problem.contacts.size(); ++i) {
    const double w_nn = contactDiagonalBlock(problem, offsets, static_cast<int>(i))(0, 0) + regularization;
    ignored[i] = w_nn <= min_w;
  }
  return ignored;
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

void appendNote(std::string& message, const std::string& note) {
  message += std::string(message.empty() ? "" : "; ") + note;
}

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

}  // namespace

void ContactSolver::prepare(const Problem& stated, Clock::time_point start, Prepared& p) const {
  p.stated = &stated;
  // build_lcp with the body form: Gauss-Seidel runs unbuilt on it (false); every other case
  // assembles the block-sparse W once and solves as usual.
  p.unbuilt = stated.bodies && !params_.build_lcp && runsUnbuilt(params_.solver);
  if (stated.bodies && !p.unbuilt) p.assembled = assembledProblem(stated);
  p.base = stated.bodies && !p.unbuilt ? &p.assembled : &stated;
  // μ = 0 contacts cost one row (docs/SOLVERS.md "Contact models"): the kernels run without their
  // tangent rows; forces, d, residual and states are reported on every row of `base`.
  p.compact = !p.unbuilt && std::any_of(p.base->contacts.begin(), p.base->contacts.end(),
                                        [this](const Contact& c) { return zeroFriction(c, params_.mu); });
  if (p.compact) p.compaction = compactZeroFriction(*p.base, params_.mu);
  p.problem = p.compact ? &p.compaction.reduced : p.base;

  SolveContext& ctx = p.ctx;
  ctx.problem = p.problem;
  ctx.params = &params_;
  ctx.offsets = p.problem->rowOffsets();
  ctx.mu = effectiveMu(*p.problem, params_.mu);
  ctx.regularization = params_.regularizationTerm;
  ctx.ignored = contactsBelowMinW(*p.problem, ctx.offsets, params_.minW, ctx.regularization);
  if (params_.time_budget > 0.0) {
    ctx.has_deadline = true;
    ctx.deadline = start + std::chrono::duration_cast<Clock::duration>(
                               std::chrono::duration<double>(std::min(params_.time_budget, 1e7)));
  }
  // auto's rank-deficiency estimate: rows against the bodies' degrees of freedom.
  ctx.body_dof = stated.bodies ? 6 * stated.bodies->bodyCount() : 0;
}

// Only nlgs has the local step of torsional and rolling contacts: every other kernel refuses
// them, with zero forces and the residual of those forces.
bool ContactSolver::refusesExtendedFriction(const Prepared& p, Clock::time_point start,
                                            SolveResult& result) const {
  const SolverKind kind = params_.solver;
  if (kind == SolverKind::kNlgs || kind == SolverKind::kAuto || !hasExtendedFriction(*p.problem))
    return false;
  const Problem& base = *p.base;
  result.status = SolveStatus::kNotApplicable;
  result.message = std::string(solverName(kind)) +
                   " does not solve torsional or rolling friction (4- and 6-row contacts); use nlgs or auto";
  result.forces = Eigen::VectorXd::Zero(base.rowCount());
  result.d = base.d_free;
  result.states.assign(base.contacts.size(), ContactState::kOpen);
  // The residual of what is returned (zero forces), as for every other result: found by
  // fuzzing, it was left at 0, which read as an exact answer.
  result.residual = naturalMapResidual(base, effectiveMu(base, params_.mu), result.forces, result.d,
                                       std::vector<bool>(base.contacts.size(), false));
  result.solve_time = secondsSince(start);
  return true;
}

KernelReport ContactSolver::solvePrepared(Prepared& p, Eigen::VectorXd& lambda, SolveResult& result) const {
  SolveContext& ctx = p.ctx;
  const SolverKind kind = params_.solver;
  // auto's first check, that the start already meets the tolerance, on the whole problem
  // before any island is built: each island alone is held to its share of the tolerance and
  // would iterate (Capsules at 1e-2: 6x). Only from λ = 0, whose residual is d_free's in every
  // storage (W, blocks or bodies), so that the built and unbuilt solves agree on it.
  if (kind == SolverKind::kAuto && params_.stopping_rule == StoppingRule::kResidual &&
      !(pyramidModel(params_) && ctx.hasFriction()) && lambda.isZero(0.0)) {
    const double start = autoStartResidual(ctx, lambda);
    if (start <= params_.tolerance) {
      KernelReport report;
      report.status = SolveStatus::kConverged;
      report.solver_error = start;
      result.solver = autoPath(result.stages);
      return report;
    }
    ctx.start_residual = start;  // the portfolio's own first check, unless islands split it
  }
  // Independent islands of W are solved apart (islands.h), built once for every maxF pass.
  std::unique_ptr<IslandSolver> islands;
  KernelReport whole_sweeps;  // auto's sweeps on the whole problem before its islands (autoWholeSweepsEnd)
  double whole_seconds = 0.0;
  // Newton on the disc stays whole: its globalisation (nlgs warm-up and bursts, ε from the
  // residual) reaches 1e-8 on Capsules-i101-404 whole but not on one of its 32 islands alone.
  const bool split = kind != SolverKind::kNewton || !ctx.hasFriction();
  if (params_.islands && split && !params_.displayDebug && p.problem->contacts.size() > 1 &&
      p.problem->rowCount() >= kMinRowsForIslands) {
    Islands found = findIslands(*p.problem);
    if (found.count() > 1) {
      // auto first sweeps the whole problem a few times (autoWholeSweepsEnd).
      if (kind == SolverKind::kAuto && autoWholeSweepsEnd(ctx, lambda, whole_sweeps, whole_seconds)) {
        zeroInactiveRows(ctx, lambda);
        result.stages.emplace_back(solverName(SolverKind::kNlgs), whole_seconds);
        result.solver = autoPath(result.stages);
        return whole_sweeps;
      }
      SolverParams rest;  // maxIt bounds the sweeps and the islands together
      const SolverParams* own = ctx.params;
      if (whole_sweeps.iterations > 0) {
        rest = params_;
        rest.maxIt -= whole_sweeps.iterations;
        ctx.params = &rest;  // the islands copy their parameters
      }
      islands = std::make_unique<IslandSolver>(ctx, std::move(found));
      ctx.params = own;
    }
  }
  const int threads = params_.threads > 0 ? params_.threads : defaultThreadCount();
  const auto kernel = [kind](const SolveContext& c, Eigen::VectorXd& l) { return runKernel(kind, c, l); };
  KernelReport report;
  // maxF: drop the contacts above the limit and solve the rest again, so the remaining
  // forces are consistent with the contacts that are left. Each pass drops at least one
  // contact, so this ends.
  for (;;) {
    zeroInactiveRows(ctx, lambda);
    KernelReport pass = islands ? islands->run(ctx, kernel, lambda, threads) : kernel(ctx, lambda);
    ctx.start_residual = std::numeric_limits<double>::quiet_NaN();  // a maxF pass starts elsewhere
    report.status = pass.status;
    report.message = pass.message;
    report.solver_error = pass.solver_error;
    report.iterations += pass.iterations;
    report.total_iterations += islands ? pass.total_iterations : pass.iterations;
    report.history.insert(report.history.end(), pass.history.begin(), pass.history.end());
    report.friction_model = pass.friction_model;
    if (result.stages.empty()) {
      result.stages = std::move(pass.stages);  // the first (usually only) pass: no copy
      pass.stages.clear();
    }
    for (const auto& stage : pass.stages) {  // auto: consecutive slices of one member are one stage
      if (!result.stages.empty() && result.stages.back().first == stage.first)
        result.stages.back().second += stage.second;
      else
        result.stages.push_back(stage);
    }
    if (failedToRun(pass.status) || pass.status == SolveStatus::kTimeBudget || params_.maxF <= 0.0) break;
    if (dropContactsAboveMaxF(ctx, lambda, params_.maxF) == 0) break;
    ++result.resolves;
  }
  zeroInactiveRows(ctx, lambda);
  if (whole_sweeps.iterations > 0) {  // they swept every island once each: counted as such
    report.iterations += whole_sweeps.iterations;
    report.total_iterations += whole_sweeps.iterations * islands->count();
    if (!result.stages.empty() && result.stages.front().first == solverName(SolverKind::kNlgs))
      result.stages.front().second += whole_seconds;
    else
      result.stages.insert(result.stages.begin(), {solverName(SolverKind::kNlgs), whole_seconds});
  }
  if (kind == SolverKind::kAuto) result.solver = autoPath(result.stages);
  return report;
}

// finish, first part: forces and d on every row of `base`, never a non-finite number.
void ContactSolver::expandForces(const Prepared& p, Eigen::VectorXd lambda, KernelReport& report,
                                 SolveResult& result) const {
  if (!lambda.allFinite()) {  // kernels promise finite output; this is the last guard
    lambda.setZero();
    report.status = SolveStatus::kNumericalFailure;
    report.message = "the solver produced a non-finite force; forces reset to zero";
  }
  result.forces = std::move(lambda);
  p.ctx.computeD(result.forces, result.d);
  if (!result.d.allFinite()) {
    result.d.setZero();
    result.forces.setZero();
    report.status = SolveStatus::kNumericalFailure;
    report.message = "W λ overflowed; forces reset to zero";
  }
  if (!p.compact) return;
  // Back to every row: the dropped tangent rows carry no force.
  const Problem& base = *p.base;
  Eigen::VectorXd forces = Eigen::VectorXd::Zero(base.rowCount());
  forces(p.compaction.kept) = result.forces;
  Eigen::VectorXd d;
  multiply(base.W, forces, d);
  d += base.d_free;
  d(p.compaction.kept) = result.d;  // the solved rows as solved (regularization included)
  if (!d.allFinite()) {
    d.setZero();
    forces.setZero();
    report.status = SolveStatus::kNumericalFailure;
    report.message = "W λ overflowed; forces reset to zero";
  }
  result.forces = std::move(forces);
  result.d = std::move(d);
}

// finish, second part: residual, states and status from the returned forces.
void ContactSolver::measureResult(const Prepared& p, KernelReport& report, SolveResult& result) const {
  const Problem& base = *p.base;
  const std::vector<double> reported_mu = p.compact ? effectiveMu(base, params_.mu) : p.ctx.mu;
  result.residual = naturalMapResidual(base, reported_mu, result.forces, result.d, p.ctx.ignored);
  result.states = classifyContacts(base, reported_mu, result.forces, p.ctx.ignored);
  if (report.status == SolveStatus::kConverged && params_.stopping_rule == StoppingRule::kResidual &&
      report.friction_model == FrictionModel::kCoulombDisc && !(result.residual <= params_.tolerance)) {
    // "converged" promises the residual of what is returned; a kernel's own measure that
    // disagrees (round-off at extreme scales, a force it left on an ignored contact) does not.
    std::ostringstream note;
    note << "the solver reported convergence, but the residual recomputed from the returned forces is "
         << result.residual << " > tolerance " << params_.tolerance;
    appendNote(report.message, note.str());
    report.status = SolveStatus::kMaxIterations;
  }
  result.status = report.status;
  result.converged = report.status == SolveStatus::kConverged;
  result.iterations = report.iterations;
  result.total_iterations = report.total_iterations;
  result.solver_error = std::isfinite(report.solver_error) ? report.solver_error : 0.0;
  result.message = report.message;
  result.friction_model = report.friction_model;
  result.residual_history = std::move(report.history);
  result.unbuilt = p.unbuilt;
}

// finish, third part: what the numbers alone do not say (friction law solved, body form).
void ContactSolver::explainResult(const Prepared& p, SolveResult& result) const {
  if (pyramidModel(params_) && result.friction_model == FrictionModel::kCoulombDisc && p.ctx.hasFriction() &&
      !failedToRun(result.status)) {
    appendNote(result.message, std::string("friction_model ") + frictionModelName(params_.friction_model) +
                                   " applies to pgs and lemke; " + result.solver +
                                   " solved the Coulomb disc");
  }
  if (result.friction_model != FrictionModel::kCoulombDisc && result.converged) {
    // "converged" is about the law that was solved; say so, since `residual` (Coulomb's
    // disc) stays large wherever a pyramid corner lets friction exceed μ λ_n.
    std::ostringstream note;
    note << "converged on the " << frictionModelName(result.friction_model) << " friction law (its residual "
         << result.solver_error << " <= tolerance); residual " << result.residual
         << " is the distance to Coulomb's disc, nonzero by design";
    appendNote(result.message, note.str());
  }
  if (params_.build_lcp) return;
  const Problem& stated = *p.stated;
  if (p.unbuilt) {
    appendNote(result.message,
               "unbuilt solve on the body form (" + std::to_string(stated.bodies->bodyCount()) + " bodies)");
  } else if (stated.bodies) {
    appendNote(result.message, std::string("build_lcp=false: ") + solverName(params_.solver) +
                                   " needs the assembled W; assembled it from the body form (block-sparse)");
  } else {
    appendNote(result.message,
               "build_lcp=false needs the body form of the compliance; solved on the assembled W");
  }
}

SolveResult ContactSolver::solveStated(const Problem& stated, Clock::time_point start) {
  SolveResult result;
  result.solver = solverName(params_.solver);
  Prepared prepared;
  prepare(stated, start, prepared);
  if (refusesExtendedFriction(prepared, start, result)) return result;
  Eigen::VectorXd lambda = initialGuess(*prepared.problem, prepared.ctx.offsets);
  KernelReport report = solvePrepared(prepared, lambda, result);
  expandForces(prepared, std::move(lambda), report, result);
  measureResult(prepared, report, result);
  explainResult(prepared, result);
  if (!failedToRun(result.status)) rememberForces(*prepared.base, prepared.base->rowOffsets(), result.forces);
  result.solve_time = secondsSince(start);
  return result;
}

SolveResult solveProblem(const Problem& problem, const SolverParams& params) {
  ContactSolver solver(params);
  SolverParams no_warm_start = params;
  no_warm_start.initial_guess = false;
  solver.setParams(no_warm_start);
  return solver.solve(problem);
}

}  // namespace lcp_contact_solver::core
