// Polyhedral (pyramid) friction: the friction polygon, its residual, and the
// Stewart-Trinkle / Anitescu-Potra LCP solved by Lemke. The boxed Gauss-Seidel is in
// gauss_seidel.cpp (it shares the sweep of the other Gauss-Seidel solvers).
#include "friction_pyramid.h"

#include "lcp_contact_solver/core/kernels/kernels.h"
#include "lcp_contact_solver/core/residual.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace lcp_contact_solver::core {

FrictionPolygon makeFrictionPolygon(FrictionModel model) {
  FrictionPolygon polygon;
  polygon.facets = model == FrictionModel::kPyramid4 ? 4 : model == FrictionModel::kPyramid8 ? 8 : 0;
  if (polygon.facets == 0) return polygon;
  const double pi = std::acos(-1.0);
  const double step = 2.0 * pi / polygon.facets;
  polygon.half_edge = std::tan(0.5 * step);
  const double vertex_radius = 1.0 / std::cos(0.5 * step);
  for (int k = 0; k < polygon.facets; ++k) {
    // Exact values on the axes (cos(π/2) is not 0 in floating point).
    auto cosine = [&](double angle) {
      const double c = std::cos(angle);
      return std::abs(c) < 1e-15 ? 0.0 : c;
    };
    auto sine = [&](double angle) {
      const double s = std::sin(angle);
      return std::abs(s) < 1e-15 ? 0.0 : s;
    };
    const double a = k * step;
    polygon.normal[k][0] = cosine(a);
    polygon.normal[k][1] = sine(a);
    polygon.along[k][0] = -polygon.normal[k][1];
    polygon.along[k][1] = polygon.normal[k][0];
    polygon.vertex[k][0] = vertex_radius * cosine(a + 0.5 * step);
    polygon.vertex[k][1] = vertex_radius * sine(a + 0.5 * step);
  }
  return polygon;
}

namespace {

bool insidePolygon(const FrictionPolygon& polygon, const Eigen::Vector2d& x, double R) {
  for (int k = 0; k < polygon.facets / 2; ++k)
    if (std::abs(polygon.normal[k][0] * x[0] + polygon.normal[k][1] * x[1]) > R) return false;
  return true;
}

}  // namespace

// Facet k is the segment x = R n_k + τ e_k, |τ| <= R tan(π/m) (e_k along the facet). On
// it f(τ) = f(R n_k) + τ g + ½ c τ² with g = e_kᵀ(T R n_k + b), c = e_kᵀ T e_k, minimised
// at τ = -g / c clamped to the segment (an end when c = 0). A convex function whose
// unconstrained minimum lies outside P attains its minimum over P on the boundary, so
// the best facet is the answer.
Eigen::Vector2d minimizeOverPolygon(const FrictionPolygon& polygon, const Eigen::Matrix2d& T,
                                    const Eigen::Vector2d& b, double R) {
  if (!(R > 0.0)) return Eigen::Vector2d::Zero();
  const double det = T(0, 0) * T(1, 1) - T(0, 1) * T(1, 0);
  const double scale = T.cwiseAbs().maxCoeff();
  if (T(0, 0) > 0.0 && det > 1e-14 * scale * scale) {
    const Eigen::Vector2d x((-T(1, 1) * b[0] + T(0, 1) * b[1]) / det,
                            (T(1, 0) * b[0] - T(0, 0) * b[1]) / det);
    if (insidePolygon(polygon, x, R)) return x;
  } else if (b[0] == 0.0 && b[1] == 0.0) {
    return Eigen::Vector2d::Zero();  // singular T without drive: 0 is a minimiser
  }
  const double limit = R * polygon.half_edge;
  double best_value = std::numeric_limits<double>::infinity();
  Eigen::Vector2d best = Eigen::Vector2d::Zero();
  for (int k = 0; k < polygon.facets; ++k) {
    const Eigen::Vector2d n(polygon.normal[k][0], polygon.normal[k][1]);
    const Eigen::Vector2d e(polygon.along[k][0], polygon.along[k][1]);
    const Eigen::Vector2d p0 = R * n;
    const Eigen::Vector2d Tp0 = T * p0;
    const Eigen::Vector2d Te = T * e;
    const double g = e.dot(Tp0 + b);
    const double c = e.dot(Te);
    double tau;
    if (c > 0.0)
      tau = std::clamp(-g / c, -limit, limit);
    else
      tau = g > 0.0 ? -limit : limit;
    const double value = 0.5 * p0.dot(Tp0) + b.dot(p0) + tau * g + 0.5 * c * tau * tau;
    if (value < best_value) {
      best_value = value;
      best = p0 + tau * e;
    }
  }
  return best;
}

Eigen::Vector2d projectOntoPolygon(const FrictionPolygon& polygon, const Eigen::Vector2d& y, double R) {
  if (!(R > 0.0)) return Eigen::Vector2d::Zero();
  if (insidePolygon(polygon, y, R)) return y;
  return minimizeOverPolygon(polygon, Eigen::Matrix2d::Identity(), -y, R);
}

double pyramidResidual(const Problem& problem, const std::vector<double>& mu, const FrictionPolygon& polygon,
                       const Eigen::VectorXd& lambda, const Eigen::VectorXd& d,
                       const std::vector<bool>& ignored) {
  double sum = 0.0;
  int row = 0;
  for (std::size_t i = 0; i < problem.contacts.size(); ++i) {
    const Contact& c = problem.contacts[i];
    const double* l = lambda.data() + row;
    const double* u = d.data() + row;
    row += c.rows;
    if (!ignored.empty() && ignored[i]) continue;
    switch (c.type) {
      case ContactType::kFrictional: {
        const double en = std::min(l[0], u[0]);  // = l − max(0, l − u), without cancellation
        const Eigen::Vector2d lt(l[1], l[2]);
        const Eigen::Vector2d et =
            lt - projectOntoPolygon(polygon, lt - Eigen::Vector2d(u[1], u[2]), mu[i] * std::max(l[0], 0.0));
        sum += en * en + et.squaredNorm();
        break;
      }
      case ContactType::kFrictionless: {
        const double e = std::min(l[0], u[0]);
        sum += e * e;
        break;
      }
      case ContactType::kBilateral:
        for (int k = 0; k < c.rows; ++k) sum += u[k] * u[k];
        break;
      case ContactType::kTorsional:  // refused before any kernel runs (contact_solver.cpp)
      case ContactType::kRolling: break;
    }
  }
  const double q_norm = problem.d_free.stableNorm();
  const double residual = std::sqrt(sum) / (q_norm > 0.0 && std::isfinite(q_norm) ? q_norm : 1.0);
  return std::isfinite(residual) ? residual : std::numeric_limits<double>::max();
}

// ---- Lemke on the Stewart-Trinkle LCP ---------------------------------------------------
//
// Derivation. Write the tangential force of a frictional contact as a combination of the
// polygon's vertices, λ_t = Σ_k β_k v_k with β_k >= 0 and Σ_k β_k <= μ λ_n: that is
// exactly λ_t ∈ P(μ λ_n) (the convex hull of μ λ_n v_k). Maximum dissipation
// over the polygon (λ_t maximises -u_tᵀ y over y ∈ P) is, with a slack γ (the sliding
// speed measured by the polygon's support function),
//   0 <= β_k ⟂ v_kᵀ u_t + γ >= 0          (k = 1..m)
//   0 <= γ   ⟂ μ λ_n - Σ_k β_k >= 0
// next to the normal 0 <= λ_n ⟂ u_n >= 0: if the contact slides, γ = max_k(-v_kᵀ u_t) > 0,
// the force is on the polygon's boundary and uses only the vertices most opposed to the
// slip; if it sticks, u_t = 0 and γ = 0. With λ = P z (P maps z = (λ_n, β, γ) per
// contact to the contact's rows; γ maps to nothing) and u = W λ + d_free, all rows read
//   w = (Pᵀ W P + G) z + Pᵀ d_free,   G: (β_k, γ) = 1, (γ, λ_n) = μ, (γ, β_k) = -1,
// an LCP with m + 2 variables per frictional contact. Pᵀ W P is positive semidefinite
// and G has the structure for which Lemke's method is known to process the problem
// (Stewart & Trinkle 1996, Anitescu & Potra 1997). Frictionless and μ = 0 contacts keep
// their normal row; bilateral rows stay bilateral (runLemke splits their sign).
//
// When to use it: small problems where an exact vertex solution of the pyramid model is
// wanted (reference answers, tests); it costs O(N²) per pivot on N = (m + 2) per
// frictional contact variables, so prefer the boxed pgs for large or real-time problems.
KernelReport runPyramidLemke(const SolveContext& ctx, Eigen::VectorXd& lambda) {
  const Problem& problem = *ctx.problem;
  const SolverParams& params = *ctx.params;
  const FrictionPolygon polygon = makeFrictionPolygon(params.friction_model);
  const int m = polygon.facets;
  const int n = problem.rowCount();

  struct Entry {
    int row;
    double value;
  };
  std::vector<std::vector<Entry>> columns;  // P, one column per LCP variable
  struct Coupling {
    int i, j;
    double value;
  };
  std::vector<Coupling> couplings;  // G
  Problem lcp;
  lcp.name = problem.name + " (pyramid LCP)";
  auto addVariable = [&](std::vector<Entry> column) {
    columns.push_back(std::move(column));
    Contact contact;
    contact.id = static_cast<std::int64_t>(lcp.contacts.size());
    contact.type = ContactType::kFrictionless;
    contact.rows = 1;
    contact.mu = 0.0;
    lcp.contacts.push_back(contact);
    return static_cast<int>(columns.size()) - 1;
  };
  for (std::size_t c = 0; c < problem.contacts.size(); ++c) {
    if (ctx.ignored[c]) continue;
    const Contact& contact = problem.contacts[c];
    const int off = ctx.offsets[c];
    if (contact.type == ContactType::kBilateral) {
      Contact bilateral;
      bilateral.id = static_cast<std::int64_t>(lcp.contacts.size());
      bilateral.type = ContactType::kBilateral;
      bilateral.rows = contact.rows;
      for (int k = 0; k < contact.rows; ++k) columns.push_back({{off + k, 1.0}});
      lcp.contacts.push_back(bilateral);
      continue;
    }
    const int jn = addVariable({{off, 1.0}});
    if (contact.type != ContactType::kFrictional || ctx.mu[c] == 0.0) continue;
    const int first_beta = static_cast<int>(columns.size());
    for (int k = 0; k < m; ++k)
      addVariable({{off + 1, polygon.vertex[k][0]}, {off + 2, polygon.vertex[k][1]}});
    const int jg = addVariable({});
    couplings.push_back({jg, jn, ctx.mu[c]});
    for (int k = 0; k < m; ++k) {
      couplings.push_back({first_beta + k, jg, 1.0});
      couplings.push_back({jg, first_beta + k, -1.0});
    }
  }
  const int N = static_cast<int>(columns.size());
  // The dense W, W P and M below: refuse sizes runLemke would refuse anyway (lemke.cpp),
  // before allocating them.
  constexpr int kMaxPyramidLemkeSize = 4096;
  if (N > kMaxPyramidLemkeSize || n > kMaxPyramidLemkeSize) {
    lambda.setZero(n);
    KernelReport report;
    report.status = SolveStatus::kNotApplicable;
    report.friction_model = params.friction_model;
    report.message = "Lemke's dense tableau is limited to " + std::to_string(kMaxPyramidLemkeSize) +
                     " variables and rows; the " + std::string(frictionModelName(params.friction_model)) +
                     " friction LCP has " + std::to_string(N) + " variables on " + std::to_string(n) +
                     " rows; use pgs (boxed Gauss-Seidel on the same pyramid)";
    report.solver_error = ctx.residual(lambda);
    return report;
  }

  // M = Pᵀ (W + r I) P + G, q = Pᵀ d_free; P has at most two entries per column.
  Eigen::MatrixXd W = toDense(problem.W);
  W.diagonal().array() += ctx.regularization;
  Eigen::MatrixXd WP = Eigen::MatrixXd::Zero(n, N);
  for (int j = 0; j < N; ++j)
    for (const Entry& e : columns[j]) WP.col(j) += e.value * W.col(e.row);
  Eigen::MatrixXd M(N, N);
  for (int j = 0; j < N; ++j) {  // column by column: contiguous in both M and WP
    const double* wp = WP.col(j).data();
    double* m = M.col(j).data();
    for (int i = 0; i < N; ++i) {
      double sum = 0.0;
      for (const Entry& e : columns[i]) sum += e.value * wp[e.row];
      m[i] = sum;
    }
  }
  Eigen::VectorXd q = Eigen::VectorXd::Zero(N);
  for (int i = 0; i < N; ++i)
    for (const Entry& e : columns[i]) q[i] += e.value * problem.d_free[e.row];
  for (const Coupling& g : couplings) M(g.i, g.j) += g.value;
  lcp.W = std::move(M);
  lcp.d_free = q;

  SolverParams lcp_params = params;
  lcp_params.friction_model = FrictionModel::kCoulombDisc;
  lcp_params.regularizationTerm = 0.0;
  SolveContext sub;
  sub.problem = &lcp;
  sub.params = &lcp_params;
  sub.offsets = lcp.rowOffsets();
  sub.mu = effectiveMu(lcp, 0.0);
  sub.ignored.assign(lcp.contacts.size(), false);
  sub.regularization = 0.0;
  sub.has_deadline = ctx.has_deadline;
  sub.deadline = ctx.deadline;
  Eigen::VectorXd z = Eigen::VectorXd::Zero(N);
  if (ctx.deadlinePassed()) {  // building the LCP used up the budget
    lambda.setZero(n);
    KernelReport report;
    report.status = SolveStatus::kTimeBudget;
    report.friction_model = params.friction_model;
    report.solver_error = ctx.residual(lambda);
    report.message = "the time budget ran out while building the " +
                     std::string(frictionModelName(params.friction_model)) + " friction LCP (" +
                     std::to_string(N) + " variables); forces are zero";
    return report;
  }
  KernelReport report = runLemke(sub, z);

  lambda.setZero(n);
  if (z.allFinite()) {
    for (int j = 0; j < N; ++j)
      for (const Entry& e : columns[j]) lambda[e.row] += e.value * z[j];
  }
  Eigen::VectorXd d;
  ctx.computeD(lambda, d);
  report.solver_error = pyramidResidual(problem, ctx.mu, polygon, lambda, d, ctx.ignored);
  report.friction_model = params.friction_model;
  if (report.status == SolveStatus::kConverged && report.solver_error > params.tolerance) {
    // Exact in exact arithmetic, but hundreds of pivots on an ill-conditioned W lose
    // digits: say so rather than claim the tolerance.
    report.status = SolveStatus::kNumericalFailure;
    report.message = "Lemke's final basis leaves a pyramid residual of " +
                     std::to_string(report.solver_error) + " > tolerance (round-off over " +
                     std::to_string(report.iterations) + " pivots); the forces are that basic solution";
  }
  if (report.status == SolveStatus::kRayTermination) {
    report.message +=
        "; with a rank-deficient W (more contact rows than body freedoms) a small "
        "regularizationTerm (e.g. 1e-8 of W's scale) usually avoids this";
  }
  const std::string note = "Lemke solved the " + std::string(frictionModelName(params.friction_model)) +
                           " friction LCP (" + std::to_string(N) + " variables)";
  report.message = report.message.empty() ? note : note + "; " + report.message;
  return report;
}

}  // namespace lcp_contact_solver::core
