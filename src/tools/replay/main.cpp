// rosrun lcp_contact_solver replay IN.bag [--out OUT.bag] [--csv STATS.csv] [name=value ...]
// Offline replay of recorded contacts/compliance through the node's solve path; see
// replay_command.h and docs/TOOLS.md ("Replaying recorded traffic").
#include "replay/replay_command.h"

#include <iostream>
#include <string>
#include <vector>

int main(int argc, char** argv) {
  const std::vector<std::string> args(argv + 1, argv + argc);
  return lcp_contact_solver_ros::runReplayCommand(args, std::cout, std::cerr);
}
