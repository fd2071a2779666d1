#include "lcp_contact_solver/ros/replay/stats_csv.h"

#include "lcp_contact_solver/ros/replay/text.h"

#include <cerrno>
#include <cstring>

namespace lcp_contact_solver_ros {

using lcp_contact_solver::SolverStats;

const char* StatsCsvWriter::header() {
  return "stamp,contacts,rows,iterations,residual,converged,status,solve_time";
}

std::string StatsCsvWriter::row(const SolverStats& s) {
  return stampDigits(s.header.stamp) + "," + std::to_string(s.num_contacts) + "," +
         std::to_string(s.num_rows) + "," + std::to_string(s.iterations) + "," + exactNumber(s.residual) +
         "," + (s.converged ? "true" : "false") + "," + s.status + "," + exactNumber(s.solve_time);
}

std::string StatsCsvWriter::open(const std::string& path) {
  out_.open(path);
  if (!out_) return path + ": cannot write (" + std::strerror(errno) + ")";
  out_ << header() << "\n";
  return "";
}

void StatsCsvWriter::write(const SolverStats& stats) { out_ << row(stats) << "\n"; }

}  // namespace lcp_contact_solver_ros
