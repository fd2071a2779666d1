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
#include "timing_util.h"
#include "scene_problems.h"

#include "lcp_contact_solver/core/contact_solver.h"
#include "lcp_contact_solver/core/residual.h"
#include "lcp_contact_solver/ros/node/cycle_solver.h"
#include "lcp_contact_solver/ros/node/markers.h"
#include "lcp_contact_solver/ros/msg_conversion/msg_conversion.h"
#include "lcp_contact_solver/ros/node/solver_params_ros.h"

#include <lcp_contact_solver/Compliance.h>
#include <lcp_contact_solver/ConstraintForces.h>
#include <lcp_contact_solver/ContactArray.h>
#include <lcp_contact_solver/SolverStats.h>
#include <nodelet/loader.h>
#include <ros/ros.h>
#include <visualization_msgs/MarkerArray.h>

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace lcs = lcp_contact_solver;
namespace lros = lcp_contact_solver_ros;
using lcs_bench::Clock;
using lcs_bench::secondsSince;

namespace {

struct Options {
  std::vector<int> bases = {5, 16};
  std::vector<int> balls;
  int steps = 3;
  int count = 200, warmup = 20;
  double rate_seconds = 10.0;
  double latency_seconds = 30.0;
  std::vector<int> inflight = {1, 4};
  std::vector<int> paces;        // Hz: phases publishing on a fixed clock (paced_<Hz>)
  double pace_seconds = 10.0;
  std::string label = "node";
  int solver_pid = 0;
  bool in_process_nodelet = false;
  bool reference_only = false;
  int markers = 0;
  std::string out = "bench/results/latency.csv";
  std::string sink;
  double duration = 1e9;
};

int usage(int code) {
  std::fprintf(code ? stderr : stdout,
               "usage: latency_bench [--bases 5,16] [--balls N,...] [--steps N] [--count N] [--warmup N] [--rate-seconds S]\n"
               "               [--latency-seconds S]\n"
               "               [--inflight 1,4] [--pace HZ,...] [--pace-seconds S]\n"
               "               [--label NAME] [--solver-pid PID] [--in-process-nodelet]\n"
               "               [--markers 0|1] [--out FILE.csv]\n"
               "       latency_bench --sink TOPIC [--duration S]\n"
               "       latency_bench --reference-only [--bases 5,16] [--out FILE.csv]\n");
  return code;
}

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

// CPU seconds (user + system) of a process.
double cpuSeconds(int pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string line;
  std::getline(in, line);
  const std::size_t close = line.rfind(')');
  if (close == std::string::npos) return std::nan("");
  std::istringstream rest(line.substr(close + 2));
  std::string field;
  double utime = 0, stime = 0;
  for (int k = 3; rest >> field; ++k) {
    if (k == 14) utime = std::stod(field);
    if (k == 15) {
      stime = std::stod(field);
      break;
    }
  }
  return (utime + stime) / sysconf(_SC_CLK_TCK);
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

template <class M>
std::uint32_t wireBytes(const M& m) {
  return ros::serialization::serializationLength(m);
}

// Serialize + deserialize, seconds per round (median of enough rounds).
template <class M>
double serializationTime(const M& m) {
  namespace ser = ros::serialization;
  std::vector<double> t;
  double total = 0.0;
  while (t.size() < 5 || total < 0.05) {
    const auto t0 = Clock::now();
    const std::uint32_t n = ser::serializationLength(m);
    std::vector<std::uint8_t> buf(n);
    ser::OStream os(buf.data(), n);
    ser::serialize(os, m);
    M back;
    ser::IStream is(buf.data(), n);
    ser::deserialize(is, back);
    const double s = secondsSince(t0);
    t.push_back(s);
    total += s;
  }
  return percentile(t, 0.5);
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

struct Pending {
  Clock::time_point sent;
  bool forces = false, stats = false;
  double lat_forces = std::nan("");  // s
};

// Shared between the publishing loop and the subscriber callbacks.
struct Tracker {
  std::mutex m;
  std::condition_variable cv;
  std::map<std::uint64_t, Pending> pending;  // by stamp (ns)
  int in_flight = 0;
  long completed = 0, failed = 0;
  std::vector<double> lat_forces, lat_stats, solve_time, iterations;
  std::vector<double> overhead;  // forces latency - the node's solve_time, same stamp
  // Inside the solver: SolverStats.latency (pair complete, i.e. both messages received and
  // deserialized, to forces published) minus its solve_time.
  std::vector<double> node_overhead;
  std::map<std::string, long> statuses;

  void reset() {
    std::lock_guard<std::mutex> lock(m);
    pending.clear();
    in_flight = 0;
    completed = failed = 0;
    lat_forces.clear();
    lat_stats.clear();
    solve_time.clear();
    iterations.clear();
    overhead.clear();
    node_overhead.clear();
    statuses.clear();
  }
  void onForces(const lcs::ConstraintForces::ConstPtr& f) {
    const auto now = Clock::now();
    std::lock_guard<std::mutex> lock(m);
    auto it = pending.find(f->header.stamp.toNSec());
    if (it == pending.end() || it->second.forces) return;
    it->second.forces = true;
    it->second.lat_forces = std::chrono::duration<double>(now - it->second.sent).count();
    lat_forces.push_back(it->second.lat_forces);
    --in_flight;
    ++completed;
    if (it->second.stats) pending.erase(it);
    cv.notify_all();
  }
  void onStats(const lcs::SolverStats::ConstPtr& s) {
    const auto now = Clock::now();
    std::lock_guard<std::mutex> lock(m);
    auto it = pending.find(s->header.stamp.toNSec());
    if (it == pending.end() || it->second.stats) return;
    it->second.stats = true;
    lat_stats.push_back(std::chrono::duration<double>(now - it->second.sent).count());
    if (s->success) {  // a dropped or unpaired array has no solve (solve_time 0)
      solve_time.push_back(s->solve_time);
      iterations.push_back(s->iterations);
    }
    ++statuses[s->status];
    if (std::isfinite(it->second.lat_forces)) overhead.push_back(it->second.lat_forces - s->solve_time);
    if (s->success) node_overhead.push_back(s->latency - s->solve_time);
    if (!s->success && !it->second.forces) {  // no forces will come
      it->second.forces = true;
      --in_flight;
      ++failed;
    }
    if (it->second.forces) pending.erase(it);
    cv.notify_all();
  }
  // Requests older than `timeout` are given up (lost in a queue).
  long expire(double timeout) {
    const auto now = Clock::now();
    long lost = 0;
    for (auto it = pending.begin(); it != pending.end();) {
      if (std::chrono::duration<double>(now - it->second.sent).count() > timeout) {
        if (!it->second.forces) {
          --in_flight;
          ++lost;
        }
        it = pending.erase(it);
      } else {
        ++it;
      }
    }
    return lost;
  }
};

struct Case {
  std::string name;
  lcs::core::Problem problem;
  lcs::ContactArray contacts;
  lcs::Compliance compliance;
};

class Sender {
 public:
  Sender(ros::NodeHandle& nh, Tracker& tracker, bool shared_ptrs) : tracker_(tracker), shared_(shared_ptrs) {
    contacts_pub_ = nh.advertise<lcs::ContactArray>("contacts", 100);
    compliance_pub_ = nh.advertise<lcs::Compliance>("compliance", 100);
  }
  bool connected() const { return contacts_pub_.getNumSubscribers() > 0 && compliance_pub_.getNumSubscribers() > 0; }

  // Publishes one pair with a fresh stamp; the caller holds no lock.
  void send(Case& p) {
    ros::WallTime now = ros::WallTime::now();
    ros::Time stamp(now.sec, now.nsec);
    if (stamp <= last_) stamp = last_ + ros::Duration(0, 1);
    last_ = stamp;
    p.contacts.header.stamp = p.compliance.header.stamp = stamp;
    boost::shared_ptr<lcs::Compliance> w;
    boost::shared_ptr<lcs::ContactArray> c;
    if (shared_) {  // fresh messages: a published shared pointer must not change afterwards
      w = boost::make_shared<lcs::Compliance>(p.compliance);
      c = boost::make_shared<lcs::ContactArray>(p.contacts);
    }
    {
      std::lock_guard<std::mutex> lock(tracker_.m);
      tracker_.pending[stamp.toNSec()] = Pending{Clock::now()};
      ++tracker_.in_flight;
    }
    if (shared_) {
      compliance_pub_.publish(w);
      contacts_pub_.publish(c);
    } else {
      compliance_pub_.publish(p.compliance);
      contacts_pub_.publish(p.contacts);
    }
  }

 private:
  Tracker& tracker_;
  bool shared_;
  ros::Publisher contacts_pub_, compliance_pub_;
  ros::Time last_;
};

// The node's cycle in-process, part by part, on the same messages (no solver process):
// conversion (toProblem), the core solve, the forces message (toConstraintForcesMsg), the
// whole CycleSolver::solve, serialization both ways, markers. Median wall times of repeats.
template <class Cases>
int runReference(const Options& o, const lros::NodeSettings& settings, Cases& problems) {
  const lcs::core::SolverParams& params = settings.solver;
  std::ifstream probe(o.out);
  const bool fresh = !probe.good() || probe.peek() == std::ifstream::traits_type::eof();
  probe.close();
  std::ofstream csv(o.out, std::ios::app);
  if (fresh)
    csv << "problem,contacts,rows,warm_start,to_problem_ms,solve_ms,solve_iterations,forces_msg_ms,cycle_ms,"
         "serialize_in_ms,serialize_out_ms,msg_in_bytes,msg_out_bytes,markers_build_ms,marker_bytes,load1\n";
  std::printf("| problem | contacts | warm start | toProblem (ms) | solve (ms) | toConstraintForcesMsg (ms) | whole cycle "
              "(ms) | serialize + deserialize in / out (ms) | bytes in / out | markers build (ms, bytes) |\n"
              "|---|---:|---|---:|---:|---:|---:|---|---|---|\n");
  for (auto& p : problems) {
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
    const double t_forces = medianTime([&] { forces = lros::toConstraintForcesMsg(p.contacts, frames, converted, result); });
    lros::CycleSolver cycle(params);
    if (params.initial_guess) cycle.solve(p.contacts, p.compliance, true);
    lros::CycleOutput out;
    const double t_cycle = medianTime([&] { out = cycle.solve(p.contacts, p.compliance, true); });
    const double t_ser_in = serializationTime(p.contacts) + serializationTime(p.compliance);
    const double t_ser_out = serializationTime(out.forces) + serializationTime(out.stats);
    const std::uint32_t bytes_in = wireBytes(p.contacts) + wireBytes(p.compliance);
    const std::uint32_t bytes_out = wireBytes(out.forces) + wireBytes(out.stats);
    const std::vector<double> mu = lcs::core::effectiveMu(out.problem, params.mu);
    visualization_msgs::MarkerArray markers;
    const double t_markers = medianTime(
        [&] { markers = lros::buildMarkers(p.contacts.header, out.frames, out.problem, out.result, mu, settings.display); });
    const std::uint32_t marker_bytes = wireBytes(markers);
    csv << p.name << ',' << p.problem.contacts.size() << ',' << p.problem.rowCount() << ','
        << (params.initial_guess ? 1 : 0) << ',' << 1e3 * t_convert << ',' << 1e3 * t_solve << ','
        << result.iterations << ',' << 1e3 * t_forces << ',' << 1e3 * t_cycle << ',' << 1e3 * t_ser_in << ','
        << 1e3 * t_ser_out << ',' << bytes_in << ',' << bytes_out << ',' << 1e3 * t_markers << ',' << marker_bytes
        << ',' << lcs_bench::loadAverage1() << '\n';
    std::printf("| %s | %zu | %s | %.3f | %.3f (%d it) | %.3f | %.3f | %.3f / %.3f | %u / %u | %.3f, %u |\n",
                p.name.c_str(), p.problem.contacts.size(), params.initial_guess ? "on" : "off", 1e3 * t_convert,
                1e3 * t_solve, result.iterations, 1e3 * t_forces, 1e3 * t_cycle, 1e3 * t_ser_in, 1e3 * t_ser_out,
                bytes_in, bytes_out, 1e3 * t_markers, marker_bytes);
    std::fflush(stdout);
  }
  return 0;
}

int runSink(const Options& o) {
  ros::NodeHandle nh;
  std::atomic<long> count{0};
  std::atomic<long> bytes{0};
  ros::Subscriber sub = nh.subscribe<visualization_msgs::MarkerArray>(
      o.sink, 10,
      [&](const visualization_msgs::MarkerArray::ConstPtr& m) {
        ++count;
        bytes += ros::serialization::serializationLength(*m);
      },
      ros::VoidConstPtr(), ros::TransportHints().tcpNoDelay());
  const ros::WallTime start = ros::WallTime::now();
  ros::WallTime last = start;
  long last_count = 0;
  while (ros::ok() && (ros::WallTime::now() - start).toSec() < o.duration) {
    ros::spinOnce();
    ros::WallDuration(0.001).sleep();
    if ((ros::WallTime::now() - last).toSec() >= 10.0) {
      std::printf("sink %s: %ld messages (%.1f/s), %.1f MB\n", o.sink.c_str(), count.load(),
                  (count - last_count) / (ros::WallTime::now() - last).toSec(), bytes.load() / 1e6);
      std::fflush(stdout);
      last = ros::WallTime::now();
      last_count = count;
    }
  }
  std::printf("sink %s: %ld messages in total, %.1f MB\n", o.sink.c_str(), count.load(), bytes.load() / 1e6);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "latency", ros::init_options::AnonymousName);
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h") return usage(0);
    if (a == "--in-process-nodelet") {
      o.in_process_nodelet = true;
      continue;
    }
    if (a == "--reference-only") {
      o.reference_only = true;
      continue;
    }
    if (i + 1 >= argc) return usage(2);
    const std::string v = argv[++i];
    if (a == "--bases") o.bases = lcs_bench::parseIntList(v);
    else if (a == "--balls") o.balls = lcs_bench::parseIntList(v);
    else if (a == "--steps") o.steps = std::stoi(v);
    else if (a == "--count") o.count = std::stoi(v);
    else if (a == "--warmup") o.warmup = std::stoi(v);
    else if (a == "--rate-seconds") o.rate_seconds = std::stod(v);
    else if (a == "--latency-seconds") o.latency_seconds = std::stod(v);
    else if (a == "--inflight") o.inflight = lcs_bench::parseIntList(v);
    else if (a == "--pace") o.paces = lcs_bench::parseIntList(v);
    else if (a == "--pace-seconds") o.pace_seconds = std::stod(v);
    else if (a == "--label") o.label = v;
    else if (a == "--solver-pid") o.solver_pid = std::stoi(v);
    else if (a == "--markers") o.markers = std::stoi(v);
    else if (a == "--out") o.out = v;
    else if (a == "--sink") o.sink = v;
    else if (a == "--duration") o.duration = std::stod(v);
    else return usage(2);
  }
  if (!o.sink.empty()) return runSink(o);
  if (o.in_process_nodelet) o.solver_pid = getpid();

  // The node's parameters, as the node reads them.
  lros::NodeSettings settings;
  if (const std::string err = lros::loadSettings(ros::NodeHandle("/contact_solver"), &settings); !err.empty()) {
    std::fprintf(stderr, "latency: /contact_solver parameters: %s\n", err.c_str());
    return 1;
  }
  const lcs::core::SolverParams& params = settings.solver;
  const bool warm = params.initial_guess;

  std::vector<Case> problems;
  for (const auto& sp : lcs_bench::makeSceneProblems(LCS_SCENES_DIR, o.bases, o.balls, o.steps)) {
    if (sp.problem.contacts.empty()) continue;
    Case p{sp.name, sp.problem, toArrayMsg(sp.problem), lros::toComplianceMsg(sp.problem)};
    problems.push_back(std::move(p));
  }

  if (o.reference_only) return runReference(o, settings, problems);

  std::unique_ptr<nodelet::Loader> loader;
  if (o.in_process_nodelet) {
    loader = std::make_unique<nodelet::Loader>(false);
    if (!loader->load("/contact_solver", "lcp_contact_solver/ContactSolverNodelet", {}, {})) {
      std::fprintf(stderr, "latency: could not load lcp_contact_solver/ContactSolverNodelet\n");
      return 1;
    }
  }
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
  const ros::WallTime give_up = ros::WallTime::now() + ros::WallDuration(30.0);
  while (ros::ok() && (!sender.connected() || forces_sub.getNumPublishers() == 0 || stats_sub.getNumPublishers() == 0)) {
    if (ros::WallTime::now() > give_up) {
      std::fprintf(stderr, "latency: no contact solver connected within 30 s\n");
      return 1;
    }
    ros::WallDuration(0.05).sleep();
  }
  ros::WallDuration(0.5).sleep();

  std::ifstream probe(o.out);
  const bool fresh = !probe.good() || probe.peek() == std::ifstream::traits_type::eof();
  probe.close();
  std::ofstream csv(o.out, std::ios::app);
  if (fresh)
    csv << "label,markers,warm_start,problem,contacts,rows,phase,inflight,received,failed,lost,seconds,rate_hz,"
           "lat_median_ms,lat_p90_ms,lat_p99_ms,lat_mean_ms,stats_lat_median_ms,node_solve_median_ms,overhead_median_ms,"
           "overhead_p90_ms,"
           "node_iterations_median,inproc_solve_ms,inproc_iterations,inproc_cycle_ms,msg_in_bytes,msg_out_bytes,"
           "serialize_in_ms,serialize_out_ms,markers_build_ms,marker_bytes,node_cpu_percent,load1,"
           "node_internal_overhead_median_ms,node_internal_overhead_p90_ms,sent,skipped,node_cpu_ms_per_answer\n";

  std::printf("latency: %s, markers subscriber %d, warm start %s; solver %s, tolerance %g, maxIt %d; load %s\n",
              o.label.c_str(), o.markers, warm ? "on" : "off", lcs::core::solverName(params.solver), params.tolerance,
              params.maxIt, lcs_bench::loadAverageText().c_str());
  std::printf("| problem | contacts | phase | received | rate (Hz) | latency median / p90 / p99 (ms) | node solve_time "
              "(ms) | latency − solve_time (ms) | in the node: latency − solve_time (ms) | in-process solve / cycle (ms) | "
              "node CPU | node CPU per answer (ms) |\n"
              "|---|---:|---|---:|---:|---|---:|---:|---:|---|---:|---:|\n");
  std::fflush(stdout);

  for (Case& p : problems) {
    // ---- in-process references ----
    lcs::core::ContactSolver solver(params);
    if (warm) solver.solve(p.problem);  // the node has seen this problem before
    lcs::core::SolveResult last;
    const double t_solve = medianTime([&] { last = solver.solve(p.problem); });
    lros::CycleSolver cycle(params);
    if (warm) cycle.solve(p.contacts, p.compliance, true);
    lros::CycleOutput out;
    const double t_cycle = medianTime([&] { out = cycle.solve(p.contacts, p.compliance, true); });
    if (out.rejected()) {
      std::fprintf(stderr, "latency: %s rejected in-process: %s\n", p.name.c_str(), out.error.c_str());
      return 1;
    }
    const double t_ser_in = serializationTime(p.contacts) + serializationTime(p.compliance);
    const double t_ser_out = serializationTime(out.forces) + serializationTime(out.stats);
    const std::uint32_t bytes_in = wireBytes(p.contacts) + wireBytes(p.compliance);
    const std::uint32_t bytes_out = wireBytes(out.forces) + wireBytes(out.stats);
    const std::vector<double> mu = lcs::core::effectiveMu(out.problem, params.mu);
    visualization_msgs::MarkerArray markers;
    const double t_markers = medianTime(
        [&] { markers = lros::buildMarkers(p.contacts.header, out.frames, out.problem, out.result, mu, settings.display); });
    const std::uint32_t marker_bytes = wireBytes(markers);

    // pace_hz > 0: a pair every 1/pace_hz s on a fixed clock whatever is in flight (a
    // simulator stepping at that rate); `inflight` only bounds the backlog (then the phase
    // is behind: the pair is not sent and counted as skipped).
    auto phase = [&](const std::string& name, int inflight, int count, double seconds, double pace_hz = 0.0) {
      tracker.reset();
      const double cpu0 = o.solver_pid > 0 ? cpuSeconds(o.solver_pid) : std::nan("");
      const auto t0 = Clock::now();
      long sent = 0, lost = 0, skipped = 0, ticks = 0;
      std::unique_lock<std::mutex> lock(tracker.m);
      for (;;) {
        const double elapsed = secondsSince(t0);
        if (count > 0 ? (sent >= count || (elapsed >= o.latency_seconds && sent >= 10)) : elapsed >= seconds) break;
        if (!ros::ok()) break;
        if (pace_hz > 0.0) {
          const auto next = t0 + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(ticks / pace_hz));
          if (Clock::now() < next) {
            lock.unlock();
            std::this_thread::sleep_until(next);
            lock.lock();
            continue;
          }
          ++ticks;
          lost += tracker.expire(5.0);
          if (tracker.in_flight >= inflight) {
            ++skipped;
            continue;
          }
        } else if (tracker.in_flight >= inflight) {
          tracker.cv.wait_for(lock, std::chrono::milliseconds(50));
          lost += tracker.expire(5.0);
          continue;
        }
        lock.unlock();
        sender.send(p);
        ++sent;
        lock.lock();
      }
      const double elapsed = secondsSince(t0);
      // Drain: the last answers are on their way.
      const auto drain = Clock::now();
      while (tracker.in_flight > 0 && secondsSince(drain) < 5.0)
        tracker.cv.wait_for(lock, std::chrono::milliseconds(50));
      lost += tracker.expire(0.0);
      const double cpu1 = o.solver_pid > 0 ? cpuSeconds(o.solver_pid) : std::nan("");
      const double wall = secondsSince(t0);
      const double rate = tracker.completed / elapsed;
      const double cpu = 100.0 * (cpu1 - cpu0) / wall;
      const auto& lf = tracker.lat_forces;
      csv << o.label << ',' << o.markers << ',' << (warm ? 1 : 0) << ',' << p.name << ',' << p.problem.contacts.size()
          << ',' << p.problem.rowCount() << ',' << name << ',' << inflight << ',' << tracker.completed << ','
          << tracker.failed << ',' << lost << ',' << elapsed << ',' << rate << ',' << 1e3 * percentile(lf, 0.5) << ','
          << 1e3 * percentile(lf, 0.9) << ',' << 1e3 * percentile(lf, 0.99) << ',' << 1e3 * mean(lf) << ','
          << 1e3 * percentile(tracker.lat_stats, 0.5) << ',' << 1e3 * percentile(tracker.solve_time, 0.5) << ','
          << 1e3 * percentile(tracker.overhead, 0.5) << ',' << 1e3 * percentile(tracker.overhead, 0.9) << ','
          << percentile(tracker.iterations, 0.5) << ',' << 1e3 * t_solve << ',' << last.iterations << ','
          << 1e3 * t_cycle << ',' << bytes_in << ',' << bytes_out << ',' << 1e3 * t_ser_in << ',' << 1e3 * t_ser_out
          << ',' << 1e3 * t_markers << ',' << marker_bytes << ',' << cpu << ',' << lcs_bench::loadAverage1() << ','
          << 1e3 * percentile(tracker.node_overhead, 0.5) << ',' << 1e3 * percentile(tracker.node_overhead, 0.9) << ','
          << sent << ',' << skipped << ',' << 1e3 * (cpu1 - cpu0) / std::max<long>(tracker.completed, 1) << '\n';
      csv.flush();
      std::printf("| %s | %zu | %s | %ld | %.0f | %.3f / %.3f / %.3f | %.3f | %.3f | %.3f | %.3f / %.3f | %.0f %% | %.3f |\n",
                  p.name.c_str(), p.problem.contacts.size(), name.c_str(), tracker.completed, rate,
                  1e3 * percentile(lf, 0.5), 1e3 * percentile(lf, 0.9), 1e3 * percentile(lf, 0.99),
                  1e3 * percentile(tracker.solve_time, 0.5), 1e3 * percentile(tracker.overhead, 0.5),
                  1e3 * percentile(tracker.node_overhead, 0.5), 1e3 * t_solve, 1e3 * t_cycle, cpu,
                  1e3 * (cpu1 - cpu0) / std::max<long>(tracker.completed, 1));
      if (pace_hz > 0.0)
        std::printf("  (%s: %ld sent on a %.0f Hz clock, %ld skipped with %d in flight, %ld answered)\n", name.c_str(), sent,
                    pace_hz, skipped, inflight, tracker.completed);
      if (tracker.failed > 0 || lost > 0) {
        std::printf("  (%ld failed, %ld lost;", tracker.failed, lost);
        for (const auto& [s, n] : tracker.statuses) std::printf(" %s %ld", s.c_str(), n);
        std::printf(")\n");
      }
      std::fflush(stdout);
    };
    phase("warmup", 1, o.warmup, 0.0);
    phase("latency", 1, o.count, 0.0);
    for (int n : o.inflight) phase("rate_" + std::to_string(n), n, 0, o.rate_seconds);
    for (int hz : o.paces) phase("paced_" + std::to_string(hz), 1000, 0, o.pace_seconds, hz);
    std::printf("  %s: in-process solve %.3f ms (%d it, %s), cycle %.3f ms, serialize+deserialize in %.3f ms (%u B) / "
                "out %.3f ms (%u B), markers build %.3f ms (%u B)\n",
                p.name.c_str(), 1e3 * t_solve, last.iterations, last.solver.c_str(), 1e3 * t_cycle, 1e3 * t_ser_in,
                bytes_in, 1e3 * t_ser_out, bytes_out, 1e3 * t_markers, marker_bytes);
    std::fflush(stdout);
  }
  spinner.stop();
  loader.reset();
  std::printf("latency: load %s at the end\n", lcs_bench::loadAverageText().c_str());
  return 0;
}
