// The live path against the offline path: `rosbag play --clock` (replay_live.test) feeds a
// recorded bag into the running contact_solver node; this node collects what the node
// publishes and compares it, cycle by cycle, with the offline replay of the same bag
// (replay.h) with the same parameters: forces within 1e-9 relative, same iteration counts,
// same status, same order of cycles (the warm start carries across cycles by contact id,
// so the order matters).
#include "lcp_contact_solver/ros/node/solver_params_ros.h"
#include "lcp_contact_solver/ros/replay/bag_replay.h"
#include "lcp_contact_solver/ros/replay/params_file.h"
#include "replay/summary.h"

#include <gtest/gtest.h>
#include <lcp_contact_solver/Compliance.h>
#include <lcp_contact_solver/ConstraintForces.h>
#include <lcp_contact_solver/ContactArray.h>
#include <lcp_contact_solver/SolverStats.h>
#include <ros/ros.h>
#include <std_srvs/SetBool.h>
#include <xmlrpcpp/XmlRpcValue.h>

#include <map>
#include <set>
#include <string>
#include <vector>

namespace lcs = lcp_contact_solver;
using namespace lcp_contact_solver_ros;
using lcp_contact_solver::ConstraintForces;
using lcp_contact_solver::SolverStats;

namespace {

constexpr double kRelativeTolerance = 1e-9;

template <typename Predicate>
bool waitFor(Predicate done, double timeout) {
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(timeout);
  while (ros::ok() && ros::WallTime::now() < end) {
    ros::spinOnce();
    if (done()) return true;
    ros::WallDuration(0.01).sleep();
  }
  return done();
}

// Nodes subscribed to `topic`, from the master.
std::set<std::string> subscribersOf(const std::string& topic) {
  XmlRpc::XmlRpcValue request, response, payload;
  request[0] = ros::this_node::getName();
  std::set<std::string> nodes;
  if (!ros::master::execute("getSystemState", request, response, payload, false)) return nodes;
  XmlRpc::XmlRpcValue& subscribers = payload[1];
  for (int i = 0; i < subscribers.size(); ++i) {
    if (static_cast<std::string>(subscribers[i][0]) != topic) continue;
    for (int j = 0; j < subscribers[i][1].size(); ++j)
      nodes.insert(static_cast<std::string>(subscribers[i][1][j]));
  }
  return nodes;
}

}  // namespace

TEST(ReplayLive, LiveNodeMatchesOfflineReplay) {
  ros::NodeHandle nh, pnh("~");
  std::string bag, params_file, solver_node = "/contact_solver", player = "/player";
  ASSERT_TRUE(pnh.getParam("bag", bag));
  ASSERT_TRUE(pnh.getParam("params_file", params_file));
  pnh.getParam("solver_node", solver_node);
  pnh.getParam("player", player);
  double timeout = 40.0;
  pnh.getParam("timeout", timeout);

  // The offline path first: what the node must produce.
  lcs::core::SolverParams params = defaultSolverParams();
  ASSERT_EQ(loadParamsFile(params_file, &params), "");
  ReplayOptions options;
  options.bag = bag;
  options.keep_cycles = true;
  const ReplayResult offline = replayBag(options, params);
  ASSERT_EQ(offline.error, "");
  ASSERT_GT(offline.cycles_kept.size(), 0u);
  // (Whether that is still what the node produced when the bag was recorded is test_replay's
  // concern; here the recording is only the input.)
  std::printf("offline replay of %s:\n%s", bag.c_str(), formatSummary(offline).c_str());

  // The live path: subscribe to the node's outputs, then let the player go.
  std::vector<SolverStats> live_stats;  // in arrival order
  std::map<ros::Time, ConstraintForces> live_forces;
  ros::Subscriber forces_sub = nh.subscribe<ConstraintForces>(
      offline.out_forces_topic, 1000,
      [&live_forces](const ConstraintForces::ConstPtr& msg) { live_forces[msg->header.stamp] = *msg; });
  ros::Subscriber stats_sub = nh.subscribe<SolverStats>(
      offline.out_stats_topic, 1000,
      [&live_stats](const SolverStats::ConstPtr& msg) { live_stats.push_back(*msg); });
  // What the player sends (to tell a lost input from a lost output when something is missing).
  std::vector<ros::Time> played_contacts, played_compliance;
  ros::Subscriber contacts_sub = nh.subscribe<lcp_contact_solver::ContactArray>(
      offline.contacts_topic, 1000,
      [&played_contacts](const lcp_contact_solver::ContactArray::ConstPtr& msg) {
        played_contacts.push_back(msg->header.stamp);
      });
  ros::Subscriber compliance_sub = nh.subscribe<lcp_contact_solver::Compliance>(
      offline.compliance_topic, 1000,
      [&played_compliance](const lcp_contact_solver::Compliance::ConstPtr& msg) {
        played_compliance.push_back(msg->header.stamp);
      });
  ASSERT_TRUE(
      waitFor([&] { return forces_sub.getNumPublishers() > 0 && stats_sub.getNumPublishers() > 0; }, 20.0))
      << "the contact solver's outputs never connected";
  ASSERT_TRUE(waitFor(
      [&] {
        return subscribersOf(offline.contacts_topic).count(solver_node) > 0 &&
               subscribersOf(offline.compliance_topic).count(solver_node) > 0;
      },
      20.0))
      << solver_node << " never subscribed to " << offline.contacts_topic << " and "
      << offline.compliance_topic;
  const std::string pause = player + "/pause_playback";
  ASSERT_TRUE(ros::service::waitForService(pause, ros::Duration(20.0))) << pause;
  ros::WallDuration(1.0).sleep();  // the player's --wait-for-subscribers covers its own connections
  std_srvs::SetBool resume;
  resume.request.data = false;
  ASSERT_TRUE(ros::service::call(pause, resume)) << pause;

  const std::size_t expected = offline.cycles_kept.size();
  const bool complete = waitFor([&] { return live_stats.size() >= expected; }, timeout);
  ros::WallDuration(0.5).sleep();  // anything beyond the expected cycles would be a fault
  ros::spinOnce();
  EXPECT_TRUE(complete) << "received stats of " << live_stats.size() << " of " << expected << " cycles";
  if (live_stats.size() != expected) {
    std::set<ros::Time> seen;
    for (const SolverStats& st : live_stats) seen.insert(st.header.stamp);
    std::string missing;
    for (const ReplayCycle& c : offline.cycles_kept)
      if (seen.count(c.stamp) == 0) missing += " " + std::to_string(c.stamp.toSec());
    std::string statuses;
    for (const SolverStats& st : live_stats)
      if (st.status_code != SolverStats::CONVERGED)
        statuses += " " + std::to_string(st.header.stamp.toSec()) + ":" + st.status;
    ADD_FAILURE() << "no stats for stamps" << missing << "; other statuses:" << statuses << "; this node saw "
                  << played_contacts.size() << " contact arrays and " << played_compliance.size()
                  << " compliances from the player";
  }
  EXPECT_EQ(live_stats.size(), expected);

  std::size_t forces_compared = 0;
  double max_relative = 0.0;
  for (std::size_t k = 0; k < std::min(expected, live_stats.size()); ++k) {
    const ReplayCycle& want = offline.cycles_kept[k];
    const SolverStats& got = live_stats[k];
    SCOPED_TRACE("cycle " + std::to_string(k) + " stamp " + std::to_string(want.stamp.toSec()));
    ASSERT_EQ(got.header.stamp, want.stamp) << "the node solved the cycles in another order";
    EXPECT_EQ(got.status_code, want.stats.status_code);
    EXPECT_EQ(got.iterations, want.stats.iterations);
    EXPECT_EQ(got.num_contacts, want.stats.num_contacts);
    EXPECT_EQ(got.num_rows, want.stats.num_rows);
    EXPECT_LE(relativeDifference(got.residual, want.stats.residual), kRelativeTolerance);
    EXPECT_EQ(got.forces_published, want.has_forces);
    const auto live = live_forces.find(want.stamp);
    ASSERT_EQ(live != live_forces.end(), want.has_forces);
    if (!want.has_forces) continue;
    const ForceDifference d = compareForces(live->second, want.forces);
    EXPECT_EQ(d.mismatch, "");
    EXPECT_LE(d.relative, kRelativeTolerance);
    max_relative = std::max(max_relative, d.relative);
    ++forces_compared;
  }
  EXPECT_EQ(forces_compared, offline.with_forces);
  std::printf("live vs offline: %zu cycles, %zu with forces, max relative force difference %.3g\n",
              live_stats.size(), forces_compared, max_relative);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_replay_live");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
