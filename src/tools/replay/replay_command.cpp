// The `replay` command: its command line (CLI11), the parameters it assembles and what it prints.
#include "replay/replay_command.h"

#include "lcp_contact_solver/ros/node/solver_params_ros.h"
#include "lcp_contact_solver/ros/replay/params_file.h"
#include "lcp_contact_solver/ros/replay/text.h"
#include "replay/summary.h"

#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>

namespace lcp_contact_solver_ros {

namespace {

const char* kUsage =
    "usage: replay IN.bag [--out OUT.bag] [--csv STATS.csv] [--params FILE.yaml | --no-params-file]\n"
    "              [name=value ...] [--tolerance-compare X] [--reference-topic T] [--per-cycle]\n"
    "              [--contacts-topic T] [--compliance-topic T] [--forces-topic T] [--stats-topic T]\n"
    "              [--no-inputs] [--no-progress] [--quiet]\n"
    "\n"
    "Solves every ContactArray/Compliance pair of a recorded bag (no roscore needed) the way\n"
    "contact_solver_node does, in the same order with the same warm start, and compares the\n"
    "forces with the ones recorded in the bag (a change detector) or with a reference from\n"
    "outside recorded beside them (--reference-topic: MuJoCo's forces, a correctness check).\n"
    "With the bag's parameter file, each recorded answer is also checked on its own problem\n"
    "(residual recomputed from the recorded forces and W, states, signs, friction cone).\n"
    "\n"
    "  --out OUT.bag          write the forces and stats (the node's topic names and stamps), and\n"
    "                         the input and reference topics unless --no-inputs; OUT.params.yaml\n"
    "                         beside it\n"
    "  --csv STATS.csv        per-cycle stats: stamp,contacts,rows,iterations,residual,converged,\n"
    "                         status,solve_time\n"
    "  --params FILE.yaml     node parameters (as config/default.yaml); default: the file beside\n"
    "                         the bag (IN.params.yaml) if there is one, else the node's defaults\n"
    "  name=value             override one parameter: initial_guess or any of the service's\n"
    "                         param_overrides (tolerance, maxIt, mu, solver, ...)\n"
    "  --tolerance-compare X  exit 1 when the forces differ from the compared ones by more than\n"
    "                         X relative (max |dlambda| / max |lambda| per cycle), or cannot be\n"
    "                         compared, or a recorded answer fails its check; with\n"
    "                         --reference-topic the reference is compared, else the recording\n"
    "  --reference-topic T    ConstraintForces from outside to compare with, one per cycle in\n"
    "                         the node's layout (the MuJoCo bridge's /mujoco_bridge/reference_forces)\n"
    "  --per-cycle            print the reference comparison of every cycle\n"
    "  --contacts-topic T, --compliance-topic T, --forces-topic T, --stats-topic T\n"
    "                         topics in the bag (default contacts, compliance, constraint_forces,\n"
    "                         contact_solver/stats; else the only topic of the type)\n"
    "  --no-progress          no progress bar (shown only on a terminal anyway)\n"
    "  --quiet                print only the verdict and errors\n"
    "exit: 0 done, 1 comparison beyond --tolerance-compare, 2 usage or input error\n";

// What the command line asks for besides ReplayOptions.
struct ReplayCommandLine {
  ReplayOptions options;
  std::string params_file;
  bool no_params_file = false, quiet = false, progress = true, have_tolerance = false, help = false;
  bool per_cycle = false;
  double tolerance = 0.0;
  std::vector<std::string> overrides;
};

// Parses `args` into *cli; empty string, or the usage error. The first positional argument
// is the bag, later ones are name=value overrides.
std::string parseCommandLine(const std::vector<std::string>& args, ReplayCommandLine* cli) {
  CLI::App app("replay");
  app.set_help_flag();  // --help prints kUsage, not CLI11's text
  app.allow_extras();   // reported below as "unknown option"
  app.option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  ReplayOptions& o = cli->options;
  std::string tolerance_text;
  std::vector<std::string> positionals;
  app.add_flag("-h,--help", cli->help);
  app.add_option("-o,--out", o.out_bag);
  app.add_option("--csv", o.csv);
  app.add_option("--params", cli->params_file);
  app.add_flag("--no-params-file", cli->no_params_file);
  app.add_option("--contacts-topic", o.contacts_topic);
  app.add_option("--compliance-topic", o.compliance_topic);
  app.add_option("--forces-topic", o.forces_topic);
  app.add_option("--stats-topic", o.stats_topic);
  app.add_option("--reference-topic", o.reference_topic);
  app.add_flag("--per-cycle", cli->per_cycle);
  CLI::Option* tolerance = app.add_option("--tolerance-compare", tolerance_text);
  bool no_inputs = false, no_progress = false;
  app.add_flag("--no-inputs", no_inputs);
  app.add_flag("--no-progress", no_progress);
  app.add_flag("-q,--quiet", cli->quiet);
  app.add_option("args", positionals);
  try {
    app.parse(std::vector<std::string>(args.rbegin(), args.rend()));  // CLI11 takes them reversed
  } catch (const CLI::ArgumentMismatch& e) {  // CLI11 says "--name: 1 required TEXT missing"
    const std::string what = e.what(), name = what.substr(0, what.find(':'));
    const bool topic = name.size() > 6 && name.compare(name.size() - 6, 6, "-topic") == 0;
    return name + " needs " +
           (name == "--tolerance-compare" ? "a number"
            : topic                       ? "a topic"
                                          : "a file name");
  } catch (const CLI::ParseError& e) {
    return e.what();
  }
  if (cli->help) return "";
  for (const std::string& extra : app.remaining())
    return "unknown option " + extra.substr(0, extra.find('='));
  o.copy_inputs = !no_inputs;
  cli->progress = !no_progress;
  if (tolerance->count() > 0) {
    char* end = nullptr;
    cli->tolerance = std::strtod(tolerance_text.c_str(), &end);
    if (tolerance_text.empty() || *end != '\0' || !std::isfinite(cli->tolerance) || cli->tolerance < 0.0)
      return "--tolerance-compare '" + tolerance_text + "' must be a finite number >= 0";
    cli->have_tolerance = true;
  }
  for (const std::string& arg : positionals) {
    if (o.bag.empty())
      o.bag = arg;
    else if (arg.find('=') != std::string::npos)
      cli->overrides.push_back(arg);
    else
      return "unexpected argument '" + arg + "' (one bag; parameter overrides are name=value)";
  }
  if (o.bag.empty()) return "no input bag given";
  if (!cli->params_file.empty() && cli->no_params_file)
    return "--params and --no-params-file exclude each other";
  return "";
}

// The node's defaults, then the parameter file (--params, or the one beside the bag), then
// the overrides. False after writing the error.
bool assembleParams(ReplayCommandLine* cli, lcs::core::SolverParams* params, std::string* source,
                    std::ostream& err) {
  *params = defaultSolverParams();
  *source = "the node's defaults";
  const std::string beside = paramsFileBeside(cli->options.bag);
  if (cli->params_file.empty() && !cli->no_params_file && std::filesystem::exists(beside))
    cli->params_file = beside;
  if (!cli->params_file.empty()) {
    if (const std::string error = loadParamsFile(cli->params_file, params); !error.empty()) {
      err << "replay: " << error << "\n";
      return false;
    }
    *source = cli->params_file;
    cli->options.recorded_params = *params;  // the recording's own: its answers are judged by them
  }
  for (const std::string& assignment : cli->overrides) {
    if (const std::string error = applyReplayOverride(assignment, params); !error.empty()) {
      err << "replay: " << error << "\n";
      return false;
    }
    *source += " + " + assignment;
  }
  if (const std::string error = lcs::core::validateParams(*params); !error.empty()) {
    err << "replay: invalid parameters: " << error << "\n";
    return false;
  }
  return true;
}

void printReport(const ReplayOptions& options, const ReplayResult& result, std::ostream& out) {
  for (const std::string& note : result.notes) out << "note: " << note << "\n";
  out << formatSummary(result);
  if (!options.out_bag.empty())
    out << "wrote " << options.out_bag << " (" << result.out_forces_topic << ", " << result.out_stats_topic
        << (options.copy_inputs ? ", inputs" : "") << ") and " << paramsFileBeside(options.out_bag) << "\n";
  if (!options.csv.empty()) out << "wrote " << options.csv << "\n";
}

// The verdict on one comparison: true when within `tolerance`.
bool judge(double tolerance, const Comparison& c, const std::string& what, std::ostream& out) {
  if (!c.hasReference()) {
    out << "FAIL: no " << (what == "recording" ? "recorded forces" : what + " forces")
        << " to compare with (--tolerance-compare " << shortNumber(tolerance) << ")\n";
    return false;
  }
  if (c.exceeds(tolerance)) {
    out << "FAIL: forces differ from the " << what << ": max relative " << shortNumber(c.max_relative)
        << (c.max_relative > tolerance ? " > " : " <= ") << shortNumber(tolerance);
    if (c.mismatched + c.missing_reference + c.missing_replay > 0)
      out << "; " << (c.mismatched + c.missing_reference + c.missing_replay) << " cycles not comparable ("
          << c.first_mismatch << ")";
    out << "\n";
    return false;
  }
  out << "OK: forces match the " << what << " within " << shortNumber(tolerance) << " relative (max "
      << shortNumber(c.max_relative) << " over " << c.compared << " cycles)\n";
  return true;
}

// --tolerance-compare: 0 when the forces match (the reference when there is one, else the
// recording) and every recorded answer checked passed, 1 otherwise.
int verdict(double tolerance, const ReplayResult& result, std::ostream& out) {
  bool ok = result.reference_topic.empty()
                ? judge(tolerance, result.comparison, "recording", out)
                : judge(tolerance, result.reference, "reference " + result.reference_topic, out);
  const AnswerChecks& a = result.answers;
  if (a.checked > 0 && !a.passed()) {
    out << "FAIL: " << a.failed << " of " << a.checked << " recorded answers fail their check ("
        << a.first_failure << ")\n";
    ok = false;
  }
  return ok ? 0 : 1;
}

}  // namespace

int runReplayCommand(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  ReplayCommandLine cli;
  if (const std::string error = parseCommandLine(args, &cli); !error.empty()) {
    err << "replay: " << error << " (replay --help for usage)\n";
    return 2;
  }
  if (cli.help) {
    out << kUsage;
    return 0;
  }
  ReplayOptions& options = cli.options;
  lcs::core::SolverParams params;
  std::string params_source;
  if (!assembleParams(&cli, &params, &params_source, err)) return 2;

  std::unique_ptr<ProgressBar> bar;  // drawn once the replay knows how many arrays the bag holds
  if (cli.progress && !cli.quiet && isTerminal(stderr))
    options.progress = [&bar](std::size_t done, std::size_t total) {
      if (!bar) bar = std::make_unique<ProgressBar>(stderr, total, true);
      bar->update(done);
    };
  if (!cli.quiet) {
    out << "replay " << options.bag << "\n"
        << "parameters: " << params_source << " (solver " << lcs::core::solverName(params.solver)
        << ", tolerance " << shortNumber(params.tolerance) << ", maxIt " << params.maxIt << ", mu "
        << shortNumber(params.mu) << ", initial_guess " << (params.initial_guess ? "true" : "false") << ")\n";
    out.flush();
  }
  const ReplayResult result = replayBag(options, params);
  if (bar) bar->finish();
  if (!result.error.empty()) {
    err << "replay: " << options.bag << ": " << result.error << "\n";
    return 2;
  }
  if (!options.out_bag.empty()) {
    if (const std::string error = writeParamsFile(paramsFileBeside(options.out_bag), params);
        !error.empty()) {
      err << "replay: " << error << "\n";
      return 2;
    }
  }
  if (!cli.quiet) {
    printReport(options, result, out);
    if (cli.per_cycle) out << formatReferenceCycles(result);
  }
  return cli.have_tolerance ? verdict(cli.tolerance, result, out) : 0;
}

}  // namespace lcp_contact_solver_ros
