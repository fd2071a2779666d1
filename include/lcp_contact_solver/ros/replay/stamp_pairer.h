// Contact arrays and compliances paired by stamp, as the node's ExactTime synchronizer pairs them.
#pragma once

#include <lcp_contact_solver/Compliance.h>
#include <lcp_contact_solver/ContactArray.h>
#include <ros/time.h>

#include <cstddef>
#include <map>
#include <vector>

namespace lcp_contact_solver_ros {

// Pairs contact arrays with compliances by exact header.stamp, emitting a pair when its
// second message arrives, like message_filters' ExactTime policy (which is what the node
// uses). Messages that never find a partner stay in the pairer; nothing is dropped for
// age or queue length (a bag is complete, unlike a live topic).
class StampPairer {
 public:
  using ContactsPtr = lcp_contact_solver::ContactArray::ConstPtr;
  using CompliancePtr = lcp_contact_solver::Compliance::ConstPtr;
  struct Pair {
    ContactsPtr contacts;
    CompliancePtr compliance;
  };

  // True when `contacts` completes a pair (then written to *pair). A second message of
  // the same topic and stamp replaces the waiting one.
  bool addContacts(const ContactsPtr& contacts, Pair* pair);
  bool addCompliance(const CompliancePtr& compliance, Pair* pair);

  // Contact arrays still waiting for their compliance, in stamp order.
  std::vector<ContactsPtr> waitingContacts() const;
  std::size_t waitingCompliance() const { return compliance_.size(); }
  // Messages replaced by a later one with the same stamp.
  std::size_t duplicates() const { return duplicates_; }

 private:
  std::map<ros::Time, ContactsPtr> contacts_;
  std::map<ros::Time, CompliancePtr> compliance_;
  std::size_t duplicates_ = 0;
};

}  // namespace lcp_contact_solver_ros
