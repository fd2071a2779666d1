#include "lcp_contact_solver/core/residual.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace lcp_contact_solver::core {

namespace {

// |(a, b)|: sqrt of the sum of squares (hypot is several times slower and this runs in
// every solver's inner loop), hypot only where the squares overflow.
inline double norm2(double a, double b) {
  const double s = a * a + b * b;
  return s < std::numeric_limits<double>::max() ? std::sqrt(s) : std::hypot(a, b);
}

}  // namespace

// Projection onto K = {|r_t| <= mu r_n}: inside stays, the polar cone maps to 0, the rest
// goes to the nearest boundary ray: r_n' = (r_n + mu |r_t|) / (1 + mu²), r_t' = mu r_n' r_t/|r_t|.
void projectOntoCone(double mu, double* r) {
  const double rt = norm2(r[1], r[2]);
  // Inside: also r_n >= 0, or with μ = 0 (the cone is the ray t = 0, n >= 0) a point with
  // r_n < 0 would pass 0 <= μ r_n and be kept (found by fuzzing the μ = 0 residual).
  if (rt <= mu * r[0] && r[0] >= 0.0) return;
  if (mu * rt <= -r[0]) {
    r[0] = r[1] = r[2] = 0.0;
    return;
  }
  const double rn = (r[0] + mu * rt) / (1.0 + mu * mu);
  const double scale = mu * rn / rt;  // rt > 0 here: rt == 0 fell in one of the cases above
  r[0] = rn;
  r[1] *= scale;
  r[2] *= scale;
}

std::vector<double> effectiveMu(const Problem& problem, double default_mu) {
  std::vector<double> mu(problem.contacts.size(), 0.0);
  for (std::size_t i = 0; i < problem.contacts.size(); ++i) {
    const Contact& c = problem.contacts[i];
    if (hasSlidingFriction(c.type)) mu[i] = c.mu < 0.0 ? default_mu : c.mu;
  }
  return mu;
}

namespace {

bool isIgnored(const std::vector<bool>& ignored, std::size_t i) { return !ignored.empty() && ignored[i]; }

// Torsional and rolling rows: the force minus its projection onto the bound μ_x λ_n after
// a step against its velocity (the natural map of maximal dissipation with λ_n given).
double extendedErrorSquared(const Contact& c, const double* lambda, const double* d) {
  const double spin_bound = c.mu_torsional * std::max(lambda[0], 0.0);
  const double s = lambda[3] - std::clamp(lambda[3] - d[3], -spin_bound, spin_bound);
  double sum = s * s;
  if (c.type == ContactType::kRolling) {
    const double roll_bound = c.mu_rolling * std::max(lambda[0], 0.0);
    double x = lambda[4] - d[4], y = lambda[5] - d[5];
    const double n = norm2(x, y);
    if (n > roll_bound) {
      x *= roll_bound / n;
      y *= roll_bound / n;
    }
    sum += (lambda[4] - x) * (lambda[4] - x) + (lambda[5] - y) * (lambda[5] - y);
  }
  return sum;
}

// Squared natural-map error of one contact (see residual.h).
double contactErrorSquared(const Contact& c, double mu, const double* lambda, const double* d) {
  switch (c.type) {
    case ContactType::kTorsional:
    case ContactType::kRolling: {
      Contact sliding = c;
      sliding.type = ContactType::kFrictional;
      sliding.rows = 3;
      return contactErrorSquared(sliding, mu, lambda, d) + extendedErrorSquared(c, lambda, d);
    }
    case ContactType::kFrictional: {
      if (mu == 0.0) {
        // The cone is the normal ray: e = (min(λ_n, d_n), λ_t). Written apart so that a huge
        // tangential velocity (μ · |d_t| = 0 · inf) cannot turn an exact answer into NaN.
        const double e = std::min(lambda[0], d[0]);
        return e * e + lambda[1] * lambda[1] + lambda[2] * lambda[2];
      }
      // De Saxcé's modified velocity makes the Coulomb law a cone complementarity problem.
      const double dt = norm2(d[1], d[2]);
      const double dn = d[0] + mu * dt;
      double x[3] = {lambda[0] - dn, lambda[1] - d[1], lambda[2] - d[2]};
      // x inside the cone: Proj(x) = x and e = λ − x is the modified velocity itself. Use it
      // as is: λ − (λ − d) cancels to 0 when |d| is below λ's rounding (forces of 1e6 N,
      // velocities of 1e-10 m), which would report an exact solution that is not one.
      // x_n >= 0 as well: with μ = 0 the cone is the ray t = 0, n >= 0, and 0 <= μ x_n
      // alone would take a separating x (x_n < 0) for one inside it (found by fuzzing).
      if (x[0] >= 0.0 && norm2(x[1], x[2]) <= mu * x[0]) return dn * dn + d[1] * d[1] + d[2] * d[2];
      projectOntoCone(mu, x);
      double sum = 0.0;
      for (int k = 0; k < 3; ++k) sum += (lambda[k] - x[k]) * (lambda[k] - x[k]);
      return sum;
    }
    case ContactType::kFrictionless: {
      // λ − max(0, λ − d) = min(λ, d), written so that it does not cancel (see above).
      const double e = std::min(lambda[0], d[0]);
      return e * e;
    }
    case ContactType::kBilateral: {
      double sum = 0.0;
      for (int k = 0; k < c.rows; ++k) sum += d[k] * d[k];
      return sum;
    }
  }
  return 0.0;
}

}  // namespace

namespace {

double errorSum(const Problem& problem, const std::vector<double>& mu, const double* lambda, const double* d,
                const std::vector<bool>& ignored) {
  double sum = 0.0;
  int row = 0;
  for (std::size_t i = 0; i < problem.contacts.size(); ++i) {
    const Contact& c = problem.contacts[i];
    if (!isIgnored(ignored, i)) sum += contactErrorSquared(c, mu[i], lambda + row, d + row);
    row += c.rows;
  }
  return sum;
}

}  // namespace

double naturalMapResidual(const Problem& problem, const std::vector<double>& mu,
                          const Eigen::VectorXd& lambda, const Eigen::VectorXd& d,
                          const std::vector<bool>& ignored) {
  const double q_norm = problem.d_free.norm();
  if (std::isfinite(q_norm)) {
    const double residual =
        std::sqrt(errorSum(problem, mu, lambda.data(), d.data(), ignored)) / (q_norm > 0.0 ? q_norm : 1.0);
    if (std::isfinite(residual)) return residual;
  }
  // Overflow, in |d_free| (entries near DBL_MAX) or in the squares of the errors (1e284):
  // every contact's error is positively homogeneous in (λ, d) (cones, min-maps, bilateral
  // rows), so the same ratio is measured on λ, d and d_free divided by m = max |d_free_i|
  // (found by fuzzing: exact answers read as DBL_MAX, or as 0 when |d_free| was inf).
  const double m = problem.d_free.size() > 0 ? problem.d_free.cwiseAbs().maxCoeff() : 0.0;
  if (m > 0.0 && std::isfinite(m)) {
    const Eigen::VectorXd lambda_scaled = lambda / m, d_scaled = d / m;
    const double residual = std::sqrt(errorSum(problem, mu, lambda_scaled.data(), d_scaled.data(), ignored)) /
                            (problem.d_free / m).norm();
    if (std::isfinite(residual)) return residual;
  }
  // Still overflowing: "far from converged", never NaN.
  return std::numeric_limits<double>::max();
}

std::vector<ContactState> classifyContacts(const Problem& problem, const std::vector<double>& mu,
                                           const Eigen::VectorXd& lambda, const std::vector<bool>& ignored) {
  // A force within this fraction of the cone's radius counts as on the boundary.
  constexpr double kBoundaryFraction = 1e-6;
  std::vector<ContactState> states(problem.contacts.size(), ContactState::kOpen);
  int row = 0;
  for (std::size_t i = 0; i < problem.contacts.size(); ++i) {
    const Contact& c = problem.contacts[i];
    const double* l = lambda.data() + row;
    row += c.rows;
    if (isIgnored(ignored, i)) {
      states[i] = ContactState::kIgnored;
    } else if (c.type == ContactType::kBilateral) {
      states[i] = ContactState::kStick;
    } else if (l[0] <= 0.0) {
      states[i] = ContactState::kOpen;
    } else if (c.type == ContactType::kFrictionless || mu[i] == 0.0) {
      states[i] = ContactState::kClosed;  // no friction law: neither stick nor slip
    } else {
      const double radius = mu[i] * l[0];
      const double tangential = std::hypot(l[1], l[2]);
      states[i] =
          tangential < radius * (1.0 - kBoundaryFraction) ? ContactState::kStick : ContactState::kSlip;
    }
  }
  return states;
}

}  // namespace lcp_contact_solver::core
