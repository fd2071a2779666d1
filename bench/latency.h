// What the parts of the latency benchmark (bench/latency.cpp) share: the options, a problem
// with its two messages, the figures measured in-process, and the report helpers.
#pragma once

#include "timing_util.h"

#include "lcp_contact_solver/core/problem.h"
#include "lcp_contact_solver/core/solve_result.h"
#include "lcp_contact_solver/ros/node/solver_params_ros.h"

#include <lcp_contact_solver/Compliance.h>
#include <lcp_contact_solver/ContactArray.h>

#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

namespace lcs_bench::latency {

namespace lros = ::lcp_contact_solver_ros;

struct Options {
  std::vector<int> bases = {5, 16};
  std::vector<int> balls;
  int steps = 3;
  int count = 200, warmup = 20;
  double rate_seconds = 10.0;
  double latency_seconds = 30.0;
  std::vector<int> inflight = {1, 4};
  std::vector<int> paces;  // Hz: phases publishing on a fixed clock (paced_<Hz>)
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

struct Case {
  std::string name;
  lcs::core::Problem problem;
  lcs::ContactArray contacts;
  lcs::Compliance compliance;
};

// The messages of one cycle: serialize + deserialize time both ways, bytes, markers.
struct MessageCosts {
  double t_ser_in = 0.0, t_ser_out = 0.0;  // s, serialize + deserialize
  // The node's own share: deserializing what comes in, serializing what goes out (s).
  double t_deser_in = 0.0, t_ser_out_only = 0.0;
  std::uint32_t bytes_in = 0, bytes_out = 0;
  double t_markers = 0.0;  // s
  std::uint32_t marker_bytes = 0;
};

// The in-process references of a case, next to the live figures.
struct InProcess {
  double t_solve = 0.0;  // s, ContactSolver::solve
  lcs::core::SolveResult last;
  double t_cycle = 0.0;  // s, CycleSolver::solve
  MessageCosts costs;
};

// ---- in-process (latency_in_process.cpp) ----
// false (after a message on stderr) when the cycle rejects the case.
bool measureInProcess(const lros::NodeSettings& settings, Case& p, InProcess* refs);
// --reference-only: the node's cycle in-process, part by part, on every case.
int runReference(const Options& o, const lros::NodeSettings& settings, std::vector<Case>& problems);

// ---- report (latency_report.cpp) ----
double percentile(std::vector<double> v, double p);
double mean(const std::vector<double>& v);
// Opened for appending; the header is written when the file is new or empty.
std::ofstream openAppending(const std::string& path, const char* header);
void printCaseSummary(const Case& p, const InProcess& refs);

}  // namespace lcs_bench::latency
