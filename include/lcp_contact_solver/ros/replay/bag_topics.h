// Which topic of a bag holds which input or recorded output of the replay (bag_replay.h):
// the one named, else the default name, else the only topic of the message type.
#pragma once

#include <ros/message_traits.h>
#include <rosbag/structures.h>

#include <string>
#include <vector>

namespace lcp_contact_solver_ros {

// "/name" for "name" or "/name" (bags store resolved names, users type either).
std::string normalizeTopic(const std::string& name);

// Finds the topic of message type `type` (md5 sum `md5`): `requested` (exact, leading '/'
// optional), else the default name, else the only topic of that type. "" when there is none
// and it is optional. `exclude` (may be empty) is never chosen by name or type. `option`
// names the command-line option that chooses the topic (in notes and errors).
std::string chooseTopic(const std::vector<const rosbag::ConnectionInfo*>& connections,
                        const std::string& type, const std::string& md5, const std::string& requested,
                        const std::string& default_name, const std::string& option, bool required,
                        std::vector<std::string>* notes, std::string* error, const std::string& exclude = "");

// The same for message type M.
template <typename M>
std::string chooseTopic(const std::vector<const rosbag::ConnectionInfo*>& connections,
                        const std::string& requested, const std::string& default_name,
                        const std::string& option, bool required, std::vector<std::string>* notes,
                        std::string* error, const std::string& exclude = "") {
  return chooseTopic(connections, ros::message_traits::DataType<M>::value(),
                     ros::message_traits::MD5Sum<M>::value(), requested, default_name, option, required,
                     notes, error, exclude);
}

}  // namespace lcp_contact_solver_ros
