// What a dense Cholesky of n rows costs in the two forms choleskyInPlace chooses between
// (kernels.h): Eigen's blocked LLᵀ and the column-by-column form, on W = J Jᵀ/n + I (J random,
// a compliance's shape), n = 8..200. Each form's time is the fastest of 7 alternating rounds,
// the copy of W into the factor's storage timed apart and taken off. CSV on stdout:
//   cholesky_forms > bench/results/cholesky_forms.csv
#include "lcp_contact_solver/core/kernels/kernels.h"

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <limits>
#include <random>

namespace {

using Clock = std::chrono::steady_clock;

// Seconds per call of `body`, the fastest of `rounds` rounds of `reps` calls.
template <class Body>
double fastestPerCall(int rounds, int reps, Body&& body) {
  double best = std::numeric_limits<double>::infinity();
  for (int r = 0; r < rounds; ++r) {
    const auto t0 = Clock::now();
    for (int k = 0; k < reps; ++k) body();
    best = std::min(best, std::chrono::duration<double>(Clock::now() - t0).count() / reps);
  }
  return best;
}

}  // namespace

int main() {
  namespace core = lcp_contact_solver::core;
  std::printf("rows,blocked_s,column_s,column_over_blocked,chosen\n");
  std::mt19937 rng(7);
  std::normal_distribution<double> g;
  for (int n : {8, 16, 24, 32, 40, 52, 64, 80, 96, 104, 112, 120, 128, 144, 160, 200}) {
    Eigen::MatrixXd J(n, n);
    for (int i = 0; i < J.size(); ++i) J.data()[i] = g(rng);
    const Eigen::MatrixXd W = J * J.transpose() / n + Eigen::MatrixXd::Identity(n, n);
    Eigen::MatrixXd A(n, n);
    const int reps = std::max(20, 2000000 / (n * n * n / 6 + 1));
    double copy = 0.0, blocked = 0.0, column = 0.0;
    bool ok = true;
    for (int round = 0; round < 7; ++round) {  // alternating, so that a slow stretch hits all three
      const double c = fastestPerCall(1, reps, [&] { A = W; });
      const double b = fastestPerCall(1, reps, [&] {
        A = W;
        ok &= Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>, Eigen::Lower>(A).info() == Eigen::Success;
      });
      const double k = fastestPerCall(1, reps, [&] {
        A = W;
        ok &= core::columnCholeskyInPlace(A);
      });
      copy = round == 0 ? c : std::min(copy, c);
      blocked = round == 0 ? b : std::min(blocked, b);
      column = round == 0 ? k : std::min(column, k);
    }
    if (!ok) {
      std::fprintf(stderr, "cholesky_forms: a factorization failed at n = %d\n", n);
      return 1;
    }
    blocked -= copy;
    column -= copy;
    std::printf("%d,%.4g,%.4g,%.3f,%s\n", n, blocked, column, column / blocked,
                n <= core::kColumnCholeskyRows ? "column" : "blocked");
  }
  return 0;
}
