// Scaling from ~10 to ~10,000 contacts (issue #8; docs/BENCHMARKS.md "Scaling"). In-process,
// ROS-free; a benchmark, never a test.
//
//   scaling_bench [--bases 2,5,16,28,50] [--balls 4,40,350,1000,2000] [--pyramid-steps 3]
//                 [--pile-steps 30] [--dense-max-gb 2] [--budget 5] [--rounds 3] [--array-mb 512]
//                 [--copies 4] [--copies-max-contacts 10000] [--threads 1] [--out FILE.csv]
//
// Problems: bench/scene_problems.h (brick pyramids, box_stack's bodies, ~4 k² contacts for k
// bricks at the base; sphere piles, sphere_pile's balls), taken after --pyramid-steps /
// --pile-steps in-process steps, W block-sparse as the scene builds it. Forms of the same
// problem:
//   dense         W converted with BlockSparseMatrix::toDense (skipped when rows² · 8 bytes
//                 exceeds --dense-max-gb: the CSV says "skipped")
//   block_sparse  the scene's W
//   unbuilt       the body form (Problem::bodies, SolverParams::build_lcp = false): no W
//   scalar_rows   the same contacts frictionless, W's normal rows as 1×1 blocks: the
//                 one-row problem the scalar-row sweep (core/kernels/scalar_rows.h) runs on
//                 (pgs for the sweeps, auto to the tolerances)
// With --copies K > 1 every problem (up to --copies-max-contacts in all) is also taken K times side by side (box_pyramid_B16x4:
// K independent islands, a block-diagonal W), its block_sparse and scalar_rows forms measured
// with islands on (each island its own stopping test; --threads 1: in the measured thread) and off.
// Per form: bytes of the compliance, time per nlgs sweep (25 sweeps from a cold start, SOFA
// rule at an unreachable tolerance: the whole solve / 25, and the marginal sweep (t(25) -
// t(5)) / 20 with the setup t(5) - 5 marginal sweeps; timing_util.h sweepRound), and time to a
// residual of 1e-4 and 1e-6 with auto (built: nlgs at 1e-4, newton ≤ 200 rows / apgd above at
// 1e-6; unbuilt: nlgs) within a wall-clock budget (--budget s, maxIt 10^6). The forms of a
// problem are measured in --rounds interleaved rounds, the fastest counts. When some contact
// penetrates (gap < 0, erp > 0) ContactSolver solves a stabilized copy of the problem, W
// included; the setup of the same problem with erp = 0 (no copy) is measured beside it.
// Bandwidth: the machine's single-thread read bandwidth, measured here (sum of a --array-mb
// array of doubles with 8 accumulators, fastest of 5 passes, before and after), and the
// ratio dense sweep / (bytes of W / bandwidth): 1 means a sweep costs exactly one read of W.
// Times are CPU time of the benchmark's thread (timing_util.h: the machine is shared), the
// fastest of the repeats.
#include "cli_options.h"
#include "scene_problems.h"
#include "timing_util.h"

#include "lcp_contact_solver/core/body_compliance.h"
#include "lcp_contact_solver/core/contact_solver.h"
#include "lcp_contact_solver/core/islands.h"

#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

namespace lcs = lcp_contact_solver;
using lcs_bench::Clock;
using lcs_bench::secondsSince;

namespace {

struct Options {
  std::vector<int> bases = {2, 5, 16, 28, 50};
  std::vector<int> balls = {4, 40, 350, 1000, 2000};
  int pyramid_steps = 3, pile_steps = 30;
  double dense_max_gb = 2.0;
  double budget = 5.0;
  int rounds = 3;
  int array_mb = 512;
  int copies = 4;                   // > 1: each problem also K times side by side (islands)
  int copies_max_contacts = 10000;  // ... when the copies have at most this many contacts
  // Island threads: 1 keeps every island in the measured thread, whose CPU time is what counts.
  int threads = 1;
  std::string out = "bench/results/scaling.csv";
};

// Single-thread read bandwidth (bytes/s): sum of `mb` MB of doubles, 8 independent
// accumulators (so the adds do not serialize), fastest of `passes` in thread CPU time.
double readBandwidth(int mb, int passes = 5) {
  const std::size_t n = static_cast<std::size_t>(mb) * 1024 * 1024 / sizeof(double);
  std::unique_ptr<double[]> a(new double[n]);
  for (std::size_t i = 0; i < n; ++i) a[i] = 1e-9 * static_cast<double>(i % 1000);
  double best = 1e300, sink = 0.0;
  for (int p = 0; p < passes; ++p) {
    const double c0 = lcs_bench::threadCpuSeconds();
    double s[8] = {0, 0, 0, 0, 0, 0, 0, 0};
    for (std::size_t i = 0; i + 8 <= n; i += 8)
      for (int k = 0; k < 8; ++k) s[k] += a[i + k];
    const double t = lcs_bench::threadCpuSeconds() - c0;
    sink += s[0] + s[1] + s[2] + s[3] + s[4] + s[5] + s[6] + s[7];
    best = std::min(best, t);
  }
  if (sink == 42.0) std::fprintf(stderr, " ");  // keep the sums
  return static_cast<double>(n * sizeof(double)) / best;
}

std::string num(double v, const char* fmt = "%.6g") {
  if (!std::isfinite(v)) return "";
  char b[64];
  std::snprintf(b, sizeof(b), fmt, v);
  return b;
}

std::string human(double bytes) {
  char b[32];
  if (bytes >= 1e9)
    std::snprintf(b, sizeof(b), "%.2f GB", bytes / 1e9);
  else if (bytes >= 1e6)
    std::snprintf(b, sizeof(b), "%.1f MB", bytes / 1e6);
  else
    std::snprintf(b, sizeof(b), "%.0f kB", bytes / 1e3);
  return b;
}

std::string ms(double s) {
  if (!std::isfinite(s)) return "✗";
  char b[32];
  if (s < 1e-3)
    std::snprintf(b, sizeof(b), "%.0f µs", 1e6 * s);
  else if (s < 1.0)
    std::snprintf(b, sizeof(b), "%.3g ms", 1e3 * s);
  else
    std::snprintf(b, sizeof(b), "%.2f s", s);
  return b;
}

// The same contacts frictionless on their normal rows: one row each, W's normal-normal
// entries as 1×1 blocks, d_free's normal rows.
lcs::core::Problem normalRowsOnly(const lcs::core::Problem& p) {
  const auto& W = std::get<lcs::core::BlockSparseMatrix>(p.W);
  const int nc = static_cast<int>(p.contacts.size());
  const std::vector<int> offsets = p.rowOffsets();
  lcs::core::Problem out;
  out.name = p.name + "_normals";
  out.contacts = p.contacts;
  for (lcs::core::Contact& c : out.contacts) {
    c.type = lcs::core::ContactType::kFrictionless;
    c.rows = 1;
  }
  out.d_free.resize(nc);
  for (int i = 0; i < nc; ++i) out.d_free[i] = p.d_free[offsets[i]];
  auto R = lcs::core::BlockSparseMatrix::withBlockSizes(std::vector<int>(nc, 1));
  for (int i = 0; i < W.blockCount(); ++i) {
    R.beginRow();
    for (int s = W.row_start[i]; s < W.row_start[i + 1]; ++s)
      R.addBlock(W.block_col[s], Eigen::MatrixXd::Constant(1, 1, W.values[W.value_start[s]]));
  }
  out.W = std::move(R);
  return out;
}

// `k` copies of a block-sparse problem side by side: a block-diagonal W, ids kept apart.
lcs::core::Problem disjointCopies(const lcs::core::Problem& p, int k) {
  const auto& W = std::get<lcs::core::BlockSparseMatrix>(p.W);
  const int nb = W.blockCount();
  std::int64_t id_span = 1;
  for (const lcs::core::Contact& c : p.contacts) id_span = std::max(id_span, c.id + 1);
  lcs::core::Problem out;
  out.name = p.name + "x" + std::to_string(k);
  std::vector<int> sizes;
  for (int c = 0; c < k; ++c)
    for (const lcs::core::Contact& contact : p.contacts) {
      out.contacts.push_back(contact);
      out.contacts.back().id = contact.id + c * id_span;
      sizes.push_back(contact.rows);
    }
  out.d_free = p.d_free.replicate(k, 1);
  auto R = lcs::core::BlockSparseMatrix::withBlockSizes(sizes);
  for (int c = 0; c < k; ++c)
    for (int i = 0; i < nb; ++i) {
      R.beginRow();
      const int rows = W.block_offset[i + 1] - W.block_offset[i];
      for (int s = W.row_start[i]; s < W.row_start[i + 1]; ++s) {
        const int j = W.block_col[s];
        const int cols = W.block_offset[j + 1] - W.block_offset[j];
        const Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> block(
            W.values.data() + W.value_start[s], rows, cols);
        R.addBlock(j + c * nb, block);
      }
    }
  out.W = std::move(R);
  return out;
}

// Fills o from the command line (CLI11); -1 to go on, else the exit code (0 after --help).
int parseOptions(int argc, char** argv, Options* options) {
  Options& o = *options;
  CLI::App app{"scaling_bench: scaling from ~10 to ~10,000 contacts (in-process, CSV)"};
  app.option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  lcs_bench::addIntListOption(app, "--bases", &o.bases, "brick pyramids: bricks at the base, comma list",
                              "2,5,16,28,50");
  lcs_bench::addIntListOption(app, "--balls", &o.balls, "sphere piles: balls, comma list",
                              "4,40,350,1000,2000");
  app.add_option("--pyramid-steps", o.pyramid_steps, "in-process steps before a pyramid problem is taken")
      ->capture_default_str();
  app.add_option("--pile-steps", o.pile_steps, "in-process steps before a pile problem is taken")
      ->capture_default_str();
  app.add_option("--dense-max-gb", o.dense_max_gb, "dense W skipped above this size (GB)")
      ->capture_default_str();
  app.add_option("--budget", o.budget, "wall-clock budget of a solve to a tolerance (s)")
      ->capture_default_str();
  app.add_option("--rounds", o.rounds, "interleaved rounds; the fastest counts")->capture_default_str();
  app.add_option("--array-mb", o.array_mb, "array summed to measure the read bandwidth (MB)")
      ->capture_default_str();
  app.add_option("--copies", o.copies, "K > 1: each problem also K times side by side (islands)")
      ->capture_default_str();
  app.add_option("--copies-max-contacts", o.copies_max_contacts,
                 "copies only up to this many contacts in all")
      ->capture_default_str();
  app.add_option("--threads", o.threads, "island threads (1: all in the measured thread)")
      ->capture_default_str();
  app.add_option("--out", o.out, "the CSV to write")->capture_default_str();
  return lcs_bench::parseArguments(app, argc, argv);
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  if (const int code = parseOptions(argc, argv, &o); code >= 0) return code;
  std::ofstream csv(o.out);
  if (!csv) {
    std::fprintf(stderr, "scaling: cannot write %s\n", o.out.c_str());
    return 1;
  }
  std::printf("scaling: load average %s at the start, %ld cores\n", lcs_bench::loadAverageText().c_str(),
              sysconf(_SC_NPROCESSORS_ONLN));
  const double bw0 = readBandwidth(o.array_mb);
  std::printf("scaling: read bandwidth %.2f GB/s (sum of %d MB, one thread, fastest of 5)\n", bw0 / 1e9,
              o.array_mb);
  std::fflush(stdout);

  csv << "problem,family,bodies,contacts,rows,form,w_bytes,setup_ms,sweeps,us_per_sweep,us_marginal_sweep,"
         "ns_per_row_sweep,bandwidth_gbs,read_w_us,sweep_over_read_w,marginal_over_read_w,t_1e-4_ms,it_1e-4,"
         "solver_1e-4,status_1e-4,t_1e-6_ms,it_1e-6,"
         "solver_1e-6,status_1e-6,residual_1e-6,penetrating_contacts,setup_without_erp_ms,load1,islands,"
         "island_count,"
         "w_bytes_per_contact\n";

  std::vector<lcs_bench::SceneProblem> problems;
  const auto t_gen = Clock::now();
  for (int b : o.bases) {
    auto p = lcs_bench::makeSceneProblems(LCS_SCENES_DIR, {b}, {}, o.pyramid_steps);
    std::fprintf(stderr, "generated %s (%zu contacts) at %.0f s\n", p[0].name.c_str(),
                 p[0].problem.contacts.size(), secondsSince(t_gen));
    problems.push_back(std::move(p[0]));
  }
  for (int n : o.balls) {
    auto p = lcs_bench::makeSceneProblems(LCS_SCENES_DIR, {}, {n}, o.pile_steps);
    std::fprintf(stderr, "generated %s (%zu contacts) at %.0f s\n", p[0].name.c_str(),
                 p[0].problem.contacts.size(), secondsSince(t_gen));
    problems.push_back(std::move(p[0]));
  }
  // Islands: each problem K times side by side (block-sparse only: the body form and the dense
  // W of a copy are the same story as the original's).
  const std::size_t originals = problems.size();
  for (std::size_t i = 0; i < originals && o.copies > 1; ++i) {
    if (problems[i].problem.contacts.size() * o.copies > static_cast<std::size_t>(o.copies_max_contacts))
      continue;
    lcs_bench::SceneProblem copy;
    copy.name = problems[i].name + "x" + std::to_string(o.copies);
    copy.scene = problems[i].scene;
    copy.bodies = problems[i].bodies * o.copies;
    copy.steps = problems[i].steps;
    copy.problem = disjointCopies(problems[i].problem, o.copies);
    problems.push_back(std::move(copy));
  }

  std::printf(
      "\n| problem | contacts | rows | form | W bytes | W bytes / contact | setup (erp = 0) | µs/sweep | "
      "marginal µs/sweep | ns/row·sweep | sweep ÷ read(W) | to 1e-4 (auto) | to 1e-6 (auto) |\n"
      "|---|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (std::size_t pi = 0; pi < problems.size(); ++pi) {
    lcs_bench::SceneProblem& sp = problems[pi];
    const lcs::core::Problem& sparse = sp.problem;
    const int nc = static_cast<int>(sparse.contacts.size()), rows = sparse.rowCount();
    if (nc == 0) continue;
    const std::string family = sp.name.rfind("box_pyramid", 0) == 0 ? "box_pyramid" : "sphere_pile";
    struct Form {
      std::string name;
      const lcs::core::Problem* problem;
      bool build_lcp;
      bool islands = true;
    };
    const bool copies = pi >= originals;  // the side-by-side copies come after the originals
    lcs::core::Problem dense;
    const double dense_bytes = static_cast<double>(rows) * rows * sizeof(double);
    const bool do_dense = dense_bytes <= o.dense_max_gb * 1e9 && !copies;
    std::vector<Form> forms;
    if (do_dense) {
      dense = sparse;
      dense.W = std::get<lcs::core::BlockSparseMatrix>(sparse.W).toDense();
      forms.push_back({"dense", &dense, true});
    } else if (!copies) {
      csv << sp.name << ',' << family << ',' << sp.bodies << ',' << nc << ',' << rows << ",dense,"
          << num(dense_bytes) << ",,,,,,,,,,,,,skipped,,,,skipped,,,,"
          << num(lcs_bench::loadAverage1(), "%.2f") << ",,,\n";
      std::printf("| %s | %d | %d | dense | %s | %.0f | skipped (W > %.1f GB) | | | | | | |\n",
                  sp.name.c_str(), nc, rows, human(dense_bytes).c_str(), dense_bytes / nc, o.dense_max_gb);
    }
    const lcs::core::Problem normals = normalRowsOnly(sparse);
    forms.push_back({"block_sparse", &sparse, true});
    if (sp.body_form.bodies) forms.push_back({"unbuilt", &sp.body_form, false});
    forms.push_back({"scalar_rows", &normals, true});
    if (copies) {
      forms.push_back({"block_sparse", &sparse, true, false});
      forms.push_back({"scalar_rows", &normals, true, false});
    }
    // The same problems without position correction (every contact's erp = 0): ContactSolver
    // then solves the problem as given instead of a stabilized copy of it (W included), so the
    // setup difference is what that copy costs per solve.
    int penetrating = 0;
    for (const lcs::core::Contact& c : sparse.contacts) penetrating += c.gap < 0.0 && c.erp > 0.0 ? 1 : 0;
    std::vector<lcs::core::Problem> plain(forms.size());
    for (std::size_t i = 0; i < forms.size(); ++i) {
      plain[i] = *forms[i].problem;
      for (lcs::core::Contact& c : plain[i].contacts) c.erp = 0.0;
    }

    // Every measurement of every form, in interleaved rounds (timing_util.h); fastest counts.
    const int sweeps = 20;  // 5 + 20 sweeps from a cold start, the whole solve divided
    const double tols[2] = {1e-4, 1e-6};
    std::vector<lcs_bench::SweepAcc> sweep_acc(forms.size()), plain_acc(forms.size());
    std::vector<std::array<lcs_bench::SolveAcc, 2>> tol_acc(forms.size());
    lcs_bench::interleavedRounds(o.rounds, forms.size(), [&](std::size_t i) {
      lcs::core::SolverParams params;
      params.solver = lcs::core::SolverKind::kNlgs;
      params.build_lcp = forms[i].build_lcp;
      params.islands = forms[i].islands;
      params.threads = o.threads;
      lcs_bench::sweepRound(*forms[i].problem, params, sweeps, &sweep_acc[i], 0.02, 1);
      if (penetrating > 0) lcs_bench::sweepRound(plain[i], params, sweeps, &plain_acc[i], 0.02, 1);
      for (int k = 0; k < 2; ++k) {
        lcs::core::SolverParams p =
            lcs_bench::toleranceParams(lcs::core::SolverKind::kAuto, tols[k], o.budget, 1000000);
        p.build_lcp = forms[i].build_lcp;
        p.islands = forms[i].islands;
        p.threads = o.threads;
        lcs_bench::solveRound(*forms[i].problem, p, &tol_acc[i][k]);
      }
    });
    for (std::size_t i = 0; i < forms.size(); ++i) {
      const Form& f = forms[i];
      const lcs_bench::SweepTiming st = lcs_bench::sweepTiming(sweep_acc[i]);
      const lcs_bench::SweepTiming st_plain =
          penetrating > 0 ? lcs_bench::sweepTiming(plain_acc[i]) : lcs_bench::SweepTiming{};
      const double plain_setup = penetrating > 0 ? st_plain.setup : st.setup;
      if (st.result.unbuilt == f.build_lcp)
        std::fprintf(stderr, "%s %s: the unbuilt path was %staken\n", sp.name.c_str(), f.name.c_str(),
                     st.result.unbuilt ? "" : "not ");
      const double bytes = static_cast<double>(lcs_bench::bytesOfCompliance(*f.problem));
      const int form_rows = f.problem->rowCount();  // scalar_rows: one per contact
      const double read_w = bytes / bw0;
      const auto& tol = tol_acc[i];
      auto t_of = [](const lcs_bench::SolveAcc& t) { return t.result.converged ? t.best : std::nan(""); };
      csv << sp.name << ',' << family << ',' << sp.bodies << ',' << nc << ',' << rows << ',' << f.name << ','
          << num(bytes) << ',' << num(1e3 * st.setup) << ',' << st.sweeps << ',' << num(1e6 * st.per_sweep)
          << ',' << num(1e6 * st.marginal) << ',' << num(1e9 * st.per_sweep / form_rows) << ','
          << num(bw0 / 1e9) << ',' << num(1e6 * read_w) << ',' << num(st.per_sweep / read_w) << ','
          << num(st.marginal / read_w) << ',';
      for (int k = 0; k < 2; ++k)
        csv << num(1e3 * t_of(tol[k])) << ',' << tol[k].result.iterations << ',' << tol[k].result.solver
            << ',' << lcs::core::statusName(tol[k].result.status) << ',';
      csv << num(tol[1].result.residual) << ',' << penetrating << ',' << num(1e3 * plain_setup) << ','
          << num(lcs_bench::loadAverage1(), "%.2f") << ',' << (f.islands ? "on" : "off") << ','
          << lcs::core::findIslands(*f.problem).count() << ',' << num(bytes / nc) << '\n';
      csv.flush();
      auto cell = [](double v, const char* fmt) { return std::isfinite(v) ? num(v, fmt) : std::string("–"); };
      const std::string setup_text = (std::isfinite(st.setup) ? ms(st.setup) : std::string("–")) + " (" +
                                     (std::isfinite(plain_setup) ? ms(plain_setup) : std::string("–")) + ")";
      const std::string form_text = f.name + (copies ? (f.islands ? ", islands on" : ", islands off") : "");
      std::printf(
          "| %s | %d | %d | %s | %s | %.0f | %s | %s | %s | %s | %s | %s (%s, %d) | %s (%s, %d) |\n",
          sp.name.c_str(), nc, rows, form_text.c_str(), human(bytes).c_str(), bytes / nc, setup_text.c_str(),
          cell(1e6 * st.per_sweep, "%.1f").c_str(), cell(1e6 * st.marginal, "%.1f").c_str(),
          cell(1e9 * st.per_sweep / form_rows, "%.1f").c_str(), cell(st.per_sweep / read_w, "%.2f").c_str(),
          ms(t_of(tol[0])).c_str(), tol[0].result.solver.c_str(), tol[0].result.iterations,
          ms(t_of(tol[1])).c_str(), tol[1].result.solver.c_str(), tol[1].result.iterations);
      std::fflush(stdout);
    }
  }
  const double bw1 = readBandwidth(o.array_mb);
  std::printf("\nscaling: read bandwidth %.2f GB/s at the end; load average %s; CSV %s\n", bw1 / 1e9,
              lcs_bench::loadAverageText().c_str(), o.out.c_str());
  return 0;
}
