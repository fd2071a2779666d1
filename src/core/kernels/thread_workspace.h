// A kernel's scratch storage kept per thread between solves. A microsecond solve (a 4-row
// LCP, a small island) spent a quarter of its time in malloc and free; vectors and matrices
// assigned in place keep their storage from one solve to the next. A problem above
// kKeptWorkspaceRows rows gets a workspace of its own (allocation is negligible there, and a
// kept dense matrix would outlive the solve), and so does a nested use on the same thread.
#pragma once

#include <memory>

namespace lcp_contact_solver::core {

constexpr int kKeptWorkspaceRows = 64;

template <typename Workspace>
class WorkspaceLease {
 public:
  explicit WorkspaceLease(int rows) {
    thread_local Workspace kept;
    thread_local bool kept_in_use = false;
    if (rows <= kKeptWorkspaceRows && !kept_in_use) {
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
