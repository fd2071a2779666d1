// The auto regret table (auto_regret_table.h) from the rows of the work-precision study.
#include "auto_regret_table.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <ostream>
#include <set>
#include <string>
#include <vector>

namespace lcs_bench::work_precision {

namespace {

// A row reached tolerance tol: its residual (disc, recomputed) is at most tol and it ended
// without a failure. Direct methods (Lemke) count at every tolerance their residual meets.
bool reached(const Row& r, double tol) {
  if (std::isnan(r.time_median) || !(r.residual <= tol)) return false;
  return r.status == "converged" || r.setting == "direct" || r.setting.rfind("it=", 0) == 0;
}

double geomean(const std::vector<double>& v) {
  if (v.empty()) return kNaN;
  double s = 0.0;
  for (double x : v) s += std::log(x);
  return std::exp(s / static_cast<double>(v.size()));
}

// (problem, tolerance) -> auto's time, fastest own, fastest peer, fastest Siconos
struct Cell {
  double auto_time = kNaN;
  bool auto_ok = false, auto_ran = false;
  double own = kNaN, peer = kNaN, siconos = kNaN;
  std::string own_name, peer_name;
};
using Cells = std::map<std::pair<std::string, double>, Cell>;

// The cells of every (problem, tolerance); order_out gets the problems in the rows' order.
Cells collectCells(const Options& opt, const std::vector<Row>& rows, std::vector<std::string>* order_out) {
  Cells cells;
  std::set<std::string> own_names;
  for (const OurSolver& s : ourSolvers()) own_names.insert(s.name);
  std::vector<std::string>& order = *order_out;
  for (const Row& r : rows) {
    const std::string key = r.family + "/" + r.problem;
    if (std::find(order.begin(), order.end(), key) == order.end()) order.push_back(key);
    for (double tol : opt.tolerances) {
      // A tolerance-swept row speaks for its own tolerance; direct and iteration-capped rows
      // for every tolerance their residual meets.
      const bool swept = !std::isnan(r.tolerance);
      if (swept && std::abs(r.tolerance - tol) > 1e-3 * tol) continue;
      Cell& c = cells[{key, tol}];
      if (r.solver == "auto") {
        c.auto_ran = c.auto_ran || !std::isnan(r.time_median);
        if (reached(r, tol)) {
          c.auto_time = r.time_median;
          c.auto_ok = true;
        }
        continue;
      }
      if (!reached(r, tol)) continue;
      auto better = [&](double& slot, std::string* name) {
        if (std::isnan(slot) || r.time_median < slot) {
          slot = r.time_median;
          if (name) *name = r.solver;
        }
      };
      if (own_names.count(r.solver))
        better(c.own, &c.own_name);
      else {
        better(c.peer, &c.peer_name);
        if (r.solver.rfind("siconos", 0) == 0) better(c.siconos, nullptr);
      }
    }
  }
  return cells;
}

void writeSummary(std::ostream& md, const Options& opt, const Cells& cells,
                  const std::vector<std::string>& order) {
  md << "Summary per tolerance (geometric means over the problems where both sides reached it;\n"
        "\"auto missed\" counts problems some own solver solved and auto did not):\n\n"
        "| tolerance | problems | auto / fastest own: geo mean | max | > 1.5x | auto missed | auto / best "
        "Siconos: geo mean (n) | Siconos solved, auto not | auto / fastest peer: geo mean (n) |\n"
        "|---|---|---|---|---|---|---|---|---|\n";
  for (double tol : opt.tolerances) {
    std::vector<double> own, sic, peer;
    int problems = 0, missed = 0, over = 0, sic_missed = 0;
    double worst = kNaN;
    for (const std::string& key : order) {
      const auto it = cells.find({key, tol});
      if (it == cells.end() || !it->second.auto_ran) continue;
      const Cell& c = it->second;
      ++problems;
      if (!std::isnan(c.own)) {
        if (!c.auto_ok)
          ++missed;
        else {
          const double q = c.auto_time / c.own;
          own.push_back(q);
          if (q > 1.5) ++over;
          if (std::isnan(worst) || q > worst) worst = q;
        }
      }
      if (!std::isnan(c.siconos)) {
        if (c.auto_ok)
          sic.push_back(c.auto_time / c.siconos);
        else
          ++sic_missed;
      }
      if (!std::isnan(c.peer) && c.auto_ok) peer.push_back(c.auto_time / c.peer);
    }
    md << "| " << fmt(tol) << " | " << problems << " | " << fmt(geomean(own)) << " | " << fmt(worst) << " | "
       << over << " | " << missed << " | " << fmt(geomean(sic)) << " (" << sic.size() << ") | " << sic_missed
       << " | " << fmt(geomean(peer)) << " (" << peer.size() << ") |\n";
  }
}

void writePerProblem(std::ostream& md, const Options& opt, const Cells& cells,
                     const std::vector<std::string>& order) {
  md << "\nPer problem: auto / fastest own solver (that solver), \"-\" where no own solver reached the\n"
        "tolerance, \"MISS\" where one did and auto did not.\n\n| problem |";
  for (double tol : opt.tolerances) md << ' ' << fmt(tol) << " |";
  md << "\n|---|";
  for (std::size_t i = 0; i < opt.tolerances.size(); ++i) md << "---|";
  md << '\n';
  for (const std::string& key : order) {
    bool any = false;
    for (double tol : opt.tolerances) {
      const auto it = cells.find({key, tol});
      any = any || (it != cells.end() && it->second.auto_ran);
    }
    if (!any) continue;
    md << "| " << key << " |";
    for (double tol : opt.tolerances) {
      const auto it = cells.find({key, tol});
      if (it == cells.end() || std::isnan(it->second.own)) {
        md << " - |";
        continue;
      }
      const Cell& c = it->second;
      if (!c.auto_ok) {
        md << " MISS (" << c.own_name << ") |";
        continue;
      }
      char buf[64];
      std::snprintf(buf, sizeof buf, " %.2f (%s) |", c.auto_time / c.own, c.own_name.c_str());
      md << buf;
    }
    md << '\n';
  }
}

}  // namespace

void writeRegret(const Options& opt, const std::vector<Row>& rows) {
  std::vector<std::string> order;
  const Cells cells = collectCells(opt, rows, &order);
  std::ofstream md(opt.regret);
  if (!md) {
    std::cerr << "work_precision: cannot write " << opt.regret << "\n";
    return;
  }
  writeSummary(md, opt, cells, order);
  writePerProblem(md, opt, cells, order);
  std::cerr << "work_precision: wrote the auto regret table to " << opt.regret << "\n";
}

}  // namespace lcs_bench::work_precision
