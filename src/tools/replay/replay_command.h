// The `replay` command (src/tools/replay/main.cpp): offline replay of a recorded bag through
// the node's solve path (lcp_contact_solver/ros/replay/bag_replay.h); kept out of the main
// so the tests can run it with string streams.
#pragma once

#include <ostream>
#include <string>
#include <vector>

namespace lcp_contact_solver_ros {

// The command line of `replay` (argv without the program name); returns the exit code:
// 0 done, 1 the comparison exceeds --tolerance-compare, 2 usage or input error.
int runReplayCommand(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

}  // namespace lcp_contact_solver_ros
