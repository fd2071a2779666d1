// The report of the latency benchmark: the statistics, the CSV rows (appended; header when
// the file is new) and the printed markdown table.
#include "latency_live.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

namespace lcs_bench::latency {

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const double pos = p * (v.size() - 1);
  const std::size_t i = static_cast<std::size_t>(pos);
  const double f = pos - i;
  return i + 1 < v.size() ? v[i] * (1 - f) + v[i + 1] * f : v[i];
}

double mean(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x;
  return v.empty() ? std::nan("") : s / v.size();
}

std::ofstream openAppending(const std::string& path, const char* header) {
  std::ifstream probe(path);
  const bool fresh = !probe.good() || probe.peek() == std::ifstream::traits_type::eof();
  probe.close();
  std::ofstream csv(path, std::ios::app);
  if (fresh) csv << header;
  return csv;
}

std::ofstream openLiveCsv(const std::string& path) {
  return openAppending(
      path,
      "label,markers,warm_start,problem,contacts,rows,phase,inflight,received,failed,lost,seconds,rate_hz,"
      "lat_median_ms,lat_p90_ms,lat_p99_ms,lat_mean_ms,stats_lat_median_ms,node_solve_median_ms,overhead_"
      "median_ms,"
      "overhead_p90_ms,"
      "node_iterations_median,inproc_solve_ms,inproc_iterations,inproc_cycle_ms,msg_in_bytes,msg_out_bytes,"
      "serialize_in_ms,serialize_out_ms,markers_build_ms,marker_bytes,node_cpu_percent,load1,"
      "node_internal_overhead_median_ms,node_internal_overhead_p90_ms,sent,skipped,node_cpu_ms_per_answer,"
      "deserialize_in_ms,serialize_out_only_ms\n");
}

void printLiveHeader(const Options& o, const lcs::core::SolverParams& params, bool warm) {
  std::printf(
      "latency: %s, markers subscriber %d, warm start %s; solver %s, tolerance %g, maxIt %d; load %s\n",
      o.label.c_str(), o.markers, warm ? "on" : "off", lcs::core::solverName(params.solver), params.tolerance,
      params.maxIt, lcs_bench::loadAverageText().c_str());
  std::printf(
      "| problem | contacts | phase | received | rate (Hz) | latency median / p90 / p99 (ms) | node "
      "solve_time "
      "(ms) | latency − solve_time (ms) | in the node, message in → forces out: latency − solve_time (ms) | "
      "in-process solve / cycle "
      "(ms) | "
      "node CPU | node CPU per answer (ms) |\n"
      "|---|---:|---|---:|---:|---|---:|---:|---:|---|---:|---:|\n");
  std::fflush(stdout);
}

namespace {

void writePhaseCsv(const PhaseContext& ctx, const std::string& name, int inflight, const PhaseCounts& c) {
  const Options& o = ctx.o;
  const Tracker& tracker = ctx.tracker;
  const Case& p = ctx.p;
  const InProcess& r = ctx.refs;
  const double rate = tracker.completed / c.elapsed;
  const double cpu = 100.0 * (c.cpu1 - c.cpu0) / c.wall;
  const auto& lf = tracker.lat_forces;
  ctx.csv << o.label << ',' << o.markers << ',' << (ctx.warm ? 1 : 0) << ',' << p.name << ','
          << p.problem.contacts.size() << ',' << p.problem.rowCount() << ',' << name << ',' << inflight << ','
          << tracker.completed << ',' << tracker.failed << ',' << c.lost << ',' << c.elapsed << ',' << rate
          << ',' << 1e3 * percentile(lf, 0.5) << ',' << 1e3 * percentile(lf, 0.9) << ','
          << 1e3 * percentile(lf, 0.99) << ',' << 1e3 * mean(lf) << ','
          << 1e3 * percentile(tracker.lat_stats, 0.5) << ',' << 1e3 * percentile(tracker.solve_time, 0.5)
          << ',' << 1e3 * percentile(tracker.overhead, 0.5) << ',' << 1e3 * percentile(tracker.overhead, 0.9)
          << ',' << percentile(tracker.iterations, 0.5) << ',' << 1e3 * r.t_solve << ',' << r.last.iterations
          << ',' << 1e3 * r.t_cycle << ',' << r.costs.bytes_in << ',' << r.costs.bytes_out << ','
          << 1e3 * r.costs.t_ser_in << ',' << 1e3 * r.costs.t_ser_out << ',' << 1e3 * r.costs.t_markers << ','
          << r.costs.marker_bytes << ',' << cpu << ',' << lcs_bench::loadAverage1() << ','
          << 1e3 * percentile(tracker.node_overhead, 0.5) << ','
          << 1e3 * percentile(tracker.node_overhead, 0.9) << ',' << c.sent << ',' << c.skipped << ','
          << 1e3 * (c.cpu1 - c.cpu0) / std::max<long>(tracker.completed, 1) << ',' << 1e3 * r.costs.t_deser_in
          << ',' << 1e3 * r.costs.t_ser_out_only << '\n';
  ctx.csv.flush();
}

void printPhaseRow(const PhaseContext& ctx, const std::string& name, const PhaseCounts& c) {
  const Tracker& tracker = ctx.tracker;
  const Case& p = ctx.p;
  const double rate = tracker.completed / c.elapsed;
  const double cpu = 100.0 * (c.cpu1 - c.cpu0) / c.wall;
  const auto& lf = tracker.lat_forces;
  std::printf(
      "| %s | %zu | %s | %ld | %.0f | %.3f / %.3f / %.3f | %.3f | %.3f | %.3f | %.3f / %.3f | %.0f %% | %.3f "
      "|\n",
      p.name.c_str(), p.problem.contacts.size(), name.c_str(), tracker.completed, rate,
      1e3 * percentile(lf, 0.5), 1e3 * percentile(lf, 0.9), 1e3 * percentile(lf, 0.99),
      1e3 * percentile(tracker.solve_time, 0.5), 1e3 * percentile(tracker.overhead, 0.5),
      1e3 * percentile(tracker.node_overhead, 0.5), 1e3 * ctx.refs.t_solve, 1e3 * ctx.refs.t_cycle, cpu,
      1e3 * (c.cpu1 - c.cpu0) / std::max<long>(tracker.completed, 1));
}

}  // namespace

void reportPhase(const PhaseContext& ctx, const std::string& name, int inflight, double pace_hz,
                 const PhaseCounts& c) {
  const Tracker& tracker = ctx.tracker;
  writePhaseCsv(ctx, name, inflight, c);
  printPhaseRow(ctx, name, c);
  if (pace_hz > 0.0)
    std::printf("  (%s: %ld sent on a %.0f Hz clock, %ld skipped with %d in flight, %ld answered)\n",
                name.c_str(), c.sent, pace_hz, c.skipped, inflight, tracker.completed);
  if (tracker.failed > 0 || c.lost > 0) {
    std::printf("  (%ld failed, %ld lost;", tracker.failed, c.lost);
    for (const auto& [s, n] : tracker.statuses) std::printf(" %s %ld", s.c_str(), n);
    std::printf(")\n");
  }
  std::fflush(stdout);
}

void printCaseSummary(const Case& p, const InProcess& refs) {
  const MessageCosts& k = refs.costs;
  std::printf(
      "  %s: in-process solve %.3f ms (%d it, %s), cycle %.3f ms, serialize+deserialize in %.3f ms (%u B; "
      "deserialize %.3f) / out %.3f ms (%u B; serialize %.3f), markers build %.3f ms (%u B)\n",
      p.name.c_str(), 1e3 * refs.t_solve, refs.last.iterations, refs.last.solver.c_str(), 1e3 * refs.t_cycle,
      1e3 * k.t_ser_in, k.bytes_in, 1e3 * k.t_deser_in, 1e3 * k.t_ser_out, k.bytes_out,
      1e3 * k.t_ser_out_only, 1e3 * k.t_markers, k.marker_bytes);
  std::fflush(stdout);
}

}  // namespace lcs_bench::latency
