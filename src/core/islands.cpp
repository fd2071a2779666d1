#include "lcp_contact_solver/core/islands.h"

#include "lcp_contact_solver/core/body_compliance.h"
#include "lcp_contact_solver/core/residual.h"

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cmath>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <numeric>
#include <string>
#include <thread>
#include <unordered_map>
#include <variant>

namespace lcp_contact_solver::core {

namespace {

constexpr int kParallelMinRows = 200;

// Quick-find over contacts: every contact holds its island's label (one of its contacts, the
// head of a list of its members), and a merge relabels the smaller island, so the test
// whether two contacts are in one island is one load per side. With a union-find's lookup per
// pair, 260 one-row contacts of a dense W in 7 islands (a MuJoCo box stack, condim 6,
// pyramidal) took 140-290 us, as long as the Cholesky steps of the solve after it.
struct IslandLabels {
  std::vector<int> label, next, tail, size;
  explicit IslandLabels(int n) : label(n), next(n, -1), tail(n), size(n, 1) {
    std::iota(label.begin(), label.end(), 0);
    std::iota(tail.begin(), tail.end(), 0);
  }
  // Two labels: the larger island's survives and is returned.
  int merge(int a, int b) {
    if (size[a] < size[b]) std::swap(a, b);
    for (int x = b; x >= 0; x = next[x]) label[x] = a;
    next[tail[a]] = b;
    tail[a] = tail[b];
    size[a] += size[b];
    return a;
  }
};

// Dense W, column by column as it is stored, W's values read only across islands (on a W that
// couples everything, a MuJoCo cloth's 265 rows, an entry-by-entry pass cost 60 % of the
// Gauss-Seidel solve after it). W need not be symmetric: every column meets every contact, so
// both blocks of a pair are read.
void denseCoupling(const Eigen::MatrixXd& W, const std::vector<int>& offsets, IslandLabels& labels) {
  const int nc = static_cast<int>(offsets.size()) - 1;
  const Eigen::Index n = W.rows();
  const std::vector<int>& label = labels.label;
  const bool one_row_each = offsets.back() == nc;  // MuJoCo's pyramid edges, LCPs: no row loop
  for (int j = 0; j < nc; ++j) {
    int label_j = label[j];
    for (int c = offsets[j]; c < offsets[j + 1]; ++c) {
      const double* col = W.data() + static_cast<std::ptrdiff_t>(c) * n;
      for (int i = 0; i < nc; ++i) {
        if (label[i] == label_j) continue;
        bool coupled = false;
        if (one_row_each)
          coupled = col[i] != 0.0;
        else
          for (int r = offsets[i]; r < offsets[i + 1]; ++r) coupled |= col[r] != 0.0;
        if (coupled) label_j = labels.merge(label[i], label_j);
      }
    }
  }
}

// A process-wide pool: the caller works too, `threads - 1` helpers join it. Calls from
// different threads are serialized (one island batch at a time).
class ThreadPool {
 public:
  static ThreadPool& instance() {
    static ThreadPool pool;
    return pool;
  }

  void run(int tasks, int threads, const std::function<void(int)>& fn) {
    std::lock_guard<std::mutex> serial(run_mutex_);
    const int helpers = std::max(0, std::min(threads, tasks) - 1);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      while (static_cast<int>(workers_.size()) < helpers) {
        const int index = static_cast<int>(workers_.size());
        workers_.emplace_back([this, index] { workerLoop(index); });
      }
      job_ = &fn;
      tasks_ = tasks;
      next_.store(0);
      helpers_ = helpers;
      pending_ = helpers;
      ++generation_;
    }
    wake_.notify_all();
    work();
    std::unique_lock<std::mutex> lock(mutex_);
    done_.wait(lock, [this] { return pending_ == 0; });
    job_ = nullptr;
  }

  ~ThreadPool() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    wake_.notify_all();
    for (std::thread& t : workers_) t.join();
  }

 private:
  void work() {
    for (int i = next_.fetch_add(1); i < tasks_; i = next_.fetch_add(1)) (*job_)(i);
  }

  void workerLoop(int index) {
    unsigned long seen = 0;
    std::unique_lock<std::mutex> lock(mutex_);
    for (;;) {
      wake_.wait(lock, [&] { return stop_ || generation_ != seen; });
      if (stop_) return;
      seen = generation_;
      if (index >= helpers_) continue;  // not needed for this batch
      lock.unlock();
      work();
      lock.lock();
      if (--pending_ == 0) done_.notify_all();
    }
  }

  std::mutex run_mutex_, mutex_;
  std::condition_variable wake_, done_;
  std::vector<std::thread> workers_;
  const std::function<void(int)>* job_ = nullptr;
  int tasks_ = 0;
  std::atomic<int> next_{0};
  int helpers_ = 0;
  int pending_ = 0;
  unsigned long generation_ = 0;
  bool stop_ = false;
};

// The kernel could not run or ended on something that is not an approximate solution.
bool failure(SolveStatus s) {
  return s == SolveStatus::kZeroDiagonal || s == SolveStatus::kNotApplicable ||
         s == SolveStatus::kRayTermination || s == SolveStatus::kNumericalFailure ||
         s == SolveStatus::kInvalidInput;
}

// Kernels name contacts "contact K (id N)" by their index in the problem they were given:
// K is renumbered to the whole problem's index.
std::string globalContactNames(const std::string& message, const std::vector<int>& contacts) {
  static const std::string kWord = "contact ";
  std::string out;
  std::size_t from = 0;
  for (std::size_t at = message.find(kWord); at != std::string::npos; at = message.find(kWord, at + 1)) {
    std::size_t end = at + kWord.size();
    while (end < message.size() && std::isdigit(static_cast<unsigned char>(message[end]))) ++end;
    if (end == at + kWord.size() || message.compare(end, 5, " (id ") != 0) continue;
    const unsigned long local = std::stoul(message.substr(at + kWord.size(), end - at - kWord.size()));
    if (local >= contacts.size()) continue;
    out += message.substr(from, at + kWord.size() - from) + std::to_string(contacts[local]);
    from = end;
  }
  return out + message.substr(from);
}

int severity(SolveStatus s) {
  if (failure(s)) return 3;
  if (s == SolveStatus::kTimeBudget) return 2;
  if (s == SolveStatus::kMaxIterations) return 1;
  return 0;
}

}  // namespace

int defaultThreadCount() {
  // Asked once: hardware_concurrency() reads the CPU affinity (microseconds per call).
  static const int count = [] {
    const unsigned n = std::thread::hardware_concurrency();
    return n == 0 ? 1 : static_cast<int>(n);
  }();
  return count;
}

Islands findIslands(const Problem& problem) {
  const int nc = static_cast<int>(problem.contacts.size());
  IslandLabels labels(nc);
  const std::vector<int>& label = labels.label;
  if (problem.bodies) {  // the body form: contacts sharing a (moving) body are coupled
    const BodyCompliance& B = *problem.bodies;
    std::vector<int> first_contact(B.body_compliance.size(), -1);
    for (int i = 0; i < nc; ++i)
      for (int b : {B.contacts[i].body_a, B.contacts[i].body_b}) {
        if (b < 0) continue;
        if (first_contact[b] < 0)
          first_contact[b] = i;
        else if (label[first_contact[b]] != label[i])
          labels.merge(label[first_contact[b]], label[i]);
      }
  } else if (const auto* dense = std::get_if<Eigen::MatrixXd>(&problem.W)) {
    denseCoupling(*dense, problem.rowOffsets(), labels);
  } else if (const auto* sparse = std::get_if<BlockSparseMatrix>(&problem.W)) {
    const BlockSparseMatrix& W = *sparse;
    for (int i = 0; i < W.blockCount(); ++i) {
      int label_i = label[i];
      const int rows_i = W.block_offset[i + 1] - W.block_offset[i];
      for (int b = W.row_start[i]; b < W.row_start[i + 1]; ++b) {
        const int j = W.block_col[b];
        if (label[j] == label_i) continue;  // values read only across islands (and j == i)
        const int size = rows_i * (W.block_offset[j + 1] - W.block_offset[j]);
        const double* v = W.values.data() + W.value_start[b];
        // A stored block of zeros couples nothing.
        if (std::any_of(v, v + size, [](double x) { return x != 0.0; })) label_i = labels.merge(label[j], label_i);
      }
    }
  }
  Islands out;
  out.island_of.assign(nc, -1);
  std::vector<int> island_of_label(nc, -1);
  for (int i = 0; i < nc; ++i) {
    const int l = label[i];
    if (island_of_label[l] < 0) {
      island_of_label[l] = out.count();
      out.contacts.emplace_back();
    }
    out.island_of[i] = island_of_label[l];
    out.contacts[island_of_label[l]].push_back(i);
  }
  return out;
}

namespace {

// islandProblem with each contact's island and position in it given (`island_of`,
// `position`), so that building every island costs O(stored blocks) in all.
Problem buildIsland(const Problem& problem, const std::vector<int>& offsets, const std::vector<int>& contacts,
                    const std::vector<int>& island_of, const std::vector<int>& position) {
  Problem out;
  out.name = problem.name;
  out.contacts.reserve(contacts.size());
  std::vector<int> rows;
  rows.reserve(contacts.size() * 3);
  for (int i : contacts) {
    out.contacts.push_back(problem.contacts[i]);
    for (int r = offsets[i]; r < offsets[i + 1]; ++r) rows.push_back(r);
  }
  out.d_free = problem.d_free(rows);
  if (problem.bodies) {  // its bodies renumbered in order of first use, their C_b copied
    const BodyCompliance& B = *problem.bodies;
    auto sub = std::make_shared<BodyCompliance>();
    std::unordered_map<int, int> local_body;
    sub->contacts.reserve(contacts.size());
    for (int i : contacts) {
      ContactJacobian c = B.contacts[i];
      for (int* b : {&c.body_a, &c.body_b}) {
        if (*b < 0) continue;
        const auto it = local_body.emplace(*b, static_cast<int>(sub->body_compliance.size())).first;
        if (it->second == static_cast<int>(sub->body_compliance.size()))
          sub->body_compliance.push_back(B.body_compliance[*b]);
        *b = it->second;
      }
      sub->contacts.push_back(std::move(c));
    }
    if (B.diagonal.size() > 0) sub->diagonal = B.diagonal(rows);
    out.bodies = std::move(sub);
    return out;
  }
  if (const auto* dense = std::get_if<Eigen::MatrixXd>(&problem.W)) {
    out.W = Eigen::MatrixXd((*dense)(rows, rows));
    return out;
  }
  const auto& W = std::get<BlockSparseMatrix>(problem.W);
  const int island = contacts.empty() ? -1 : island_of[contacts.front()];
  BlockSparseMatrix R;
  R.block_offset.assign(1, 0);
  R.row_start.assign(1, 0);
  // Sized once from the stored blocks' extents (values of block row i run from
  // value_start[row_start[i]] to the next row's): no regrowth while copying.
  std::size_t blocks = 0, values = 0;
  const auto valueAt = [&](int b) {
    return b < static_cast<int>(W.value_start.size()) ? static_cast<std::size_t>(W.value_start[b])
                                                      : W.values.size();
  };
  for (int i : contacts) {
    blocks += W.row_start[i + 1] - W.row_start[i];
    values += valueAt(W.row_start[i + 1]) - valueAt(W.row_start[i]);
  }
  R.block_offset.reserve(contacts.size() + 1);
  R.row_start.reserve(contacts.size() + 1);
  R.block_col.resize(blocks);
  R.value_start.resize(blocks);
  R.values.resize(values);
  const int* offset = W.block_offset.data();
  std::size_t nb = 0, nv = 0;
  for (int i : contacts) {
    const int rows_i = offset[i + 1] - offset[i];
    R.block_offset.push_back(R.block_offset.back() + rows_i);
    for (int b = W.row_start[i]; b < W.row_start[i + 1]; ++b) {
      const int col = W.block_col[b];
      // Blocks to other islands are zero (findIslands) and left out.
      if (island_of[col] != island) continue;
      const int size = rows_i * (offset[col + 1] - offset[col]);
      R.block_col[nb] = position[col];
      R.value_start[nb++] = static_cast<int>(nv);
      const double* v = W.values.data() + W.value_start[b];
      if (size == 1)
        R.values[nv] = *v;  // scalar rows: no copy call per entry
      else
        std::copy_n(v, size, R.values.data() + nv);
      nv += size;
    }
    R.row_start.push_back(static_cast<int>(nb));
  }
  R.block_col.resize(nb);
  R.value_start.resize(nb);
  R.values.resize(nv);
  out.W = std::move(R);
  return out;
}

}  // namespace

Problem islandProblem(const Problem& problem, const std::vector<int>& offsets,
                      const std::vector<int>& contacts) {
  std::vector<int> island_of(problem.contacts.size(), 1), position(problem.contacts.size(), -1);
  for (std::size_t k = 0; k < contacts.size(); ++k) {
    island_of[contacts[k]] = 0;
    position[contacts[k]] = static_cast<int>(k);
  }
  return buildIsland(problem, offsets, contacts, island_of, position);
}

IslandSolver::IslandSolver(const SolveContext& ctx, Islands islands) {
  const Problem& problem = *ctx.problem;
  const SolverParams& params = *ctx.params;
  islands_.resize(islands.contacts.size());
  // Per-island tolerances. The residual is |e| / |d_free| (1 for d_free = 0); the whole
  // problem meets tol when Σ |e_i|² <= tol² |d_free|², which holds when island i meets
  // |e_i| <= tol |d_free| w_i with Σ w_i² <= 1. w_i² = ½ |d_free_i|² / |d_free|² + ½ / k
  // (k islands): at most √2 tighter than the island's own relative tolerance, and an island
  // whose d_free is tiny (or zero) is not asked for a relative accuracy it cannot reach.
  std::vector<double> norms(islands_.size());
  std::vector<int> position(problem.contacts.size());
  for (const auto& list : islands.contacts)
    for (std::size_t k = 0; k < list.size(); ++k) position[list[k]] = static_cast<int>(k);
  for (std::size_t k = 0; k < islands_.size(); ++k) {
    Island& isl = islands_[k];
    isl.contacts = std::move(islands.contacts[k]);
    isl.problem = buildIsland(problem, ctx.offsets, isl.contacts, islands.island_of, position);
    norms[k] = isl.problem.d_free.stableNorm();
    isl.rows.reserve(isl.problem.d_free.size());
    for (int i : isl.contacts)
      for (int r = ctx.offsets[i]; r < ctx.offsets[i + 1]; ++r) isl.rows.push_back(r);
  }
  const double whole = problem.d_free.stableNorm();
  const double scale = whole > 0.0 && std::isfinite(whole) ? whole : 1.0;
  for (std::size_t k = 0; k < islands_.size(); ++k) {
    Island& isl = islands_[k];
    isl.params = params;
    if (params.stopping_rule == StoppingRule::kResidual) {
      const double share = norms[k] / scale;
      const double w2 = 0.5 * share * share + 0.5 / count();
      const double own_scale = norms[k] > 0.0 ? norms[k] : 1.0;
      isl.params.tolerance = params.tolerance * scale * std::sqrt(w2) / own_scale;
    }
    isl.weight = (norms[k] > 0.0 ? norms[k] : 1.0) / scale;
    isl.tolerance = isl.params.tolerance;
    SolveContext& c = isl.ctx;
    c.problem = &isl.problem;
    c.params = &isl.params;
    c.offsets = isl.problem.rowOffsets();
    c.regularization = ctx.regularization;
    c.has_deadline = ctx.has_deadline;
    c.deadline = ctx.deadline;
    c.mu.reserve(isl.contacts.size());
    for (int i : isl.contacts) c.mu.push_back(ctx.mu[i]);
    c.ignored.assign(isl.contacts.size(), false);
  }
  if (params.stopping_rule == StoppingRule::kResidual && count() > 1) {
    std::size_t largest = 0, total = 0;
    for (std::size_t k = 0; k < islands_.size(); ++k) {
      total += islands_[k].rows.size();
      if (islands_[k].rows.size() > islands_[largest].rows.size()) largest = k;
    }
    if (2 * islands_[largest].rows.size() > total) dominant_ = static_cast<int>(largest);
  }
}

// The whole problem meets tol when Σ (e_i w_i)² <= tol² (e_i each island's relative residual,
// w_i its weight). Once the other islands are solved their sum is known, and usually below
// their shares (a Gauss-Seidel sweep overshoots its target, a one-contact island is solved
// exactly): the dominant island may use what is left, never less than its own share.
double IslandSolver::dominantTolerance(const SolverParams& params) const {
  const Island& dom = islands_[dominant_];
  double used = 0.0;
  for (int k = 0; k < count(); ++k) {
    if (k == dominant_) continue;
    const double e = islands_[k].report.solver_error * islands_[k].weight;
    if (!std::isfinite(e)) return dom.tolerance;
    used += e * e;
  }
  const double left = params.tolerance * params.tolerance - used;
  if (!(left > 0.0)) return dom.tolerance;
  return std::max(dom.tolerance, std::sqrt(left) / dom.weight);
}

KernelReport IslandSolver::run(const SolveContext& ctx, const IslandKernel& kernel, Eigen::VectorXd& lambda,
                               int threads) {
  for (Island& isl : islands_) {
    for (std::size_t k = 0; k < isl.contacts.size(); ++k) isl.ctx.ignored[k] = ctx.ignored[isl.contacts[k]];
    isl.lambda = lambda(isl.rows);
  }
  std::vector<std::exception_ptr> errors(islands_.size());
  // The dominant island (more rows than all others together) runs last, with the tolerance
  // the others left unused (dominantTolerance); the others in order, or on the workers.
  const int last = dominant_;
  const std::function<void(int)> task = [&](int k) {
    if (last >= 0 && k >= last) ++k;  // the dominant island is not among the first tasks
    try {
      islands_[k].report = kernel(islands_[k].ctx, islands_[k].lambda);
    } catch (...) {
      errors[k] = std::current_exception();
    }
  };
  const int first_tasks = last >= 0 ? count() - 1 : count();
  // Below kParallelMinRows rows, waking a worker costs more than the islands' solves.
  if (threads <= 1 || first_tasks <= 1 || static_cast<int>(ctx.offsets.back()) < kParallelMinRows) {
    for (int k = 0; k < first_tasks; ++k) task(k);
  } else {
    ThreadPool::instance().run(first_tasks, threads, task);
  }
  for (const std::exception_ptr& e : errors)
    if (e) std::rethrow_exception(e);
  if (last >= 0) {
    Island& isl = islands_[last];
    isl.params.tolerance = dominantTolerance(*ctx.params);
    try {
      isl.report = kernel(isl.ctx, isl.lambda);
    } catch (...) {
      isl.params.tolerance = isl.tolerance;
      throw;
    }
    isl.params.tolerance = isl.tolerance;
  }

  // The island whose report speaks for the solve: the worst status, then the most
  // iterations. Its report is copied whole (message and any per-kernel detail).
  const Island* worst = &islands_.front();
  for (const Island& isl : islands_) {
    const KernelReport& r = isl.report;
    if (severity(r.status) > severity(worst->report.status) ||
        (severity(r.status) == severity(worst->report.status) && r.iterations > worst->report.iterations))
      worst = &isl;
  }
  KernelReport out = worst->report;
  out.history.clear();
  // auto's path: the island that took longest, which the solve's time is mostly made of (the
  // one with the most iterations had read "auto:nlgs" on Capsules-i100-1090 at 1e-6, where a
  // 177-row island's nlgs->apgd->newton took 1.6 of the 3.4 ms).
  const Island* slowest = worst;
  double slowest_seconds = -1.0;
  for (const Island& isl : islands_) {
    double seconds = 0.0;
    for (const auto& stage : isl.report.stages) seconds += stage.second;
    if (!isl.report.stages.empty() && seconds > slowest_seconds) {
      slowest = &isl;
      slowest_seconds = seconds;
    }
  }
  if (slowest != worst) out.stages = slowest->report.stages;
  out.message = globalContactNames(out.message, worst->contacts);
  bool friction_model_set = false;
  out.total_iterations = 0;
  for (const Island& isl : islands_) {
    lambda(isl.rows) = isl.lambda;
    out.solver_error = std::max(out.solver_error, isl.report.solver_error);
    out.iterations = std::max(out.iterations, isl.report.iterations);
    out.total_iterations += isl.report.iterations;
    if (!friction_model_set && isl.ctx.hasFriction()) {
      out.friction_model = isl.report.friction_model;
      friction_model_set = true;
    }
  }
  // Residuals are |e_i| / |d_free_i|: the whole problem's is the weighted 2-norm of them.
  if (ctx.params->stopping_rule == StoppingRule::kResidual) {
    double sum = 0.0;
    for (const Island& isl : islands_) {
      const double e = isl.report.solver_error * isl.weight;
      sum += e * e;
    }
    out.solver_error = std::sqrt(sum);
  }
  return out;
}

}  // namespace lcp_contact_solver::core
