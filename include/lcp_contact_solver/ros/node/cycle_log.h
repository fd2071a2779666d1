// The one-line per-cycle summary logged with displayDebug.
#pragma once

#include "lcp_contact_solver/core/problem.h"
#include "lcp_contact_solver/core/solve_result.h"

#include <string>
#include <vector>

namespace lcp_contact_solver_ros {

namespace lcs = ::lcp_contact_solver;

// Index of the contact with the largest natural-map error (core residual.h, not
// normalised), or -1 when every contact is ignored. `mu`: effective μ per contact.
int worstContact(const lcs::core::Problem& problem, const lcs::core::SolveResult& result,
                 const std::vector<double>& mu, double* error);

// Sizes, solver, iterations, residual, status and the worst contact.
std::string cycleSummary(const lcs::core::Problem& problem, const lcs::core::SolveResult& result,
                         const std::vector<double>& mu);

}  // namespace lcp_contact_solver_ros
