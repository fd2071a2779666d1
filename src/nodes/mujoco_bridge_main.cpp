// The MuJoCo bridge: see include/lcp_contact_solver/ros/sim/mujoco_bridge_node.h.
#include "lcp_contact_solver/ros/sim/mujoco_bridge_node.h"
#include "lcp_contact_solver/ros/sim/simulator_main.h"

int main(int argc, char** argv) {
  return lcp_contact_solver_ros::runSimulatorMain<lcp_contact_solver_ros::MujocoBridgeNode,
                                                  std::runtime_error>(argc, argv, "mujoco_bridge",
                                                                      "MuJoCo bridge stopped: ");
}
