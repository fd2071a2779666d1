// The report of the effects-cost benchmark: the CSV (one row per measurement) and the
// printed markdown tables.
#include "effects_cost.h"

#include <cmath>
#include <cstdio>
#include <ostream>
#include <string>
#include <vector>

namespace lcs_bench::effects_cost {

namespace {

const char* const kVariantNames[] = {"mu0.5",      "mu0_3row",  "frictionless", "mixed_1row",
                                     "mixed_3row", "torsional", "rolling"};

// A table cell: ✗ for a figure not reached; a ratio: – where either side is missing.
std::string cell(double v, const char* fmt = "%.3g") {
  return std::isfinite(v) ? num(v, fmt) : std::string("✗");
}
std::string ratio(double a, double b) {
  return std::isfinite(a) && std::isfinite(b) && b > 0 ? num(a / b, "%.2f") : std::string("–");
}

}  // namespace

std::string num(double v, const char* fmt) {
  if (!std::isfinite(v)) return "";
  char b[64];
  std::snprintf(b, sizeof(b), fmt, v);
  return b;
}

void csvHeader(std::ostream& csv) {
  csv << "section,problem,variant,contacts,rows,frictionless_contacts,solver,ran,mode,tolerance,iterations,"
         "seconds,"
         "us_per_sweep,us_marginal_sweep,residual,status,broadphase_pairs,skipped_disabled,narrowphase_tests,"
         "load1\n";
}

void csvWrite(std::ostream& csv, const CsvRow& r) {
  csv << r.section << ',' << r.problem << ',' << r.variant << ',' << r.contacts << ',' << r.rows << ','
      << r.frictionless << ',' << r.solver << ',' << r.ran << ',' << r.mode << ',' << num(r.tolerance) << ','
      << r.iterations << ',' << num(r.seconds) << ',' << num(r.us_per_sweep) << ',' << num(r.us_marginal)
      << ',' << num(r.residual) << ',' << r.status << ','
      << (r.broadphase >= 0 ? std::to_string(r.broadphase) : "") << ','
      << (r.skipped >= 0 ? std::to_string(r.skipped) : "") << ','
      << (r.narrowphase >= 0 ? std::to_string(r.narrowphase) : "") << ','
      << num(lcs_bench::loadAverage1(), "%.2f") << '\n';
  csv.flush();
}

void printSolveTables(const std::vector<std::string>& names, const SolveTables& tables) {
  std::printf(
      "\n(a)(b)(c) per sweep, µs (fixed sweeps, cold; auto runs what it picks: pgs without friction)\n");
  std::printf(
      "| problem | contacts | variant | rows | nlgs µs/sweep | ÷ mu0.5 | auto (ran) µs/sweep | ÷ mu0.5 |\n");
  std::printf("|---|---:|---|---:|---:|---:|---:|---:|\n");
  for (const std::string& n : names) {
    const auto& t = tables.values.at(n);
    for (const char* vn : kVariantNames) {
      const auto& m = t.at(vn);
      const auto& ref = t.at("mu0.5");
      std::printf("| %s | %.0f | %s | %.0f | %s | %s | %s (%s) | %s |\n", n.c_str(), m.at("contacts"), vn,
                  m.at("rows"), cell(m.at("sweep_nlgs")).c_str(),
                  ratio(m.at("sweep_nlgs"), ref.at("sweep_nlgs")).c_str(), cell(m.at("sweep_auto")).c_str(),
                  tables.ran.at(n).at(vn).at("sweep_auto").c_str(),
                  ratio(m.at("sweep_auto"), ref.at("sweep_auto")).c_str());
    }
  }
  std::printf(
      "\nto a tolerance, ms, fastest of the repeats (✗ = not reached within the budget), sweeps/iterations "
      "in brackets\n");
  std::printf(
      "| problem | variant | nlgs 1e-4 | auto 1e-4 (ran) | auto 1e-6 (ran) |\n|---|---|---:|---:|---:|\n");
  for (const std::string& n : names)
    for (const char* vn : kVariantNames) {
      const auto& m = tables.values.at(n).at(vn);
      const auto& ran = tables.ran.at(n).at(vn);
      std::printf("| %s | %s | %s (%.0f) | %s (%.0f, %s) | %s (%.0f, %s) |\n", n.c_str(), vn,
                  cell(m.at("t_nlgs@1e-04")).c_str(), m.at("it_nlgs@1e-04"),
                  cell(m.at("t_auto@1e-04")).c_str(), m.at("it_auto@1e-04"), ran.at("t_auto@1e-04").c_str(),
                  cell(m.at("t_auto@1e-06")).c_str(), m.at("it_auto@1e-06"), ran.at("t_auto@1e-06").c_str());
    }
}

void printGenerationHeader() {
  std::printf("\n(d) contact generation at the same poses (fastest call of the repeats)\n");
  std::printf(
      "| pile | variant | broadphase pairs | skipped (disabled) | narrowphase tests | contacts | rows | "
      "generate() µs | buildStep() µs | step() ms (status) "
      "|\n|---|---|---:|---:|---:|---:|---:|---:|---:|---:|\n");
}

void reportGeneration(std::ostream& csv, int n, int reps, const std::vector<GenRow>& rows) {
  for (const GenRow& g : rows) {
    const std::string pname = "pile_" + std::to_string(n);
    CsvRow r{"generation", pname, g.variant, g.t.contacts, g.t.rows, g.t.frictionless, "", "", "generate"};
    r.iterations = reps;
    r.seconds = g.t.generate;
    r.broadphase = g.t.stats.broadphase_pairs;
    r.skipped = g.t.stats.skipped_disabled;
    r.narrowphase = g.t.stats.narrowphase_tests;
    csvWrite(csv, r);
    r.mode = "buildStep";
    r.seconds = g.t.build;
    csvWrite(csv, r);
    r.mode = "step";
    r.seconds = g.t.step;
    r.status = g.t.step_status;
    csvWrite(csv, r);
    r.mode = "step_solve_wall";
    r.seconds = g.t.step_solve;
    csvWrite(csv, r);
    std::printf("| %s | %s | %d | %d | %d | %d | %d | %.0f | %.0f | %.2f (%s) |\n", pname.c_str(),
                g.variant.c_str(), g.t.stats.broadphase_pairs, g.t.stats.skipped_disabled,
                g.t.stats.narrowphase_tests, g.t.contacts, g.t.rows, 1e6 * g.t.generate, 1e6 * g.t.build,
                1e3 * g.t.step, g.t.step_status.c_str());
  }
  std::printf("| %s | disabled ÷ all | | | %s | | | %s | %s | %s |\n", ("pile_" + std::to_string(n)).c_str(),
              ratio(rows[1].t.stats.narrowphase_tests, rows[0].t.stats.narrowphase_tests).c_str(),
              ratio(rows[1].t.generate, rows[0].t.generate).c_str(),
              ratio(rows[1].t.build, rows[0].t.build).c_str(), ratio(rows[1].t.step, rows[0].t.step).c_str());
  std::printf("| %s | mixed ÷ all | | | | | | %s | %s | %s |\n", ("pile_" + std::to_string(n)).c_str(),
              ratio(rows[2].t.generate, rows[0].t.generate).c_str(),
              ratio(rows[2].t.build, rows[0].t.build).c_str(), ratio(rows[2].t.step, rows[0].t.step).c_str());
  std::fflush(stdout);
}

}  // namespace lcs_bench::effects_cost
