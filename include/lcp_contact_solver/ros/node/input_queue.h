// The node's inputs between their arrival and their solve: pairs each ContactArray with the
// Compliance of the same stamp, holds the complete pairs for the solver thread, and accounts
// for every array. Each one ends as exactly one outcome: solved (taken by the solver),
// unpaired (its compliance did not come within the window), or dropped because the node was
// behind (policy below), so "no_compliance" never stands for the node's own backlog.
//
// The subscriber callbacks only call add*(), which is cheap, so roscpp's own queues do not
// overflow under load: the backlog lives here, where it is counted.
#pragma once

#include <lcp_contact_solver/Compliance.h>
#include <lcp_contact_solver/ContactArray.h>
#include <ros/time.h>

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <map>
#include <mutex>
#include <string>
#include <vector>

namespace lcp_contact_solver_ros {

enum class OverloadPolicy {
  kDropOldest,  // solve the newest complete pair; the older ones waiting are dropped
  kQueue,       // solve in arrival order; past `capacity` waiting pairs the oldest is dropped
};
// "drop_oldest", "queue"; false for an unknown name.
bool parseOverloadPolicy(const std::string& name, OverloadPolicy* policy);
const char* overloadPolicyName(OverloadPolicy policy);

struct InputPair {
  lcp_contact_solver::ContactArray::ConstPtr contacts;
  lcp_contact_solver::Compliance::ConstPtr compliance;
  ros::WallTime complete;  // arrival of the later half
};

// An array that will not be solved, and why.
struct UnsolvedInput {
  std_msgs::Header header;
  std::string reason;
  bool behind = false;  // true: dropped because the node was behind; false: unpaired
};

struct InputCounts {
  std::uint64_t arrays_received = 0;
  std::uint64_t compliances_received = 0;
  std::uint64_t taken = 0;                 // handed to the solver (then solved or rejected there)
  std::uint64_t unpaired = 0;              // no compliance within the window
  std::uint64_t dropped = 0;               // the node was behind
  std::uint64_t compliances_unpaired = 0;  // a compliance whose array never came
  std::uint64_t waiting() const { return arrays_received - taken - unpaired - dropped; }
};

class InputQueue {
 public:
  InputQueue(OverloadPolicy policy, std::size_t capacity);

  // A stamp older than the topic's previous one means a restart: what the old run left
  // waiting is given up first (arrays as unpaired, reason "jumped back"), except halves of the
  // other topic at stamps <= the new one, which the new run may already have sent.
  // `now` is the arrival time the window counts from (the node passes wall time).
  void addContacts(const lcp_contact_solver::ContactArray::ConstPtr& contacts, const ros::Time& now);
  void addCompliance(const lcp_contact_solver::Compliance::ConstPtr& compliance, const ros::Time& now);

  // Waits up to `timeout` for a complete pair; true with it in `pair`. Pairs that the policy
  // drops on the way are appended to `dropped`. False on timeout or after stop().
  bool take(std::chrono::milliseconds timeout, InputPair* pair, std::vector<UnsolvedInput>* dropped);
  // Arrays waiting longer than `window` seconds for their compliance, removed; compliances
  // waiting as long for their array are removed and counted.
  std::vector<UnsolvedInput> takeExpired(const ros::Time& now, double window);
  // Wakes a waiting take() for good.
  void stop();

  InputCounts counts() const;
  OverloadPolicy policy() const { return policy_; }

 private:
  struct Pending {
    lcp_contact_solver::ContactArray::ConstPtr contacts;
    lcp_contact_solver::Compliance::ConstPtr compliance;
    ros::Time first_arrival;
  };
  void completeLocked(std::map<ros::Time, Pending>::iterator it);
  // Stamps on one topic went back to `stamp` (the simulator restarted): gives up what the
  // old run left waiting, so no new half pairs with an old one.
  void forgetOldRunLocked(const ros::Time& stamp, bool contacts_topic);
  void dropLocked(const InputPair& pair, const std::string& reason);

  const OverloadPolicy policy_;
  const std::size_t capacity_;
  mutable std::mutex mutex_;
  std::condition_variable ready_cv_;
  std::map<ros::Time, Pending> pending_;  // by stamp: one half has come
  std::deque<InputPair> ready_;           // complete, in order of completion
  std::vector<UnsolvedInput> dropped_;    // dropped by add*() (queue policy), for take()
  InputCounts counts_;
  bool stopped_ = false;
  // The newest stamp seen on each topic (messages of one publisher arrive in order).
  ros::Time last_contacts_stamp_;
  ros::Time last_compliance_stamp_;
};

}  // namespace lcp_contact_solver_ros
