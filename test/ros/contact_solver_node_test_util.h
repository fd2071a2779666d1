// The live node seen from the test: fresh ids and stamps, inboxes of its topics and the test
// fixture, shared by the test_contact_solver_node*.cpp files (one executable, one id counter).
#pragma once

#include "lcp_contact_solver/core/body_compliance.h"
#include "lcp_contact_solver/core/contact_solver.h"
#include "lcp_contact_solver/ros/msg_conversion/msg_conversion.h"
#include "lcp_contact_solver/ros/node/markers.h"
#include "lcp_contact_solver/ros/node/solver_params_ros.h"
#include "test_scene.h"

#include <diagnostic_msgs/DiagnosticArray.h>
#include <dynamic_reconfigure/Reconfigure.h>
#include <gtest/gtest.h>
#include <lcp_contact_solver/ConstraintForces.h>
#include <lcp_contact_solver/SolveContacts.h>
#include <lcp_contact_solver/SolverStats.h>
#include <nodelet/loader.h>
#include <ros/ros.h>
#include <visualization_msgs/MarkerArray.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <memory>
#include <set>

namespace lcs = lcp_contact_solver;
using lcp_contact_solver_test::makeScene;
using lcp_contact_solver_test::Scene;

inline const std::string kSolver = "contact_solver";  // node or nodelet name
inline bool g_nodelet = false;
inline std::int64_t g_next_id = 1000;  // fresh contact ids per test: no warm start between tests

inline std::int64_t freshIds() {
  g_next_id += 100;
  return g_next_id;
}

inline ros::Time freshStamp() {
  static ros::Time last;
  ros::Time now = ros::Time::now();
  if (now <= last) now = last + ros::Duration(0, 1000);
  last = now;
  return now;
}

template <typename Predicate>
bool waitFor(Predicate done, double timeout = 5.0) {
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(timeout);
  while (ros::ok() && ros::WallTime::now() < end) {
    ros::spinOnce();
    if (done()) return true;
    ros::WallDuration(0.005).sleep();
  }
  return done();
}

// Messages received on one topic, by stamp.
template <typename M>
class Inbox {
 public:
  Inbox(ros::NodeHandle& nh, const std::string& topic) {
    sub_ = nh.subscribe<M>(topic, 50,
                           [this](const typename M::ConstPtr& msg) { by_stamp_[msg->header.stamp] = *msg; });
  }
  bool connected() const { return sub_.getNumPublishers() > 0; }
  const M* get(const ros::Time& stamp) const {
    const auto it = by_stamp_.find(stamp);
    return it == by_stamp_.end() ? nullptr : &it->second;
  }
  bool wait(const ros::Time& stamp, double timeout = 5.0) const {
    return waitFor([&] { return get(stamp) != nullptr; }, timeout);
  }

 private:
  ros::Subscriber sub_;
  std::map<ros::Time, M> by_stamp_;
};

class ContactSolverNodeTest : public ::testing::Test {
 protected:
  void SetUp() override {
    contacts_pub_ = nh_.advertise<lcs::ContactArray>("contacts", 10);
    compliance_pub_ = nh_.advertise<lcs::Compliance>("compliance", 10);
    stats_ = std::make_unique<Inbox<lcs::SolverStats>>(nh_, kSolver + "/stats");
    ASSERT_TRUE(waitFor([&] {
      return contacts_pub_.getNumSubscribers() > 0 && compliance_pub_.getNumSubscribers() > 0 &&
             stats_->connected();
    })) << "the solver did not connect";
  }

  void TearDown() override {
    // Leave the solver as the launch file configured it.
    dynamic_reconfigure::Config config;
    setInt(&config, "maxIt", 1000);
    setDouble(&config, "tolerance", 0.001);
    setDouble(&config, "showCellWidth", 0.0);
    setBool(&config, "computeConstraintForces", false);
    reconfigure(config);
  }

  void publish(const Scene& scene) {
    compliance_pub_.publish(scene.compliance);
    contacts_pub_.publish(scene.contacts);
  }

  // Publishes a scene and waits for its stats.
  const lcs::SolverStats* solve(const Scene& scene) {
    publish(scene);
    if (!stats_->wait(scene.contacts.header.stamp)) return nullptr;
    return stats_->get(scene.contacts.header.stamp);
  }

  static void setInt(dynamic_reconfigure::Config* c, const std::string& name, int value) {
    dynamic_reconfigure::IntParameter p;
    p.name = name;
    p.value = value;
    c->ints.push_back(p);
  }
  static void setDouble(dynamic_reconfigure::Config* c, const std::string& name, double value) {
    dynamic_reconfigure::DoubleParameter p;
    p.name = name;
    p.value = value;
    c->doubles.push_back(p);
  }
  static void setBool(dynamic_reconfigure::Config* c, const std::string& name, bool value) {
    dynamic_reconfigure::BoolParameter p;
    p.name = name;
    p.value = value;
    c->bools.push_back(p);
  }

  // Sends a change through dynamic_reconfigure; returns the configuration in force after it.
  dynamic_reconfigure::Config reconfigure(const dynamic_reconfigure::Config& change) {
    dynamic_reconfigure::Reconfigure srv;
    srv.request.config = change;
    EXPECT_TRUE(ros::service::call(kSolver + "/set_parameters", srv));
    return srv.response.config;
  }

  static double doubleIn(const dynamic_reconfigure::Config& c, const std::string& name) {
    for (const auto& p : c.doubles)
      if (p.name == name) return p.value;
    return std::numeric_limits<double>::quiet_NaN();
  }

  // What the core gives for the same messages, parameters as in config/default.yaml.
  static lcs::core::SolveResult directSolve(
      const Scene& scene, lcs::core::Problem* problem = nullptr,
      std::vector<lcp_contact_solver_ros::ContactFrame>* frames = nullptr) {
    lcs::core::Problem p;
    std::vector<lcp_contact_solver_ros::ContactFrame> f;
    EXPECT_EQ(lcp_contact_solver_ros::toProblem(scene.contacts, scene.compliance, 0, &p, &f), "");
    if (problem) *problem = p;
    if (frames) *frames = f;
    return lcs::core::solveProblem(p, lcp_contact_solver_ros::defaultSolverParams());
  }

  static void expectForcesEqual(const lcs::ConstraintForces& msg, const lcs::core::Problem& problem,
                                const lcs::core::SolveResult& result) {
    ASSERT_EQ(msg.forces.size(), problem.contacts.size());
    const std::vector<int> offsets = problem.rowOffsets();
    for (std::size_t i = 0; i < problem.contacts.size(); ++i) {
      EXPECT_EQ(msg.forces[i].id, problem.contacts[i].id);
      EXPECT_EQ(msg.forces[i].state, static_cast<std::uint8_t>(result.states[i]));
      ASSERT_EQ(msg.forces[i].lambda.size(), static_cast<std::size_t>(problem.contacts[i].rows));
      for (int k = 0; k < problem.contacts[i].rows; ++k)
        EXPECT_NEAR(msg.forces[i].lambda[k], result.forces[offsets[i] + k], 1e-12)
            << "contact " << i << " row " << k;
    }
  }

  ros::NodeHandle nh_;
  ros::Publisher contacts_pub_;
  ros::Publisher compliance_pub_;
  std::unique_ptr<Inbox<lcs::SolverStats>> stats_;
};
