// Solver-independent error measures, in the convention Siconos and the FCLIB comparisons
// publish, so our figures compare with theirs:
//   frictional contact c: e_c = λ_c - Proj_K(λ_c - (d_c + μ |d_t| e_n)), K = {|λ_t| <= μ λ_n}
//   unilateral row:       e_i = λ_i - max(0, λ_i - d_i)
//   bilateral row:        e_i = d_i
//   residual = sqrt(sum e²) / |d_free|   (divided by 1 when d_free = 0)
// Ignored contacts (minW, maxF) are not constraints of the solved problem and do not count.
#pragma once

#include "lcp_contact_solver/core/problem.h"
#include "lcp_contact_solver/core/solve_result.h"

#include <Eigen/Core>

#include <vector>

namespace lcp_contact_solver::core {

// Projection of (rn, rt1, rt2) onto the Coulomb cone of coefficient mu (in place).
void projectOntoCone(double mu, double* r);

// Residual of forces λ given d = W λ + d_free. `mu` holds each contact's effective μ;
// `ignored` (may be empty) marks contacts left out.
double naturalMapResidual(const Problem& problem, const std::vector<double>& mu,
                          const Eigen::VectorXd& lambda, const Eigen::VectorXd& d,
                          const std::vector<bool>& ignored = {});

// The effective μ of each contact: its own, or `default_mu` when it gives none.
std::vector<double> effectiveMu(const Problem& problem, double default_mu);

// Classifies each contact from its force; `ignored` marks contacts forced to kIgnored.
std::vector<ContactState> classifyContacts(const Problem& problem, const std::vector<double>& mu,
                                           const Eigen::VectorXd& lambda,
                                           const std::vector<bool>& ignored = {});

}  // namespace lcp_contact_solver::core
