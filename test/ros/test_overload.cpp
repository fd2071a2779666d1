// Overload: contact arrays come ten times faster than the node solves them. Every array the
// node received must end as exactly one outcome on /diagnostics (solved, rejected, unpaired,
// dropped because the node was behind), and none may be blamed on a missing compliance.
// The solves are made slow on purpose (~time_budget with an unreachable tolerance), so the
// sustainable rate is 1 / time_budget whatever the machine.
#include "test_scene.h"

#include <diagnostic_msgs/DiagnosticArray.h>
#include <gtest/gtest.h>
#include <lcp_contact_solver/SolverStats.h>
#include <ros/ros.h>

#include <map>
#include <set>
#include <string>

namespace {

using lcp_contact_solver::SolverStats;
using lcp_contact_solver_test::makeScene;
using lcp_contact_solver_test::Scene;

std::uint64_t valueOf(const diagnostic_msgs::DiagnosticStatus& status, const std::string& key) {
  for (const auto& kv : status.values)
    if (kv.key == key) return std::stoull(kv.value);
  ADD_FAILURE() << "no key '" << key << "' in " << status.name;
  return 0;
}

TEST(Overload, EveryArrayIsAccountedForAndNoneIsBlamedOnTheCompliance) {
  ros::NodeHandle nh, pnh("~");
  double rate_factor = 10.0, seconds = 10.0, time_budget = 0.01;
  std::string policy;
  pnh.param("rate_factor", rate_factor, rate_factor);
  pnh.param("seconds", seconds, seconds);
  ASSERT_TRUE(ros::param::get("/contact_solver/time_budget", time_budget));
  ASSERT_TRUE(ros::param::get("/contact_solver/overload", policy));

  std::map<ros::Time, std::vector<std::uint8_t>> outcomes;  // per stamp, every stats status
  ros::Subscriber stats_sub = nh.subscribe<SolverStats>(
      "/contact_solver/stats", 100000,
      [&outcomes](const SolverStats::ConstPtr& s) { outcomes[s->header.stamp].push_back(s->status_code); });
  diagnostic_msgs::DiagnosticStatus last_solver;
  ros::Subscriber diag_sub = nh.subscribe<diagnostic_msgs::DiagnosticArray>(
      "/diagnostics", 100, [&last_solver](const diagnostic_msgs::DiagnosticArray::ConstPtr& array) {
        for (const auto& status : array->status)
          if (status.name == "contact_solver: solver") last_solver = status;
      });
  ros::Publisher contacts_pub = nh.advertise<lcp_contact_solver::ContactArray>("/contacts", 100000);
  ros::Publisher compliance_pub = nh.advertise<lcp_contact_solver::Compliance>("/compliance", 100000);
  const ros::WallTime connect_deadline = ros::WallTime::now() + ros::WallDuration(20.0);
  while ((contacts_pub.getNumSubscribers() == 0 || compliance_pub.getNumSubscribers() == 0 ||
          stats_sub.getNumPublishers() == 0 || diag_sub.getNumPublishers() == 0) &&
         ros::WallTime::now() < connect_deadline) {
    ros::WallDuration(0.05).sleep();
  }
  ASSERT_GT(contacts_pub.getNumSubscribers(), 0u);

  // Ten times the sustainable rate, for `seconds`.
  const double rate = rate_factor / time_budget;
  const int count = static_cast<int>(rate * seconds);
  ros::WallRate pace(rate);
  for (int k = 0; k < count; ++k) {
    const Scene scene = makeScene(1, ros::Time(1.0 + 0.001 * k));
    contacts_pub.publish(scene.contacts);
    compliance_pub.publish(scene.compliance);
    pace.sleep();
  }

  // Every array gets its stats message, and /diagnostics its outcome, within the window.
  auto answered = [&] { return outcomes.size() == static_cast<std::size_t>(count); };
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(60.0);
  while (!answered() && ros::WallTime::now() < deadline) ros::WallDuration(0.05).sleep();
  const ros::WallTime settle = ros::WallTime::now() + ros::WallDuration(3.0);
  while (ros::WallTime::now() < settle) ros::WallDuration(0.05).sleep();  // a report after the last one

  int solved = 0, dropped = 0;
  for (const auto& entry : outcomes) {
    ASSERT_EQ(entry.second.size(), 1u)
        << "stamp " << entry.first << " reported " << entry.second.size() << " times";
    const std::uint8_t code = entry.second.front();
    EXPECT_NE(code, SolverStats::NO_COMPLIANCE) << "stamp " << entry.first;
    if (code == SolverStats::DROPPED) {
      ++dropped;
    } else {
      EXPECT_EQ(code, SolverStats::TIME_BUDGET);
      ++solved;
    }
  }
  EXPECT_EQ(outcomes.size(), static_cast<std::size_t>(count));
  EXPECT_GT(dropped, 0) << "at " << rate_factor << "x the sustainable rate something must be dropped";
  EXPECT_GT(solved, 0);
  RecordProperty("arrays", count);
  RecordProperty("solved", solved);
  RecordProperty("dropped", dropped);

  ASSERT_FALSE(last_solver.name.empty()) << "no diagnostics from the node";
  const std::uint64_t received = valueOf(last_solver, "contact arrays received");
  EXPECT_EQ(received, static_cast<std::uint64_t>(count));
  EXPECT_EQ(valueOf(last_solver, "outcome: solved") + valueOf(last_solver, "outcome: rejected") +
                valueOf(last_solver, "outcome: unpaired (no compliance)") +
                valueOf(last_solver, "outcome: dropped (node behind)") +
                valueOf(last_solver, "outcome: waiting or being solved"),
            received);
  EXPECT_EQ(valueOf(last_solver, "outcome: waiting or being solved"), 0u);
  EXPECT_EQ(valueOf(last_solver, "outcome: unpaired (no compliance)"), 0u);
  EXPECT_EQ(valueOf(last_solver, "outcome: solved"), static_cast<std::uint64_t>(solved));
  EXPECT_EQ(valueOf(last_solver, "outcome: dropped (node behind)"), static_cast<std::uint64_t>(dropped));
  std::string reported_policy;
  for (const auto& kv : last_solver.values)
    if (kv.key == "overload policy") reported_policy = kv.value;
  EXPECT_EQ(reported_policy, policy);
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_overload");
  ros::AsyncSpinner spinner(2);
  spinner.start();
  const int result = RUN_ALL_TESTS();
  ros::shutdown();
  return result;
}
