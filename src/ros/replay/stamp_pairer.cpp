#include "lcp_contact_solver/ros/replay/stamp_pairer.h"

namespace lcp_contact_solver_ros {

bool StampPairer::addContacts(const ContactsPtr& contacts, Pair* pair) {
  const ros::Time stamp = contacts->header.stamp;
  const auto partner = compliance_.find(stamp);
  if (partner != compliance_.end()) {
    pair->contacts = contacts;
    pair->compliance = partner->second;
    compliance_.erase(partner);
    return true;
  }
  auto [it, inserted] = contacts_.emplace(stamp, contacts);
  if (!inserted) {
    ++duplicates_;
    it->second = contacts;
  }
  return false;
}

bool StampPairer::addCompliance(const CompliancePtr& compliance, Pair* pair) {
  const ros::Time stamp = compliance->header.stamp;
  const auto partner = contacts_.find(stamp);
  if (partner != contacts_.end()) {
    pair->contacts = partner->second;
    pair->compliance = compliance;
    contacts_.erase(partner);
    return true;
  }
  auto [it, inserted] = compliance_.emplace(stamp, compliance);
  if (!inserted) {
    ++duplicates_;
    it->second = compliance;
  }
  return false;
}

std::vector<StampPairer::ContactsPtr> StampPairer::waitingContacts() const {
  std::vector<ContactsPtr> out;
  for (const auto& entry : contacts_) out.push_back(entry.second);
  return out;
}

}  // namespace lcp_contact_solver_ros
