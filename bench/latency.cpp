// End-to-end latency and sustained rate of the live solver (issue #8; docs/BENCHMARKS.md
// "Latency and rate"; run by bench/latency.sh). A benchmark, never a test.
//
//   latency_bench [--bases 5,16] [--balls N,...] [--steps 3] [--count 200] [--warmup 20]
//           [--rate-seconds 10] [--latency-seconds 30] [--inflight 1,4] [--label NAME] [--solver-pid PID]
//           [--in-process-nodelet] [--markers 0|1] [--out FILE.csv]
//   latency_bench --sink TOPIC [--duration S]      (a marker subscriber that only counts)
//   latency_bench --reference-only [--bases ...] [--out FILE.csv]   (the node's cycle in-process, by part)
//
// Problems: bench/scene_problems.h (brick pyramids with box_stack's bodies: base 5 ≈ 100
// contacts, base 16 ≈ 1000), each turned into a ContactArray (ids, μ, types, rows, d_free,
// gap, erp, softness of the problem; body names from the ids; every contact at the origin
// with normal +z and explicit tangents: the solve uses only W and d_free, the geometry only
// feeds the force vectors and the markers) and a Compliance (msg_conversion's
// toComplianceMsg, block-sparse).
//
// Against a running contact_solver (node, nodelet in a manager, or with --in-process-nodelet
// the nodelet loaded here by nodelet::Loader so that messages pass as shared pointers):
//   latency  one pair in flight: stamp, publish Compliance then ContactArray, wait for the
//            ConstraintForces of that stamp; `count` round trips after `warmup` (at most
//            --latency-seconds once 10 are done). Also the
//            node's SolverStats (solve_time, iterations) of each stamp.
//   rate_N   N pairs in flight for --rate-seconds: a new pair is published whenever forces
//            come back; forces per second.
// In-process references on the same problem with the node's own parameters (read from
// /contact_solver on the parameter server): ContactSolver::solve, CycleSolver::solve (the
// node's whole cycle from messages to the ConstraintForces message), the serialization of
// the messages both ways, and buildMarkers. Node CPU from /proc/<solver-pid>/stat per phase.
// Appends CSV rows (header when the file is new).
//
// The parts: latency_solver_link.cpp (the solver process: pairing its answers, publishing,
// the nodelet, its CPU time, the sink), latency_phases.cpp (the measurement loop),
// latency_in_process.cpp (the in-process references, --reference-only), latency_report.cpp
// (CSV and table).
#include "cli_options.h"
#include "latency_live.h"
#include "scene_problems.h"

#include "lcp_contact_solver/ros/msg_conversion/msg_conversion.h"

#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

namespace lcs_bench::latency {
namespace {

// Fills o from the command line (CLI11); -1 to go on, else the exit code (0 after --help).
int parseOptions(int argc, char** argv, Options* options) {
  Options& o = *options;
  CLI::App app{
      "latency_bench: end-to-end latency and sustained rate of the live solver (CSV)\n"
      "  latency_bench --sink TOPIC [--duration S]: a marker subscriber that only counts\n"
      "  latency_bench --reference-only [--bases ...] [--out FILE.csv]: the node's cycle in-process"};
  app.option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  lcs_bench::addIntListOption(app, "--bases", &o.bases, "brick pyramids: bricks at the base, comma list",
                              "5,16");
  lcs_bench::addIntListOption(app, "--balls", &o.balls, "sphere piles: balls, comma list", "");
  app.add_option("--steps", o.steps, "in-process steps before a problem is taken")->capture_default_str();
  app.add_option("--count", o.count, "latency round trips measured")->capture_default_str();
  app.add_option("--warmup", o.warmup, "round trips before the measured ones")->capture_default_str();
  app.add_option("--rate-seconds", o.rate_seconds, "duration of each rate_N phase (s)")
      ->capture_default_str();
  app.add_option("--latency-seconds", o.latency_seconds,
                 "latency phase at most this long once 10 are done (s)")
      ->capture_default_str();
  lcs_bench::addIntListOption(app, "--inflight", &o.inflight,
                              "pairs in flight of the rate_N phases, comma list", "1,4");
  lcs_bench::addIntListOption(app, "--pace", &o.paces, "Hz of the paced phases (a fixed clock), comma list",
                              "");
  app.add_option("--pace-seconds", o.pace_seconds, "duration of each paced phase (s)")->capture_default_str();
  app.add_option("--label", o.label, "the CSV's label of the solver process")->capture_default_str();
  app.add_option("--solver-pid", o.solver_pid, "the solver process, for its CPU time from /proc")
      ->capture_default_str();
  app.add_flag("--in-process-nodelet", o.in_process_nodelet, "load the nodelet here (nodelet::Loader)");
  app.add_option("--markers", o.markers, "0|1: the node publishes markers")->capture_default_str();
  app.add_option("--out", o.out, "the CSV to append to")->capture_default_str();
  app.add_option("--sink", o.sink, "only count the messages on this topic (a marker subscriber)");
  app.add_option("--duration", o.duration, "--sink: for this long (s; default: no limit)");
  app.add_flag("--reference-only", o.reference_only, "only the in-process references of the node's cycle");
  return lcs_bench::parseArguments(app, argc, argv);
}

// Every contact at the origin with normal +z and that normal's rule tangents, given
// explicitly (a default ContactFrame): the geometry does not enter the solve.
lcs::ContactArray toArrayMsg(const lcs::core::Problem& p) {
  std_msgs::Header header;
  header.frame_id = "world";
  std::vector<lros::ContactBodies> bodies(p.contacts.size());
  for (std::size_t i = 0; i < p.contacts.size(); ++i)
    bodies[i] = {"body_" + std::to_string(p.contacts[i].id >> 40),
                 "body_" + std::to_string((p.contacts[i].id >> 16) & 0xFFFFFF)};
  return lros::toContactArrayMsg(p, std::vector<lros::ContactFrame>(p.contacts.size()), bodies, header);
}

// The scene problems as messages.
std::vector<Case> makeCases(const Options& o) {
  std::vector<Case> problems;
  for (const auto& sp : lcs_bench::makeSceneProblems(LCS_SCENES_DIR, o.bases, o.balls, o.steps)) {
    if (sp.problem.contacts.empty()) continue;
    Case p{sp.name, sp.problem, toArrayMsg(sp.problem), lros::toComplianceMsg(sp.problem)};
    problems.push_back(std::move(p));
  }
  return problems;
}

// The in-process references of one case, then its phases against the live solver.
bool runCase(const Options& o, const lros::NodeSettings& settings, Tracker& tracker, Sender& sender, Case& p,
             std::ostream& csv) {
  InProcess refs;
  if (!measureInProcess(settings, p, &refs)) return false;
  const PhaseContext ctx{o, settings.solver.initial_guess, tracker, sender, p, refs, csv};
  runPhase(ctx, "warmup", 1, o.warmup, 0.0);
  runPhase(ctx, "latency", 1, o.count, 0.0);
  for (int n : o.inflight) runPhase(ctx, "rate_" + std::to_string(n), n, 0, o.rate_seconds);
  for (int hz : o.paces) runPhase(ctx, "paced_" + std::to_string(hz), 1000, 0, o.pace_seconds, hz);
  printCaseSummary(p, refs);
  return true;
}

// Against the running solver (or the nodelet loaded here): every case, every phase.
int runLive(const Options& o, const lros::NodeSettings& settings, std::vector<Case>& problems) {
  std::unique_ptr<nodelet::Loader> loader;
  if (o.in_process_nodelet && !(loader = loadNodelet())) return 1;
  ros::NodeHandle nh;
  Tracker tracker;
  const ros::TransportHints no_delay = ros::TransportHints().tcpNoDelay();
  ros::Subscriber forces_sub = nh.subscribe<lcs::ConstraintForces>(
      "constraint_forces", 1000, [&](const lcs::ConstraintForces::ConstPtr& f) { tracker.onForces(f); },
      ros::VoidConstPtr(), no_delay);
  ros::Subscriber stats_sub = nh.subscribe<lcs::SolverStats>(
      "contact_solver/stats", 1000, [&](const lcs::SolverStats::ConstPtr& s) { tracker.onStats(s); },
      ros::VoidConstPtr(), no_delay);
  Sender sender(nh, tracker, o.in_process_nodelet);
  ros::AsyncSpinner spinner(1);
  spinner.start();
  if (!waitForSolver(sender, forces_sub, stats_sub)) return 1;

  std::ofstream csv = openLiveCsv(o.out);
  printLiveHeader(o, settings.solver, settings.solver.initial_guess);
  for (Case& p : problems)
    if (!runCase(o, settings, tracker, sender, p, csv)) return 1;
  spinner.stop();
  loader.reset();
  std::printf("latency: load %s at the end\n", lcs_bench::loadAverageText().c_str());
  return 0;
}

}  // namespace
}  // namespace lcs_bench::latency

int main(int argc, char** argv) {
  namespace lat = lcs_bench::latency;
  ros::init(argc, argv, "latency", ros::init_options::AnonymousName);
  lat::Options o;
  if (const int code = lat::parseOptions(argc, argv, &o); code >= 0) return code;
  if (!o.sink.empty()) return lat::runSink(o);
  if (o.in_process_nodelet) o.solver_pid = getpid();

  // The node's parameters, as the node reads them.
  lat::lros::NodeSettings settings;
  if (const std::string err = lat::lros::loadSettings(ros::NodeHandle("/contact_solver"), &settings);
      !err.empty()) {
    std::fprintf(stderr, "latency: /contact_solver parameters: %s\n", err.c_str());
    return 1;
  }

  std::vector<lat::Case> problems = lat::makeCases(o);
  if (o.reference_only) return lat::runReference(o, settings, problems);
  return lat::runLive(o, settings, problems);
}
