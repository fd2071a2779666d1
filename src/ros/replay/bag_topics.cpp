#include "lcp_contact_solver/ros/replay/bag_topics.h"

#include <set>

namespace lcp_contact_solver_ros {

namespace {

std::string joined(const std::vector<std::string>& items) {
  std::string out;
  for (const std::string& item : items) out += (out.empty() ? "" : ", ") + item;
  return out;
}

}  // namespace

std::string normalizeTopic(const std::string& name) {
  if (name.empty()) return name;
  const std::size_t start = name.find_first_not_of('/');
  return start == std::string::npos ? "/" : "/" + name.substr(start);
}

std::string chooseTopic(const std::vector<const rosbag::ConnectionInfo*>& connections,
                        const std::string& type, const std::string& md5, const std::string& requested,
                        const std::string& default_name, const std::string& option, bool required,
                        std::vector<std::string>* notes, std::string* error, const std::string& exclude) {
  std::set<std::string> all_topics, typed_topics;
  for (const rosbag::ConnectionInfo* c : connections) {
    all_topics.insert(c->topic);
    if (c->datatype == type && c->topic != exclude) typed_topics.insert(c->topic);
  }
  auto check = [&](const std::string& topic) -> std::string {
    for (const rosbag::ConnectionInfo* c : connections) {
      if (c->topic != topic) continue;
      if (c->datatype != type) {
        *error = "topic " + topic + " holds " + c->datatype + ", not " + type;
        return "";
      }
      if (c->md5sum != md5) {
        *error = "topic " + topic + " was recorded with another definition of " + type + " (md5 " +
                 c->md5sum + ", this build has " + md5 + ")";
        return "";
      }
    }
    return topic;
  };
  const std::string wanted = normalizeTopic(requested.empty() ? default_name : requested);
  for (const std::string& topic : all_topics)
    if (normalizeTopic(topic) == wanted && (topic != exclude || !requested.empty())) return check(topic);
  if (!requested.empty()) {
    *error = "no topic " + wanted + " in the bag (topics: " +
             joined(std::vector<std::string>(all_topics.begin(), all_topics.end())) + ")";
    return "";
  }
  if (typed_topics.size() == 1) {
    const std::string topic = *typed_topics.begin();
    notes->push_back("using " + topic + " (the only " + type + " topic; " + option + " chooses another)");
    return check(topic);
  }
  if (typed_topics.size() > 1) {
    *error = "several " + type + " topics (" +
             joined(std::vector<std::string>(typed_topics.begin(), typed_topics.end())) +
             "): choose one with " + option;
    return "";
  }
  if (required) *error = "no " + type + " topic in the bag (expected " + wanted + ")";
  return "";
}

}  // namespace lcp_contact_solver_ros
