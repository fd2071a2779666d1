// What `lcp_solve` prints: the result table and the JSON lines.
#pragma once

#include "lcp_contact_solver/core/problem.h"
#include "lcp_contact_solver/core/solve_result.h"

#include <string>

namespace lcp_contact_solver {

// Table output: a header line and one row per problem (fixed-width columns).
std::string formatTableHeader(int name_width);
std::string formatTableRow(const core::Problem& problem, const core::SolveResult& result, int name_width);

// One JSON object (no trailing newline) with the table's fields plus forces, d, states.
// Numbers use %.17g; a non-finite number is written as null.
std::string formatJsonLine(const core::Problem& problem, const core::SolveResult& result);

// Residual history (--display-debug), one line per sweep/pivot.
std::string formatResidualHistory(const core::Problem& problem, const core::SolveResult& result);

}  // namespace lcp_contact_solver
