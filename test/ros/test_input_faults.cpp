// Faults a simulator's inputs produce, through the live node: a burst of malformed arrays
// among good ones, and contacts and compliances sent at mismatched rates. Every array is
// answered exactly once on ~stats, with the outcome it deserves.
#include "test_scene.h"

#include <gtest/gtest.h>
#include <lcp_contact_solver/SolverStats.h>
#include <ros/ros.h>

#include <limits>
#include <map>
#include <mutex>

namespace {

using lcp_contact_solver::SolverStats;
using lcp_contact_solver_test::makeScene;
using lcp_contact_solver_test::Scene;

class InputFaults : public testing::Test {
 protected:
  void SetUp() override {
    stats_sub_ =
        nh_.subscribe<SolverStats>("/contact_solver/stats", 100000, [this](const SolverStats::ConstPtr& s) {
          std::lock_guard<std::mutex> lock(mutex_);
          outcomes_[s->header.stamp].push_back(s->status_code);
        });
    contacts_pub_ = nh_.advertise<lcp_contact_solver::ContactArray>("/contacts", 100000);
    compliance_pub_ = nh_.advertise<lcp_contact_solver::Compliance>("/compliance", 100000);
    const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(20.0);
    while ((contacts_pub_.getNumSubscribers() == 0 || compliance_pub_.getNumSubscribers() == 0 ||
            stats_sub_.getNumPublishers() == 0) &&
           ros::WallTime::now() < deadline) {
      ros::WallDuration(0.05).sleep();
    }
    ASSERT_GT(contacts_pub_.getNumSubscribers(), 0u);
  }

  // Waits until `count` stamps have an answer (or 60 s), then a little for duplicates.
  std::map<ros::Time, std::vector<std::uint8_t>> waitForAnswers(std::size_t count) {
    const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(60.0);
    while (ros::WallTime::now() < deadline) {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        if (outcomes_.size() >= count) break;
      }
      ros::WallDuration(0.05).sleep();
    }
    ros::WallDuration(1.0).sleep();
    std::lock_guard<std::mutex> lock(mutex_);
    return outcomes_;
  }

  ros::NodeHandle nh_;
  ros::Subscriber stats_sub_;
  ros::Publisher contacts_pub_;
  ros::Publisher compliance_pub_;
  std::mutex mutex_;
  std::map<ros::Time, std::vector<std::uint8_t>> outcomes_;
};

TEST_F(InputFaults, EveryGoodArrayOfABurstWithTenThousandMalformedOnesIsSolved) {
  const int good = 200, bad_per_good = 50;
  std::size_t sent = 0;
  // Stamps increase on each topic, as a simulator's do (a stamp going back means a restart).
  for (int k = 0; k < good; ++k) {
    const Scene scene = makeScene(1, ros::Time(10.0 + k));
    contacts_pub_.publish(scene.contacts);
    compliance_pub_.publish(scene.compliance);
    ++sent;
    for (int b = 0; b < bad_per_good; ++b) {
      Scene bad = makeScene(1, ros::Time(10.0 + k + 0.001 * (b + 1)));
      bad.contacts.contacts[b % 4].d_free[0] = std::numeric_limits<double>::quiet_NaN();
      if (b % 3 == 0) bad.compliance.data.pop_back();  // and a wrong size now and then
      contacts_pub_.publish(bad.contacts);
      compliance_pub_.publish(bad.compliance);
      ++sent;
    }
    if (k % 20 == 19) ros::WallDuration(0.01).sleep();  // let the transport breathe
  }
  const auto outcomes = waitForAnswers(sent);
  ASSERT_EQ(outcomes.size(), sent);
  int solved = 0, rejected = 0;
  for (const auto& entry : outcomes) {
    ASSERT_EQ(entry.second.size(), 1u) << "stamp " << entry.first;
    const bool is_good = entry.first.nsec == 0;
    if (is_good) {
      EXPECT_EQ(entry.second[0], SolverStats::CONVERGED) << "stamp " << entry.first;
      ++solved;
    } else {
      EXPECT_EQ(entry.second[0], SolverStats::INVALID_INPUT) << "stamp " << entry.first;
      ++rejected;
    }
  }
  EXPECT_EQ(solved, good);
  EXPECT_EQ(rejected, good * bad_per_good);
}

TEST_F(InputFaults, MismatchedRatesLeaveOnlyTheArraysWithoutCompliancesUnpaired) {
  // Contacts at 1 kHz, compliances at 999 Hz: one compliance in a thousand never comes.
  const int count = 3000;
  int without = 0;
  ros::WallRate pace(1000.0);
  for (int k = 0; k < count; ++k) {
    const Scene scene = makeScene(500, ros::Time(5000.0 + 0.001 * k));
    contacts_pub_.publish(scene.contacts);
    if (k % 1000 == 999) {
      ++without;
    } else {
      compliance_pub_.publish(scene.compliance);
    }
    pace.sleep();
  }
  const auto outcomes = waitForAnswers(count);
  int unpaired = 0, solved = 0;
  for (const auto& entry : outcomes) {
    if (entry.first < ros::Time(5000.0)) continue;  // another test's
    ASSERT_EQ(entry.second.size(), 1u);
    if (entry.second[0] == SolverStats::NO_COMPLIANCE) {
      ++unpaired;
    } else {
      EXPECT_EQ(entry.second[0], SolverStats::CONVERGED);
      ++solved;
    }
  }
  EXPECT_EQ(unpaired, without);
  EXPECT_EQ(solved, count - without);
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_input_faults");
  ros::AsyncSpinner spinner(2);
  spinner.start();
  const int result = RUN_ALL_TESTS();
  ros::shutdown();
  return result;
}
