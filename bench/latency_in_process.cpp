// The in-process references of the latency benchmark: the node's cycle on the same messages
// without a solver process (conversion, core solve, forces message, the whole
// CycleSolver::solve, serialization both ways, markers), median wall times of repeats.
#include "latency.h"

#include "lcp_contact_solver/core/contact_solver.h"
#include "lcp_contact_solver/core/residual.h"
#include "lcp_contact_solver/ros/msg_conversion/msg_conversion.h"
#include "lcp_contact_solver/ros/node/cycle_solver.h"
#include "lcp_contact_solver/ros/node/markers.h"

#include <lcp_contact_solver/ConstraintForces.h>
#include <ros/serialization.h>
#include <visualization_msgs/MarkerArray.h>

#include <cstdio>
#include <fstream>
#include <ostream>
#include <string>
#include <vector>

namespace lcs_bench::latency {

namespace {

template <class M>
std::uint32_t wireBytes(const M& m) {
  return ros::serialization::serializationLength(m);
}

// Serialize and deserialize, seconds per round: medians of each part and of both.
struct SerializationTimes {
  double both = 0.0, serialize = 0.0, deserialize = 0.0;
};

template <class M>
SerializationTimes serializationTimes(const M& m) {
  namespace ser = ros::serialization;
  std::vector<double> both, out, in;
  double total = 0.0;
  while (both.size() < 5 || total < 0.05) {
    const auto t0 = Clock::now();
    const std::uint32_t n = ser::serializationLength(m);
    std::vector<std::uint8_t> buf(n);
    ser::OStream os(buf.data(), n);
    ser::serialize(os, m);
    const double t_out = secondsSince(t0);
    const auto t1 = Clock::now();
    M back;
    ser::IStream is(buf.data(), n);
    ser::deserialize(is, back);
    const double t_in = secondsSince(t1);
    out.push_back(t_out);
    in.push_back(t_in);
    both.push_back(t_out + t_in);
    total += t_out + t_in;
  }
  return {percentile(both, 0.5), percentile(out, 0.5), percentile(in, 0.5)};
}

template <class F>
double medianTime(F&& f, double min_total = 0.1, int min_runs = 5) {
  std::vector<double> t;
  double total = 0.0;
  while (static_cast<int>(t.size()) < min_runs || total < min_total) {
    const auto t0 = Clock::now();
    f();
    const double s = secondsSince(t0);
    t.push_back(s);
    total += s;
    if (t.size() >= 5000) break;
  }
  return percentile(t, 0.5);
}

// CycleSolver::solve (warmed when the node warm-starts); its last output in *out.
double cycleTime(const lcs::core::SolverParams& params, Case& p, lros::CycleOutput* out) {
  lros::CycleSolver cycle(params);
  if (params.initial_guess) cycle.solve(p.contacts, p.compliance, true);
  return medianTime([&] { *out = cycle.solve(p.contacts, p.compliance, true); });
}

MessageCosts messageCosts(const lros::NodeSettings& settings, const Case& p, const lros::CycleOutput& out) {
  const lcs::core::SolverParams& params = settings.solver;
  MessageCosts k;
  const SerializationTimes contacts = serializationTimes(p.contacts);
  const SerializationTimes compliance = serializationTimes(p.compliance);
  const SerializationTimes forces = serializationTimes(out.forces);
  const SerializationTimes stats = serializationTimes(out.stats);
  k.t_ser_in = contacts.both + compliance.both;
  k.t_ser_out = forces.both + stats.both;
  k.t_deser_in = contacts.deserialize + compliance.deserialize;
  k.t_ser_out_only = forces.serialize + stats.serialize;
  k.bytes_in = wireBytes(p.contacts) + wireBytes(p.compliance);
  k.bytes_out = wireBytes(out.forces) + wireBytes(out.stats);
  const std::vector<double> mu = lcs::core::effectiveMu(out.problem, params.mu);
  visualization_msgs::MarkerArray markers;
  k.t_markers = medianTime([&] {
    markers =
        lros::buildMarkers(p.contacts.header, out.frames, out.problem, out.result, mu, settings.display);
  });
  k.marker_bytes = wireBytes(markers);
  return k;
}

}  // namespace

bool measureInProcess(const lros::NodeSettings& settings, Case& p, InProcess* refs) {
  const lcs::core::SolverParams& params = settings.solver;
  lcs::core::ContactSolver solver(params);
  if (params.initial_guess) solver.solve(p.problem);  // the node has seen this problem before
  refs->t_solve = medianTime([&] { refs->last = solver.solve(p.problem); });
  lros::CycleOutput out;
  refs->t_cycle = cycleTime(params, p, &out);
  if (out.rejected()) {
    std::fprintf(stderr, "latency: %s rejected in-process: %s\n", p.name.c_str(), out.error.c_str());
    return false;
  }
  refs->costs = messageCosts(settings, p, out);
  return true;
}

namespace {

// One case of --reference-only: a CSV row and a table row.
void referenceCase(const lros::NodeSettings& settings, Case& p, std::ostream& csv) {
  const lcs::core::SolverParams& params = settings.solver;
  lcs::core::Problem converted;
  std::vector<lros::ContactFrame> frames;
  const double t_convert = medianTime([&] {
    converted = lcs::core::Problem();
    frames.clear();
    lros::toProblem(p.contacts, p.compliance, 0, &converted, &frames);
  });
  lcs::core::ContactSolver solver(params);
  if (params.initial_guess) solver.solve(converted);
  lcs::core::SolveResult result;
  const double t_solve = medianTime([&] { result = solver.solve(converted); });
  lcs::ConstraintForces forces;
  const double t_forces =
      medianTime([&] { forces = lros::toConstraintForcesMsg(p.contacts, frames, converted, result); });
  lros::CycleOutput out;
  const double t_cycle = cycleTime(params, p, &out);
  const MessageCosts k = messageCosts(settings, p, out);
  csv << p.name << ',' << p.problem.contacts.size() << ',' << p.problem.rowCount() << ','
      << (params.initial_guess ? 1 : 0) << ',' << 1e3 * t_convert << ',' << 1e3 * t_solve << ','
      << result.iterations << ',' << 1e3 * t_forces << ',' << 1e3 * t_cycle << ',' << 1e3 * k.t_ser_in << ','
      << 1e3 * k.t_ser_out << ',' << k.bytes_in << ',' << k.bytes_out << ',' << 1e3 * k.t_markers << ','
      << k.marker_bytes << ',' << lcs_bench::loadAverage1() << '\n';
  std::printf("| %s | %zu | %s | %.3f | %.3f (%d it) | %.3f | %.3f | %.3f / %.3f | %u / %u | %.3f, %u |\n",
              p.name.c_str(), p.problem.contacts.size(), params.initial_guess ? "on" : "off", 1e3 * t_convert,
              1e3 * t_solve, result.iterations, 1e3 * t_forces, 1e3 * t_cycle, 1e3 * k.t_ser_in,
              1e3 * k.t_ser_out, k.bytes_in, k.bytes_out, 1e3 * k.t_markers, k.marker_bytes);
  std::fflush(stdout);
}

}  // namespace

// The node's cycle in-process, part by part, on the same messages (no solver process):
// conversion (toProblem), the core solve, the forces message (toConstraintForcesMsg), the
// whole CycleSolver::solve, serialization both ways, markers. Median wall times of repeats.
int runReference(const Options& o, const lros::NodeSettings& settings, std::vector<Case>& problems) {
  std::ofstream csv = openAppending(
      o.out,
      "problem,contacts,rows,warm_start,to_problem_ms,solve_ms,solve_iterations,forces_msg_ms,cycle_ms,"
      "serialize_in_ms,serialize_out_ms,msg_in_bytes,msg_out_bytes,markers_build_ms,marker_bytes,load1\n");
  std::printf(
      "| problem | contacts | warm start | toProblem (ms) | solve (ms) | toConstraintForcesMsg (ms) | whole "
      "cycle "
      "(ms) | serialize + deserialize in / out (ms) | bytes in / out | markers build (ms, bytes) |\n"
      "|---|---:|---|---:|---:|---:|---:|---|---|---|\n");
  for (auto& p : problems) referenceCase(settings, p, csv);
  return 0;
}

}  // namespace lcs_bench::latency
