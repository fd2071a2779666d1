// Polyhedral friction (SolverParams::friction_model kPyramid4 / kPyramid8), shared by the
// boxed Gauss-Seidel (gauss_seidel.cpp) and the Stewart-Trinkle LCP for Lemke
// (pyramid.cpp). Private to the core library.
//
// The friction polygon P(R) of a contact with normal force λ_n is the regular polygon with
// m facets circumscribing the disc of radius R = μ λ_n: facet k has the outward unit
// normal n_k at angle 2πk/m and lies at distance R from the origin, so
//   P(R) = { x : n_kᵀ x <= R, k = 0..m-1 } = { x : |n_kᵀ x| <= R, k = 0..m/2-1 }.
// m = 4 is the box |λ_t1| <= μ λ_n, |λ_t2| <= μ λ_n; m = 8 adds the two diagonals. Its
// vertices v_k (between facets k and k+1) are at angle 2πk/m + π/m and distance
// R / cos(π/m), so P(R) is also the convex hull of R v_k (the Stewart-Trinkle form).
#pragma once

#include "lcp_contact_solver/core/problem.h"
#include "lcp_contact_solver/core/solver_params.h"

#include <Eigen/Core>

#include <vector>

namespace lcp_contact_solver::core {

struct FrictionPolygon {
  int facets = 0;            // m: 4 or 8
  double normal[8][2] = {};  // n_k, unit
  double along[8][2] = {};   // unit direction of facet k (n_k turned by +90°)
  double vertex[8][2] = {};  // v_k for unit inradius (|v_k| = 1 / cos(π/m))
  double half_edge = 0.0;    // tan(π/m): half a facet's length for unit inradius
};

// The polygon of a pyramid model (facets 0 for the disc).
FrictionPolygon makeFrictionPolygon(FrictionModel model);

// argmin ½ xᵀ T x + bᵀ x over P(R), T symmetric positive semidefinite. If the
// unconstrained minimiser is inside it is the answer; otherwise the minimiser is on the
// boundary and is the best of the m facets, each minimised exactly over its segment.
Eigen::Vector2d minimizeOverPolygon(const FrictionPolygon& polygon, const Eigen::Matrix2d& T,
                                    const Eigen::Vector2d& b, double R);

// Euclidean projection of y onto P(R).
Eigen::Vector2d projectOntoPolygon(const FrictionPolygon& polygon, const Eigen::Vector2d& y, double R);

// Natural-map residual of the pyramid problem, normalised like naturalMapResidual:
// frictional contacts e_n = λ_n - max(0, λ_n - d_n), e_t = λ_t - Proj_P(μ max(λ_n, 0))(λ_t - d_t),
// which is zero exactly when 0 <= λ_n ⟂ d_n >= 0, λ_t ∈ P(μ λ_n) and -d_t is in the
// normal cone of P at λ_t (maximum dissipation over the polygon); other rows as the disc.
double pyramidResidual(const Problem& problem, const std::vector<double>& mu, const FrictionPolygon& polygon,
                       const Eigen::VectorXd& lambda, const Eigen::VectorXd& d,
                       const std::vector<bool>& ignored);

}  // namespace lcp_contact_solver::core
