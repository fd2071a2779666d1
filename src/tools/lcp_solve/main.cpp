// lcp_solve: solves contact problem files from the command line (docs/TOOLS.md "Solving
// problem files"). Arguments are parsed with CLI11; the table and JSON lines are problem_report.h's.
#include "problem_report.h"

#include "lcp_contact_solver/core/contact_solver.h"
#include "lcp_contact_solver/core/problem_io.h"
#include "lcp_contact_solver/core/solver_param_table.h"
#include "lcp_contact_solver/core/solver_params.h"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cctype>
#include <exception>
#include <filesystem>
#include <iostream>
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
  core::SolverParams params;
  bool json = false;              // one JSON object per line instead of the table
  bool fail_unconverged = false;  // exit 1 when some problem did not converge
  bool help = false;
};

// ---- argument parsing ---------------------------------------------------------------------
// Every solver parameter of the table (core/solver_param_table.def) is an option under its
// own name and its kebab-case spelling (--maxIt, --max-it); booleans are flags with a
// --no- form. --regularization is the older name of --regularization-term.

std::string kebab(const std::string& name) {
  std::string out;
  for (char c : name) {
    if (c == '_') {
      out += '-';
    } else if (std::isupper(static_cast<unsigned char>(c))) {
      out += '-';
      out += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    } else {
      out += c;
    }
  }
  return out;
}

// The option's spellings, table name first: "--maxIt,--max-it".
std::vector<std::string> spellings(const core::ParamSpec& spec) {
  std::vector<std::string> names = {"--" + spec.name};
  if (kebab(spec.name) != spec.name) names.push_back("--" + kebab(spec.name));
  if (spec.name == "regularizationTerm") names.push_back("--regularization");
  return names;
}

std::string joined(const std::vector<std::string>& names, const char* separator) {
  std::string out;
  for (const std::string& name : names) out += (out.empty() ? "" : separator) + name;
  return out;
}

// Parses the arguments after the program name: empty string, or the usage error. Values
// are taken as text by CLI11 and set through the table's parsers, so a bad one is named
// with its option.
std::string parseArgs(const std::vector<std::string>& args, LcpSolveOptions* options) {
  CLI::App app(kProgram);
  app.set_help_flag();  // --help prints lcpSolveUsage(), not CLI11's text
  app.allow_extras();   // reported below as "unknown option"
  app.option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  const std::vector<core::ParamSpec>& specs = core::solverParamSpecs();
  std::vector<std::string> values(specs.size());
  std::vector<CLI::Option*> given(specs.size()), negated(specs.size(), nullptr);
  for (std::size_t i = 0; i < specs.size(); ++i) {
    const std::string names = joined(spellings(specs[i]), ",");
    if (specs[i].type == core::ParamType::kBool) {
      given[i] = app.add_flag(names);
      negated[i] = app.add_flag("--no-" + kebab(specs[i].name));
    } else {
      given[i] = app.add_option(names, values[i]);
    }
  }
  app.add_flag("--json", options->json);
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
  for (std::size_t i = 0; i < specs.size(); ++i) {
    std::string text;
    if (given[i]->count() > 0) text = specs[i].type == core::ParamType::kBool ? "true" : values[i];
    if (negated[i] != nullptr && negated[i]->count() > 0) text = "false";
    if (given[i]->count() == 0 && (negated[i] == nullptr || negated[i]->count() == 0)) continue;
    if (const std::string why = core::setParam(&options->params, specs[i].name, text); !why.empty())
      return "option " + spellings(specs[i]).back() + ": " + why;
  }
  if (options->help) return "";
  if (const std::string why = core::validateParams(options->params); !why.empty()) return why;
  if (options->files.empty()) return "no problem file given";
  return "";
}

std::string lcpSolveUsage() {
  std::ostringstream usage;
  usage << "usage: " << kProgram << " FILE... [options]\n"
        << "Reads contact problems (Siconos .dat LCP/FC3D, FCLIB .hdf5) and solves each one.\n"
        << "\n"
        << "solver parameters (the node's names, README \"Parameters\"; problem files give their\n"
        << "own mu per contact, mu is for those that give none; --display-debug prints each\n"
        << "problem's residual history on stderr):\n";
  for (const core::ParamSpec& spec : core::solverParamSpecs()) {
    std::string names = joined(spellings(spec), ", ");
    if (spec.type == core::ParamType::kBool) {
      names += ", --no-" + kebab(spec.name);
    } else {
      names += spec.type == core::ParamType::kEnum  ? " NAME"
               : spec.type == core::ParamType::kInt ? " N"
                                                    : " X";
    }
    usage << "  " << names << "\n      " << spec.doc << "; default " << spec.default_text << "\n";
  }
  usage << "\n"
        << "output:\n"
        << "  --json                 one JSON object per line: the table's fields plus forces,\n"
        << "                         d = W forces + d_free, states; with a pyramid\n"
        << "                         friction_model also solver_error (the pyramid's own\n"
        << "                         residual; the residual column stays the disc's)\n"
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
bool solveFile(const std::string& file, const LcpSolveOptions& options, int name_width, bool* header_written,
               bool* converged, std::ostream& out, std::ostream& err) {
  core::Problem problem;
  try {
    problem = core::readProblemFile(file);
  } catch (const std::exception& e) {
    // ProblemFileError already names the file; anything else (bad_alloc) does not.
    const std::string reason = e.what();
    const std::string prefix = file + ": ";
    err << kProgram << ": " << (reason.rfind(prefix, 0) == 0 ? reason : prefix + reason) << "\n";
    return false;
  }
  core::SolveResult result;
  try {
    core::ContactSolver solver(options.params);  // fresh per file: no warm start across files
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
  if (result.status == core::SolveStatus::kInvalidInput) {
    err << kProgram << ": " << file << ": solver refused the problem: " << result.message << "\n";
    return false;
  }
  return true;
}

int runLcpSolve(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  LcpSolveOptions options;
  if (const std::string why = parseArgs(args, &options); !why.empty()) {
    err << kProgram << ": " << why << "\n"
        << "Try '" << kProgram << " --help'.\n";
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
