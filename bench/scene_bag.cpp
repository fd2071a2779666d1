// Writes a bag of consecutive contact problems of a generated scene (bench/scene_problems.h:
// a brick pyramid or a sphere pile of any size), for the soak feeder and other replays that
// need more contacts than the shipped scenes give. A benchmark tool, never a test.
//
//   scene_bag --family sphere_pile --size 100 --first 150 --count 300 --out FILE.bag
//
// The scene is stepped in-process (nlgs at 1e-6, the bodies move as in a simulation); from
// step `first` on, each step's ContactArray and Compliance (the scene simulator node's own
// conversion, block-sparse W, contact ids stable across steps) are written with the stamp of
// the simulated time, on /contacts and /compliance. Prints contacts and rows per step.
#include "scene_problems.h"

#include "lcp_contact_solver/ros/msg_conversion/scene_msg_conversion.h"
#include "lcp_contact_solver/scene/scene_simulator.h"

#include <rosbag/bag.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cstdio>
#include <exception>
#include <string>

namespace sc = lcp_contact_solver::scene;
namespace lros = lcp_contact_solver_ros;

int main(int argc, char** argv) {
  CLI::App app{"scene_bag: consecutive contact problems of a generated scene, as a bag"};
  std::string family = "sphere_pile", out;
  int size = 100, first = 150, count = 300;
  app.add_option("--family", family, "box_pyramid or sphere_pile")->capture_default_str();
  app.add_option("--size", size, "bricks at the base, or balls")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--first", first, "steps simulated before the first one written")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  app.add_option("--count", count, "steps written")->capture_default_str()->check(CLI::PositiveNumber);
  app.add_option("--out", out, "the bag to write")->required();
  CLI11_PARSE(app, argc, argv);

  try {
    sc::SceneSimulator sim(lcs_bench::makeBenchScene(LCS_SCENES_DIR, family, size));
    for (int i = 0; i < first; ++i) sim.step();
    rosbag::Bag bag(out, rosbag::bagmode::Write);
    bag.setCompression(rosbag::compression::BZ2);
    int min_contacts = 1 << 30, max_contacts = 0, written = 0;
    for (int i = 0; i < count; ++i) {
      sim.step();
      const sc::StepProblem& step = sim.lastProblem();
      if (step.problem.contacts.empty()) continue;
      std_msgs::Header header;
      header.frame_id = "world";
      header.stamp = ros::Time(std::max(step.time, 1e-3));
      bag.write("/compliance", header.stamp, lros::toComplianceMsg(step, header));
      bag.write("/contacts", header.stamp, lros::toContactArrayMsg(step, header));
      const int n = static_cast<int>(step.problem.contacts.size());
      min_contacts = std::min(min_contacts, n);
      max_contacts = std::max(max_contacts, n);
      ++written;
    }
    bag.close();
    std::printf("scene_bag: %s_%d steps %d..%d: %d problems written to %s, %d to %d contacts\n",
                family.c_str(), size, first, first + count - 1, written, out.c_str(), min_contacts,
                max_contacts);
    return written > 0 ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "scene_bag: %s\n", e.what());
    return 1;
  }
}
