#include "problem_report.h"

#include "lcp_contact_solver/core/solver_params.h"

#include <cmath>
#include <cstdio>
#include <vector>

namespace lcp_contact_solver {
namespace {

// ---- formatting ---------------------------------------------------------------------------

std::string formatNumber(const char* format, double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, format, value);
  return buffer;
}

// Full precision for JSON; never NaN/Inf, which JSON cannot hold.
std::string jsonNumber(double value) { return std::isfinite(value) ? formatNumber("%.17g", value) : "null"; }

std::string jsonString(const std::string& text) {
  std::string quoted = "\"";
  for (unsigned char ch : text) {
    switch (ch) {
      case '"': quoted += "\\\""; break;
      case '\\': quoted += "\\\\"; break;
      case '\n': quoted += "\\n"; break;
      case '\r': quoted += "\\r"; break;
      case '\t': quoted += "\\t"; break;
      default:
        if (ch < 0x20) {
          char escaped[8];
          std::snprintf(escaped, sizeof escaped, "\\u%04x", ch);
          quoted += escaped;
        } else {
          quoted += static_cast<char>(ch);
        }
    }
  }
  return quoted + "\"";
}

std::string jsonArray(const Eigen::VectorXd& values) {
  std::string array = "[";
  for (Eigen::Index i = 0; i < values.size(); ++i) {
    if (i > 0) array += ",";
    array += jsonNumber(values[i]);
  }
  return array + "]";
}

std::string jsonStates(const std::vector<core::ContactState>& states) {
  std::string array = "[";
  for (std::size_t i = 0; i < states.size(); ++i) {
    if (i > 0) array += ",";
    array += jsonString(core::stateName(states[i]));
  }
  return array + "]";
}

std::string padRight(const std::string& text, int width) {
  return text.size() >= static_cast<std::size_t>(width) ? text : text + std::string(width - text.size(), ' ');
}

std::string padLeft(const std::string& text, int width) {
  return text.size() >= static_cast<std::size_t>(width) ? text : std::string(width - text.size(), ' ') + text;
}

// Column widths of the table (name width varies with the files).
constexpr int kNumberWidth = 9;
constexpr int kSolverWidth = 7;
constexpr int kResidualWidth = 11;
constexpr int kConvergedWidth = 9;
constexpr int kStatusWidth = 16;
constexpr int kTimeWidth = 11;

std::string tableLine(int name_width, const std::vector<std::string>& cells) {
  std::string line = padRight(cells[0], name_width);
  line += " " + padLeft(cells[1], kNumberWidth);
  line += " " + padLeft(cells[2], kNumberWidth);
  line += "  " + padRight(cells[3], kSolverWidth);
  line += " " + padLeft(cells[4], kNumberWidth);
  line += " " + padLeft(cells[5], kResidualWidth);
  line += "  " + padRight(cells[6], kConvergedWidth);
  line += " " + padRight(cells[7], kStatusWidth);
  line += " " + padLeft(cells[8], kTimeWidth);
  return line;
}

}  // namespace

std::string formatTableHeader(int name_width) {
  return tableLine(name_width, {"problem", "contacts", "rows", "solver", "iters", "residual", "converged",
                                "status", "time_s"});
}

std::string formatTableRow(const core::Problem& problem, const core::SolveResult& result, int name_width) {
  return tableLine(name_width,
                   {problem.name, std::to_string(problem.contacts.size()), std::to_string(problem.rowCount()),
                    result.solver, std::to_string(result.iterations), formatNumber("%.3e", result.residual),
                    result.converged ? "yes" : "no", core::statusName(result.status),
                    formatNumber("%.6f", result.solve_time)});
}

std::string formatJsonLine(const core::Problem& problem, const core::SolveResult& result) {
  std::string json = "{";
  json += "\"name\":" + jsonString(problem.name);
  json += ",\"contacts\":" + std::to_string(problem.contacts.size());
  json += ",\"rows\":" + std::to_string(problem.rowCount());
  json += ",\"solver\":" + jsonString(result.solver);
  json += ",\"iterations\":" + std::to_string(result.iterations);
  json += ",\"residual\":" + jsonNumber(result.residual);
  json += std::string(",\"converged\":") + (result.converged ? "true" : "false");
  json += ",\"status\":" + jsonString(core::statusName(result.status));
  json += ",\"friction_model\":" + jsonString(core::frictionModelName(result.friction_model));
  json += ",\"solver_error\":" + jsonNumber(result.solver_error);
  json += ",\"solve_time\":" + jsonNumber(result.solve_time);
  json += ",\"message\":" + jsonString(result.message);
  json += ",\"forces\":" + jsonArray(result.forces);
  json += ",\"d\":" + jsonArray(result.d);
  json += ",\"states\":" + jsonStates(result.states);
  return json + "}";
}

std::string formatResidualHistory(const core::Problem& problem, const core::SolveResult& result) {
  std::string text = problem.name + ": residual history (" + std::to_string(result.residual_history.size()) +
                     " entries, solver " + result.solver + ")\n";
  for (std::size_t k = 0; k < result.residual_history.size(); ++k)
    text += "  " + padLeft(std::to_string(k + 1), 6) + " " +
            formatNumber("%.6e", result.residual_history[k]) + "\n";
  return text;
}

}  // namespace lcp_contact_solver
