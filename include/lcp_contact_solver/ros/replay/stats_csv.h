// The replay's per-cycle stats as CSV (replay --csv).
#pragma once

#include <lcp_contact_solver/SolverStats.h>

#include <fstream>
#include <string>

namespace lcp_contact_solver_ros {

// Per-cycle stats as CSV: stamp,contacts,rows,iterations,residual,converged,status,solve_time
class StatsCsvWriter {
 public:
  // Empty string, or why the file cannot be written.
  std::string open(const std::string& path);
  void write(const lcp_contact_solver::SolverStats& stats);
  bool good() const { return out_.good(); }
  static const char* header();
  static std::string row(const lcp_contact_solver::SolverStats& stats);

 private:
  std::ofstream out_;
};

}  // namespace lcp_contact_solver_ros
