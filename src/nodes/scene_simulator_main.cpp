// The example simulator node: see include/lcp_contact_solver/ros/sim/scene_simulator_node.h.
#include "lcp_contact_solver/ros/sim/scene_simulator_node.h"
#include "lcp_contact_solver/ros/sim/simulator_main.h"
#include "lcp_contact_solver/scene/scene_params.h"

int main(int argc, char** argv) {
  return lcp_contact_solver_ros::runSimulatorMain<lcp_contact_solver_ros::SceneSimulatorNode,
                                                  lcp_contact_solver::scene::SceneError>(
      argc, argv, "scene_simulator", "Cannot load the scene: ");
}
