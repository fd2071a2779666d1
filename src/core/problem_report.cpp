#include "lcp_contact_solver/core/problem_report.h"

#include "lcp_contact_solver/core/contact_solver.h"
#include "lcp_contact_solver/core/problem_io.h"

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <functional>
#include <map>
#include <sstream>

namespace lcp_contact_solver {
namespace {

constexpr const char* kProgram = "lcp_solve";

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

// Flags without a value; returns false for an unknown flag.
bool applyFlag(const std::string& flag, LcpSolveOptions* options) {
  if (flag == "--json") options->json = true;
  else if (flag == "--no-initial-guess") options->params.initial_guess = false;
  else if (flag == "--display-debug") options->params.displayDebug = true;
  else if (flag == "--fail-unconverged") options->fail_unconverged = true;
  else if (flag == "--help" || flag == "-h") options->help = true;
  else return false;
  return true;
}

// ---- formatting ---------------------------------------------------------------------------

std::string formatNumber(const char* format, double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, format, value);
  return buffer;
}

// Full precision for JSON; never NaN/Inf, which JSON cannot hold.
std::string jsonNumber(double value) {
  return std::isfinite(value) ? formatNumber("%.17g", value) : "null";
}

std::string jsonString(const std::string& text) {
  std::string quoted = "\"";
  for (unsigned char ch : text) {
    switch (ch) {
      case '"': quoted += "\\\""; break;
      case '\\': quoted += "\\\\"; break;
      case '\n': quoted += "\\n"; break;
      case '\r': quoted += "\\r"; break;
      case '\t': quoted += "\\t"; break;
      default:
        if (ch < 0x20) {
          char escaped[8];
          std::snprintf(escaped, sizeof escaped, "\\u%04x", ch);
          quoted += escaped;
        } else {
          quoted += static_cast<char>(ch);
        }
    }
  }
  return quoted + "\"";
}

std::string jsonArray(const Eigen::VectorXd& values) {
  std::string array = "[";
  for (Eigen::Index i = 0; i < values.size(); ++i) {
    if (i > 0) array += ",";
    array += jsonNumber(values[i]);
  }
  return array + "]";
}

std::string jsonStates(const std::vector<ContactState>& states) {
  std::string array = "[";
  for (std::size_t i = 0; i < states.size(); ++i) {
    if (i > 0) array += ",";
    array += jsonString(stateName(states[i]));
  }
  return array + "]";
}

std::string padRight(const std::string& text, int width) {
  return text.size() >= static_cast<std::size_t>(width) ? text : text + std::string(width - text.size(), ' ');
}

std::string padLeft(const std::string& text, int width) {
  return text.size() >= static_cast<std::size_t>(width) ? text : std::string(width - text.size(), ' ') + text;
}

// Column widths of the table (name width varies with the files).
constexpr int kNumberWidth = 9;
constexpr int kSolverWidth = 7;
constexpr int kResidualWidth = 11;
constexpr int kConvergedWidth = 9;
constexpr int kStatusWidth = 16;
constexpr int kTimeWidth = 11;

std::string tableLine(int name_width, const std::vector<std::string>& cells) {
  std::string line = padRight(cells[0], name_width);
  line += " " + padLeft(cells[1], kNumberWidth);
  line += " " + padLeft(cells[2], kNumberWidth);
  line += "  " + padRight(cells[3], kSolverWidth);
  line += " " + padLeft(cells[4], kNumberWidth);
  line += " " + padLeft(cells[5], kResidualWidth);
  line += "  " + padRight(cells[6], kConvergedWidth);
  line += " " + padRight(cells[7], kStatusWidth);
  line += " " + padLeft(cells[8], kTimeWidth);
  return line;
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

}  // namespace

std::string parseLcpSolveArgs(const std::vector<std::string>& args, LcpSolveOptions* options) {
  bool only_files = false;  // after "--"
  for (std::size_t k = 0; k < args.size(); ++k) {
    const std::string& arg = args[k];
    if (only_files || arg.empty() || arg[0] != '-' || arg == "-") {
      options->files.push_back(arg);
      continue;
    }
    if (arg == "--") {
      only_files = true;
      continue;
    }
    if (applyFlag(arg, options)) continue;
    // --name value or --name=value
    const std::size_t equals = arg.find('=');
    const std::string name = arg.substr(0, equals);
    const auto option = valueOptions().find(name);
    if (option == valueOptions().end()) return "unknown option '" + name + "'";
    std::string value;
    if (equals != std::string::npos) {
      value = arg.substr(equals + 1);
    } else if (k + 1 < args.size()) {
      value = args[++k];
    } else {
      return "option " + name + " needs a value";
    }
    if (const std::string why = option->second(value, &options->params); !why.empty())
      return "option " + name + " " + why + ", got '" + value + "'";
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

std::string formatTableHeader(int name_width) {
  return tableLine(name_width, {"problem", "contacts", "rows", "solver", "iters", "residual",
                                "converged", "status", "time_s"});
}

std::string formatTableRow(const Problem& problem, const SolveResult& result, int name_width) {
  return tableLine(name_width,
                   {problem.name, std::to_string(problem.contacts.size()),
                    std::to_string(problem.rowCount()), result.solver,
                    std::to_string(result.iterations), formatNumber("%.3e", result.residual),
                    result.converged ? "yes" : "no", statusName(result.status),
                    formatNumber("%.6f", result.solve_time)});
}

std::string formatJsonLine(const Problem& problem, const SolveResult& result) {
  std::string json = "{";
  json += "\"name\":" + jsonString(problem.name);
  json += ",\"contacts\":" + std::to_string(problem.contacts.size());
  json += ",\"rows\":" + std::to_string(problem.rowCount());
  json += ",\"solver\":" + jsonString(result.solver);
  json += ",\"iterations\":" + std::to_string(result.iterations);
  json += ",\"residual\":" + jsonNumber(result.residual);
  json += std::string(",\"converged\":") + (result.converged ? "true" : "false");
  json += ",\"status\":" + jsonString(statusName(result.status));
  json += ",\"friction_model\":" + jsonString(frictionModelName(result.friction_model));
  json += ",\"solver_error\":" + jsonNumber(result.solver_error);
  json += ",\"solve_time\":" + jsonNumber(result.solve_time);
  json += ",\"message\":" + jsonString(result.message);
  json += ",\"forces\":" + jsonArray(result.forces);
  json += ",\"d\":" + jsonArray(result.d);
  json += ",\"states\":" + jsonStates(result.states);
  return json + "}";
}

std::string formatResidualHistory(const Problem& problem, const SolveResult& result) {
  std::string text = problem.name + ": residual history (" +
                     std::to_string(result.residual_history.size()) + " entries, solver " +
                     result.solver + ")\n";
  for (std::size_t k = 0; k < result.residual_history.size(); ++k)
    text += "  " + padLeft(std::to_string(k + 1), 6) + " " +
            formatNumber("%.6e", result.residual_history[k]) + "\n";
  return text;
}

int runLcpSolve(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  LcpSolveOptions options;
  if (const std::string why = parseLcpSolveArgs(args, &options); !why.empty()) {
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

}  // namespace lcp_contact_solver
