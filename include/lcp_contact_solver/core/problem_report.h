// The command-line tool `lcp_solve`: argument parsing, the result table and the JSON lines.
// Kept out of the main so it can be tested with string streams.
#pragma once

#include "lcp_contact_solver/core/problem.h"
#include "lcp_contact_solver/core/solve_result.h"
#include "lcp_contact_solver/core/solver_params.h"

#include <ostream>
#include <string>
#include <vector>

namespace lcp_contact_solver {

struct LcpSolveOptions {
  std::vector<std::string> files;
  SolverParams params;
  bool json = false;              // one JSON object per line instead of the table
  bool fail_unconverged = false;  // exit 1 when some problem did not converge
  bool help = false;
};

// Exit codes of lcp_solve.
constexpr int kExitOk = 0;
constexpr int kExitFailure = 1;  // a file could not be read or solved (or, on request, converge)
constexpr int kExitUsage = 2;    // bad command line

// Parses the arguments after the program name. Returns an empty string on success,
// otherwise a one-line description of the usage error.
std::string parseLcpSolveArgs(const std::vector<std::string>& args, LcpSolveOptions* options);

// The --help text; lists every solver name.
std::string lcpSolveUsage();

// Table output: a header line and one row per problem (fixed-width columns).
std::string formatTableHeader(int name_width);
std::string formatTableRow(const Problem& problem, const SolveResult& result, int name_width);

// One JSON object (no trailing newline) with the table's fields plus forces, d, states.
// Numbers use %.17g; a non-finite number is written as null.
std::string formatJsonLine(const Problem& problem, const SolveResult& result);

// Residual history (--display-debug), one line per sweep/pivot.
std::string formatResidualHistory(const Problem& problem, const SolveResult& result);

// The whole tool: reads and solves every file, writes results to `out` and errors to `err`,
// returns the exit code.
int runLcpSolve(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

}  // namespace lcp_contact_solver
