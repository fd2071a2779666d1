// Message -> Problem (lcp_contact_solver_ros::toProblem, the node's conversion) at 100 and
// 1000 frictional contacts, block-sparse W (each contact coupled to its 8 neighbours, 3x3
// blocks): best of 5 rounds of 20 conversions (issue #15, "the node without copies"), with
// validateProblem and without it (validate=false: what CycleSolver calls, the core's solve
// runs the same check).
//   to_problem_bench
#include <chrono>
#include <cstdio>
#include "lcp_contact_solver/ros/msg_conversion/msg_conversion.h"
namespace lcs = lcp_contact_solver;
int main() {
  for (int n : {100, 1000}) {
    lcs::ContactArray a;
    lcs::Compliance w;
    a.contacts.resize(n);
    for (int i = 0; i < n; ++i) {
      auto& c = a.contacts[i];
      c.id = 1000 + 7 * i;
      c.type = lcs::ContactPoint::FRICTIONAL;
      c.mu = 0.5;
      c.erp = c.softness = -1;
      c.normal.z = 1.0;
      c.position.x = i;
      c.d_free = {-0.01, 0.001, 0.002};
    }
    w.storage = lcs::Compliance::STORAGE_BLOCK_SPARSE;
    w.rows = 3 * n;
    for (int i = 0; i < n; ++i)
      for (int j = std::max(0, i - 4); j <= std::min(n - 1, i + 4); ++j) {
        w.block_rows.push_back(i);
        w.block_cols.push_back(j);
        for (int k = 0; k < 9; ++k) w.block_data.push_back(i == j ? (k % 4 == 0 ? 1.0 : 0.0) : 0.01);
      }
    for (bool validate : {true, false}) {
      double best = 1e9;
      for (int round = 0; round < 5; ++round) {
        auto t0 = std::chrono::steady_clock::now();
        for (int k = 0; k < 20; ++k) {
          lcs::core::Problem p;
          std::vector<lcp_contact_solver_ros::ContactFrame> frames;
          const std::string err = lcp_contact_solver_ros::toProblem(a, w, 0, &p, &frames, validate);
          if (!err.empty()) {
            std::printf("error: %s\n", err.c_str());
            return 1;
          }
        }
        best =
            std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / 20);
      }
      std::printf("%d contacts: toProblem %.1f us (%s)\n", n, 1e6 * best,
                  validate ? "with validateProblem" : "validate=false, as CycleSolver");
    }
  }
}
