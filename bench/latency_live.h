// The live part of the latency benchmark: the link with the running solver (node, nodelet
// in a manager, or the nodelet loaded here) and the phases measured through it.
#pragma once

#include "latency.h"

#include <lcp_contact_solver/ConstraintForces.h>
#include <lcp_contact_solver/SolverStats.h>
#include <nodelet/loader.h>
#include <ros/ros.h>

#include <cmath>
#include <condition_variable>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <ostream>
#include <string>
#include <vector>

namespace lcs_bench::latency {

// ---- the solver process (latency_solver_link.cpp) ----

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

  void reset();
  // The pending request of this stamp, its `answer` now marked as come; end() when unknown
  // or already answered (a late or repeated message). The caller holds m.
  std::map<std::uint64_t, Pending>::iterator claim(std::uint64_t stamp, bool Pending::*answer);
  void onForces(const lcs::ConstraintForces::ConstPtr& f);
  void onStats(const lcs::SolverStats::ConstPtr& s);
  // Requests older than `timeout` are given up (lost in a queue).
  long expire(double timeout);
};

class Sender {
 public:
  Sender(ros::NodeHandle& nh, Tracker& tracker, bool shared_ptrs);
  bool connected() const {
    return contacts_pub_.getNumSubscribers() > 0 && compliance_pub_.getNumSubscribers() > 0;
  }

  // Publishes one pair with a fresh stamp; the caller holds no lock.
  void send(Case& p);

 private:
  Tracker& tracker_;
  bool shared_;
  ros::Publisher contacts_pub_, compliance_pub_;
  ros::Time last_;
};

// CPU seconds (user + system) of a process.
double cpuSeconds(int pid);
// The nodelet loaded in this process as /contact_solver; null (after a message) on failure.
std::unique_ptr<nodelet::Loader> loadNodelet();
// Waits until the solver is on every topic (false after 30 s), then lets it settle.
bool waitForSolver(const Sender& sender, const ros::Subscriber& forces_sub, const ros::Subscriber& stats_sub);
// --sink: a marker subscriber that only counts.
int runSink(const Options& o);

// ---- the phases (latency_phases.cpp) ----

// What a phase of one case runs with and reports to.
struct PhaseContext {
  const Options& o;
  bool warm;
  Tracker& tracker;
  Sender& sender;
  Case& p;
  const InProcess& refs;
  std::ostream& csv;
};

// pace_hz > 0: a pair every 1/pace_hz s on a fixed clock whatever is in flight (a
// simulator stepping at that rate); `inflight` only bounds the backlog (then the phase
// is behind: the pair is not sent and counted as skipped).
void runPhase(const PhaseContext& ctx, const std::string& name, int inflight, int count, double seconds,
              double pace_hz = 0.0);

// ---- report (latency_report.cpp) ----

// What a phase counted besides the tracker's figures.
struct PhaseCounts {
  long sent = 0, lost = 0, skipped = 0;
  double elapsed = 0.0, wall = 0.0;  // s: sending, and sending + draining
  double cpu0 = 0.0, cpu1 = 0.0;     // the solver's CPU seconds before and after
};

// The live CSV (header when new) and the printed table's header.
std::ofstream openLiveCsv(const std::string& path);
void printLiveHeader(const Options& o, const lcs::core::SolverParams& params, bool warm);
// A CSV row and a table row (with notes) for one phase; the caller holds tracker.m.
void reportPhase(const PhaseContext& ctx, const std::string& name, int inflight, double pace_hz,
                 const PhaseCounts& c);

}  // namespace lcs_bench::latency
