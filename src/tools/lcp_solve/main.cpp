// lcp_solve: solves contact problem files from the command line (README "Solving problem
// files"). Arguments are parsed with CLI11; the table and JSON lines are problem_report.h's.
#include "problem_report.h"

#include "lcp_contact_solver/core/contact_solver.h"
#include "lcp_contact_solver/core/problem_io.h"
#include "lcp_contact_solver/core/solver_params.h"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <functional>
#include <iostream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace lcp_contact_solver {
namespace {

constexpr const char* kProgram = "lcp_solve";

// Exit codes.
constexpr int kExitOk = 0;
constexpr int kExitFailure = 1;  // a file could not be read or solved (or, on request, converge)
constexpr int kExitUsage = 2;    // bad command line

struct LcpSolveOptions {
  std::vector<std::string> files;
  SolverParams params;
  bool json = false;              // one JSON object per line instead of the table
  bool fail_unconverged = false;  // exit 1 when some problem did not converge
  bool help = false;
};

// ---- argument parsing ---------------------------------------------------------------------

bool parseFiniteDouble(const std::string& text, double* value) {
  if (text.empty()) return false;
  char* end = nullptr;
  const double parsed = std::strtod(text.c_str(), &end);
  if (end != text.c_str() + text.size() || !std::isfinite(parsed)) return false;
  *value = parsed;
  return true;
}

bool parseInt(const std::string& text, int* value) {
  if (text.empty()) return false;
  errno = 0;
  char* end = nullptr;
  const long parsed = std::strtol(text.c_str(), &end, 10);
  if (end != text.c_str() + text.size() || errno == ERANGE || parsed < INT_MIN || parsed > INT_MAX)
    return false;
  *value = static_cast<int>(parsed);
  return true;
}

// Each option that takes a value: stores it, or returns why it cannot.
using ValueSetter = std::function<std::string(const std::string&, SolverParams*)>;

ValueSetter doubleSetter(double SolverParams::*field) {
  return [field](const std::string& text, SolverParams* params) -> std::string {
    if (!parseFiniteDouble(text, &(params->*field))) return "expects a finite number";
    return "";
  };
}

const std::map<std::string, ValueSetter>& valueOptions() {
  static const std::map<std::string, ValueSetter> options = {
      {"--solver",
       [](const std::string& text, SolverParams* params) -> std::string {
         return parseSolverName(text, &params->solver) ? "" : "unknown solver";
       }},
      {"--tolerance", doubleSetter(&SolverParams::tolerance)},
      {"--max-it",
       [](const std::string& text, SolverParams* params) -> std::string {
         return parseInt(text, &params->maxIt) ? "" : "expects an integer";
       }},
      {"--mu", doubleSetter(&SolverParams::mu)},
      {"--regularization", doubleSetter(&SolverParams::regularizationTerm)},
      {"--min-w", doubleSetter(&SolverParams::minW)},
      {"--max-f", doubleSetter(&SolverParams::maxF)},
      {"--sor", doubleSetter(&SolverParams::sor)},
      {"--time-budget", doubleSetter(&SolverParams::time_budget)},
      {"--friction-model",
       [](const std::string& text, SolverParams* params) -> std::string {
         return parseFrictionModel(text, &params->friction_model) ? "" : "expects disc, pyramid4 or pyramid8";
       }},
      {"--stopping-rule",
       [](const std::string& text, SolverParams* params) -> std::string {
         return parseStoppingRule(text, &params->stopping_rule) ? "" : "expects residual or sofa";
       }},
  };
  return options;
}

// Parses the arguments after the program name: empty string, or the usage error. Values
// are taken as text by CLI11 and checked here, so a bad one is named with its option.
std::string parseArgs(const std::vector<std::string>& args, LcpSolveOptions* options) {
  CLI::App app(kProgram);
  app.set_help_flag();  // --help prints lcpSolveUsage(), not CLI11's text
  app.allow_extras();   // reported below as "unknown option"
  app.option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  std::map<std::string, std::string> values;
  std::map<std::string, CLI::Option*> given;
  for (const auto& entry : valueOptions()) given[entry.first] = app.add_option(entry.first, values[entry.first]);
  bool no_initial_guess = false;
  app.add_flag("--json", options->json);
  app.add_flag("--no-initial-guess", no_initial_guess);
  app.add_flag("--display-debug", options->params.displayDebug);
  app.add_flag("--fail-unconverged", options->fail_unconverged);
  app.add_flag("-h,--help", options->help);
  app.add_option("files", options->files);  // also everything after "--"
  try {
    app.parse(std::vector<std::string>(args.rbegin(), args.rend()));  // CLI11 takes them reversed
  } catch (const CLI::ArgumentMismatch& e) {  // CLI11 says "--name: 1 required TEXT missing"
    const std::string what = e.what();
    return "option " + what.substr(0, what.find(':')) + " needs a value";
  } catch (const CLI::ParseError& e) {
    return e.what();
  }
  for (const std::string& extra : app.remaining())
    if (extra != "--") return "unknown option '" + extra.substr(0, extra.find('=')) + "'";
  if (no_initial_guess) options->params.initial_guess = false;
  for (const auto& [name, setter] : valueOptions()) {
    if (given[name]->count() == 0) continue;
    if (const std::string why = setter(values[name], &options->params); !why.empty())
      return "option " + name + " " + why + ", got '" + values[name] + "'";
  }
  if (options->help) return "";
  if (const std::string why = validateParams(options->params); !why.empty()) return why;
  if (options->files.empty()) return "no problem file given";
  return "";
}

std::string lcpSolveUsage() {
  std::string solvers;
  for (const std::string& name : solverNames()) solvers += (solvers.empty() ? "" : ", ") + name;
  std::string models;
  for (const std::string& name : frictionModelNames()) models += (models.empty() ? "" : ", ") + name;
  const SolverParams defaults;
  std::ostringstream usage;
  usage << "usage: " << kProgram << " FILE... [options]\n"
        << "Reads contact problems (Siconos .dat LCP/FC3D, FCLIB .hdf5) and solves each one.\n"
        << "\n"
        << "options:\n"
        << "  --solver NAME          " << solvers << " (default " << solverName(defaults.solver) << ")\n"
        << "  --tolerance X          convergence threshold (default " << defaults.tolerance << ")\n"
        << "  --max-it N             maximum sweeps, iterations or pivots (default " << defaults.maxIt << ")\n"
        << "  --mu X                 friction for contacts that give none; problem files give\n"
        << "                         their own (default " << defaults.mu << ")\n"
        << "  --regularization X     add X to W's diagonal (default 0)\n"
        << "  --min-w X              ignore contacts with normal compliance <= X (default 0: off)\n"
        << "  --max-f X              drop contacts whose force exceeds X and re-solve (0: off)\n"
        << "  --sor X                over-relaxation of pgs/nlgs, in (0, 2) (default " << defaults.sor << ")\n"
        << "  --time-budget S        stop each solve after S seconds with its best iterate,\n"
        << "                         status time_budget (default 0: no budget)\n"
        << "  --friction-model M     " << models << " (default "
        << frictionModelName(defaults.friction_model) << "); pgs and\n"
        << "                         lemke solve a pyramid as an LCP; the residual column\n"
        << "                         stays the disc's (nonzero by design), --json adds\n"
        << "                         solver_error (the pyramid's own) and friction_model\n"
        << "  --stopping-rule RULE   residual or sofa (default "
        << stoppingRuleName(defaults.stopping_rule) << ")\n"
        << "  --no-initial-guess     no warm start (each file is solved cold anyway)\n"
        << "  --display-debug        print each problem's residual history on stderr\n"
        << "  --json                 one JSON object per line: the table's fields plus forces,\n"
        << "                         d = W forces + d_free, states\n"
        << "  --fail-unconverged     exit 1 if some problem did not converge\n"
        << "  --help                 this text\n"
        << "\n"
        << "exit status: 0 all files read and solved (converged or not), 1 some file failed,\n"
        << "2 bad command line.\n";
  return usage.str();
}

// ---- running ------------------------------------------------------------------------------

int nameWidth(const std::vector<std::string>& files) {
  std::size_t width = std::string("problem").size();
  for (const std::string& file : files)
    width = std::max(width, std::filesystem::path(file).filename().string().size());
  return static_cast<int>(width);
}

// One file: read, solve, print. Returns false if it could not be read or solved.
bool solveFile(const std::string& file, const LcpSolveOptions& options, int name_width,
               bool* header_written, bool* converged, std::ostream& out, std::ostream& err) {
  Problem problem;
  try {
    problem = readProblemFile(file);
  } catch (const std::exception& e) {
    // ProblemFileError already names the file; anything else (bad_alloc) does not.
    const std::string reason = e.what();
    const std::string prefix = file + ": ";
    err << kProgram << ": " << (reason.rfind(prefix, 0) == 0 ? reason : prefix + reason) << "\n";
    return false;
  }
  SolveResult result;
  try {
    ContactSolver solver(options.params);  // fresh per file: no warm start across files
    result = solver.solve(problem);
  } catch (const std::exception& e) {
    err << kProgram << ": " << file << ": solve failed: " << e.what() << "\n";
    return false;
  }
  if (options.json) {
    out << formatJsonLine(problem, result) << "\n";
  } else {
    if (!*header_written) out << formatTableHeader(name_width) << "\n";
    *header_written = true;
    out << formatTableRow(problem, result, name_width) << "\n";
  }
  out.flush();
  if (options.params.displayDebug) err << formatResidualHistory(problem, result);
  *converged = result.converged;
  if (result.status == SolveStatus::kInvalidInput) {
    err << kProgram << ": " << file << ": solver refused the problem: " << result.message << "\n";
    return false;
  }
  return true;
}

int runLcpSolve(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  LcpSolveOptions options;
  if (const std::string why = parseArgs(args, &options); !why.empty()) {
    err << kProgram << ": " << why << "\n" << "Try '" << kProgram << " --help'.\n";
    return kExitUsage;
  }
  if (options.help) {
    out << lcpSolveUsage();
    return kExitOk;
  }
  const int name_width = nameWidth(options.files);
  bool header_written = false;
  bool any_failed = false;
  bool any_unconverged = false;
  for (const std::string& file : options.files) {
    bool converged = false;
    if (!solveFile(file, options, name_width, &header_written, &converged, out, err)) {
      any_failed = true;
    } else if (!converged) {
      any_unconverged = true;
    }
  }
  if (any_failed) return kExitFailure;
  if (options.fail_unconverged && any_unconverged) return kExitFailure;
  return kExitOk;
}

}  // namespace
}  // namespace lcp_contact_solver

int main(int argc, char** argv) {
  const std::vector<std::string> args(argv + 1, argv + argc);
  return lcp_contact_solver::runLcpSolve(args, std::cout, std::cerr);
}
