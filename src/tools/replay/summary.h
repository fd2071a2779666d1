// What the `replay` command prints: the end-of-run report and the progress bar.
#pragma once

#include "lcp_contact_solver/ros/replay/bag_replay.h"

#include <cstddef>
#include <cstdio>
#include <string>

namespace lcp_contact_solver_ros {

// The end-of-run report: counts, residual summary, comparison with the recorded forces.
std::string formatSummary(const ReplayResult& result);
// One line per cycle of the reference comparison (--per-cycle).
std::string formatReferenceCycles(const ReplayResult& result);

// A one-line progress bar on a terminal; does nothing when disabled (not a terminal).
class ProgressBar {
 public:
  ProgressBar(std::FILE* stream, std::size_t total, bool enabled);
  void update(std::size_t done);
  void finish();

 private:
  std::FILE* stream_;
  std::size_t total_;
  bool enabled_;
  int last_permille_ = -1;
};

// True when the file descriptor of `stream` is a terminal.
bool isTerminal(std::FILE* stream);

}  // namespace lcp_contact_solver_ros
