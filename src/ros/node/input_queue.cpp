#include "lcp_contact_solver/ros/node/input_queue.h"

#include <sstream>

namespace lcp_contact_solver_ros {

bool parseOverloadPolicy(const std::string& name, OverloadPolicy* policy) {
  if (name == "drop_oldest") {
    *policy = OverloadPolicy::kDropOldest;
  } else if (name == "queue") {
    *policy = OverloadPolicy::kQueue;
  } else {
    return false;
  }
  return true;
}

const char* overloadPolicyName(OverloadPolicy policy) {
  return policy == OverloadPolicy::kQueue ? "queue" : "drop_oldest";
}

InputQueue::InputQueue(OverloadPolicy policy, std::size_t capacity)
    : policy_(policy), capacity_(capacity < 1 ? 1 : capacity) {}

void InputQueue::addContacts(const lcp_contact_solver::ContactArray::ConstPtr& contacts,
                             const ros::Time& now) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++counts_.arrays_received;
  if (contacts->header.stamp < last_contacts_stamp_) forgetOldRunLocked(contacts->header.stamp, true);
  last_contacts_stamp_ = contacts->header.stamp;
  auto it = pending_.find(contacts->header.stamp);
  if (it != pending_.end() && it->second.contacts) {
    // The same stamp again before its compliance (a simulator that restarted): the first
    // array can no longer be told apart from the second, so it is given up.
    ++counts_.unpaired;
    dropped_.push_back({it->second.contacts->header,
                        "superseded by a later ContactArray with the same stamp "
                        "before its Compliance came",
                        false});
    it->second.contacts = contacts;
    it->second.first_arrival = now;
    return;
  }
  if (it == pending_.end())
    it = pending_.emplace(contacts->header.stamp, Pending{nullptr, nullptr, now}).first;
  it->second.contacts = contacts;
  if (it->second.compliance) completeLocked(it);
}

void InputQueue::addCompliance(const lcp_contact_solver::Compliance::ConstPtr& compliance,
                               const ros::Time& now) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++counts_.compliances_received;
  if (compliance->header.stamp < last_compliance_stamp_) forgetOldRunLocked(compliance->header.stamp, false);
  last_compliance_stamp_ = compliance->header.stamp;
  auto it = pending_.find(compliance->header.stamp);
  if (it == pending_.end())
    it = pending_.emplace(compliance->header.stamp, Pending{nullptr, nullptr, now}).first;
  if (it->second.compliance) ++counts_.compliances_unpaired;  // a duplicate: the newer one counts
  it->second.compliance = compliance;
  if (it->second.contacts) completeLocked(it);
}

void InputQueue::completeLocked(std::map<ros::Time, Pending>::iterator it) {
  ready_.push_back({it->second.contacts, it->second.compliance, ros::WallTime::now()});
  pending_.erase(it);
  if (policy_ == OverloadPolicy::kQueue && ready_.size() > capacity_) {
    std::ostringstream reason;
    reason << "dropped: the node was behind and its queue (overload queue, queue_size " << capacity_
           << ") was full";
    dropLocked(ready_.front(), reason.str());
    ready_.pop_front();
  }
  ready_cv_.notify_one();
}

void InputQueue::forgetOldRunLocked(const ros::Time& stamp, bool contacts_topic) {
  const ros::Time& last = contacts_topic ? last_contacts_stamp_ : last_compliance_stamp_;
  for (auto it = pending_.begin(); it != pending_.end();) {
    const Pending& p = it->second;
    const bool has_this_half =
        contacts_topic ? static_cast<bool>(p.contacts) : static_cast<bool>(p.compliance);
    // A half of this topic came before the jump: old. A half of the other topic at a later
    // stamp than the new run's first: old too (the new run has not got that far).
    if (!has_this_half && it->first <= stamp) {
      ++it;
      continue;
    }
    if (p.contacts) {
      ++counts_.unpaired;
      std::ostringstream reason;
      reason << "given up: stamps on " << (contacts_topic ? "contacts" : "compliance") << " jumped back from "
             << last << " to " << stamp << " (simulator restart?) before its Compliance came";
      dropped_.push_back({p.contacts->header, reason.str(), false});
    } else {
      ++counts_.compliances_unpaired;
    }
    it = pending_.erase(it);
  }
  ready_cv_.notify_one();  // take() reports the given-up arrays
}

void InputQueue::dropLocked(const InputPair& pair, const std::string& reason) {
  ++counts_.dropped;
  dropped_.push_back({pair.contacts->header, reason, true});
}

bool InputQueue::take(std::chrono::milliseconds timeout, InputPair* pair,
                      std::vector<UnsolvedInput>* dropped) {
  std::unique_lock<std::mutex> lock(mutex_);
  ready_cv_.wait_for(lock, timeout, [this] { return stopped_ || !ready_.empty() || !dropped_.empty(); });
  if (policy_ == OverloadPolicy::kDropOldest && ready_.size() > 1) {
    std::ostringstream reason;
    reason << "dropped: the node was behind (overload drop_oldest: " << ready_.size() - 1
           << " older complete pairs skipped for the newest)";
    while (ready_.size() > 1) {
      dropLocked(ready_.front(), reason.str());
      ready_.pop_front();
    }
  }
  dropped->insert(dropped->end(), dropped_.begin(), dropped_.end());
  dropped_.clear();
  if (stopped_ || ready_.empty()) return false;
  *pair = ready_.front();
  ready_.pop_front();
  ++counts_.taken;
  return true;
}

std::vector<UnsolvedInput> InputQueue::takeExpired(const ros::Time& now, double window) {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<UnsolvedInput> expired;
  for (auto it = pending_.begin(); it != pending_.end();) {
    if ((now - it->second.first_arrival).toSec() <= window) {
      ++it;
      continue;
    }
    if (it->second.contacts) {
      ++counts_.unpaired;
      std::ostringstream reason;
      reason << "no compliance with stamp " << it->first << " arrived within " << window << " s";
      expired.push_back({it->second.contacts->header, reason.str(), false});
    } else {
      ++counts_.compliances_unpaired;
    }
    it = pending_.erase(it);
  }
  return expired;
}

void InputQueue::stop() {
  std::lock_guard<std::mutex> lock(mutex_);
  stopped_ = true;
  ready_cv_.notify_all();
}

InputCounts InputQueue::counts() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return counts_;
}

}  // namespace lcp_contact_solver_ros
