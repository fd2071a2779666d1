// The live node over time: warm start, bad input, reconfigure, diagnostics and markers.
#include "contact_solver_node_test_util.h"

namespace {

TEST_F(ContactSolverNodeTest, WarmStartLowersIterations) {
  const std::int64_t ids = freshIds();
  const lcs::SolverStats* cold = solve(makeScene(ids, freshStamp()));
  ASSERT_NE(cold, nullptr);
  const int cold_iterations = cold->iterations;
  const lcs::SolverStats* warm = solve(makeScene(ids, freshStamp()));  // same ids, same problem
  ASSERT_NE(warm, nullptr);
  EXPECT_GT(cold_iterations, 1);
  EXPECT_LT(warm->iterations, cold_iterations);
  EXPECT_TRUE(warm->converged);
  // A contact id not seen before starts from zero: new ids solve like the cold one.
  const lcs::SolverStats* fresh = solve(makeScene(freshIds(), freshStamp()));
  ASSERT_NE(fresh, nullptr);
  EXPECT_EQ(fresh->iterations, cold_iterations);
}

TEST_F(ContactSolverNodeTest, BadMessagesAreRejectedAndTheNodeGoesOn) {
  Inbox<lcs::ConstraintForces> forces(nh_, "constraint_forces");
  ASSERT_TRUE(waitFor([&] { return forces.connected(); }));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<std::pair<std::string, std::function<void(Scene*)>>> faults = {
      {"non-finite", [nan](Scene* s) { s->contacts.contacts[0].d_free[1] = nan; }},
      {"compliance has rows", [](Scene* s) { s->compliance.rows = 4; }},
      {"negative mu", [](Scene* s) { s->contacts.contacts[1].mu = -2.0; }},
      {"zero normal",
       [](Scene* s) { s->contacts.contacts[0].normal = lcp_contact_solver_test::vec(0, 0, 0); }},
      {"empty", [](Scene* s) { s->contacts.contacts.clear(); }},
  };
  std::vector<ros::Time> rejected;
  for (const auto& fault : faults) {
    Scene scene = makeScene(freshIds(), freshStamp());
    fault.second(&scene);
    const lcs::SolverStats* stats = solve(scene);
    ASSERT_NE(stats, nullptr) << fault.first;
    EXPECT_FALSE(stats->success) << fault.first;
    EXPECT_EQ(stats->status, "invalid_input") << fault.first;
    EXPECT_NE(stats->message.find(fault.first), std::string::npos) << stats->message;
    rejected.push_back(scene.contacts.header.stamp);
  }
  const Scene good = makeScene(freshIds(), freshStamp());
  const lcs::SolverStats* stats = solve(good);
  ASSERT_NE(stats, nullptr);
  EXPECT_TRUE(stats->success);
  ASSERT_TRUE(forces.wait(good.contacts.header.stamp));
  for (const ros::Time& stamp : rejected) EXPECT_EQ(forces.get(stamp), nullptr);  // nothing for bad input
}

TEST_F(ContactSolverNodeTest, UnpairedContactsAreReported) {
  const Scene scene = makeScene(freshIds(), freshStamp());
  contacts_pub_.publish(scene.contacts);  // no compliance
  ASSERT_TRUE(stats_->wait(scene.contacts.header.stamp, 3.0));
  const lcs::SolverStats* stats = stats_->get(scene.contacts.header.stamp);
  EXPECT_FALSE(stats->success);
  EXPECT_EQ(stats->status_code, lcs::SolverStats::NO_COMPLIANCE);
  EXPECT_EQ(stats->status, "no_compliance");
}

TEST_F(ContactSolverNodeTest, ReconfigureTakesEffectAndRejectsInvalidValues) {
  dynamic_reconfigure::Config change;
  setInt(&change, "maxIt", 2);
  reconfigure(change);
  const lcs::SolverStats* capped = solve(makeScene(freshIds(), freshStamp()));
  ASSERT_NE(capped, nullptr);
  EXPECT_EQ(capped->iterations, 2);
  EXPECT_EQ(capped->status, "max_iterations");
  EXPECT_TRUE(capped->success);  // best iterate at the cap is still published

  dynamic_reconfigure::Config invalid;
  setDouble(&invalid, "tolerance", std::numeric_limits<double>::quiet_NaN());  // no range stops a NaN
  const dynamic_reconfigure::Config in_force = reconfigure(invalid);
  EXPECT_EQ(doubleIn(in_force, "tolerance"), 0.001);  // refused: the old value stays
  const lcs::SolverStats* still = solve(makeScene(freshIds(), freshStamp()));
  ASSERT_NE(still, nullptr);
  EXPECT_EQ(still->iterations, 2);  // maxIt=2 still in force, tolerance unchanged

  // Out of the .cfg's range: dynamic_reconfigure clamps to the bound (what tools show).
  dynamic_reconfigure::Config negative;
  setDouble(&negative, "erp", -1.0);
  EXPECT_EQ(doubleIn(reconfigure(negative), "erp"), 0.0);
  dynamic_reconfigure::Config large;
  setDouble(&large, "erp", 7.0);
  EXPECT_EQ(doubleIn(reconfigure(large), "erp"), 1.0);
  dynamic_reconfigure::Config back;
  setDouble(&back, "erp", 0.0);
  reconfigure(back);
}

TEST_F(ContactSolverNodeTest, TimeJumpingBackResetsTheWarmStart) {
  const std::int64_t ids = freshIds();
  const lcs::SolverStats* first = solve(makeScene(ids, freshStamp()));
  ASSERT_NE(first, nullptr);
  const int cold = first->iterations;
  const lcs::SolverStats* again = solve(makeScene(ids, freshStamp()));
  ASSERT_NE(again, nullptr);
  ASSERT_LT(again->iterations, cold);  // warm: the same contacts start from their forces
  // A simulator that restarted: its stamps begin again, the same ids name new contacts.
  const lcs::SolverStats* restarted = solve(makeScene(ids, ros::Time(1000.0 + static_cast<double>(ids))));
  ASSERT_NE(restarted, nullptr);
  EXPECT_EQ(restarted->iterations, cold);  // from zero, as the first time
  EXPECT_TRUE(restarted->success);
}

TEST_F(ContactSolverNodeTest, ReconfigureKeepsTheShowTranslationListInStep) {
  dynamic_reconfigure::Config change;
  setDouble(&change, "showTranslation_x", 1.5);
  setDouble(&change, "showTranslation_z", -0.25);
  reconfigure(change);
  std::vector<double> list;
  ASSERT_TRUE(ros::param::get(kSolver + "/showTranslation", list));
  ASSERT_EQ(list.size(), 3u);
  EXPECT_EQ(list[0], 1.5);
  EXPECT_EQ(list[2], -0.25);
  dynamic_reconfigure::Config back;
  setDouble(&back, "showTranslation_x", 0.0);
  setDouble(&back, "showTranslation_z", 0.0);
  reconfigure(back);
}

TEST_F(ContactSolverNodeTest, ForcesPublishedWithoutSubscriberOnlyWithComputeConstraintForces) {
  // No ConstraintForces subscriber in this test; an earlier test's may take a moment to
  // disconnect, so solve until the node sees none.
  EXPECT_TRUE(waitFor([&] {
    const lcs::SolverStats* off = solve(makeScene(freshIds(), freshStamp()));
    return off != nullptr && off->success && !off->forces_published;
  }));

  dynamic_reconfigure::Config change;
  setBool(&change, "computeConstraintForces", true);
  reconfigure(change);
  const lcs::SolverStats* on = solve(makeScene(freshIds(), freshStamp()));
  ASSERT_NE(on, nullptr);
  EXPECT_TRUE(on->forces_published);
}

TEST_F(ContactSolverNodeTest, DiagnosticsReportRejectedInput) {
  std::vector<diagnostic_msgs::DiagnosticStatus> solver_statuses;
  ros::Subscriber sub = nh_.subscribe<diagnostic_msgs::DiagnosticArray>(
      "/diagnostics", 10, [&solver_statuses](const diagnostic_msgs::DiagnosticArray::ConstPtr& array) {
        for (const auto& status : array->status) {
          const std::string suffix = ": solver";
          if (status.name.size() > suffix.size() &&
              status.name.compare(status.name.size() - suffix.size(), suffix.size(), suffix) == 0)
            solver_statuses.push_back(status);
        }
      });
  // A report between the rejection and our connection would carry the warning unseen.
  ASSERT_TRUE(waitFor([&] { return sub.getNumPublishers() > 0; }));
  Scene bad = makeScene(freshIds(), freshStamp());
  bad.contacts.contacts[0].mu = -3.0;
  ASSERT_NE(solve(bad), nullptr);
  auto value = [](const diagnostic_msgs::DiagnosticStatus& status, const std::string& key) {
    for (const auto& kv : status.values)
      if (kv.key == key) return kv.value;
    return std::string();
  };
  ASSERT_TRUE(waitFor(
      [&] {
        for (const auto& status : solver_statuses)
          if (status.level == diagnostic_msgs::DiagnosticStatus::WARN &&
              value(status, "rejected inputs") != "0")
            return true;
        return false;
      },
      4.0));
  EXPECT_NE(value(solver_statuses.back(), "last residual"), "");
  EXPECT_NE(value(solver_statuses.back(), "non-converged solves"), "");
}

TEST_F(ContactSolverNodeTest, MarkersOnlyWhenSubscribed) {
  const lcs::SolverStats* unwatched = solve(makeScene(freshIds(), freshStamp()));
  ASSERT_NE(unwatched, nullptr);
  EXPECT_FALSE(unwatched->markers_published);

  dynamic_reconfigure::Config change;
  setDouble(&change, "showCellWidth", 0.05);
  reconfigure(change);
  std::vector<visualization_msgs::MarkerArray> received;
  ros::Subscriber sub = nh_.subscribe<visualization_msgs::MarkerArray>(
      kSolver + "/markers", 10,
      [&received](const visualization_msgs::MarkerArray::ConstPtr& m) { received.push_back(*m); });
  // The node sees the subscriber once the connection is made; solve until it does.
  bool published = false;
  ros::Time stamp;
  for (int attempt = 0; attempt < 50 && !published; ++attempt) {
    const Scene scene = makeScene(freshIds(), freshStamp());
    const lcs::SolverStats* stats = solve(scene);
    ASSERT_NE(stats, nullptr);
    published = stats->markers_published;
    stamp = scene.contacts.header.stamp;
  }
  ASSERT_TRUE(published);
  ASSERT_TRUE(waitFor([&] {
    for (const auto& array : received)
      if (!array.markers.empty() && array.markers[0].header.stamp == stamp) return true;
    return false;
  }));
  std::set<std::string> namespaces;
  for (const auto& m : received.back().markers) namespaces.insert(m.ns);
  for (const char* ns :
       {lcp_contact_solver_ros::kNsContactPoints, lcp_contact_solver_ros::kNsNormals,
        lcp_contact_solver_ros::kNsForces, lcp_contact_solver_ros::kNsFrictionCones,
        lcp_contact_solver_ros::kNsComplianceHeatmap, lcp_contact_solver_ros::kNsLambdaHeatmap})
    EXPECT_EQ(namespaces.count(ns), 1u) << ns;

  sub.shutdown();
  EXPECT_TRUE(waitFor([&] {
    const lcs::SolverStats* stats = solve(makeScene(freshIds(), freshStamp()));
    return stats != nullptr && !stats->markers_published;
  }));
}

}  // namespace
