#include "replay/summary.h"

#include "lcp_contact_solver/ros/replay/text.h"

#include <unistd.h>

#include <algorithm>
#include <ostream>
#include <sstream>
#include <string>

namespace lcp_contact_solver_ros {
namespace {

// What a comparison's lines say: recorded forces (a change detector) or a reference.
struct ComparisonWords {
  std::string title;
  std::string not_comparable;
  std::string missing_reference;
  std::string missing_replay;
};

void writeComparison(std::ostream& out, const Comparison& c, const ComparisonWords& words) {
  out << words.title << ": " << c.compared << " cycles compared";
  if (c.compared > 0) {
    out << "; max |dlambda| " << shortNumber(c.max_abs) << " N, RMS " << shortNumber(c.rms())
        << " N, max relative " << shortNumber(c.max_relative) << " (worst cycle #" << c.worst_cycle
        << ", stamp " << stampDigits(c.worst_stamp) << ")";
  }
  out << "\n";
  if (c.mismatched + c.missing_reference + c.missing_replay > 0) {
    out << words.not_comparable << ": " << c.mismatched << " cycles with other contacts, "
        << c.missing_reference << " " << words.missing_reference << ", " << c.missing_replay << " "
        << words.missing_replay << "; first: " << c.first_mismatch << "\n";
  }
}

}  // namespace

std::string formatSummary(const ReplayResult& r) {
  std::ostringstream out;
  out << "cycles: " << r.cycles << " from " << r.contacts_topic << " (" << r.contact_messages << ") + "
      << r.compliance_topic << " (" << r.compliance_messages << "): " << r.solved << " solved, " << r.rejected
      << " rejected, " << r.unpaired << " contact arrays without compliance";
  if (r.unused_compliance > 0) out << ", " << r.unused_compliance << " compliances without contacts";
  if (r.duplicates > 0) out << ", " << r.duplicates << " duplicate stamps (the later message kept)";
  out << "\n";
  if (r.solved > 0) {
    out << "solves: " << r.converged << "/" << r.solved << " converged, " << r.with_forces
        << " with forces; iterations " << r.total_iterations << " in all, max " << r.max_iterations
        << "; residual max " << shortNumber(r.max_residual) << " (stamp "
        << stampDigits(r.worst_residual_stamp) << "), mean " << shortNumber(r.meanResidual())
        << "; solve time " << shortNumber(r.total_solve_time) << " s\n";
  }
  if (r.forces_topic.empty()) {
    if (r.reference_topic.empty()) out << "forces: no recorded forces in the bag, nothing compared\n";
  } else {
    writeComparison(out, r.comparison,
                    {"forces vs recorded " + r.forces_topic, "forces not comparable",
                     "replayed without a recorded counterpart", "recorded without a replayed counterpart"});
  }
  if (!r.reference_topic.empty()) {
    writeComparison(out, r.reference,
                    {"forces vs reference " + r.reference_topic, "reference not comparable",
                     "replayed without a reference", "references without a replayed cycle"});
  }
  const AnswerChecks& a = r.answers;
  if (a.checked > 0) {
    out << "recorded answers checked on their own problem: " << a.checked << "; recomputed residual max "
        << shortNumber(a.max_residual) << ", differs from the recorded stats by at most "
        << shortNumber(a.max_residual_difference) << "; " << a.residual_differs << " residuals differ, "
        << a.above_tolerance << " converged above the tolerance, " << a.invariant_failures
        << " with wrong states, negative normal forces or friction outside the cone, " << a.unfit
        << " that do not fit";
    if (a.without_stats > 0) out << ", " << a.without_stats << " without recorded stats";
    if (!a.first_failure.empty()) out << "; first: " << a.first_failure;
    out << "\n";
  }
  if (!r.stats_topic.empty()) {
    const Comparison& c = r.comparison;
    out << "stats vs recorded " << r.stats_topic << ": " << c.stats_compared
        << " cycles; iterations differ in " << c.iteration_differences;
    if (c.iteration_differences > 0)
      out << " (first at stamp " << stampDigits(c.first_iteration_difference) << ")";
    out << ", status differs in " << c.status_differences << "; max relative residual difference "
        << shortNumber(c.max_residual_relative) << "\n";
  }
  return out.str();
}

std::string formatReferenceCycles(const ReplayResult& r) {
  std::ostringstream out;
  if (r.reference_topic.empty()) return "";
  out << "cycle stamp contacts max_abs_dlambda_N max_relative (vs " << r.reference_topic << ")\n";
  for (const CycleDifference& c : r.reference_cycles) {
    out << c.cycle << " " << stampDigits(c.stamp) << " " << c.contacts << " ";
    if (c.mismatch.empty())
      out << shortNumber(c.max_abs) << " " << shortNumber(c.relative) << "\n";
    else
      out << "- - " << c.mismatch << "\n";
  }
  return out.str();
}

bool isTerminal(std::FILE* stream) { return stream != nullptr && ::isatty(::fileno(stream)) == 1; }

ProgressBar::ProgressBar(std::FILE* stream, std::size_t total, bool enabled)
    : stream_(stream), total_(total), enabled_(enabled && stream != nullptr && total > 0) {}

void ProgressBar::update(std::size_t done) {
  if (!enabled_) return;
  const int permille = static_cast<int>(std::min<std::size_t>(1000, done * 1000 / total_));
  if (permille / 10 == last_permille_ / 10 && done != total_) return;  // redraw each percent
  last_permille_ = permille;
  constexpr int kWidth = 40;
  const int filled = permille * kWidth / 1000;
  std::fprintf(stream_, "\rreplay [%.*s%*s] %3d%%  %zu/%zu", filled,
               "########################################", kWidth - filled, "", permille / 10, done, total_);
  std::fflush(stream_);
}

void ProgressBar::finish() {
  if (!enabled_ || last_permille_ < 0) return;
  std::fprintf(stream_, "\n");
  std::fflush(stream_);
  enabled_ = false;
}

}  // namespace lcp_contact_solver_ros
