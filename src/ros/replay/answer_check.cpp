#include "lcp_contact_solver/ros/replay/answer_check.h"

#include "lcp_contact_solver/core/body_compliance.h"
#include "lcp_contact_solver/core/residual.h"
#include "lcp_contact_solver/core/stabilization.h"
#include "lcp_contact_solver/ros/replay/text.h"

#include <algorithm>
#include <cmath>

namespace lcp_contact_solver_ros {

namespace {

// Rounding slack of the cone and sign tests, relative to the contact's normal force: the
// kernels project onto the cone, so a solved force is inside it to a few ulps.
constexpr double kConeSlack = 1e-9;

}  // namespace

AnswerCheck checkAnswer(const lcs::core::Problem& input, const lcs::core::SolverParams& params,
                        const lcp_contact_solver::ConstraintForces& forces) {
  AnswerCheck check;
  auto violation = [&check](std::size_t* counter, const std::string& what) {
    ++*counter;
    if (check.first_violation.empty()) check.first_violation = what;
  };
  const std::size_t n = input.contacts.size();
  if (forces.forces.size() != n) {
    check.unfit = std::to_string(forces.forces.size()) + " forces for " + std::to_string(n) + " contacts";
    return check;
  }
  // The problem the kernel solved: Baumgarte and softness as ContactSolver applies them.
  lcs::core::Problem stabilized;
  const bool stabilize = lcs::core::needsStabilization(input, params);
  if (stabilize) {
    stabilized = input;
    if (const std::string error = lcs::core::applyStabilization(params, &stabilized); !error.empty()) {
      check.unfit = "stabilization: " + error;
      return check;
    }
  }
  const lcs::core::Problem& problem = stabilize ? stabilized : input;
  const std::vector<int> offsets = problem.rowOffsets();
  Eigen::VectorXd lambda(offsets.back());
  std::vector<bool> ignored(n, false);
  for (std::size_t i = 0; i < n; ++i) {
    const auto& f = forces.forces[i];
    const std::string name =
        "contact " + std::to_string(i) + " (id " + std::to_string(problem.contacts[i].id) + ")";
    const int rows = offsets[i + 1] - offsets[i];
    if (f.id != problem.contacts[i].id || static_cast<int>(f.lambda.size()) != rows) {
      check.unfit = name + ": the forces have id " + std::to_string(f.id) + " and " +
                    std::to_string(f.lambda.size()) + " rows";
      return check;
    }
    for (int r = 0; r < rows; ++r) {
      if (!std::isfinite(f.lambda[r])) {
        check.unfit = name + ": a non-finite force";
        return check;
      }
      lambda[offsets[i] + r] = f.lambda[r];
    }
    ignored[i] = f.state == static_cast<std::uint8_t>(lcs::core::ContactState::kIgnored);
  }
  Eigen::VectorXd d;
  lcs::core::multiplyCompliance(problem, lambda, d);
  d += problem.d_free;
  if (params.regularizationTerm != 0.0) d += params.regularizationTerm * lambda;
  const std::vector<double> mu = lcs::core::effectiveMu(problem, params.mu);
  check.residual = lcs::core::naturalMapResidual(problem, mu, lambda, d, ignored);

  const std::vector<lcs::core::ContactState> states =
      lcs::core::classifyContacts(problem, mu, lambda, ignored);
  const bool disc = params.friction_model == lcs::core::FrictionModel::kCoulombDisc;
  for (std::size_t i = 0; i < n; ++i) {
    const lcs::core::Contact& c = problem.contacts[i];
    const double* l = lambda.data() + offsets[i];
    const int rows = offsets[i + 1] - offsets[i];
    const std::string name = "contact " + std::to_string(i) + " (id " + std::to_string(c.id) + ")";
    if (static_cast<std::uint8_t>(states[i]) != forces.forces[i].state)
      violation(&check.state_differences, name + ": recorded state " +
                                              std::to_string(forces.forces[i].state) + ", its force gives " +
                                              std::to_string(static_cast<int>(states[i])));
    if (ignored[i]) {
      for (int r = 0; r < rows; ++r)
        if (l[r] != 0.0) {
          violation(&check.ignored_with_force, name + ": ignored, with a force");
          break;
        }
      continue;
    }
    if (c.type == lcs::core::ContactType::kBilateral) continue;
    if (l[0] < 0.0) violation(&check.negative_normals, name + ": normal force " + exactNumber(l[0]) + " < 0");
    if (!lcs::core::hasSlidingFriction(c.type) || rows < 3) continue;
    const double bound = mu[i] * l[0] * (1.0 + kConeSlack) + 1e-300;
    const double tangential = disc ? std::hypot(l[1], l[2]) : std::max(std::abs(l[1]), std::abs(l[2]));
    if (tangential > bound)
      violation(&check.outside_cone, name + ": friction " + exactNumber(tangential) + " > mu lambda_n " +
                                         exactNumber(mu[i] * l[0]));
  }
  return check;
}

bool residualsAgree(double recomputed, double reported) {
  return std::abs(recomputed - reported) <= 1e-6 * std::max(recomputed, reported) + 1e-12;
}

bool AnswerChecks::add(const AnswerCheck& check, const lcp_contact_solver::SolverStats* stats,
                       const lcs::core::SolverParams& params, const ros::Time& stamp) {
  ++checked;
  std::string failure;
  if (!check.unfit.empty()) {
    ++unfit;
    failure = check.unfit;
  } else {
    max_residual = std::max(max_residual, check.residual);
    if (!check.invariantsHold()) {
      ++invariant_failures;
      failure = check.first_violation;
    }
    if (stats == nullptr) {
      ++without_stats;
    } else {
      max_residual_difference = std::max(max_residual_difference, std::abs(check.residual - stats->residual));
      if (!residualsAgree(check.residual, stats->residual)) {
        ++residual_differs;
        if (failure.empty())
          failure = "residual " + exactNumber(check.residual) + " recomputed, " +
                    exactNumber(stats->residual) + " recorded";
      }
      // The pyramid models converge on their own law; their disc residual is not bounded.
      if (stats->converged && params.stopping_rule == lcs::core::StoppingRule::kResidual &&
          params.friction_model == lcs::core::FrictionModel::kCoulombDisc &&
          !(check.residual <= params.tolerance)) {
        ++above_tolerance;
        if (failure.empty())
          failure = "recorded as converged, residual " + exactNumber(check.residual) + " > tolerance " +
                    exactNumber(params.tolerance);
      }
    }
  }
  if (failure.empty()) return true;
  ++failed;
  if (first_failure.empty()) first_failure = "stamp " + stampDigits(stamp) + ": " + failure;
  return false;
}

}  // namespace lcp_contact_solver_ros
