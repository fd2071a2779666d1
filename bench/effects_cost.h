// What the parts of the effects-cost benchmark (bench/effects_cost.cpp) share: the scenes
// and variants measured, the measurements, and the CSV row each becomes.
#pragma once

#include "timing_util.h"

#include "lcp_contact_solver/core/problem.h"
#include "lcp_contact_solver/scene/contact_generator.h"
#include "lcp_contact_solver/scene/scene.h"

#include <cmath>
#include <map>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

namespace lcs_bench::effects_cost {

namespace sc = ::lcp_contact_solver::scene;

// ---- the scenes (effects_cost_scenes.cpp) ----

struct Variant {
  std::string name;
  lcs::core::Problem problem;
};

// The variants (a)(b)(c) of a problem of 6-row contacts, in the tables' order.
std::vector<Variant> variantsOf(const lcs::core::Problem& p6, double mu_tor, double mu_roll);
// The URDF of n balls in a square bin of static walls, as a loose lattice.
std::string pileUrdf(int n);
// The settled pile with every ball-ball pair disabled, and with half of the touching
// ball-ball pairs made frictionless (friction_pairs).
sc::Scene withBallPairsDisabled(const sc::Scene& settled);
sc::Scene withHalfTouchingFrictionless(const sc::Scene& settled);
// A temporary copy of the scene YAMLs the generators read, with torsional and rolling set.
std::string rollingScenesDir(double torsional, double rolling);

// ---- the measurements (effects_cost_measure.cpp) ----

// Results kept for the printed table: [problem][variant][key] = value, and what auto ran.
struct SolveTables {
  std::map<std::string, std::map<std::string, std::map<std::string, double>>> values;
  std::map<std::string, std::map<std::string, std::map<std::string, std::string>>> ran;
};

// Every measurement of every variant of one problem, in `rounds` interleaved rounds.
void measureProblem(const std::string& problem_name, const std::vector<Variant>& variants, double budget,
                    int rounds, std::ostream& csv, SolveTables* tables);

struct GenTiming {
  double generate = 0.0, build = 0.0, step = 0.0, step_solve = 0.0;  // s per call (fastest)
  sc::ContactGenerationStats stats;
  int contacts = 0, rows = 0, frictionless = 0;
  std::string step_status;
};

struct GenRow {
  std::string variant;
  GenTiming t;
};

// (d): a settled pile of n balls with all pairs, ball-ball pairs disabled, mixed friction.
std::vector<GenRow> measureGeneration(const std::string& scenes_dir, int n, int reps);

int frictionlessCount(const lcs::core::Problem& p);

// ---- CSV and tables (effects_cost_report.cpp) ----

struct CsvRow {
  CsvRow(std::string section_, std::string problem_, std::string variant_, int contacts_, int rows_,
         int frictionless_, std::string solver_, std::string ran_, std::string mode_)
      : section(std::move(section_)),
        problem(std::move(problem_)),
        variant(std::move(variant_)),
        contacts(contacts_),
        rows(rows_),
        frictionless(frictionless_),
        solver(std::move(solver_)),
        ran(std::move(ran_)),
        mode(std::move(mode_)) {}
  std::string section, problem, variant;
  int contacts = 0, rows = 0, frictionless = 0;
  std::string solver, ran, mode;
  double tolerance = 0.0;
  long iterations = 0;
  double seconds = 0.0, us_per_sweep = std::nan(""), us_marginal = std::nan(""), residual = std::nan("");
  std::string status;
  long broadphase = -1, skipped = -1, narrowphase = -1;
};

std::string num(double v, const char* fmt = "%.6g");
void csvHeader(std::ostream& csv);
void csvWrite(std::ostream& csv, const CsvRow& r);
// The (a)(b)(c) tables: per sweep, and to a tolerance.
void printSolveTables(const std::vector<std::string>& names, const SolveTables& tables);
// The (d) table's header, and the CSV and table rows of one pile.
void printGenerationHeader();
void reportGeneration(std::ostream& csv, int n, int reps, const std::vector<GenRow>& rows);

}  // namespace lcs_bench::effects_cost
