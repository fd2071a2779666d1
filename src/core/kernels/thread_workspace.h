// A kernel's scratch storage kept per thread between solves. A microsecond solve (a 4-row
// LCP, a small island) spent a quarter of its time in malloc and free; vectors and matrices
// assigned in place keep their storage from one solve to the next. The n x n arrays of a
// factorization or a tableau (newton's Newton matrix and copy of W, the active-set path's W
// and W_AA, Lemke's M and B⁻¹) are vectors whose capacity survives a change of size, kept up
// to kKeptDenseRows: freed, a megabyte array goes back to the system when it tops the heap,
// and each of its 4 KB pages faults again when the next solve writes it
// (bench/storage_stream.cpp: a stream of 700-row LCPs faulted 1 900 pages per solve, 53 ms
// against 23 ms kept, on this VM). Kept, such an array holds at most 8 MB per thread. A
// problem above the lease's bound gets a workspace of its own, and so does a nested use on
// the same thread.
#pragma once

#include <memory>

namespace lcp_contact_solver::core {

constexpr int kKeptDenseRows = 1024;

template <typename Workspace, int kMaxRows>
class WorkspaceLease {
 public:
  explicit WorkspaceLease(int rows) {
    thread_local Workspace kept;
    thread_local bool kept_in_use = false;
    if (rows <= kMaxRows && !kept_in_use) {
      workspace_ = &kept;
      in_use_ = &kept_in_use;
      kept_in_use = true;
    } else {
      own_ = std::make_unique<Workspace>();
      workspace_ = own_.get();
    }
  }
  ~WorkspaceLease() {
    if (in_use_ != nullptr) *in_use_ = false;
  }
  WorkspaceLease(const WorkspaceLease&) = delete;
  WorkspaceLease& operator=(const WorkspaceLease&) = delete;
  Workspace& operator*() const { return *workspace_; }

 private:
  Workspace* workspace_ = nullptr;
  std::unique_ptr<Workspace> own_;
  bool* in_use_ = nullptr;
};

}  // namespace lcp_contact_solver::core
