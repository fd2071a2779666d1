#include "portfolio.h"

#include "kernel_dispatch.h"
#include "kernels/local_contact_laws.h"
#include "kernels/newton_symmetric.h"

#include "lcp_contact_solver/core/body_compliance.h"
#include "lcp_contact_solver/core/residual.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <limits>
#include <memory>
#include <string>
#include <utility>

namespace lcp_contact_solver::core {

namespace {

using Clock = std::chrono::steady_clock;

// ---- auto: the portfolio ----------------------------------------------------------------
//
// auto predicts an order of members from features that do not depend on any benchmark set:
// the friction law and contact types (what each kernel can solve), the tolerance (Gauss-
// Seidel and APGD converge linearly or sublinearly, Newton superlinearly), the size (a
// Newton step factorizes, a sweep or an APGD iteration is one pass over W), the storage
// (body form: Gauss-Seidel runs unbuilt; block-sparse: a Newton step is a sparse LU), for
// LCPs W's symmetry (a convex QP: newton's active-set path) and Gauss-Seidel's contraction
// bound (a non-symmetric W where pgs provably converges), the number of contacts (one is
// Gauss-Seidel's own local solve), and two estimates of how hard W is for Gauss-Seidel: the
// normal coupling κ (mean over contacts of Σ_j≠i |W_nn,ij| / W_nn,ii; below 1 W is
// diagonally dominant on the normal rows), rank deficiency (active rows above the bodies'
// 6 DoF each when the body form is known, else a quarter of the contacts with a nearly
// parallel partner) and multi-point contacts (a quarter of the contacts in groups of three or
// more coupled to exactly the same contacts: several points between the same bodies; both
// shares over the contacts that are not bilateral, joints having no contact point), which
// decide between Gauss-Seidel and apgd from 1e-3 down to 1e-4 (at any tolerance where most
// rows are bilateral; where about two digits are asked the probe's rate decides instead, at
// its end) and put an apgd scout before a planned
// newton (kAutoScoutIterations). The start is measured first: a
// warm start that already meets the tolerance runs no member. Then, before any feature is
// measured and wherever Gauss-Seidel can start (but not on a dense symmetric LCP whose plan
// is newton's few Cholesky steps), a probe of its sweeps: three (three more if they raised
// the residual from the start), then stage by stage while the rate of the last stage reaches
// the tolerance, with a margin of 2, within
// ten sweeps or, once the plan is measured, within a lower bound of its first member's cost
// (probeAllowance; ten again before a scout on faces resting on faces, and before apgd at
// three digits where most of their load sticks; where it slides, apgd goes behind
// Gauss-Seidel after the probe). A few weakly coupled
// contacts with exact local solves end there, at a fraction of a Newton step's cost.
// Otherwise a Gauss-Seidel plan goes on from the probe's iterate, newton too if the probe was
// no longer than its own warm-up, and any other plan starts from the start, as it would have
// without the probe.
// Then each member runs in slices of iterations from the best iterate so far (the Gauss-Seidel
// blocks formed once, an apgd slice resuming the last one's momentum: kernels.h memos): a slice that
// ends without lowering the residual by the member's factor (10 for newton/prox, 2 for the
// first-order methods) hands over to the next member; a member that fails (not_applicable,
// zero_diagonal, numerical_failure, ray termination) leaves the rotation; a member that
// progresses continues with a doubled slice (but a Gauss-Seidel member whose remaining sweeps
// would cost more than newton's warm-up and two factorizations hands over to an untried
// newton: newtonCheaperThanSweeps); a member not tried yet runs its first slice on trial,
// stopped once it has taken as long as the solve so far without lowering the residual; once
// every member ran, a stall hands over to the member with the fastest residual decrease per
// second in its last slice (or, where none lowered it, over all its slices), and a member that
// could not move from the best iterate at all gets one slice from the warm start instead. The first
// slices of a plan's Gauss-Seidel member are a trial of over-relaxation (kAutoOmegaTrial).
// Members rotate until the tolerance, maxIt
// (summed over every slice) or time_budget (a slice gets at most half the remaining time
// while another member is left, or the plan waits behind the probe) ends the solve.

constexpr double kAutoTightTolerance = 1e-3;   // below: a superlinear method pays off
constexpr double kAutoModerateTolerance = 1e-4;  // down to it: Gauss-Seidel before apgd (below)
// About two digits (a 1e-2 solve's islands get >= 0.7e-2): where the probe's sweeps are the
// early, fast ones that may be the whole solve (an LCP's probe, Gauss-Seidel before apgd).
constexpr double kAutoTwoDigits = 5e-3;
constexpr double kAutoNewtonTolerance = 1e-6;  // below: newton up to kAutoNewtonRowsTight rows
constexpr int kAutoNewtonRows = 200;           // factorization vs passes over W (see above)
constexpr int kAutoNewtonRowsTight = 1000;
constexpr int kAutoNewtonSmallRows = 32;       // loose tolerance: newton first up to this size (its plain LU)
constexpr int kAutoSmallRows = 200;           // loose tolerance: nlgs first up to this size
constexpr double kAutoDominant = 1.0;         // normal coupling below this: diagonally dominant
constexpr double kAutoRedundant = 0.9;        // normal rows this parallel (W metric): same body pair
constexpr double kAutoRedundantShare = 0.25;  // this share of such contacts: W taken as rank-deficient
constexpr int kAutoMultiPoint = 3;  // contacts between the same bodies: 3 x 3 rows > 6 DoF
constexpr int kAutoLemkeRows = 1000;          // LCPs up to this size may start with Lemke
// A symmetric LCP up to this size whose plan starts with newton runs its active-set path
// without the portfolio's bookkeeping (directActiveSet): one Cholesky step of 16 rows, about
// 1 400 flops, costs as much as that bookkeeping, so above it the bookkeeping does not count.
constexpr int kAutoDirectRows = 16;
// Block-sparse W (scenes: one block per pair of contacts sharing a body): Gauss-Seidel first
// below this coupling, at any tolerance. Chosen between the generated scenes' sphere piles
// (κ ≈ 1.8, where nlgs is fastest) and box stacks (κ ≥ 2.8, face contacts, where apgd is).
constexpr double kAutoSparseGs = 2.0;
constexpr double kAutoStrongDominant = 0.25;  // a Jacobi bound of 4x per sweep: nlgs at any tolerance
// Every plan starts with a probe of Gauss-Seidel sweeps: on weakly coupled problems (exact
// local solves, a few contacts) they meet the tolerance. Its allowances, in sweeps:
constexpr int kAutoProbeFirst = 3;  // then stage by stage while their rate reaches the tolerance
// Whole sweeps before islands (autoWholeSweepsEnd): from a start within a digit of the tolerance.
constexpr double kAutoWholeSweepsReach = 10.0;
constexpr int kAutoProbeSweeps = 10;  // before the plan is measured; newton's own warm-up is as long
constexpr int kAutoProbeApgdSweeps = 50;  // before apgd (below)
// A symmetric LCP's newton (its active-set path) factorizes W_AA once per step, 1 to 4 steps:
// a dense Cholesky of n rows is n³/6 multiply-adds where a sweep is n², about n/6 sweeps
// (MuJoCo's sparse cloths and soft boxes measured n/13..n/6 per step). Gauss-Seidel probes
// such an LCP only where two digits are asked, where a few sweeps may do (an active set is
// exact whatever the tolerance, sweeps pay per digit: at 1e-3 the probe lost as often as it
// won on MuJoCo's cloths, soft boxes and active_adhesion), and only where one factorization
// costs at least kAutoProbeLcpFactorSweeps sweeps: a probe that gives up after its first
// three then adds about 3/20 of a factorization to newton's solve (MuJoCo's humanoid
// islands, 20-40 rows, are not probed).
constexpr int kAutoProbeLcpFactorSweeps = 20;
// Before newton on multi-point or rank-deficient contacts, an apgd scout: where such a W is
// well conditioned on the active set apgd ends in tens of iterations (box pyramids: 30-60)
// against newton's 8-20 slow steps; where it is not (BoxesStack1, OneObject: thousands) the
// scout's iterate is dropped and newton starts where it would have. It runs kAutoScoutFirst
// iterations, then on, in slices no longer than the scout so far, while the rate of its last
// slice reaches the tolerance within kAutoScoutIterations in all. Its first 20 products with W
// cost less than two dense factorizations (2 n³/3 flops) from 30 rows up: below that the
// scout could cost more than newton's whole solve.
constexpr int kAutoScoutFirst = 20;
constexpr int kAutoScoutIterations = 100;
constexpr int kAutoScoutRows = 30;
// Past kAutoScoutIterations the scout goes on only where what is left is short: its forecast
// reaches no further than the scout has run (a rate measured over at least as many iterations
// as it predicts) and the scout in all costs less than newton's modeled cost, its warm-up and
// kAutoScoutNewtonSteps steps of n/3 sweeps (an apgd iteration costs about a sweep). LMGC's
// periodic box of grains at 1e-4 (180 rows): 80 iterations 22x above the tolerance forecast 72
// more; dropped at the cap, newton took 3.7 ms where apgd alone takes 1.4. The cost bound alone,
// without the horizon, lost 2-3x on BoxesStack1 at 1e-5/1e-6, whose early rate promises what
// apgd does not keep (20-40 iterations forecasting 140-200).
constexpr int kAutoScoutNewtonSteps = 8;  // the low end of newton's 8-20 steps on such contacts
// A contact sticks where its tangential force is inside this fraction of μ λ_n
// (slidingLoadShare), and the load is taken to stick (probeAllowance) where at most
// kAutoSlidingLoad of it slides: between what the probe's iterate showed after three
// sweeps on brick pyramids at rest (0.28-0.55 sliding) and on stacks pushed sideways (1.0).
constexpr double kAutoStickInside = 0.99;
constexpr double kAutoSlidingLoad = 0.75;
// Gauss-Seidel's over-relaxation ω, chosen online where the user left sor at 1: a plan's
// Gauss-Seidel member first sweeps kAutoOmegaTrial times plainly, measuring its rate ρ per
// sweep, then, if at that rate it would need more sweeps than that again, as many at Young's
// ω = 2 / (1 + √(1 − ρ)) (optimal for a linear, consistently ordered W whose plain
// Gauss-Seidel rate is ρ), and keeps ω only if those sweeps did better.
// Frictional and unilateral rows are neither linear nor stationary: ω is capped at 1.5 (a
// window where plain sweeps stalled while the active set moved asked for 1.9, which then
// tripled a MuJoCo humanoid island's sweeps), and the trial's later window is judged against
// an earlier plain one, whose rate is the faster while the active set settles: ω stays only
// where it clearly helps (the 12-sphere pile: half the sweeps) and costs at most the trial's
// sweeps elsewhere (ball and box stacks, where over-relaxation would pay only later).
// The probe's sweeps, where they go on past newton's warm-up (kept plain: newton resumes from
// them) and their last stage's rate would need more than kAutoOmegaTrial further sweeps, run
// a like trial: a window at Young's ω for that stage's rate, kept if it did better; if not,
// a plain window follows and ω is kept if it did better than that one (plain sweeps only
// slow as they go: the window before favours them). A MuJoCo cloth whose probe sweeps to 1e-5
// alone: ω = 1.43 swept at 0.79 per sweep against the plain stage's 0.84, 42 sweeps where
// plain nlgs takes 55.
constexpr double kAutoOmegaMax = 1.5;
constexpr int kAutoOmegaTrial = 10;
// A member that progresses but whose rate needs more than this many times the solve's
// iterations so far lets the members not tried yet run one slice each (runPortfolio).
constexpr double kAutoExploreFactor = 4.0;
// Also, newton before any other member not tried yet, where a Gauss-Seidel member's remaining
// sweeps at the rate of its last slice outnumber what newton would cost from its iterate: its
// own warm-up and kAutoNewtonSteps LU factorizations, each 2n³/3 flops against a sweep's 2n²,
// i.e. n/3 sweeps. Gauss-Seidel converges linearly, so its sweeps grow with every digit asked
// while newton's steps do not. Only where that flop count holds: a dense W, or a block-sparse
// one up to kAutoNewtonRows rows (a larger sparse LU fills in: on a 40-sphere pile newton took
// 5.7x Gauss-Seidel's time); not on the body form, whose W newton would first assemble.
constexpr int kAutoNewtonSteps = 2;
// A Gauss-Seidel slice that stalls can be a drift rather than a plateau: load moving slowly
// between contacts that share it along a nearly flat direction of the problem (a capsule
// lying on two others), the residual almost flat, λ moving the same way sweep after sweep
// until a pressing contact's normal force reaches zero and the active set changes, after
// which the sweeps converge at once. Where the slice's change δ of λ brings a normal force
// to zero within kAutoDriftReach more such slices, λ jumps there, λ + t δ with t the first
// such zero (projected onto the feasible sets), and kAutoDriftSweeps sweeps settle the
// others; kept only if that lowered the residual below the stalled iterate's.
// Capsules-i101's 48-row island at 1e-6: plain sweeps sit at 5.6e-6 for 900 sweeps; from
// sweeps 50-100 a jump predicts the separation 770 sweeps ahead, 10 sweeps after it reach
// 4.4e-6 and 50 more 7e-9. A slice that is a plateau instead (the iterate converging slowly
// everywhere) rarely brings a normal force to zero within that reach, and a jump that does
// not pay costs its ten sweeps.
constexpr double kAutoDriftReach = 1000.0;
constexpr int kAutoDriftSweeps = 10;

// The step t along `drift` from `lambda` at which the first pressing contact's normal force
// reaches zero (kAutoDriftReach); infinity where no normal force falls.
double separationStep(const SolveContext& ctx, const Eigen::VectorXd& lambda, const Eigen::VectorXd& drift) {
  double step = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < ctx.problem->contacts.size(); ++i) {
    const ContactType type = ctx.problem->contacts[i].type;
    if (ctx.ignored[i] || !(type == ContactType::kFrictional || type == ContactType::kFrictionless)) continue;
    const int n = ctx.offsets[i];
    if (lambda[n] > 0.0 && drift[n] < 0.0) step = std::min(step, -lambda[n] / drift[n]);
  }
  return step;
}

// Young's ω for a plain Gauss-Seidel rate ρ per sweep, capped at kAutoOmegaMax.
double youngOmega(double rho) { return std::min(kAutoOmegaMax, 2.0 / (1.0 + std::sqrt(1.0 - rho))); }

// One Newton step in sweeps: an LU of n rows (2n³/3 flops) against a sweep's 2n².
double newtonStepSweeps(const SolveContext& ctx) { return ctx.problem->rowCount() / 3.0; }

// newton's modeled cost in sweeps: its warm-up and `steps` Newton steps.
double newtonCostSweeps(const SolveContext& ctx, int steps) {
  return kNewtonWarmupSweeps + steps * newtonStepSweeps(ctx);
}

// newton's modeled cost in sweeps from a probe's iterate after `probe_sweeps` plain sweeps at
// `residual`: what is left of its warm-up (none once that tolerance is met) and `steps` steps.
double newtonCostFrom(const SolveContext& ctx, int steps, int probe_sweeps, double residual) {
  const bool warmed = residual <= std::max(ctx.params->tolerance, kNewtonWarmupTolerance);
  return newtonCostSweeps(ctx, steps) - (warmed ? kNewtonWarmupSweeps : std::min(probe_sweeps, kNewtonWarmupSweeps));
}

// The rate per sweep of Gauss-Seidel over-relaxed by ω where its plain rate is ρ, for a linear,
// consistently ordered W (Young): the larger root of (r + ω - 1)² = r ω² ρ, ω - 1 past Young's ω.
double sorRate(double rho, double omega) {
  const double disc = omega * omega * rho - 4.0 * (omega - 1.0);
  if (disc < 0.0) return omega - 1.0;
  const double root = 0.5 * (omega * std::sqrt(rho) + std::sqrt(disc));
  return root * root;
}

// Whether the apgd scout goes on, after `iterations` in all, with `needed` more forecast by
// its last slice's rate (kAutoScoutIterations, kAutoScoutNewtonSteps).
bool scoutGoesOn(const SolveContext& ctx, int iterations, double needed) {
  if (iterations + needed <= kAutoScoutIterations) return true;
  return needed <= iterations && iterations + needed <= newtonCostSweeps(ctx, kAutoScoutNewtonSteps);
}

bool newtonCheaperThanSweeps(const SolveContext& ctx, double sweeps) {
  const int n = ctx.problem->rowCount();
  const bool counted = !ctx.problem->bodies &&
                       (std::holds_alternative<Eigen::MatrixXd>(ctx.problem->W) || n <= kAutoNewtonRows);
  return counted && sweeps > newtonCostSweeps(ctx, kAutoNewtonSteps);
}
// The probe's last window, at a loose tolerance where a small problem's plan is newton
// (kAutoNewtonSmallRows): where the probe's stages stop because their plain rate ρ asks for
// more sweeps (twice the forecast, as above) than newton's modeled cost from the probe's
// iterate (what is left of its warm-up, then kAutoNewtonSteps steps of n/3 sweeps), but
// Young's theory says over-relaxed sweeps would fit (sorRate), kAutoOmegaTrial sweeps run at
// Young's ω for ρ. Where they meet the tolerance, or their own rate forecasts the rest within
// newton's cost, Gauss-Seidel goes first at that ω; otherwise the window is dropped and the
// plan goes on as it would have (its sweeps lost, at most a third of newton's warm-up on a
// problem of at most 32 rows). Its forecast is taken once, not twice: over-relaxed sweeps start
// slow and speed up past their transient (OneObject-i1028's first sweep at ω = 1.5 raised the
// residual 1.6x, its later ones fell 0.92-0.94 per sweep against plain sweeps' 0.97).
// MuJoCo's rope at 1e-3 (12 rows): the window met the tolerance, 14 sweeps in all where newton
// took its warm-up and a step (0.72x the time).
// Not at a tight tolerance: there a small problem's newton ends in a few quadratic steps
// (Siconos' rovers at 1e-8..1e-10: 8-13 sweeps at ω against 6-9 iterations, 1.0-1.2x the
// time), and on the scout's plans (multi-point, rank-deficient contacts) newton's steps were
// as slow as the model's eight (OneObject-i1028 at 1e-4: 7 steps; the window kept Gauss-Seidel
// at 0.45x the time) or one step ended it (a condim-6 box stack written after this rule, 60
// rows: the window's ω swept slower than plain and its ten sweeps cost 1.27x at 1e-4..1e-10),
// and no feature measured told the two apart. Except within newton's warm-up
// (omegaWindowsWithinWarmup), where a window that is dropped costs nothing.
// Returns that ω where the window is due (0 where not), and in *newton_cost the sweeps its
// forecast must fit: the probe's last stage swept plainly at `rho` per sweep down to `to`,
// `needed` more forecast, `probe_sweeps` in all.
double lastOmegaWindow(const SolveContext& ctx, int probe_sweeps, double rho, double to, double needed,
                       double* newton_cost, bool within_warmup) {
  if (ctx.params->tolerance < kAutoTightTolerance && !within_warmup) return 0.0;
  const double omega = youngOmega(rho);
  *newton_cost = newtonCostFrom(ctx, kAutoNewtonSteps, probe_sweeps, to);
  const double young_needed = needed * std::log(rho) / std::log(sorRate(rho, omega));
  const bool due = 2.0 * needed > *newton_cost && std::max<double>(young_needed, kAutoOmegaTrial) < *newton_cost;
  return due ? omega : 0.0;
}

// The probe's window at Young's ω as part of newton's warm-up, on the scout's plans at a tight
// tolerance. newton's warm-up is kNewtonWarmupSweeps nlgs sweeps, of which the probe ran
// `probe_sweeps`; the window's sweeps, over-relaxed, are the next ones: where its forecast
// does not fit newton's cost its iterate, when it lowered the residual, is where newton's
// warm-up goes on from (the condim-6 box stack, in a variant without the rate condition below:
// its one Newton step as before, the same iterations in all), so that the window is nearly
// free. Where the window beat the plain stage's rate without fitting yet, a second one runs the
// rest of the warm-up: over-relaxed sweeps start slow (OneObject-i1028 at 1e-4: 0.974 per sweep in the first window against the plain
// stage's 0.979, then 0.91 in the second, which forecast 32 sweeps more where newton's steps
// took the time of about 110; `auto:nlgs`, 71 sweeps, 0.49x the time).
// Only where that plain stage swept slower than kAutoOmegaSlowRate per sweep: Young's ω
// describes sweeps that have reached their asymptotic rate, the slowest mode's, which from the
// start only sweeps that slow already have; faster early sweeps are the faster modes' transient,
// and an ω taken from their rate over-relaxes an iterate whose active set has not settled
// (OneObject-i100000: three sweeps at 0.89, then its window at ω = 1.5 raised the residual
// 1.8x and was lost, 1.15x the time at 1e-5..1e-10).
constexpr double kAutoOmegaSlowRate = 0.95;
bool omegaWindowsWithinWarmup(int probe_sweeps, double stage_rate) {
  return probe_sweeps + kAutoOmegaTrial <= kNewtonWarmupSweeps && stage_rate >= kAutoOmegaSlowRate;
}

// Whether a plan's first member starts from the start rather than from the probe's iterate:
// the probe's sweeps are then lost (Gauss-Seidel and newton go on from them, newton's warm-up).
bool startsFromTheStart(SolverKind first) {
  return !(first == SolverKind::kNlgs || first == SolverKind::kPgs || first == SolverKind::kNewton);
}

// auto's order of members: at most four, kept inline (no allocation on a microsecond solve).
class Plan {
 public:
  Plan() = default;
  Plan(std::initializer_list<SolverKind> kinds) {
    for (SolverKind k : kinds) kinds_[size_++] = k;
  }
  bool empty() const { return size_ == 0; }
  SolverKind front() const { return kinds_[0]; }
  const SolverKind* begin() const { return kinds_.data(); }
  const SolverKind* end() const { return kinds_.data() + size_; }

 private:
  std::array<SolverKind, 4> kinds_{};
  int size_ = 0;
};

// The share of the frictional contacts' normal load at `lambda` carried by contacts on the
// edge of their friction cone (sliding; a μ = 0 contact's load does not slide in this sense:
// apgd's shift μ |u_t| stays 0 there); 1 where no contact carries a load.
double slidingLoadShare(const SolveContext& ctx, const Eigen::VectorXd& lambda) {
  const Problem& p = *ctx.problem;
  double load = 0.0;
  double sliding = 0.0;
  for (std::size_t i = 0; i < p.contacts.size(); ++i) {
    if (ctx.ignored[i] || p.contacts[i].type != ContactType::kFrictional) continue;
    const int off = ctx.offsets[i];
    const double normal = lambda[off];
    if (!(normal > 0.0)) continue;
    load += normal;
    if (ctx.mu[i] > 0.0 && !(std::hypot(lambda[off + 1], lambda[off + 2]) < kAutoStickInside * ctx.mu[i] * normal))
      sliding += normal;
  }
  return load > 0.0 ? sliding / load : 1.0;
}

// At most kAutoSlidingLoad of the load slides at `lambda` (probeAllowance, the probe's end).
bool loadSticks(const SolveContext& ctx, const Eigen::VectorXd& lambda) {
  return slidingLoadShare(ctx, lambda) <= kAutoSlidingLoad;
}

// One dense factorization of a symmetric LCP's rows, in sweeps (kAutoProbeLcpFactorSweeps).
int lcpFactorSweeps(const SolveContext& ctx) { return ctx.problem->rowCount() / 6; }

// Whether Gauss-Seidel probes a symmetric LCP whose plan starts with newton's active-set path
// (asked only under the residual rule, the one the probe runs under).
bool probesSymmetricLcp(const SolveContext& ctx) {
  return ctx.params->tolerance >= kAutoTwoDigits && lcpFactorSweeps(ctx) >= kAutoProbeLcpFactorSweeps;
}

// How many sweeps the probe may go on for, when their rate says they reach the tolerance,
// before the plan's first member would be cheaper. A Newton step factorizes W (n³/3 flops
// dense) where a sweep is one pass over it: a frictional Newton solve costs at least about n
// sweeps (measured 1.7..17 n on the fc3d problems and the scenes). On an LCP newton's
// active-set path is a few Cholesky steps: one of them (n/6 sweeps), at least the probe's
// ten. apgd's iteration is one product with W and the residual of its iterate, about a
// sweep (0.6..1.7 of one on the study's block-sparse problems, the product alone 0.4), and
// where Gauss-Seidel's rate is good apgd needs 2..6x its iterations: fifty; before newton
// behind an apgd scout, the smaller of newton's and apgd's (the scout is the member the
// probe's sweeps would save first). Others (Lemke, prox, a fixed plan): ten. Ten too before
// a scout that holds (apgdHolds: multi-point contacts spread over their faces, most rows
// contacts): there apgd needs about as many iterations as Gauss-Seidel sweeps, each cheaper,
// and the probe's sweeps are only insurance against a problem that a few of them solve; those
// that go on to the tolerance cost more than the scout they replace, and those that stop short
// are lost, the scout starting from the start (the scenes' brick pyramids B2 and B3 at
// 1e-4..1e-8: 0.7-0.8x auto's time). At three digits, where apgd goes first and no scout
// runs, ten only where at most kAutoSlidingLoad of the load slides at the probe's iterate
// (slidingLoadShare). apgd solves Coulomb's law as a sequence of convex problems, one per
// shift μ |u_t| on each normal row, each update restarting its momentum (apgd.cpp); a sticking
// contact's shift is 0 and stays 0, so where the load sticks one convex problem is most of the
// solve and the momentum carries it: brick pyramids at rest (B3: 30 iterations against nlgs's
// 47 sweeps, which the probe had swept; BoxesStack1: 95 against 226). Where it slides, every
// shift moves: stacks of boxes pushed sideways, all of their load sliding, are solved by the
// sweeps that the probe's rate puts first, or by newton, in a seventh to a fifteenth of
// apgd's iterations (test_portfolio.cpp): there the allowance stays at fifty, and after the
// probe apgd goes behind Gauss-Seidel (runPortfolio, the probe's end).
int probeAllowance(const Plan& plan, bool scout, const SolveContext& ctx, bool friction, bool apgd_holds,
                   const Eigen::VectorXd& lambda) {
  if (apgd_holds && (scout || (ctx.params->tolerance < kAutoTwoDigits && loadSticks(ctx, lambda))))
    return kAutoProbeSweeps;
  switch (plan.front()) {
    case SolverKind::kNewton: {
      // With friction, where newton's warm-up runs to the tolerance itself (a loose one), at
      // least its sweeps: newton would run them anyway, with its set-up on top.
      const bool warmup_to_tolerance = ctx.params->tolerance >= kNewtonWarmupTolerance;
      const int newton =
          friction ? std::max(warmup_to_tolerance ? kNewtonWarmupSweeps : kAutoProbeSweeps, ctx.problem->rowCount())
                   : std::max(kAutoProbeSweeps, lcpFactorSweeps(ctx));
      return scout ? std::min(newton, kAutoProbeApgdSweeps) : newton;
    }
    case SolverKind::kApgd: return kAutoProbeApgdSweeps;
    default: return kAutoProbeSweeps;
  }
}

// The further iterations a run that went from residual `from` to `to` (< from) in
// `iterations` needs to reach `tolerance` at the same geometric rate (the probe's stages, the
// scout).
double iterationsToReach(double tolerance, double from, double to, int iterations) {
  const double per_iteration = std::pow(to / from, 1.0 / iterations);
  return std::log(tolerance / to) / std::log(per_iteration);
}

// The further sweeps a probe stage forecasts from how its rate slowed within it. A residual
// made of many modes decaying at different rates falls like a power of the sweep count until
// the slowest mode is left, not geometrically: its log-rate per sweep g(k) decays as k^-a
// (a = 0 geometric, a = 1 a power law r ∝ k^-p). The stage's two halves measure g at two sweep
// counts, hence a, and the forecast integrates g from the stage's end to the tolerance,
// ∫ g2 (k/k2)^-a dk = ln(r/tol). Where a is near 0 this is the stage's geometric forecast, which
// the probe doubles anyway; it binds only where the stage slowed faster than that margin
// allows for. BoxesStack1 at 1e-2: sweeps 3-6 fell 0.81 per sweep and 6-10 0.90 (a = 1.16),
// 132 more forecast where the stage's mean rate said 12 (plain nlgs takes 86 in all); LMGC's
// box of grains, sweeps 3-14: 6.1 where the mean rate said 5.5 (it ends at 23).
// The model is pessimistic: the slowest mode's geometric rate takes over later, and the halves
// of a stage on MuJoCo's soft bodies swing (a from -1.5 to 2.5 on a cloth's successive stages).
// So it binds only before a member that starts from the start (startsFromTheStart), where the
// probe's sweeps past what it forecasts are pure loss; before Gauss-Seidel or newton they are
// kept, and stopping them early cost up to 3x (the held-out softbox's elliptic steps at
// 1e-7..1e-10: nlgs's 177-264 sweeps where newton then took 34 slow iterations).
// `history`: the residual after each of the stage's sweeps, `from` its start's, `before` the
// sweeps before it (the first stage, from the start, falls fast in any case: not measured).
// NaN where the halves do not both fall, infinity where the slowing never reaches the tolerance.
double slowingSweepsToReach(double tolerance, double from, const std::vector<double>& history, int before) {
  const int n = static_cast<int>(history.size());
  if (n < 4 || before <= 0) return std::numeric_limits<double>::quiet_NaN();
  const int h = n / 2;
  const double mid = history[h - 1];
  const double end = history[n - 1];
  if (!(mid < from && end < mid && end > tolerance)) return std::numeric_limits<double>::quiet_NaN();
  const double g1 = std::log(from / mid) / h;
  const double g2 = std::log(mid / end) / (n - h);
  const double k1 = before + 0.5 * h;
  const double k2 = before + h + 0.5 * (n - h);
  const double a = std::log(g1 / g2) / std::log(k2 / k1);
  const double k_end = before + n;
  const double left = std::log(end / tolerance);
  const double c = g2 * std::pow(k2, a);
  if (std::abs(a - 1.0) < 1e-9) return k_end * std::expm1(left / c);
  const double t = std::pow(k_end, 1.0 - a) + left * (1.0 - a) / c;
  if (!(t > 0.0)) return std::numeric_limits<double>::infinity();
  return std::pow(t, 1.0 / (1.0 - a)) - k_end;
}

// After a Gauss-Seidel run (the probe's first stage, and any later stage, trial window or
// slice that lowered the residual), newton's sticking active-set path (newton_symmetric.h) is
// tried once per solve where it applies (W assembled, gathered dense) when the iterate says
// every contact sticks (a scene at rest) and Gauss-Seidel would need more sweeps than the
// path costs. One Cholesky of n rows is n³/3 flops against a sweep's 2 × (W's stored entries):
// n/6 sweeps on a dense W, more on a sparse one gathered dense; the path takes one or two
// steps, and its blocked factorization runs about twice as fast per flop as a sweep (MuJoCo's
// softbox, 735 dense rows: one step 10-12 ms, a sweep 0.17 ms), so n/6 covers both. At least
// kAutoStickFixedSweeps for its set-up on small problems. The sweeps needed are twice what
// the run's rate says, as for the probe's own stages. Where a contact slides after all, the
// solve goes on from the Gauss-Seidel iterate. (Tried after the probe's first stage only, the
// path was missed where those sweeps raised the residual: the softbox's joints, 1.0 → 1.4.)
// Where the path applies and the rate says the sweeps finish first, the next Gauss-Seidel
// slice lasts only the sweeps forecast (`recheck`): a rate that slowed is then measured before
// a slice of 100 or more has run (MuJoCo's active_adhesion, step 1000 at 1e-6: declined on
// forecasts of 34-44 sweeps, then 163 sweeps without it; 69 and the path with the recheck).
constexpr double kAutoStickFixedSweeps = 10.0;
constexpr int kAutoStickWarmRows = 128;  // a warm start that sticks: tried first up to this size
// W_AA gathered dense for the path up to this size whatever W's fill (8 MB): the cost above
// counts the dense flops against the sweeps' (MuJoCo's active_adhesion, a 206-row island 19 %
// full, 194 of its rows bilateral: 124 iterations at 1e-8 where Gauss-Seidel took 302).
constexpr int kAutoStickDenseRows = 1024;
// A block-sparse sweep costs about twice a dense one per stored entry (its block indices:
// 0.5-1.6 ns against 0.3 ns, `work_precision --sweep-cost`), so there the same flops cover two
// steps as well (the model over the measured Cholesky: 1.4-2.6 dense, 2.3-10.8 block-sparse).
constexpr double kAutoSparseSweepEntryCost = 2.0;
double stickingCostSweeps(const SolveContext& ctx) {
  const double n = ctx.problem->rowCount();
  const auto* sparse = std::get_if<BlockSparseMatrix>(&ctx.problem->W);
  const double stored =
      sparse ? kAutoSparseSweepEntryCost * std::max<double>(1.0, sparse->values.size()) : n * n;
  return std::max(kAutoStickFixedSweeps, n * n * n / 3.0 / (2.0 * stored));
}
bool stickingPays(const SolveContext& ctx, const Eigen::VectorXd& lambda, double needed_sweeps, double* recheck) {
  if (!stickingPathApplies(ctx, kAutoStickDenseRows) || !allSticking(ctx, lambda)) return false;
  if (2.0 * needed_sweeps > stickingCostSweeps(ctx)) return true;
  *recheck = needed_sweeps;
  return false;
}

// SolveContext::positiveDiagonal, measured at most once per solve (the probe and the plan
// both read it).
class PositiveDiagonal {
 public:
  explicit PositiveDiagonal(const SolveContext& ctx) : ctx_(ctx) {}
  bool operator()() const {
    if (state_ < 0) state_ = ctx_.positiveDiagonal() ? 1 : 0;
    return state_ == 1;
  }

 private:
  const SolveContext& ctx_;
  mutable int state_ = -1;
};

struct AutoFeatures {
  int rows = 0;
  double coupling = 0.0;           // mean normal off-diagonal / diagonal ratio
  double gs_bound = 0.0;           // Gauss-Seidel's contraction bound (Coupling::gs_bound)
  bool positive_diagonal = false;  // Coupling::positive_diagonal
  bool rank_deficient = false;     // active rows > 6 × bodies, or redundant contacts (below)
  bool multi_point = false;        // multiPointShare >= kAutoRedundantShare
  bool body_form = false;          // unbuilt: ctx.problem carries the bodies, no W
  bool sparse = false;             // block-sparse W
  bool symmetric = false;          // W = Wᵀ (to round-off); computed for LCPs only
};

// The normal coupling κ (above) and the fraction of contacts whose normal row is nearly
// parallel to another's in the W metric (|W_ij| >= kAutoRedundant √(W_ii W_jj)): several
// contacts between the same two bodies (a face on a face), i.e. more rows than the bodies'
// DoF can tell apart, the rank-deficiency estimate when the bodies are not known. Both
// shares are over the active contacts that are not bilateral (a joint is no contact point).
struct Coupling {
  double kappa = 0.0;
  // max_i Σ_{j>i} |W_ij| / (W_ii − Σ_{j<i} |W_ij|), infinite where a denominator is not
  // positive: the ∞-norm bound on Gauss-Seidel's iteration matrix (D + L)⁻¹U; below 1 a sweep
  // contracts (a strictly dominant W, and a triangular one, where one sweep is exact).
  double gs_bound = 0.0;
  bool positive_diagonal = true;  // W_nn + r > 0 on every active contact: Gauss-Seidel can start
  double redundant = 0.0;
  double multi_point = 0.0;  // multiPointShare
};

bool anyIgnored(const SolveContext& ctx) {
  return std::find(ctx.ignored.begin(), ctx.ignored.end(), true) != ctx.ignored.end();
}

int activeContacts(const SolveContext& ctx) {
  int n = 0;
  for (std::size_t i = 0; i < ctx.problem->contacts.size(); ++i) n += ctx.ignored[i] ? 0 : 1;
  return n;
}

// The active contacts' rows, and how many of them are bilateral.
struct ActiveRows {
  int all = 0;
  int bilateral = 0;
};
ActiveRows activeRows(const SolveContext& ctx) {
  ActiveRows rows;
  for (std::size_t i = 0; i < ctx.problem->contacts.size(); ++i) {
    if (ctx.ignored[i]) continue;
    const Contact& c = ctx.problem->contacts[i];
    rows.all += c.rows;
    rows.bilateral += c.type == ContactType::kBilateral ? c.rows : 0;
  }
  return rows;
}

// The set of contacts one contact is coupled to, itself included, kept as a sum of a hash of
// each member (order-free) and its size: two contacts between the same bodies have the same set.
struct CouplingSet {
  std::uint64_t hash = 0;
  int size = 0;
  static std::uint64_t mix(std::uint64_t x) {  // splitmix64's finalizer
    x += 0x9e3779b97f4a7c15ULL;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
    return x ^ (x >> 31);
  }
  void add(int j) {
    hash += mix(static_cast<std::uint64_t>(j));
    ++size;
  }
  bool operator<(const CouplingSet& o) const { return hash != o.hash ? hash < o.hash : size < o.size; }
  bool operator==(const CouplingSet& o) const { return hash == o.hash && size == o.size; }
};

// The share of active contacts in a group of kAutoMultiPoint or more that are coupled to exactly
// the same contacts: several contact points between the same bodies (a face on a face or on the
// ground), more rows than those bodies' degrees of freedom. A set holding every active contact
// says nothing (one body, or a deformable one whose compliance couples everything). Bilateral
// rows are joints, not contact points: they are counted in the sets (a contact coupled to
// them) but not as members of a group, and `contacts` is the number of the others.
double multiPointShare(const SolveContext& ctx, std::vector<CouplingSet>& coupled, std::vector<CouplingSet>& sets,
                       int active, int contacts) {
  sets.clear();
  for (std::size_t i = 0; i < coupled.size(); ++i) {
    if (ctx.ignored[i] || ctx.problem->contacts[i].type == ContactType::kBilateral) continue;
    coupled[i].add(static_cast<int>(i));
    if (coupled[i].size < active) sets.push_back(coupled[i]);
  }
  std::sort(sets.begin(), sets.end());
  int grouped = 0;
  for (std::size_t a = 0, b = 0; a < sets.size(); a = b) {
    while (b < sets.size() && sets[b] == sets[a]) ++b;
    if (b - a >= static_cast<std::size_t>(kAutoMultiPoint)) grouped += static_cast<int>(b - a);
  }
  return contacts > 0 ? static_cast<double>(grouped) / contacts : 0.0;
}

// normalCoupling's scratch, kept per thread: no allocation on a microsecond solve after the
// first. Reached through one call, not by name: in a shared library the compiler recomputes a
// thread_local's address (a call) wherever it reuses it, in the loops over W too.
struct CouplingScratch {
  std::vector<double> sums;
  std::vector<char> redundant;
  std::vector<double> active_weight;  // 1 or 0 (ignored): the LCP loop below without branches
  // Which contacts each contact is coupled to, as an order-free hash of the set and its size.
  std::vector<CouplingSet> coupled, sets;
  std::vector<int> members;  // the contacts whose sets are read: active, not bilateral
};
[[gnu::noinline]] CouplingScratch& couplingScratch() {
  thread_local CouplingScratch scratch;
  return scratch;
}

// `redundancy`: also the share of nearly parallel normals (only the frictional plan reads it),
// and with `sets` that of multi-point contacts (an order-free hash per coupled pair), with
// `sets_only` that alone on a dense W (the rest left out of the result).
Coupling normalCoupling(const SolveContext& ctx, bool redundancy, bool sets, bool sets_only = false) {
  const Problem& p = *ctx.problem;
  const int nc = static_cast<int>(p.contacts.size());
  CouplingScratch& work = couplingScratch();
  std::vector<double>& scratch = work.sums;
  std::vector<char>& redundant = work.redundant;
  std::vector<double>& active_weight = work.active_weight;
  std::vector<CouplingSet>& coupled = work.coupled;
  scratch.assign(4 * static_cast<std::size_t>(nc), 0.0);
  redundant.assign(redundancy ? nc : 0, 0);
  sets = sets && redundancy;
  coupled.assign(sets ? nc : 0, CouplingSet{});
  std::vector<int>& members = work.members;  // multiPointShare reads only their sets
  members.clear();
  if (sets)
    for (int i = 0; i < nc; ++i)
      if (!ctx.ignored[i] && p.contacts[i].type != ContactType::kBilateral) members.push_back(i);
  active_weight.resize(nc);
  for (int i = 0; i < nc; ++i) active_weight[i] = ctx.ignored[i] ? 0.0 : 1.0;
  double* diag = scratch.data();
  double* off_sum = diag + nc;
  double* lower_sum = off_sum + nc;
  double* positive_diag = lower_sum + nc;  // W_ii where positive, else infinite (below)
  const auto* dense = std::get_if<Eigen::MatrixXd>(&p.W);
  constexpr double kInfinity = std::numeric_limits<double>::infinity();
  for (int i = 0; i < nc; ++i) {
    diag[i] = ctx.normalDiagonal(i);
    positive_diag[i] = diag[i] > 0.0 ? diag[i] : kInfinity;
  }
  // Rows i and j nearly parallel: |w| >= kAutoRedundant √(W_ii W_jj), squared (no square
  // root per pair of a dense W), as w² >= parallelTo(j) · positive_diag[i]: false wherever a
  // diagonal is not positive, one of the two factors being infinite.
  auto parallelTo = [&](int j) { return diag[j] > 0.0 ? kAutoRedundant * kAutoRedundant * diag[j] : kInfinity; };
  auto visit = [&](int i, int j, double w) {
    off_sum[i] += std::abs(w);
    if (j < i) lower_sum[i] += std::abs(w);
    if (sets && p.contacts[i].type != ContactType::kBilateral && (w != 0.0 || !dense))
      coupled[i].add(j);  // a stored block couples
    if (redundancy && w * w >= parallelTo(j) * positive_diag[i]) redundant[i] = 1;
  };
  const int* offsets = ctx.offsets.data();
  // One column j of a dense frictional W: the LCP's loops below, and visit's parallel test
  // without its branches (visit per pair, every row's set hashed, had cost a third of the
  // sweeps' time on MuJoCo's softbox: 679 entries, 651 of them joint rows).
  auto pairs = [&](int j, const double* column) {
    const double parallel_j = parallelTo(j);
    auto range = [&](int from, int to, bool lower) {
      for (int i = from; i < to; ++i) {
        const double w = active_weight[i] * std::abs(column[offsets[i]]);
        off_sum[i] += w;
        if (lower) lower_sum[i] += w;
        redundant[i] |= static_cast<char>(w * w >= parallel_j * positive_diag[i]);
      }
    };
    range(0, j, false);
    range(j + 1, nc, true);
  };
  if (dense) {
    for (int j = 0; j < nc; ++j) {
      if (active_weight[j] == 0.0) continue;
      const double* column = dense->data() + static_cast<std::ptrdiff_t>(offsets[j]) * dense->rows();
      if (!redundancy) {  // an LCP: only κ and the Gauss-Seidel bound, branch-free loops
        for (int i = 0; i < j; ++i) off_sum[i] += active_weight[i] * std::abs(column[offsets[i]]);
        for (int i = j + 1; i < nc; ++i) {
          const double w = active_weight[i] * std::abs(column[offsets[i]]);
          off_sum[i] += w;
          lower_sum[i] += w;
        }
        continue;
      }
      // Frictional. The coupling sets, a hash per coupled pair, apart and only for the
      // members (a soft body's 28 contacts among its 651 joint rows).
      if (!sets_only) pairs(j, column);
      for (int i : members)
        if (i != j && column[offsets[i]] != 0.0) coupled[i].add(j);
    }
  } else if (const auto* sparse = std::get_if<BlockSparseMatrix>(&p.W)) {
    for (int i = 0; i < sparse->blockCount() && i < nc; ++i) {
      if (ctx.ignored[i]) continue;
      for (int b = sparse->row_start[i]; b < sparse->row_start[i + 1]; ++b) {
        const int j = sparse->block_col[b];
        if (j != i && !ctx.ignored[j]) visit(i, j, sparse->values[sparse->value_start[b]]);
      }
    }
  }
  double sum = 0.0, gs_bound = 0.0;
  int active = 0, repeated = 0, contacts = 0;  // contacts: the active ones not bilateral
  bool positive = true;
  for (int i = 0; i < nc; ++i)
    if (!ctx.ignored[i] && !(diag[i] + ctx.regularization > 0.0)) positive = false;
  for (int i = 0; i < nc; ++i) {
    if (ctx.ignored[i] || diag[i] <= 0.0) continue;  // no diagonal: Gauss-Seidel cannot use the row
    sum += off_sum[i] / diag[i];
    const double pivot = diag[i] - lower_sum[i];
    gs_bound = std::max(gs_bound, pivot > 0.0 ? (off_sum[i] - lower_sum[i]) / pivot
                                              : std::numeric_limits<double>::infinity());
    ++active;
    if (p.contacts[i].type == ContactType::kBilateral) continue;  // a joint: no contact point
    repeated += redundancy && redundant[i] ? 1 : 0;
    ++contacts;
  }
  Coupling c;
  c.positive_diagonal = positive;
  if (active > 0) {
    c.kappa = sum / active;
    c.gs_bound = gs_bound;
    c.redundant = contacts > 0 ? static_cast<double>(repeated) / contacts : 0.0;
    if (sets) c.multi_point = multiPointShare(ctx, coupled, work.sets, active, contacts);
  }
  return c;
}

// normalCoupling's κ on a block-sparse W, read row by row only until it is known to reach
// `enough` (the terms are not negative): then a lower bound >= `enough`. An LCP's plan reads
// only κ < kAutoStrongDominant, and on MuJoCo's steps (strongly coupled humanoids) the full
// pass cost a quarter of newton's solve. Same rows, terms and order as normalCoupling.
double sparseCoupling(const SolveContext& ctx, const BlockSparseMatrix& W, double enough) {
  const int nc = std::min(static_cast<int>(ctx.problem->contacts.size()), W.blockCount());
  const double stop = enough * activeContacts(ctx);  // activeContacts >= the rows summed below
  double sum = 0.0;
  int active = 0;
  for (int i = 0; i < nc; ++i) {
    if (ctx.ignored[i]) continue;
    double diag = 0.0, off = 0.0;
    for (int b = W.row_start[i]; b < W.row_start[i + 1]; ++b) {
      const int j = W.block_col[b];
      const double w = W.values[W.value_start[b]];
      if (j == i) diag = w;  // as diagonalValues: the last stored diagonal block
      else if (!ctx.ignored[j]) off += std::abs(w);
    }
    if (diag <= 0.0) continue;  // as normalCoupling: a row without diagonal adds nothing
    sum += off / diag;
    ++active;
    if (sum >= stop) return sum / active;
  }
  return active > 0 ? sum / active : 0.0;
}

// normalCoupling's κ on a dense symmetric W, column by column (contiguous; a column's sum is
// its row's), read only until it is known to reach `enough`, as sparseCoupling: on MuJoCo's
// dense pyramidal islands the full pass cost a fifth of newton's solve.
double denseSymmetricCoupling(const SolveContext& ctx, const Eigen::MatrixXd& W, double enough) {
  const int nc = static_cast<int>(ctx.problem->contacts.size());
  const int* offsets = ctx.offsets.data();
  const double stop = enough * activeContacts(ctx);
  const bool any_ignored = anyIgnored(ctx);
  double sum = 0.0;
  int active = 0;
  for (int j = 0; j < nc; ++j) {
    if (ctx.ignored[j]) continue;
    const double* column = W.data() + static_cast<std::ptrdiff_t>(offsets[j]) * W.rows();
    const double diag = column[offsets[j]];
    if (diag <= 0.0) continue;  // as normalCoupling: a row without diagonal adds nothing
    double off = 0.0;
    for (int i = 0; i < nc; ++i)
      if (i != j && (!any_ignored || !ctx.ignored[i])) off += std::abs(column[offsets[i]]);
    sum += off / diag;
    ++active;
    if (sum >= stop) return sum / active;
  }
  return active > 0 ? sum / active : 0.0;
}

// A frictional plan that starts with Gauss-Seidel (autoPlan, below): block-sparse or dense
// above kAutoNewtonRows rows and a moderate coupling, at any tolerance where W has full rank,
// and down to kAutoNewtonTolerance (residual rule) where it does not. Nearly parallel normal
// rows between the same two bodies (a capsule lying on another along a line: two points) leave
// the split of the force between them open, and Gauss-Seidel picks one without losing its
// rate while the coupling stays moderate; the scout and newton that such rows otherwise get
// are for the strongly coupled face contacts of box stacks (κ 2.3-3.6). The capsule piles'
// rank-deficient islands (12-177 rows, κ 0.5-1.9) at 1e-5/1e-6: Gauss-Seidel (sor 1.3) is the
// fastest own solver, and the scout-then-newton plan took 1.5-2.3x its time. Below
// kAutoNewtonTolerance newton's superlinear steps pay there as elsewhere.
bool firstOrderBySize(const AutoFeatures& f, const SolverParams& p) {
  if (!(f.sparse || f.rows > kAutoNewtonRows) || !(f.coupling < kAutoSparseGs)) return false;
  return !f.rank_deficient || (p.stopping_rule == StoppingRule::kResidual && p.tolerance >= kAutoNewtonTolerance);
}

// A dense LCP's W is compared for symmetry (a non-symmetric one usually at its first pair); a
// block-sparse W is assembled (J M⁻¹ Jᵀ: scenes, MuJoCo's efc_AR) and presumed symmetric:
// comparing every island's blocks cost as much as newton's whole solve on MuJoCo's steps, and
// newton tests the symmetry itself before its active-set path (a non-symmetric W gets its
// general semismooth path, then Lemke on a stall). `known_symmetric`: W's symmetry when the
// caller measured it already (-1: not measured).
AutoFeatures autoFeatures(const SolveContext& ctx, int body_dof, bool friction, int known_symmetric,
                          const PositiveDiagonal& positive_diagonal) {
  AutoFeatures f;
  f.rows = ctx.problem->rowCount();
  f.body_form = static_cast<bool>(ctx.problem->bodies);
  f.sparse = std::holds_alternative<BlockSparseMatrix>(ctx.problem->W) && !f.body_form;
  if (!friction && f.rows > kAutoLemkeRows) return f;  // the plan reads only the size there
  if (!friction && f.sparse) {  // the plan reads κ < kAutoStrongDominant and, below it, the diagonal
    f.coupling = sparseCoupling(ctx, std::get<BlockSparseMatrix>(ctx.problem->W), kAutoStrongDominant);
    f.positive_diagonal = f.coupling < kAutoStrongDominant && positive_diagonal();  // else unread
    f.symmetric = true;  // presumed (below)
    return f;
  }
  if (!friction && !f.body_form) {  // a dense LCP: its symmetry first (below)
    f.symmetric = known_symmetric >= 0 ? known_symmetric == 1 : isSymmetric(ctx.problem->W, 1e-12);
    if (f.symmetric) {  // the plan reads κ < kAutoStrongDominant and, below it, the diagonal
      f.coupling = denseSymmetricCoupling(ctx, std::get<Eigen::MatrixXd>(ctx.problem->W), kAutoStrongDominant);
      f.positive_diagonal = positive_diagonal();
      return f;
    }
    // Non-symmetric: the plan reads Gauss-Seidel's contraction bound only where pgs can start
    // (a zero diagonal, the usual non-monotone LCP, goes to Lemke without it).
    if (!positive_diagonal()) return f;
  }
  // Above the small size the multi-point share is measured only where the plan reads it,
  // in a second pass (firstOrderBySize): on a MuJoCo cloth's dense 265 rows, which go to
  // Gauss-Seidel anyway, the pass with the sets had cost 15 % of the sweeps' time. Up to it,
  // dense or block-sparse, the sets come with the first pass: a second pass over every stored
  // block costs more than their hashes (a 48-row box pyramid: 8 % of auto's instructions
  // went to the two passes).
  const bool one_pass = f.rows <= kAutoNewtonRows;
  if (!f.body_form) {
    const Coupling c = normalCoupling(ctx, friction, one_pass);
    f.coupling = c.kappa;
    f.gs_bound = c.gs_bound;
    f.positive_diagonal = c.positive_diagonal;
    f.rank_deficient = c.redundant >= kAutoRedundantShare;
    f.multi_point = c.multi_point >= kAutoRedundantShare;
  }
  if (body_dof > 0) f.rank_deficient = f.rank_deficient || activeRows(ctx).all > body_dof;
  if (!f.body_form && friction && !one_pass && !firstOrderBySize(f, *ctx.params))
    f.multi_point = normalCoupling(ctx, friction, true, true).multi_point >= kAutoRedundantShare;
  return f;
}


// More than half the active rows bilateral (joints, a soft body's equality constraints).
bool mostlyBilateral(const SolveContext& ctx) {
  const ActiveRows rows = activeRows(ctx);
  return 2 * rows.bilateral > rows.all;
}

// Multi-point contacts whose points are spread over their faces (no nearly parallel normal
// rows), most rows contacts: apgd needs about as many iterations as Gauss-Seidel sweeps, each
// one product with the block-sparse W (autoPlan's `apgd_holds`, read in runPortfolio).
bool apgdHolds(const AutoFeatures& f, const SolveContext& ctx) {
  return f.multi_point && !f.rank_deficient && !mostlyBilateral(ctx);
}

// `friction`: ctx.hasFriction(), measured once per solve by the caller.
Plan autoPlan(const SolveContext& ctx, bool friction, bool* scout, bool* apgd_holds,
              int known_symmetric, const PositiveDiagonal& positive_diagonal) {
  using K = SolverKind;
  const SolverParams& p = *ctx.params;
  if (hasExtendedFriction(*ctx.problem)) return {K::kNlgs};
  if (friction && pyramidModel(p)) return {K::kPgs, K::kLemke};
  // One contact (most islands of a scene at rest): Gauss-Seidel's local step is that
  // contact's own exact solve, so no feature is worth measuring.
  if (activeContacts(ctx) <= 1 && !ctx.problem->bodies && positive_diagonal())
    return friction ? Plan{K::kNlgs, K::kNewton, K::kApgd, K::kProx}
                    : Plan{K::kPgs, K::kLemke, K::kNewton, K::kApgd};
  if (ctx.problem->bodies)  // unbuilt first: no W
    return friction ? Plan{K::kNlgs, K::kApgd, K::kNewton, K::kProx}
                    : Plan{K::kPgs, K::kNewton, K::kApgd};
  const AutoFeatures f = autoFeatures(ctx, ctx.body_dof, friction, known_symmetric, positive_diagonal);
  if (!friction) {
    // An LCP. Symmetric W (a convex QP): newton's active-set path ends in a few Cholesky
    // steps whatever the coupling; projected Gauss-Seidel only where W is so diagonally
    // dominant that a few sweeps contract it (κ < 1/4: a Jacobi bound of 4x per sweep).
    // Non-symmetric: Gauss-Seidel where its sweep provably contracts (gs_bound < 1: a
    // strictly dominant or a triangular W); otherwise Lemke's pivoting is exact and, up to a dense
    // tableau of kAutoLemkeRows, cheap.
    if (f.rows > kAutoLemkeRows) return {K::kPgs, K::kNewton, K::kApgd};
    // Without a positive diagonal pgs cannot start (zero_diagonal): it is left out.
    const bool positive = f.positive_diagonal;
    if (f.symmetric && f.coupling < kAutoStrongDominant && positive)
      return {K::kPgs, K::kNewton, K::kLemke, K::kApgd};
    if (f.symmetric) return positive ? Plan{K::kNewton, K::kPgs, K::kLemke, K::kApgd} : Plan{K::kNewton, K::kLemke, K::kApgd};
    if (positive && f.gs_bound < 1.0) return {K::kPgs, K::kLemke, K::kNewton, K::kApgd};
    return positive ? Plan{K::kLemke, K::kPgs, K::kNewton, K::kApgd} : Plan{K::kLemke, K::kNewton, K::kApgd};
  }
  const bool dominant = f.coupling < kAutoDominant && !f.rank_deficient;
  // Block-sparse W (one block per pair of contacts sharing a body) with a moderate coupling:
  // Gauss-Seidel first at any size (and tolerance, unless W is rank-deficient:
  // firstOrderBySize); so too a dense W above kAutoNewtonRows, where the plan is first-order
  // either way and a sweep, like an apgd iteration, is one pass over W whatever its storage
  // (a MuJoCo W stored dense because it is full).
  if (firstOrderBySize(f, p)) return {K::kNlgs, K::kApgd, K::kNewton, K::kProx};
  // Between the first-order methods: Gauss-Seidel's early sweeps are its fast ones, so it goes
  // first down to kAutoModerateTolerance unless W is rank-deficient or has multi-point contacts,
  // where its rate collapses and apgd's momentum wins (box pyramids at 1e-4: apgd 5-11x faster;
  // sphere piles, one contact per pair of bodies: nlgs 2-5x faster than apgd).
  const bool loose = p.stopping_rule != StoppingRule::kResidual || p.tolerance >= kAutoTightTolerance;
  const bool gs_suits =
      !f.rank_deficient && !f.multi_point && (loose || p.tolerance >= kAutoModerateTolerance);
  if (loose) {
    // A few contacts: the probe's sweeps are newton's warm-up, and where they have not met
    // the tolerance by its end a few Newton steps (a plain LU of at most kAutoNewtonSmallRows
    // rows, a few sweeps' cost each) usually finish, where Gauss-Seidel goes on at the rate
    // that left it short and apgd crawls on a stack's mass ratios (MuJoCo's humanoid and mug
    // at 1e-3: 20 sweeps and one step against 39-113 sweeps; 2-8 boxes stacked with a mass
    // ratio of 10-100: 21-134 iterations against apgd's 100-740). Where Newton's steps stall
    // (a capsule pile's 5-contact island at 1e-3: 137 iterations, 1.5x apgd's time) the slices
    // hand over.
    if (p.stopping_rule == StoppingRule::kResidual && f.rows <= kAutoNewtonSmallRows)
      return {K::kNewton, K::kNlgs, K::kApgd, K::kProx};
    if ((dominant && f.rows <= kAutoSmallRows) || gs_suits)
      return {K::kNlgs, K::kApgd, K::kNewton, K::kProx};
    // Where apgd holds (apgdHolds) it keeps its place at two digits too (runPortfolio).
    *apgd_holds = apgdHolds(f, ctx);
    return {K::kApgd, K::kNlgs, K::kNewton, K::kProx};
  }
  // Tight: Gauss-Seidel only where it contracts fast whatever the size.
  if (f.coupling < kAutoStrongDominant && !f.rank_deficient)
    return {K::kNlgs, K::kNewton, K::kProx, K::kApgd};
  // Block-sparse W above the small size: a Newton step is a sparse LU (a large constant per
  // row), so the first-order methods go first and newton/prox take over when they stall.
  // Gauss-Seidel first down to kAutoModerateTolerance (gs_suits), and at any tolerance where
  // most rows are bilateral and its rate holds (no multi-point contacts, no rank deficiency,
  // below): a soft body's or a cloth's equality rows are a linear system, solved at a steady
  // rate with no active set to settle, whose widely spread spectrum makes apgd's steps crawl
  // (MuJoCo's softbox: 117 sweeps against apgd's 11 578 iterations). Where most rows are
  // contacts Gauss-Seidel's rate slows as the active set settles (sphere_pile_40 at 1e-5: apgd's
  // 5 351 iterations, nlgs stalled).
  const bool gs_first = gs_suits || (!f.rank_deficient && !f.multi_point && mostlyBilateral(ctx));
  if (f.sparse && f.rows > kAutoNewtonRows)
    return gs_first ? Plan{K::kNlgs, K::kApgd, K::kNewton, K::kProx}
                    : Plan{K::kApgd, K::kNlgs, K::kNewton, K::kProx};
  const int newton_rows = p.tolerance < kAutoNewtonTolerance ? kAutoNewtonRowsTight : kAutoNewtonRows;
  if (f.rows <= newton_rows) {
    // Multi-point or rank-deficient contacts: apgd scouts first (below). Reached under the
    // residual rule only (any other is `loose`), which the scout's rate test needs.
    *scout = (f.multi_point || f.rank_deficient) && f.rows >= kAutoScoutRows;
    // A scout that holds: the probe before it stops at ten sweeps (probeAllowance).
    *apgd_holds = *scout && apgdHolds(f, ctx);
    return {K::kNewton, K::kProx, K::kApgd, K::kNlgs};
  }
  return gs_first ? Plan{K::kNlgs, K::kApgd, K::kProx, K::kNewton}
                  : Plan{K::kApgd, K::kProx, K::kNewton, K::kNlgs};
}

// Iterations of a member's first slice, and the residual factor a slice must reach to keep
// the member running; a slice doubles while the member keeps its place.
int firstSlice(SolverKind kind) {
  switch (kind) {
    case SolverKind::kNewton: return 300;  // 20 warm-up sweeps, Newton steps and two nlgs bursts
    case SolverKind::kProx: return 300;
    case SolverKind::kApgd: return 200;       // each slice restarts its momentum
    case SolverKind::kLemke: return 1 << 30;  // pivoting is not sliced
    default: return 100;
  }
}
double sliceFactor(SolverKind kind) {
  return kind == SolverKind::kNewton || kind == SolverKind::kProx ? 0.1 : 0.5;
}

// λ onto the contacts' feasible sets (Coulomb cone, λ_n >= 0); other rows unchanged.
void projectFeasible(const SolveContext& ctx, Eigen::VectorXd& x) {
  for (std::size_t i = 0; i < ctx.problem->contacts.size(); ++i) {
    const Contact& c = ctx.problem->contacts[i];
    double* l = x.data() + ctx.offsets[i];
    if (c.type == ContactType::kFrictionless) {
      l[0] = std::max(0.0, l[0]);
    } else if (c.type == ContactType::kFrictional && c.rows == 3) {
      projectOntoCone(ctx.mu[i], l);
    }
  }
}

// The Gauss-Seidel kernel that can probe this problem (kAuto: none): not where the plan is
// fixed (torsional/rolling contacts, the pyramid), not without a positive normal diagonal,
// not for a block-sparse LCP unless probesSymmetricLcp.
SolverKind probeKind(const SolveContext& ctx, bool friction, const PositiveDiagonal& positive_diagonal) {
  if (hasExtendedFriction(*ctx.problem)) return SolverKind::kAuto;
  if (friction && pyramidModel(*ctx.params)) return SolverKind::kAuto;
  // A block-sparse LCP is presumed symmetric (below): newton's active-set path, a few
  // Cholesky steps, is what the probe would delay (MuJoCo's pyramidal steps: +10..40 %).
  if (!friction && std::holds_alternative<BlockSparseMatrix>(ctx.problem->W) && !probesSymmetricLcp(ctx))
    return SolverKind::kAuto;
  if (!ctx.problem->bodies && !positive_diagonal()) return SolverKind::kAuto;
  return friction ? SolverKind::kNlgs : SolverKind::kPgs;
}

}  // namespace

double autoStartResidual(const SolveContext& ctx, const Eigen::VectorXd& lambda) {
  if (!std::isnan(ctx.start_residual)) return ctx.start_residual;
  if (!lambda.isZero(0.0)) return ctx.residual(lambda);
  return naturalMapResidual(*ctx.problem, ctx.mu, lambda, ctx.problem->d_free, ctx.ignored);
}

// Each island alone is held to its share of the tolerance (islands.h: all islands meeting
// theirs implies the whole residual meets it), which is stricter than the whole problem's test
// wherever the islands' residuals are unequal: an island whose residual is small next to the
// others' would be allowed far more, but its share cannot know that in advance. Where the start
// is within a digit of the tolerance (at two or three digits: a start of mostly separating
// contacts and shallow penetrations), the first plain sweeps on the whole problem, the probe's
// own first stage, often meet it whole: the capsule piles at 1e-3, two whole sweeps where their
// 32-39 islands took 66-78 in all (5-6 on the slowest). Where they do not, their iterate is
// dropped and each island's plan starts from the start as before (kept, it changed the islands'
// paths: MuJoCo's humanoids at 1e-3, 1.1-1.7x); the sweeps count in the solve's iterations.
bool autoWholeSweepsEnd(const SolveContext& ctx, Eigen::VectorXd& lambda, KernelReport& report, double& seconds) {
  const SolverParams& params = *ctx.params;
  report = KernelReport();
  seconds = 0.0;
  if (params.stopping_rule != StoppingRule::kResidual || params.tolerance < kAutoTightTolerance ||
      !(ctx.start_residual <= kAutoWholeSweepsReach * params.tolerance) || !ctx.hasFriction() ||
      pyramidModel(params) || hasExtendedFriction(*ctx.problem) || params.maxIt <= 2 * kAutoProbeFirst ||
      params.maxF > 0.0 || !lambda.isZero(0.0))
    return false;
  SolverParams whole = params;
  whole.maxIt = kAutoProbeFirst;
  SolveContext sweeps = ctx;
  sweeps.params = &whole;
  Eigen::VectorXd x = lambda;
  const auto t0 = std::chrono::steady_clock::now();
  report = runKernel(SolverKind::kNlgs, sweeps, x);
  seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (report.status != SolveStatus::kConverged) return false;
  lambda = std::move(x);
  report.total_iterations = report.iterations;
  return true;
}

struct PortfolioMember {
  SolverKind kind;
  int slice;
  double rate = 0.0;      // log residual decrease per second, last slice
  double decrease = 0.0;  // log residual decrease over all its slices
  double seconds = 0.0;   // and their time
  bool tried = false;
  int retry_origin = 0;  // 0 not needed, 1 due, 2 done
  bool probe = false;    // one slice only, then out of the rotation
  bool scout = false;    // apgd before newton, from the start: its iterate dropped unless it ends the solve
  int warmup_credit = 0;  // newton after the probe: the warm-up sweeps the probe ran (its first run only)
  bool trial = false;     // its next slice is a trial (kernels.h: trialPassed)
  bool capped = false;    // its next slice lasts at most as long as the solve so far (a stall's hand-over)
  double trial_cut = 0.0;  // its first trial, stopped at the trial's deadline, lasted this long (s)
  bool second_trial = false;  // that trial's second is due or done (dueSecondTrials)
};

// A member's log residual decrease per second over all its slices.
double overallRate(const PortfolioMember& member) { return member.decrease / std::max(member.seconds, 1e-9); }

// After a stall chosen by rate (runPortfolio), whether the member that just stalled, `m`, takes
// the next slice itself: only where its last slice's rate is at least every other member's
// record, the larger of that member's last-slice rate and its rate over all its slices.
// Otherwise the other with the best record goes. A member that lowered the residual a little
// in each slice, less than its factor, would otherwise be handed ever longer slices while the
// member that lowered it fastest before sits idle with a last slice that did not (apgd, whose
// residual rises before it falls when it restarts from another member's iterate): on stacks of
// 6-9 boxes with a mass ratio of 100 (bench/stacked_boxes.cpp) prox took slice after slice,
// 0.19-1.2 s in all, where apgd alone converges in 13-66 ms.
std::size_t stallTakerAfter(const std::vector<PortfolioMember>& members, std::size_t m) {
  auto record = [](const PortfolioMember& mem) { return std::max(mem.rate, overallRate(mem)); };
  std::size_t other = members.size();
  for (std::size_t k = 0; k < members.size(); ++k)
    if (k != m && record(members[k]) > 0.0 &&
        (other == members.size() || record(members[k]) > record(members[other])))
      other = k;
  return other != members.size() && members[m].rate < record(members[other]) ? other : m;
}

// A member whose first trial was stopped at its deadline (trialPassed) has not shown what it
// does: the clock judged it, and timing noise can decide that. Once the solve has used half of
// maxIt or of time_budget, such a member is due a second trial, twice as long as the first, at
// the next stall: before the limits run out, every member gets a fair chance. Not earlier,
// where a member that cannot help (newton on stacks of boxes with mass ratios, 3 Newton steps
// of a dense W on trial) would cost the stacks' solves (bench/stacked_boxes.cpp at 1e-3: 1.84 ->
// 2.01x the fastest own solver with a second trial at every next stall). The sphere_pile demo's
// step 356 at 1e-9 (81 rows, maxIt 5000): newton's trial was cut after 8 of the ~10 steps it
// needs (115 us of 130), and nlgs and apgd then used up maxIt above the tolerance, in about one
// run in twenty (test_portfolio_scene.cpp). While a second trial is pending a slice takes at
// most half the iterations left, so that a stall comes before maxIt (the time budget's slices
// already take at most half the time left).
bool awaitsSecondTrial(const PortfolioMember& mem) { return mem.trial_cut > 0.0 && !mem.second_trial; }
bool secondTrialPending(const std::vector<PortfolioMember>& members) {
  return std::any_of(members.begin(), members.end(), awaitsSecondTrial);
}
void dueSecondTrials(std::vector<PortfolioMember>& members) {
  for (PortfolioMember& mem : members)
    if (awaitsSecondTrial(mem)) {
      mem.second_trial = true;
      mem.tried = false;
    }
}

// The best iterate with its measures, set aside while a member runs that may be undone.
struct SavedBest {
  Eigen::VectorXd x;
  double residual = std::numeric_limits<double>::infinity();  // infinite: nothing saved
  double error = 0.0;
  FrictionModel model = FrictionModel::kCoulombDisc;
};

// What one solve's portfolio needs besides its report, kept per thread (islands run on a
// pool) so that a microsecond island pays no allocation for it after the first solve: the
// members, the member context (its vectors assigned in place) and the iterates.
struct Workspace {
  std::vector<PortfolioMember> members;
  SolveContext member;
  Eigen::VectorXd best, x, returned_rows;
  SavedBest warmup;        // the probe's iterate after newton's warm-up sweeps
  SavedBest before_scout;  // what newton starts from if the apgd scout does not end the solve
  SavedBest probe_end;     // the probe's last iterate, where an apgd scout follows it
  GaussSeidelMemo gs_memo;  // the probe's blocks serve every later Gauss-Seidel slice
  ApgdMemo apgd_memo;       // an apgd slice resumes the last one when handed its answer back
};

// Moves the member of that kind, if any, to the front of the plan; whether there was one.
bool moveFirst(std::vector<PortfolioMember>& members, SolverKind kind) {
  const auto it = std::find_if(members.begin(), members.end(),
                               [kind](const PortfolioMember& mem) { return mem.kind == kind; });
  if (it == members.end()) return false;
  std::rotate(members.begin(), it, it + 1);
  return true;
}

// Moves the member `kind` to just before `before` where it comes after it (scouts aside).
void putBefore(std::vector<PortfolioMember>& members, SolverKind kind, SolverKind before) {
  auto is = [](SolverKind k) { return [k](const PortfolioMember& mem) { return mem.kind == k && !mem.scout; }; };
  const auto target = std::find_if(members.begin(), members.end(), is(before));
  const auto it = std::find_if(members.begin(), members.end(), is(kind));
  if (target < it && it != members.end()) std::rotate(target, it, it + 1);
}

// Puts newton first in a plan, with a first slice of its warm-up and as many steps as
// `sweeps` pay for (newtonStepSweeps each), at least kAutoNewtonSteps.
void newtonFirst(std::vector<PortfolioMember>& members, const SolveContext& ctx, double sweeps) {
  if (!moveFirst(members, SolverKind::kNewton)) return;
  const double step_sweeps = std::max(1.0, newtonStepSweeps(ctx));
  const double steps = std::max<double>(kAutoNewtonSteps, (sweeps - kNewtonWarmupSweeps) / step_sweeps);
  members.front().slice = kNewtonWarmupSweeps + static_cast<int>(std::min(steps, 1e6));
}

// A small symmetric LCP (W dense or in blocks) whose plan starts with newton: newton's
// active-set path (a few Cholesky steps of at most kAutoDirectRows rows) runs directly,
// without the portfolio's set-up and slice bookkeeping, which cost more than the path itself
// there (a 2-row LCP: about 1 500 of auto's 11 000 instructions per solve). True, with
// `lambda` and `report` filled, when it converges; otherwise `lambda` is untouched and the
// portfolio starts as it would have (its newton runs the same few steps again, the price of
// a rare failure).
bool directActiveSet(const SolveContext& ctx, Eigen::VectorXd& lambda, Eigen::VectorXd& x, KernelReport& report) {
  const Clock::time_point t0 = Clock::now();
  x = lambda;
  KernelReport r;
  if (!solveSymmetricActiveSet(ctx, x, &r)) return false;
  lambda = x;
  report.status = SolveStatus::kConverged;
  report.iterations = r.iterations;
  report.solver_error = r.solver_error;
  report.stages.emplace_back(solverName(SolverKind::kNewton),
                             std::chrono::duration<double>(Clock::now() - t0).count());
  return true;
}

Workspace& portfolioWorkspace() {
  thread_local Workspace work;
  return work;
}

KernelReport runPortfolio(const SolveContext& ctx, Eigen::VectorXd& lambda) {
  const SolverParams& params = *ctx.params;
  KernelReport report;
  // The measure members are compared by: the disc residual, or for a pyramid the kernels'
  // own pyramid residual (the disc's is nonzero there by design).
  const bool friction = ctx.hasFriction();
  const bool pyramid = pyramidModel(params) && friction;
  const bool by_residual = params.stopping_rule == StoppingRule::kResidual && !pyramid;
  double best_residual = pyramid ? std::numeric_limits<double>::infinity() : autoStartResidual(ctx, lambda);
  if (!std::isfinite(best_residual)) best_residual = std::numeric_limits<double>::infinity();
  if (by_residual && best_residual <= params.tolerance) {  // the (warm) start is an answer: path "auto"
    report.status = SolveStatus::kConverged;
    report.solver_error = best_residual;
    return report;
  }

  Workspace& work = portfolioWorkspace();  // one thread-local lookup per solve
  std::vector<PortfolioMember>& members = work.members;
  members.clear();
  Plan plan;                     // measured once, when first needed
  bool plan_scout = false;       // autoPlan's: an apgd scout goes before newton (residual rule only)
  bool plan_apgd_holds = false;  // autoPlan's: apgd, first or scout, needs about nlgs's iterations
  int known_symmetric = -1;      // W's symmetry once measured (LCPs)
  const PositiveDiagonal positive_diagonal(ctx);
  auto planned = [&]() -> const Plan& {
    if (plan.empty())
      plan = autoPlan(ctx, friction, &plan_scout, &plan_apgd_holds, known_symmetric, positive_diagonal);
    return plan;
  };
  auto startPlan = [&] {
    members.clear();
    for (SolverKind kind : planned()) members.push_back({kind, firstSlice(kind)});
    if (plan_scout) {
      PortfolioMember apgd{SolverKind::kApgd, kAutoScoutFirst};
      apgd.scout = true;
      members.insert(members.begin(), apgd);
    }
  };
  // The probe runs before the features are even measured: a problem it solves pays for
  // nothing else.
  SolverKind probe_kind = by_residual ? probeKind(ctx, friction, positive_diagonal) : SolverKind::kAuto;
  // Except on a dense symmetric LCP (a convex QP) whose plan is newton's active-set path: a
  // few Cholesky steps whatever the coupling, which the probe's sweeps would only delay
  // (MuJoCo's dense pyramidal steps: +45 %), unless probesSymmetricLcp. The symmetry test
  // stops at the first unequal pair, so a non-symmetric W pays almost nothing for it.
  if (probe_kind == SolverKind::kPgs && std::holds_alternative<Eigen::MatrixXd>(ctx.problem->W) &&
      ctx.problem->rowCount() <= kAutoLemkeRows) {
    known_symmetric = isSymmetric(ctx.problem->W, 1e-12) ? 1 : 0;
    if (known_symmetric == 1 && planned().front() == SolverKind::kNewton && !probesSymmetricLcp(ctx))
      probe_kind = SolverKind::kAuto;
  }
  if (by_residual && !friction && probe_kind == SolverKind::kAuto && !ctx.problem->bodies &&
      ctx.problem->rowCount() <= kAutoDirectRows && planned().front() == SolverKind::kNewton &&
      directActiveSet(ctx, lambda, work.x, report))
    return report;
  if (probe_kind != SolverKind::kAuto) {
    PortfolioMember probe{probe_kind, kAutoProbeFirst};
    probe.probe = true;
    members.push_back(probe);
  } else {
    startPlan();
  }
  const double probe_start = best_residual;
  double stage_start = best_residual;
  int probe_sweeps = 0;
  bool warmup_over = false;  // the probe swept through newton's warm-up
  SavedBest& warmup_best = work.warmup;
  warmup_best.residual = std::numeric_limits<double>::infinity();
  int warmup_end_sweeps = 0;  // the probe's sweeps when warmup_best was saved
  std::unique_ptr<Problem> assembled;      // the body form's W, assembled only if a member needs it
  const Eigen::VectorXd& origin = lambda;  // lambda itself is written once, at the end
  // A kernel may leave a force on an ignored contact (minW, maxF) or on the tangent rows of a
  // μ = 0 contact; what the solve returns has none, so that is what is measured.
  bool needs_zeroing = anyIgnored(ctx);
  for (std::size_t i = 0; i < ctx.problem->contacts.size() && !needs_zeroing; ++i)
    needs_zeroing = hasSlidingFriction(ctx.problem->contacts[i].type) && ctx.mu[i] == 0.0;
  SolverParams member_params = params;
  SolveContext& member = work.member;
  member = ctx;  // each slice changes its limits only
  work.gs_memo.clear();
  member.gs_memo = &work.gs_memo;
  work.apgd_memo.clear();
  member.apgd_memo = &work.apgd_memo;
  Eigen::VectorXd& best = work.best;
  Eigen::VectorXd& x = work.x;
  Eigen::VectorXd& returned_rows = work.returned_rows;
  best = lambda;

  std::vector<std::pair<std::string, double>>* stages = &report.stages;
  stages->reserve(4);  // most paths have one to three stages: one allocation, not two
  double best_error = best_residual;
  FrictionModel best_model = FrictionModel::kCoulombDisc;
  SolveStatus last_failure = SolveStatus::kMaxIterations;
  SolverKind last_failed = SolverKind::kAuto;
  std::string last_message;  // the member's own: composed only if every member fails
  int used = 0;
  std::size_t m = 0;
  struct {
    Eigen::VectorXd x;     // its own last iterate
    int iterations = 0;
    double last_residual = 0.0;  // at the end of its last slice
  } scout;  // the apgd scout's state
  SavedBest& before_scout = work.before_scout;
  SavedBest& probe_end = work.probe_end;
  probe_end.residual = std::numeric_limits<double>::infinity();
  double probe_end_needed = std::numeric_limits<double>::infinity();  // sweeps its last stage's rate asked for
  // Sets the best iterate aside, and puts a saved one back (swapped: the saved copy is spent).
  auto saveBest = [&](SavedBest& saved) {
    saved.x = best;
    saved.residual = best_residual;
    saved.error = best_error;
    saved.model = best_model;
  };
  // A few Gauss-Seidel sweeps of `kind` at `omega` from x outside any member's slice (the
  // probe's last window, a drift's jump), counted against maxIt. `start`: x's residual, NaN
  // where not known.
  auto sweepsOutsideSlices = [&](SolverKind kind, int sweeps, double omega, double start) {
    member_params.maxIt = sweeps;
    member_params.sor = omega;
    member_params.tolerance = params.tolerance;
    member.start_residual = start;
    member.has_trial_deadline = false;
    const KernelReport swept = runKernel(kind, member, x);
    if (needs_zeroing) zeroInactiveRows(ctx, x);
    used += swept.iterations;
    return swept;
  };
  auto restoreBest = [&](SavedBest& saved) {
    best.swap(saved.x);
    best_residual = saved.residual;
    best_error = saved.error;
    best_model = saved.model;
  };
  // Gauss-Seidel's over-relaxation (kAutoOmegaTrial): a user's own sor is kept as it is.
  const bool adapt_omega = params.sor == 1.0;
  double plain_rate = 0.0;  // residual factor per plain sweep: the first window's or the probe's stage's
  double gs_omega = 1.0;
  int omega_state = 0;  // 0: the plain window is due, 1: the window at Young's ω, 2: decided,
                        // 3: the probe's plain window after the one at ω
  double omega_rate = 1.0;  // the probe's window at ω: its rate per sweep
  double kept_omega = 1.0;  // and its ω
  // The probe's rate put Gauss-Seidel before a planned apgd (gs_in_slice, below); the sweeps
  // its plain window then forecast (0: none measured).
  bool gs_before_apgd = false;
  double gs_window_needed = 0.0;
  // newton's sticking active-set path from `best`, once per solve (stickingPays); true when it
  // ends the solve.
  bool sticking_tried = false;
  // Where the path applied but Gauss-Seidel's rate said the sweeps would finish first: the
  // sweeps that rate asked for, the length of the next Gauss-Seidel slice (0: none pending).
  double stick_recheck = 0.0;
  auto stickingPathSolves = [&]() {
    sticking_tried = true;
    const Clock::time_point s0 = Clock::now();
    member_params.maxIt = params.maxIt - used;
    member_params.tolerance = params.tolerance;  // not the probe's warm-up stage's
    member.params = &member_params;
    member.has_deadline = ctx.has_deadline;
    member.deadline = ctx.deadline;
    KernelReport stick;
    x = best;
    const bool solved = solveStickingActiveSet(member, x, &stick, kAutoStickDenseRows);
    stages->emplace_back("active-set", std::chrono::duration<double>(Clock::now() - s0).count());
    used += stick.iterations;
    if (!solved) return false;
    best.swap(x);
    best_residual = best_error = stick.solver_error;
    report.status = SolveStatus::kConverged;
    return true;
  };
  // A warm start in which every contact sticks (the last step of a scene at rest): its active
  // set is usually still right, and the path then ends the solve in one Cholesky step where
  // the probe's first sweeps would only confirm it. Up to kAutoStickWarmRows rows: a step on
  // which a contact starts to slide pays one wasted Cholesky of at most that size (~40 sweeps).
  if (by_residual && friction && ctx.problem->rowCount() <= kAutoStickWarmRows && !origin.isZero(0.0) &&
      stickingPathApplies(ctx) && allSticking(ctx, best) && stickingPathSolves())
    members.clear();
  const Clock::time_point solve_start = Clock::now();
  while (!members.empty()) {
    PortfolioMember& cur = members[m];
    member_params.maxIt = std::min(cur.slice, params.maxIt - used);
    if (members.size() > 1 && secondTrialPending(members))  // leave the second trial iterations
      member_params.maxIt = std::min(member_params.maxIt, std::max(1, (params.maxIt - used) / 2));
    member.params = &member_params;
    const Clock::time_point t0 = Clock::now();
    member.has_deadline = ctx.has_deadline;
    member.deadline = ctx.deadline;
    if (ctx.has_deadline && (members.size() > 1 || cur.probe)) {  // leave the others (the plan) half of what is left
      member.deadline = t0 + (ctx.deadline - t0) / 2;
    }
    // A slice handed over on a stall lasts at most as long as the solve so far: a member chosen
    // by its rate may need far more time per iteration than the solve's others (a proximal step
    // solves a Newton sub-problem), and the solve's time at most doubles per hand-over.
    const Clock::time_point as_long_again = t0 + (t0 - solve_start);  // the solve so far, once more
    if (cur.capped) {
      cur.capped = false;
      if (!member.has_deadline || as_long_again < member.deadline) member.deadline = as_long_again;
      member.has_deadline = true;
    }
    member.problem = ctx.problem;
    if (ctx.problem->bodies && cur.kind != SolverKind::kNlgs && cur.kind != SolverKind::kPgs) {
      if (!assembled) assembled = std::make_unique<Problem>(assembledProblem(*ctx.problem));
      member.problem = assembled.get();
    }
    // From the best iterate; a member that could not move from it at all runs once more
    // from the portfolio's own start (the warm start), projected onto the feasible sets.
    const bool from_origin = cur.retry_origin == 1 || (cur.scout && scout.iterations == 0);
    if (cur.retry_origin == 1) cur.retry_origin = 2;
    if (cur.scout && scout.iterations > 0) {
      x = scout.x;  // its own last iterate: apgd resumes (ApgdMemo)
    } else {
      x = from_origin ? origin : best;  // the scout from the start: apgd crawls from a Gauss-Seidel iterate
      if (from_origin) projectFeasible(ctx, x);
    }
    if (cur.scout && scout.iterations == 0) saveBest(before_scout);
    const bool gauss_seidel = cur.kind == SolverKind::kNlgs || cur.kind == SolverKind::kPgs;
    int saved_slice = 0;
    member_params.sor = params.sor;
    if (gauss_seidel && adapt_omega && !cur.probe) {
      if (omega_state < 2) {  // a window of the trial, then the member's own slice goes on
        saved_slice = cur.slice;
        member_params.maxIt = std::min(kAutoOmegaTrial, params.maxIt - used);
        gs_omega = omega_state == 0 ? 1.0 : youngOmega(plain_rate);
      }
      member_params.sor = gs_omega;
    }
    // Gauss-Seidel's rate only slows: where the sticking path was declined on the sweeps its
    // last rate forecast, this slice lasts about that many, so that the path is weighed again
    // on the rate measured next rather than after a slice of 100 or more (stickingPays).
    if (gauss_seidel && !cur.probe && saved_slice == 0 && !sticking_tried && stick_recheck > 0.0) {
      const int forecast = std::max(kAutoOmegaTrial, static_cast<int>(std::ceil(stick_recheck)) + 1);
      member_params.maxIt = std::min(member_params.maxIt, forecast);
      stick_recheck = 0.0;
    }
    // A trial (trialPassed) lasts as long as the solve so far; a Gauss-Seidel member's is its
    // slice after the ω window.
    member.has_trial_deadline = cur.trial && saved_slice == 0;
    member.trial_deadline = as_long_again;
    if (cur.trial_cut > 0.0)  // a second trial (dueSecondTrials): twice as long as the first
      member.trial_deadline = t0 + std::chrono::duration_cast<Clock::duration>(
                                       std::chrono::duration<double>(2.0 * cur.trial_cut));
    if (saved_slice == 0) cur.trial = false;
    // The probe's own windows at Young's ω and plainly after it (probe_omega_window), and its
    // later stages at the ω kept.
    const bool probe_omega_window = cur.probe && (omega_state == 1 || omega_state == 3);
    if (cur.probe && adapt_omega) {
      if (probe_omega_window) gs_omega = omega_state == 1 ? youngOmega(plain_rate) : 1.0;
      member_params.sor = gs_omega;
    }
    // The probe's nlgs sweeps are newton's warm-up, whose end (kNewtonWarmupTolerance or
    // kNewtonWarmupSweeps) a stage stops at, so that its iterate can be kept for newton.
    const bool warmup_stage = cur.probe && probe_kind == SolverKind::kNlgs && !warmup_over;
    member_params.tolerance = params.tolerance;
    // The probe's stages after its first record the residual of each sweep (which the kernel
    // computes anyway under the residual rule) for slowingSweepsToReach; the report carries
    // such histories only where the user asked for them.
    member_params.displayDebug = params.displayDebug || (cur.probe && probe_sweeps > 0);
    if (warmup_stage) {
      member_params.maxIt = std::min(member_params.maxIt, kNewtonWarmupSweeps - probe_sweeps);
      member_params.tolerance = std::max(params.tolerance, kNewtonWarmupTolerance);
    }
    // x's residual when x is the best iterate (newton's own first check of it is then free).
    const bool from_best = !from_origin && !(cur.scout && scout.iterations > 0);
    member.start_residual = by_residual && from_best ? best_residual : std::numeric_limits<double>::quiet_NaN();
    member.warmup_sweeps_done = cur.warmup_credit;
    member.warmup_start_was_warm = cur.warmup_credit > 0 && !origin.isZero(0.0);
    cur.warmup_credit = 0;
    KernelReport r = runKernel(cur.kind, member, x);  // not const: a failed member's message is moved
    member_params.displayDebug = params.displayDebug;
    const bool sticking_before = sticking_tried;  // that path, when it runs below, overwrites x
    if (cur.scout) scout.x = x;
    // A kernel that let a force through on an ignored contact measured the rest against it
    // (fuzzing: a 1e-18 force times a W entry of DBL_MAX made a penetrating contact look
    // separated, "converged"): then its own measure does not count.
    bool kernel_measured_x = true;
    if (needs_zeroing) {
      returned_rows = x;
      zeroInactiveRows(ctx, x);
      kernel_measured_x = x == returned_rows;
    }
    double seconds = std::chrono::duration<double>(Clock::now() - t0).count();  // a drift jump adds its own
    if (stages->empty() || stages->back().first != solverName(cur.kind))
      stages->emplace_back(solverName(cur.kind), 0.0);
    stages->back().second += seconds;
    if (params.displayDebug && !r.history.empty())
      report.history.insert(report.history.end(), r.history.begin(), r.history.end());
    used += r.iterations;
    const double start_residual = best_residual;
    // With the residual rule every kernel's solver_error is the residual of what it returned
    // (a pyramid's own residual for a pyramid); otherwise measure it. Lemke, the one kernel
    // that ends on a ray, measured the forces it returned there too (auto's plans on
    // non-monotone LCPs end there often), a pyramid Lemke by its pyramid residual as pgs's is
    // (measured again here it was the disc residual, compared with pgs's pyramid one).
    const bool measured_run = !failedToRun(r.status) || r.status == SolveStatus::kRayTermination;
    const bool own_measure =
        (by_residual || pyramid) && measured_run && std::isfinite(r.solver_error) && kernel_measured_x;
    double residual = !x.allFinite() ? std::numeric_limits<double>::infinity()
                      : own_measure  ? r.solver_error
                                     : ctx.residual(x);
    if (!std::isfinite(residual)) residual = std::numeric_limits<double>::infinity();
    const bool converged =
        r.status == SolveStatus::kConverged && (!by_residual || residual <= params.tolerance);
    if (residual < best_residual || converged) {
      best_residual = residual;
      best.swap(x);
      best_error = r.solver_error;
      best_model = r.friction_model;
    }
    // A window of the over-relaxation trial: whether it lowered the residual, and its residual
    // factor per sweep (1 where it did not).
    const bool window_moved = r.iterations > 0 && residual < start_residual && !failedToRun(r.status);
    auto windowRate = [&] {
      return window_moved ? std::pow(residual / start_residual, 1.0 / r.iterations) : 1.0;
    };
    if (probe_omega_window) {
      // ω is kept where its window beat the plain sweeps before it; otherwise a plain window
      // follows, and ω is kept if it beat that one. Plain sweeps only slow as they go, so the
      // window before favours them, the window after less so.
      const double rate = windowRate();
      if (omega_state == 1) {
        omega_rate = rate;
        kept_omega = gs_omega;
        if (rate < plain_rate) {
          omega_state = 2;
        } else {
          omega_state = 3;
          gs_omega = 1.0;
        }
      } else {
        if (omega_rate < rate) gs_omega = kept_omega;
        omega_state = 2;
      }
    }
    if (saved_slice > 0) {  // a trial window: its rate per sweep
      const double rate = windowRate();
      if (omega_state == 0) {  // the trial only where the plain sweeps would outlast it
        plain_rate = rate;
        const double window_needed =  // read only where the window moved
            window_moved ? iterationsToReach(params.tolerance, start_residual, residual, r.iterations) : 0.0;
        if (gs_before_apgd) gs_window_needed = window_needed;
        omega_state = window_moved && window_needed > kAutoOmegaTrial ? 1 : 2;
      } else {
        if (!(rate < plain_rate)) gs_omega = 1.0;
        omega_state = 2;
      }
      cur.slice = saved_slice;
    }
    if (converged || (by_residual && best_residual <= params.tolerance)) {
      report.status = SolveStatus::kConverged;
      break;
    }
    if (ctx.deadlinePassed()) {
      report.status = SolveStatus::kTimeBudget;
      report.message =
          "auto: time budget (" + std::to_string(params.time_budget) + " s) ran out; best iterate returned";
      break;
    }
    if (used >= params.maxIt) {
      report.status = SolveStatus::kMaxIterations;
      report.message =
          "auto: maxIt (" + std::to_string(params.maxIt) + ") iterations over every member reached";
      break;
    }
    // A Gauss-Seidel member's iterate that sticks everywhere: the sticking path (stickingPays).
    if (gauss_seidel && friction && by_residual && !sticking_tried && r.iterations > 0 && !failedToRun(r.status) &&
        best_residual < start_residual &&
        stickingPays(ctx, best, iterationsToReach(params.tolerance, start_residual, best_residual, r.iterations),
                     &stick_recheck) &&
        stickingPathSolves())
      break;
    // Gauss-Seidel went before a planned apgd on the probe's forecast that its sweeps fit one
    // slice. Where the plan says apgd's momentum carries this W (apgdHolds: faces resting on
    // faces) and Gauss-Seidel's first plain window after the probe says its sweeps no longer
    // fit, apgd goes first again, from the start as planned (from a Gauss-Seidel iterate it
    // crawls). BoxesStack1 at 1e-3: the probe forecast 45 sweeps in all, the window 118; nlgs
    // takes 226, apgd 95 iterations (213 sweeps before, 0.71x the time now). Not where apgd
    // does not hold: MuJoCo's hammock at 1e-2 (joints) forecast 80 sweeps, then 207 after its
    // window, and Gauss-Seidel's rate then rose again, 82 sweeps in all where apgd took 499.
    if (gs_before_apgd && gs_window_needed > 0.0 && plan_apgd_holds) {
      gs_before_apgd = false;
      if (used + gs_window_needed > firstSlice(cur.kind)) {
        for (PortfolioMember& mem : members)
          if (mem.kind == SolverKind::kApgd) mem.retry_origin = 1;
        if (moveFirst(members, SolverKind::kApgd)) {
          m = 0;
          continue;
        }
      }
    }
    if (saved_slice > 0 && !failedToRun(r.status)) continue;  // a trial window is no slice: no stall test
    if (cur.scout) {
      // Go on while the rate of its last slice (the first: from the start) reaches the
      // tolerance within its allowance (scoutGoesOn), as the probe's stages do: apgd's rate
      // slows as it goes, and a scout that runs out of its allowance is pure loss. A slice is
      // at most as long as the scout so far, so that a rate which slows within it is seen
      // after at most twice the iterations it took to predict it. Otherwise newton starts
      // from what it would have started from.
      const double slice_start = scout.iterations == 0 ? probe_start : scout.last_residual;
      scout.iterations += r.iterations;
      scout.last_residual = residual;
      if (r.iterations > 0 && residual < slice_start && !failedToRun(r.status) &&
          r.status != SolveStatus::kTimeBudget) {
        const double needed = iterationsToReach(params.tolerance, slice_start, residual, r.iterations);
        if (scoutGoesOn(ctx, scout.iterations, needed)) {
          cur.slice = std::min(static_cast<int>(std::ceil(needed)) + 1, scout.iterations);
          continue;
        }
      }
      restoreBest(before_scout);
      members.erase(members.begin() + static_cast<long>(m));
      m = 0;
      // The scout says apgd's momentum does not carry this W, and newton on multi-point or
      // rank-deficient contacts takes slow steps: where the probe's last stage said Gauss-Seidel
      // would finish within half of newton's lower bound (n sweeps, probeAllowance), it goes on
      // from the probe's last iterate instead. The probe had stopped at the scout's cap of
      // fifty sweeps, or at n: twice its need no longer fitted on top of the sweeps it had run.
      // Capsules-i101's 72-row island at 1e-6: 39 sweeps to 2.3e-6 needing about 30 more, then
      // newton took 670 us where nlgs alone takes 220 (`auto:nlgs->apgd->nlgs` now: 370 us).
      // The need is the smaller of the last stage's and the one since newton's warm-up ended
      // (probe_end_needed): Capsules-i100's 51-row island at 1e-5 swept 0.986 per sweep in its
      // last ten (the plain window after an ω window), 0.91 since its warm-up; newton took
      // 480 us where nlgs needed 30 more sweeps, about 50 us.
      if (std::isfinite(probe_end.residual) && probe_end.residual < best_residual &&
          2.0 * probe_end_needed <= ctx.problem->rowCount() && moveFirst(members, SolverKind::kNlgs))
        restoreBest(probe_end);
      continue;
    }
    if (cur.probe) {
      // The stage ended where newton's warm-up would have: its iterate is kept for newton.
      if (warmup_stage) {
        warmup_over = probe_sweeps + r.iterations >= kNewtonWarmupSweeps ||
                      best_residual <= std::max(params.tolerance, kNewtonWarmupTolerance);
        if (warmup_over && !(best_residual > probe_start) && !failedToRun(r.status)) {
          saveBest(warmup_best);
          warmup_end_sweeps = probe_sweeps + r.iterations;
        }
      }
      // Go on while the rate of the last stage reaches the tolerance within the probe's
      // allowance (what the plan's first member would cost, in sweeps).
      const double needed = r.iterations > 0 && best_residual < stage_start
                                ? iterationsToReach(params.tolerance, stage_start, best_residual, r.iterations)
                                : std::numeric_limits<double>::infinity();
      if ((probe_sweeps == 0 || std::isfinite(needed)) && friction && !sticking_tried && !failedToRun(r.status) &&
          stickingPays(ctx, best, needed, &stick_recheck) && stickingPathSolves())
        break;
      // Gauss-Seidel's first sweeps from the start can raise the residual while the iterate is
      // on its way (a MuJoCo soft body's joints: 0.99, then 2.5, 1.4, 1.1): a first stage that
      // did goes on once, measured from its own end, and its iterate is the best so far (a
      // Gauss-Seidel plan went on from the start again: 3 sweeps lost, and the over-relaxation
      // trial then measured its plain window through that rise and kept an ω that doubled the
      // sweeps).
      if (probe_sweeps == 0 && r.iterations > 0 && !(best_residual < stage_start) && std::isfinite(residual) &&
          !failedToRun(r.status) && r.status != SolveStatus::kTimeBudget) {
        probe_sweeps = r.iterations;
        best.swap(x);
        best_residual = stage_start = residual;
        best_error = r.solver_error;
        best_model = r.friction_model;
        continue;
      }
      probe_sweeps += r.iterations;
      if (r.iterations > 0 && best_residual < stage_start && !failedToRun(r.status) &&
          r.status != SolveStatus::kTimeBudget) {
        // Twice the sweeps the rate says: Gauss-Seidel's rate only slows as it goes (box stacks).
        int allowance = kAutoProbeSweeps;
        if (probe_sweeps + 2.0 * needed > allowance) {
          const Plan& plan_now = planned();  // sets plan_scout: measured before it is read
          allowance = probeAllowance(plan_now, plan_scout, ctx, friction, plan_apgd_holds, best);
        }
        // And, where the plan's first member would lose the probe's sweeps (it starts from the
        // start), no fewer than the stage's own slowing forecasts (slowingSweepsToReach).
        const bool goes_on =
            probe_sweeps + 2.0 * needed <= allowance &&
            !(probe_sweeps + slowingSweepsToReach(params.tolerance, stage_start, r.history,
                                                  probe_sweeps - r.iterations) >
                  allowance &&
              startsFromTheStart(planned().front()));
        if (goes_on) {
          cur.slice = std::min(static_cast<int>(std::ceil(needed)) + 1, allowance - probe_sweeps);
          // Over-relaxation's trial (kAutoOmegaTrial), where the plain sweeps would outlast it:
          // plain_rate that of the stage just run (not the first: its sweeps from the start
          // fall fast), once newton's warm-up (plain nlgs, kept for newton) is over.
          if (adapt_omega && omega_state == 0 && needed > kAutoOmegaTrial && probe_sweeps > r.iterations &&
              (probe_kind != SolverKind::kNlgs || warmup_over)) {
            plain_rate = std::pow(best_residual / stage_start, 1.0 / r.iterations);
            omega_state = 1;
          }
          if (adapt_omega && (omega_state == 1 || omega_state == 3))
            cur.slice = std::min(cur.slice, kAutoOmegaTrial);
          stage_start = best_residual;
          continue;
        }
      }
      // The plain rate leaves the sweeps behind newton's modeled cost: one window at Young's ω
      // may not (lastOmegaWindow). Kept, Gauss-Seidel goes first at that ω.
      double newton_cost = 0.0;
      const bool stage_fell = r.iterations > 0 && best_residual < stage_start;
      const double stage_rate = stage_fell ? std::pow(best_residual / stage_start, 1.0 / r.iterations) : 1.0;
      const bool within_warmup =
          plan_scout && friction && !warmup_over && stage_fell && omegaWindowsWithinWarmup(probe_sweeps, stage_rate);
      const double omega =
          adapt_omega && omega_state == 0 && probe_kind == SolverKind::kNlgs && std::isfinite(needed) &&
                  stage_fell && !failedToRun(r.status) &&
                  r.status != SolveStatus::kTimeBudget && planned().front() == SolverKind::kNewton &&
                  used + kAutoOmegaTrial <= params.maxIt
              ? lastOmegaWindow(ctx, probe_sweeps, stage_rate, best_residual, needed, &newton_cost, within_warmup)
              : 0.0;
      if (omega > 0.0) {
        int window_sweeps = 0;  // the windows' sweeps so far
        bool gs_goes_first = false;
        bool solved = false;
        for (int window = 0; window < 2; ++window) {
          const int length = window == 0 ? kAutoOmegaTrial : kNewtonWarmupSweeps - probe_sweeps;
          if (window == 1 && (!within_warmup || length < kAutoProbeFirst)) break;
          const Clock::time_point w0 = Clock::now();
          x = best;
          const KernelReport wr = sweepsOutsideSlices(probe_kind, length, omega, best_residual);
          stages->back().second += std::chrono::duration<double>(Clock::now() - w0).count();
          window_sweeps += wr.iterations;
          const double w_residual = !x.allFinite() || failedToRun(wr.status) ? std::numeric_limits<double>::infinity()
                                    : ctx.residual(x);
          if (!(w_residual < best_residual)) break;
          solved = w_residual <= params.tolerance;
          const double w_needed =
              solved ? 0.0 : iterationsToReach(params.tolerance, best_residual, w_residual, wr.iterations);
          const double w_rate = std::pow(w_residual / best_residual, 1.0 / wr.iterations);
          gs_goes_first = solved || window_sweeps + w_needed <= newton_cost;
          if (!within_warmup && !gs_goes_first) break;
          best.swap(x);
          best_residual = best_error = w_residual;
          best_model = FrictionModel::kCoulombDisc;
          if (within_warmup) probe_sweeps += wr.iterations;
          if (gs_goes_first || !(w_rate < stage_rate)) break;
        }
        if (solved) {
          report.status = SolveStatus::kConverged;
          break;
        }
        if (gs_goes_first) {
          gs_omega = omega;
          omega_state = 2;
          startPlan();
          moveFirst(members, probe_kind);
          m = 0;
          continue;
        }
      }
      // Not solved. A plan that starts with Gauss-Seidel continues from the probe's iterate.
      // newton too: nlgs sweeps from the start are its own warm-up, so it goes on from where
      // that warm-up ended (the probe's stage stopped there) or, for a probe shorter than the
      // warm-up, from the probe's iterate with the rest of the warm-up to run; either way its
      // steps are those it takes alone (with its whole warm-up again after 3 of the probe's
      // sweeps, a box stack's Newton steps stalled four times: 1.4×; from 35 sweeps, twice and
      // restarted: 3.5×). Any other member starts from the start as it would have without the
      // probe (apgd from a Gauss-Seidel iterate crawled on the box pyramids: 80×).
      startPlan();
      m = 0;
      if (plan_scout && friction && std::isfinite(needed) && probe_kind == SolverKind::kNlgs) {
        saveBest(probe_end);  // where Gauss-Seidel resumes if the scout fails (below)
        // Its need at the better of the last stage's rate and the rate since newton's warm-up
        // ended: a last stage can be a plateau or the plain window after an ω window.
        probe_end_needed = needed;
        if (std::isfinite(warmup_best.residual) && probe_sweeps > warmup_end_sweeps &&
            best_residual < warmup_best.residual)
          probe_end_needed = std::min(needed, iterationsToReach(params.tolerance, warmup_best.residual, best_residual,
                                                                probe_sweeps - warmup_end_sweeps));
      }
      // Where about two digits are asked and the probe's rate says Gauss-Seidel reaches them
      // within a slice of its own, it goes before a planned apgd: multi-point contacts and rank
      // deficiency slow its rate only later, as the active set settles (kAutoTwoDigits). At
      // three digits (any loose tolerance) too, where that rate was measured past the probe's
      // first stage (the first sweeps from the start fall faster than the later ones: a box
      // pyramid whose three sweeps promised 38 more took 114) and the sweeps cost less than
      // newton (newtonCheaperThanSweeps; the rule below otherwise): apgd's cost is not known,
      // these sweeps' is, and the probe's would be lost (LMGC at 1e-3 with apgd kept first:
      // 1.6x the time). Not at two digits where the plan says apgd holds (apgdHolds: multi-point
      // contacts spread over their faces, most rows contacts): there an apgd iteration, one
      // product with the block-sparse W, costs less than a sweep and the two need about as many
      // (box pyramids of 15-136 cubes at 1e-2: 22-139 sweeps against 21-82 iterations, apgd
      // 0.45-0.77x nlgs's time), where nearly parallel normal rows (stacks with four close
      // points per face) or joints (MuJoCo's hammock: 82 sweeps against 499 iterations) leave
      // Gauss-Seidel ahead.
      const bool gs_in_slice = probe_sweeps + needed <= firstSlice(probe_kind);
      const bool rate_past_first_stage = probe_sweeps > kAutoProbeFirst;
      const bool apgd_holds = params.tolerance >= kAutoTwoDigits && plan_apgd_holds;
      if (members.front().kind == SolverKind::kApgd && !members.front().scout && gs_in_slice && !apgd_holds &&
          (params.tolerance >= kAutoTwoDigits ||
           (params.tolerance >= kAutoTightTolerance && rate_past_first_stage &&
            !newtonCheaperThanSweeps(ctx, probe_sweeps + needed))))
        gs_before_apgd = moveFirst(members, probe_kind);
      // Where apgd would go first at a loose tolerance and the probe's rate says Gauss-Seidel
      // needs more sweeps than newton's warm-up and kAutoNewtonSteps factorizations cost
      // (newtonCheaperThanSweeps), but at most twice that, newton goes on from the probe's
      // sweeps: apgd's cost is not known, newton's is bounded. A rate slower than that marks a
      // W ill-conditioned on the active set, where semismooth Newton stalls on rank-deficient
      // contacts and apgd's momentum does better (box stacks with a mass ratio of 100: 20-30
      // times newton's cost). newton's first slice is what those sweeps would cost (steps of
      // n/3 sweeps each, at least kAutoNewtonSteps), so that where its steps stall all the
      // same apgd takes over after that, not after newton's own 300 iterations.
      // OneObject-i1028 at 1e-3: 21 iterations where apgd took 161, 0.24x the time; stacks of
      // 3-8 boxes, 4 or 8 points per face, mass ratio 1-100: 0.96x (0.36-1.32x) over 33.
      if (members.front().kind == SolverKind::kApgd && !members.front().scout &&
          params.tolerance >= kAutoTightTolerance && std::isfinite(needed) &&
          newtonCheaperThanSweeps(ctx, probe_sweeps + needed) &&
          !newtonCheaperThanSweeps(ctx, (probe_sweeps + needed) / 2))
        newtonFirst(members, ctx, probe_sweeps + needed);
      // The converse of probeAllowance's test: where more than kAutoSlidingLoad of the load
      // slides at the probe's iterate, an apgd planned because it holds (faces resting on faces)
      // goes behind Gauss-Seidel, whose sweeps go on from that iterate: every shift μ |u_t| of
      // a sliding contact moves, and each update restarts apgd's momentum. Stacks of eight boxes
      // pushed sideways at 1e-3, all their load sliding: 178 sweeps where the path through apgd
      // took 852 iterations (nlgs alone 180, apgd 849); with four points per face, behind
      // newton (newtonFirst), 219 where newton's stall had handed over to apgd, 728.
      if (plan_apgd_holds && !plan_scout && params.tolerance < kAutoTwoDigits && !loadSticks(ctx, best))
        putBefore(members, probe_kind, SolverKind::kApgd);
      // The plan's first member (the scout starts from the start anyway).
      const SolverKind first = members.front().scout ? planned().front() : members.front().kind;
      const bool warmup = probe_kind == SolverKind::kNlgs;  // newton's warm-up sweeps are nlgs's
      // newton not from an iterate above the start's residual (the probe's first stage rose).
      const bool keep =
          first == SolverKind::kNlgs || first == SolverKind::kPgs ||
          (first == SolverKind::kNewton && probe_sweeps <= (warmup ? kNewtonWarmupSweeps : kAutoProbeSweeps) &&
           !(best_residual > probe_start));
      // A probe that ran through newton's warm-up hands newton the iterate at its end.
      const bool warmup_done = warmup && first == SolverKind::kNewton && std::isfinite(warmup_best.residual);
      if (warmup_done) restoreBest(warmup_best);
      if (warmup && first == SolverKind::kNewton && (keep || warmup_done))
        for (PortfolioMember& mem : members)
          if (mem.kind == SolverKind::kNewton) mem.warmup_credit = warmup_done ? kNewtonWarmupSweeps : probe_sweeps;
      if (!keep && !warmup_done) {
        best = origin;
        best_residual = probe_start;
        best_error = probe_start;
        best_model = FrictionModel::kCoulombDisc;
      }
      continue;
    }
    if (failedToRun(r.status) || (r.status == SolveStatus::kConverged && !converged)) {
      last_failure = failedToRun(r.status) ? r.status : SolveStatus::kNumericalFailure;
      last_failed = cur.kind;
      last_message = std::move(r.message);
      members.erase(members.begin() + static_cast<long>(m));
      if (m >= members.size()) m = 0;
      continue;
    }
    // A Gauss-Seidel slice from the best iterate that lowered the residual by less than its
    // factor: a drift to a separation is jumped (kAutoDriftReach); x is the slice's start.
    bool jumped = false;
    if (gauss_seidel && friction && by_residual && from_best && sticking_tried == sticking_before &&
        !hasExtendedFriction(*ctx.problem) &&
        r.iterations > 0 && !failedToRun(r.status) && r.status != SolveStatus::kTimeBudget &&
        residual < start_residual && best_residual > sliceFactor(cur.kind) * start_residual &&
        used + kAutoDriftSweeps <= params.maxIt) {
      x = best - x;  // the slice's drift
      const double step = separationStep(ctx, best, x);
      if (step > 1.0 && step <= kAutoDriftReach) {
        const Clock::time_point j0 = Clock::now();
        x = best + step * x;
        projectFeasible(ctx, x);
        sweepsOutsideSlices(cur.kind, kAutoDriftSweeps, 1.0, std::numeric_limits<double>::quiet_NaN());
        const double jump_seconds = std::chrono::duration<double>(Clock::now() - j0).count();
        stages->back().second += jump_seconds;
        seconds += jump_seconds;
        const double jump_residual = x.allFinite() ? ctx.residual(x) : std::numeric_limits<double>::infinity();
        if (jump_residual < best_residual) {
          best.swap(x);
          best_residual = best_error = jump_residual;
          best_model = FrictionModel::kCoulombDisc;
          jumped = true;
          if (best_residual <= params.tolerance) {
            report.status = SolveStatus::kConverged;
            break;
          }
        }
      }
    }
    // Slice used up (iterations or its share of the time): keep the member while it
    // progresses, otherwise the next one continues from the best iterate.
    const bool progressing = jumped || (r.iterations > 0 && best_residual <= sliceFactor(cur.kind) * start_residual);
    const double decrease = std::log(start_residual / std::max(best_residual, 1e-300));
    cur.rate = decrease / std::max(seconds, 1e-9);
    if (std::isfinite(decrease)) cur.decrease += decrease;
    cur.seconds += seconds;
    cur.tried = true;
    // A first trial stopped at its deadline: a second one once half the limits are used.
    const bool cut = member.has_trial_deadline && r.status == SolveStatus::kTimeBudget &&
                     !(residual < start_residual) && cur.trial_cut == 0.0;
    if (cut) cur.trial_cut = seconds;
    const bool half_used = 2 * used >= params.maxIt ||
                           (ctx.has_deadline && Clock::now() - solve_start >= (ctx.deadline - solve_start) / 2);
    if (half_used) dueSecondTrials(members);
    if (!cut && cur.retry_origin == 0 && r.iterations > 0 && !(residual < start_residual) && !from_origin)
      cur.retry_origin = 1;
    std::size_t untried = members.size();
    for (std::size_t k = 1; k < members.size() && untried == members.size(); ++k)
      if (!members[(m + k) % members.size()].tried) untried = (m + k) % members.size();
    if (progressing) {
      cur.slice = std::min(2 * cur.slice, 1 << 28);
      // Progressing, but at a rate (per iteration, its last slice) that needs more than
      // kAutoExploreFactor times the iterations the solve took so far: the next member not
      // tried yet runs one slice from the best iterate, no longer than the solve so far, so
      // that a member which keeps halving the residual in ever longer slices cannot hide a
      // faster one. Counted in iterations, not seconds: the same problem takes the same path.
      // After a Gauss-Seidel slice, an untried newton goes first where newtonCheaperThanSweeps.
      if (by_residual && untried != members.size()) {
        const double per_iteration = std::log(start_residual / best_residual) / r.iterations;
        const double needed = std::log(best_residual / params.tolerance) / per_iteration;
        std::size_t newton = members.size();
        if (gauss_seidel)
          for (std::size_t k = 0; k < members.size(); ++k)
            if (members[k].kind == SolverKind::kNewton && !members[k].tried) newton = k;
        const bool newton_cheaper = newton != members.size() && newtonCheaperThanSweeps(ctx, needed);
        if (newton_cheaper) untried = newton;
        if (needed > kAutoExploreFactor * used || newton_cheaper) {
          PortfolioMember& next = members[untried];
          if (next.kind != SolverKind::kLemke) next.slice = std::max(1, std::min(next.slice, used));  // pivots: not sliced
          m = untried;
        }
      }
      continue;
    }
    // Stalled: the next member not tried yet, else the one that lowered the residual
    // fastest for its time in its last slice (a stalled member keeps its slice; the chosen
    // one doubles it). Where no last slice lowered it, the one that did fastest over all its
    // slices, not the next in turn: apgd's residual can sit on a plateau for thousands of
    // iterations before it falls, and a member that never lowered it would be handed ever
    // longer slices in between (30 boxes stacked, mass ratio 100, at 1e-3: nlgs raised the
    // residual in every slice, newton failed; the rotation gave them 0.43 s of 2.4). The
    // member that just stalled takes the next slice itself only where no other member's record
    // beats its last slice (stallTakerAfter), and that slice, whoever takes it, lasts at most
    // as long as the solve so far (capped).
    // A member not tried yet runs its first slice on trial (kernels.h: trialPassed): once it
    // has taken as long as the solve so far without lowering the residual it started from, it
    // stops there. Iterations are no measure of that: a Newton step costs a factorization
    // (the stack's newton: 300 iterations, 0.21 s after apgd's 0.01 s, none better than its
    // start; on an island of Capsules-i101: 3 ms of the solve's 12). A member that lowers it
    // runs on (sphere_pile_40's newton and prox, whose whole slices its later steps need).
    // Not Lemke: its pivots are not sliced.
    if (members.size() > 1) {
      std::size_t next = untried;
      if (next != members.size()) members[next].trial = members[next].kind != SolverKind::kLemke;
      if (next == members.size()) {
        next = (m + 1) % members.size();
        for (std::size_t k = 0; k < members.size(); ++k)
          if (members[k].rate > members[next].rate) next = k;
        if (!(members[next].rate > 0.0))
          for (std::size_t k = 0; k < members.size(); ++k)
            if (overallRate(members[k]) > overallRate(members[next])) next = k;
        if (next == m) next = stallTakerAfter(members, m);
        members[next].slice = std::min(2 * members[next].slice, 1 << 28);
        members[next].capped = true;
      }
      m = next;
    }
  }
  if (members.empty() && report.status != SolveStatus::kConverged) {  // (converged: a warm start's active set)
    report.status = last_failure;
    // Some kernels name themselves in their messages ("apgd: the iterate became non-finite …").
    const std::string name = std::string(solverName(last_failed)) + ": ";
    report.message = "auto: every member failed; last " + (last_message.rfind(name, 0) == 0 ? "" : name) + last_message;
  }
  // The probe's restarted stage may have made an iterate above the start's residual the best
  // so far: a solve that ended without lowering it returns the start.
  if (best_residual > probe_start) {
    best = origin;
    best_error = probe_start;
    best_model = FrictionModel::kCoulombDisc;
  }
  lambda = best;
  report.iterations = used;
  report.solver_error = std::isfinite(best_error) ? best_error : best_residual;
  report.friction_model = best_model;
  return report;
}

std::string autoPath(const std::vector<std::pair<std::string, double>>& stages) {
  if (stages.empty()) return "auto";
  if (stages.size() == 1) return "auto:" + stages.front().first;  // the common case, no loop
  std::size_t length = 5;
  for (const auto& stage : stages) length += stage.first.size() + 2;
  std::string path;  // one allocation: this runs on every auto solve, microsecond ones too
  path.reserve(length);
  path.append("auto:");
  for (std::size_t i = 0; i < stages.size(); ++i) path.append(i ? "->" : "").append(stages[i].first);
  return path;
}

}  // namespace lcp_contact_solver::core
