// Synthetic recordings written through the node's CycleSolver, a temporary folder and the
// replay command run in-process, shared by the test_replay*.cpp files.
#pragma once

#include "lcp_contact_solver/core/residual.h"
#include "lcp_contact_solver/core/solver_param_table.h"
#include "lcp_contact_solver/ros/node/cycle_solver.h"
#include "lcp_contact_solver/ros/node/solver_params_ros.h"
#include "lcp_contact_solver/ros/replay/answer_check.h"
#include "lcp_contact_solver/ros/replay/bag_replay.h"
#include "lcp_contact_solver/ros/replay/params_file.h"
#include "replay/replay_command.h"
#include "test_scene.h"

#include <gtest/gtest.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

namespace fs = std::filesystem;
namespace lcs = lcp_contact_solver;
using namespace lcp_contact_solver_ros;
using lcp_contact_solver::Compliance;
using lcp_contact_solver::ConstraintForces;
using lcp_contact_solver::ContactArray;
using lcp_contact_solver::SolverStats;
using lcp_contact_solver_test::makeScene;
using lcp_contact_solver_test::Scene;

namespace replay_test {

inline fs::path tmpDir() {
  static const fs::path dir = [] {
    fs::path d = fs::path(LCS_TEST_TMP_DIR) / ("test_replay_" + std::to_string(::getpid()));
    fs::create_directories(d);
    return d;
  }();
  return dir;
}

inline std::string tmpFile(const std::string& name) { return (tmpDir() / name).string(); }

// The bags and files written here go when the tests end.
class RemoveTmpDir : public ::testing::Environment {
 public:
  void TearDown() override {
    std::error_code ignored;
    fs::remove_all(tmpDir(), ignored);
  }
};
inline const ::testing::Environment* const kRemoveTmpDir =
    ::testing::AddGlobalTestEnvironment(new RemoveTmpDir);

// How a synthetic recording is written.
struct Recording {
  int cycles = 12;
  std::string prefix = "/";          // topic namespace
  bool compliance_first_odd = true;  // odd cycles: compliance recorded before contacts
  int unpaired_cycle = -1;           // this cycle's compliance is missing
  double force_scale = 1.0;          // recorded forces = solved forces × this (perturbation)
  bool with_outputs = true;          // record forces and stats
  double reference_scale = 0.0;      // > 0: "reference_forces" = solved forces × this (from outside)
  bool block_sparse = false;
  lcs::core::SolverParams params = defaultSolverParams();
};

// The test scene with cycle-dependent d_free (so warm starts matter), solved in order by
// the node's CycleSolver, written as a live recording would be: contacts and compliance
// at t, the node's forces and stats a little later.
inline Scene cycleScene(int k, bool block_sparse) {
  const ros::Time stamp(100.0 + 0.01 * k);
  Scene s = makeScene(7000, stamp, block_sparse);
  for (auto& c : s.contacts.contacts)
    for (double& d : c.d_free) d *= 1.0 + 0.3 * std::sin(0.7 * k);
  return s;
}

inline void writeRecording(const std::string& path, const Recording& rec) {
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  bag.setCompression(rosbag::compression::LZ4);
  CycleSolver solver(rec.params);
  for (int k = 0; k < rec.cycles; ++k) {
    const Scene s = cycleScene(k, rec.block_sparse);
    const ros::Time t(1000.0 + 0.01 * k);
    const ros::Duration us(0, 1000);
    const bool skip_compliance = k == rec.unpaired_cycle;
    if (rec.compliance_first_odd && k % 2 == 1) {
      if (!skip_compliance) bag.write(rec.prefix + "compliance", t, s.compliance);
      bag.write(rec.prefix + "contacts", t + us, s.contacts);
    } else {
      bag.write(rec.prefix + "contacts", t, s.contacts);
      if (!skip_compliance) bag.write(rec.prefix + "compliance", t + us, s.compliance);
    }
    if (skip_compliance || (!rec.with_outputs && rec.reference_scale <= 0.0)) continue;
    CycleOutput out = solver.solve(s.contacts, s.compliance);
    out.stats.forces_published = out.has_forces;
    if (rec.reference_scale > 0.0 && out.has_forces) {
      ConstraintForces reference = out.forces;
      for (auto& f : reference.forces)
        for (double& l : f.lambda) l *= rec.reference_scale;
      bag.write(rec.prefix + "reference_forces", t + us + us, reference);
    }
    if (!rec.with_outputs) continue;
    if (out.has_forces) {
      for (auto& f : out.forces.forces)
        for (double& l : f.lambda) l *= rec.force_scale;
      bag.write(rec.prefix + "constraint_forces", t + us + us, out.forces);
    }
    bag.write(rec.prefix + "contact_solver/stats", t + us + us, out.stats);
  }
  bag.close();
}

inline ReplayResult replayFile(const std::string& path,
                               const lcs::core::SolverParams& params = defaultSolverParams(),
                               ReplayOptions options = ReplayOptions()) {
  options.bag = path;
  options.keep_cycles = true;
  return replayBag(options, params);
}

inline int runCommand(const std::vector<std::string>& args, std::string* out_text = nullptr,
                      std::string* err_text = nullptr) {
  std::ostringstream out, err;
  const int code = runReplayCommand(args, out, err);
  if (out_text) *out_text = out.str();
  if (err_text) *err_text = err.str();
  return code;
}

inline std::vector<std::string> readLines(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

inline std::size_t countMessages(const std::string& path, const std::string& topic) {
  rosbag::Bag bag(path, rosbag::bagmode::Read);
  rosbag::View view(bag, rosbag::TopicQuery(topic));
  return view.size();
}

}  // namespace replay_test
