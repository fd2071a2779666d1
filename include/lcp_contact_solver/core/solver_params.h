// Solver parameters. Names, meanings and defaults follow SOFA's LCPConstraintSolver
// (the xml names are given in brackets) so a SOFA scene's settings carry over; where SOFA
// has a known fault the difference is stated.
#pragma once

#include <string>
#include <vector>

namespace lcp_contact_solver::core {

enum class SolverKind {
  kAuto,    // the portfolio (portfolio.cpp, docs/ARCHITECTURE.md): starts with the
            // member the problem's features predict, watches its progress in slices and
            // continues from the best iterate with the next member when it stalls or fails.
            // maxIt and time_budget bound the whole portfolio; SolveResult::solver reports
            // the path ("auto:newton->prox"), SolveResult::stages the time in each member.
  kPgs,     // projected Gauss-Seidel on the LCP (SOFA gaussSeidelLCP1); with friction
            // only for a pyramid friction_model (boxed PGS)
  kNlgs,    // nonlinear block Gauss-Seidel on the Coulomb disc (SOFA nlcp_gaussseidel)
  kLemke,   // lexicographic Lemke pivoting; exact, for LCPs (no friction, or friction
            // with a pyramid friction_model: the Stewart-Trinkle LCP)
  kApgd,    // accelerated projected gradient (Nesterov, adaptive step, restart) on the
            // cone complementarity problem with De Saxcé's fixed point; Coulomb disc
  kNewton,  // semismooth Newton on the Alart-Curnier function, regularized, with line
            // search, warm-started by nlgs; high accuracy, rank-deficient W
  kProx,    // proximal point outer loop around newton (W + σI, moving prox centre, σ
            // adapted; prox_newton.cpp): rank-deficient or ill-conditioned W at 1e-8..1e-12
};

// The friction law. The disc is Coulomb's isotropic cone |λ_t| <= μ λ_n. The pyramids
// replace it by a polygon circumscribing the disc: 4 facets is the box |λ_t1|, |λ_t2| <=
// μ λ_n (threshold μ along a tangent, μ√2 along a diagonal), 8 facets the regular octagon
// with facet normals every 45° (threshold μ along those, μ/cos 22.5° ≈ 1.08 μ between).
// Only pgs and lemke solve a pyramid (it makes the problem an LCP); the other solvers
// always solve the disc. A pyramid solution has a nonzero disc residual by design.
enum class FrictionModel {
  kCoulombDisc,  // "disc"
  kPyramid4,     // "pyramid4"
  kPyramid8,     // "pyramid8"
};

// How the Gauss-Seidel solvers decide they are done.
enum class StoppingRule {
  // Stop when the solver-independent residual (residual.h) is <= tolerance. This is the
  // figure every result reports, so "converged" means the same for every solver.
  kResidual,
  // SOFA's rule: stop when the sweep's summed change, sum_c |W_cc (λ_c^new - λ_c^old)|
  // (a displacement), is < tolerance. Cheap but absolute and solver-specific.
  kSofa,
};

// What d measures, which decides how a gap enters it (stabilization.h).
enum class ConstraintLevel {
  kPosition,  // d is a displacement over the step (m), SOFA's d_free: β·gap is added
  kVelocity,  // d is a velocity (m/s): β·gap/time_step is added (Baumgarte's form)
};

struct SolverParams {
  // [tolerance] Convergence threshold. With kResidual: the normalised natural-map
  // residual (dimensionless). With kSofa: the per-sweep summed displacement change, in
  // the units of d (m or m/s).
  double tolerance = 1e-3;
  // [maxIt] Maximum Gauss-Seidel sweeps; for Lemke, the pivot cap.
  int maxIt = 1000;
  // [mu] Friction coefficient for contacts that give none (Contact::mu < 0). Unlike SOFA
  // this is only a default: every contact may carry its own μ.
  double mu = 0.6;
  // [initial_guess] Warm start: start each contact from the force it had, by contact id,
  // in the previous solve of the same ContactSolver. New ids start from zero.
  bool initial_guess = true;
  // [build_lcp] true: solve on the assembled W (dense or block-sparse). false: the unbuilt
  // solve, which needs the body form of the compliance; with an assembled W the built
  // solve is used and the result says so in its message.
  bool build_lcp = true;
  // [regularizationTerm] r >= 0 added to W's diagonal (W + r I) during the solve, in the
  // units of W (m/N). Makes forces unique on rank-deficient W at the cost of r·λ error.
  double regularizationTerm = 0.0;
  // [minW] If > 0, contacts whose normal self-compliance W_nn (after regularization) is
  // <= minW get no force and state "ignored". SOFA compares with "smaller than"; a zero
  // or negative diagonal with minW = 0 is reported as a failure instead of dividing by it.
  double minW = 0.0;
  // [maxF] If > 0, a contact whose force norm exceeds maxF (N) is dropped (state
  // "ignored") and the remaining contacts are solved again, until no force exceeds it.
  // SOFA drops the force without re-solving, leaving the others inconsistent.
  double maxF = 0.0;
  // [computeConstraintForces] Keep and publish the forces (ROS layer). The core always
  // returns them; the node skips storing/publishing when false and nobody subscribes.
  bool computeConstraintForces = false;
  // [displayDebug] Record the residual after every sweep/pivot in the result and, in the
  // node, log per-cycle debug lines.
  bool displayDebug = false;

  SolverKind solver = SolverKind::kAuto;
  // Over-relaxation ω of the Gauss-Seidel solvers (pgs, nlgs), in (0, 2): each contact
  // moves λ_c <- λ_c + ω (λ_c^local - λ_c) and is projected back onto its feasible set.
  // 1 is plain Gauss-Seidel (bit-identical to no relaxation); left at 1, `auto` tries a
  // measured ω for its Gauss-Seidel member and keeps it only if it sweeps faster.
  double sor = 1.0;
  // Friction law for pgs and lemke (see FrictionModel).
  FrictionModel friction_model = FrictionModel::kCoulombDisc;
  // Wall-clock budget of one solve in seconds (0 = none). When it runs out the kernel
  // stops with its best iterate and status kTimeBudget. Checked once per sweep,
  // iteration or pivot, so the overshoot is at most one of those.
  double time_budget = 0.0;
  StoppingRule stopping_rule = StoppingRule::kResidual;
  // Refuse problems with more rows than this (0 = no limit); protects against
  // allocation failures from hostile input.
  int max_rows = 0;
  // Position-error correction (Baumgarte, ODE's ERP) for contacts that give none: the
  // fraction β in [0, 1] of a penetration (Contact::gap < 0) removed per solve. 0 = none.
  double erp = 0.0;
  // Softness (ODE's CFM) for contacts that give none: added to the contact's W_nn, in the
  // units of W. With erp it makes the contact a spring of stiffness β / softness.
  double softness = 0.0;
  ConstraintLevel constraint_level = ConstraintLevel::kPosition;
  // The step h (s) dividing β·gap at velocity level; required (> 0) only there.
  double time_step = 0.0;
  // Solve W's independent islands separately (islands.h), each with its own stopping
  // test; off: one kernel run on the whole problem. Not with displayDebug (the history is
  // the whole problem's). The body form splits by shared bodies.
  bool islands = true;
  // Threads solving islands concurrently (0 = the core count, 1 = the calling thread
  // only). The result does not depend on it.
  int threads = 0;
};

const char* solverName(SolverKind kind);
// Parses "auto", "pgs", "nlgs", "lemke", "apgd", "newton", "prox"; false for an unknown name.
bool parseSolverName(const std::string& name, SolverKind* kind);
std::vector<std::string> solverNames();
const char* stoppingRuleName(StoppingRule rule);
bool parseStoppingRule(const std::string& name, StoppingRule* rule);
// "disc", "pyramid4", "pyramid8".
const char* frictionModelName(FrictionModel model);
bool parseFrictionModel(const std::string& name, FrictionModel* model);
std::vector<std::string> frictionModelNames();
// "position", "velocity".
const char* constraintLevelName(ConstraintLevel level);
bool parseConstraintLevel(const std::string& name, ConstraintLevel* level);

// Empty string if the parameters are valid, otherwise a sentence naming the bad field.
std::string validateParams(const SolverParams& params);

}  // namespace lcp_contact_solver::core
