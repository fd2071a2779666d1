// The node's parts that need no master: markers, input pairing, the cycle log and the rate status.
#include "msg_conversion_test_util.h"

using namespace msg_conversion_test;

// ---- markers --------------------------------------------------------------------------

class Markers : public ::testing::Test {
 protected:
  void SetUp() override {
    scene_ = makeScene(10, kStamp);
    c_ = convert(scene_);
    ASSERT_EQ(c_.error, "");
    result_ = lcs::core::solveProblem(c_.problem, defaultSolverParams());
    mu_ = lcs::core::effectiveMu(c_.problem, 0.6);
  }

  std::set<std::string> namespaces(const visualization_msgs::MarkerArray& markers) const {
    std::set<std::string> ns;
    for (const auto& m : markers.markers) ns.insert(m.ns);
    return ns;
  }

  const visualization_msgs::Marker* find(const visualization_msgs::MarkerArray& markers,
                                         const std::string& ns) const {
    for (const auto& m : markers.markers)
      if (m.ns == ns) return &m;
    return nullptr;
  }

  Scene scene_;
  Converted c_;
  lcs::core::SolveResult result_;
  std::vector<double> mu_;
};

TEST_F(Markers, BuiltOnlyWithSubscribers) {
  EXPECT_FALSE(shouldBuildMarkers(0));
  EXPECT_TRUE(shouldBuildMarkers(1));
}

TEST_F(Markers, StableNamespacesAndNoHeatmapByDefault) {
  const DisplayOptions options;  // showCellWidth 0: SOFA's default, no heat map
  const auto markers = buildMarkers(scene_.contacts.header, c_.frames, c_.problem, result_, mu_, options);
  EXPECT_EQ(namespaces(markers),
            (std::set<std::string>{kNsContactPoints, kNsNormals, kNsForces, kNsFrictionCones}));
  for (const auto& m : markers.markers) {
    EXPECT_EQ(m.header.frame_id, "world");
    EXPECT_EQ(m.lifetime.toSec(), 0.5);
    if (m.ns != kNsForces) {
      EXPECT_EQ(m.id, 0);
    }
  }
  const auto* points = find(markers, kNsContactPoints);
  ASSERT_NE(points, nullptr);
  ASSERT_EQ(points->points.size(), 4u);
  EXPECT_EQ(points->colors[0], stateColor(result_.states[0]));
  // Two frictional contacts with μ > 0, 12 triangles each.
  EXPECT_EQ(find(markers, kNsFrictionCones)->points.size(), 2u * 12u * 3u);
}

TEST_F(Markers, ColoursTellStatesAndForcesApart) {
  const auto markers =
      buildMarkers(scene_.contacts.header, c_.frames, c_.problem, result_, mu_, DisplayOptions());
  std::vector<std_msgs::ColorRGBA> colours;
  for (int s = 0; s < lcs::core::kContactStateCount; ++s)
    colours.push_back(stateColor(static_cast<lcs::core::ContactState>(s)));
  bool arrows = false;
  for (const auto& m : markers.markers) {
    if (m.ns != kNsForces) continue;
    arrows = true;
    for (const auto& state : colours) EXPECT_NE(m.color, state) << "a force arrow has a state's colour";
    EXPECT_GE(m.scale.x, 0.1 * DisplayOptions().cone_height);  // readable shaft
  }
  ASSERT_TRUE(arrows);
  for (std::size_t a = 0; a < colours.size(); ++a)
    for (std::size_t b = a + 1; b < colours.size(); ++b) EXPECT_NE(colours[a], colours[b]) << a << " " << b;
}

TEST_F(Markers, ForceArrowsScaleWithTheParameter) {
  DisplayOptions options;
  options.force_arrow_scale = 0.5;
  const auto markers = buildMarkers(scene_.contacts.header, c_.frames, c_.problem, result_, mu_, options);
  const lcs::ConstraintForces forces = toConstraintForcesMsg(scene_.contacts, c_.frames, c_.problem, result_);
  for (const auto& m : markers.markers) {
    if (m.ns != kNsForces) continue;
    ASSERT_EQ(m.points.size(), 2u);
    const Eigen::Vector3d arrow = toEigen(m.points[1]) - toEigen(m.points[0]);
    EXPECT_NEAR((arrow - 0.5 * toEigen(forces.forces[m.id].force)).norm(), 0.0, 1e-12);
  }
}

TEST_F(Markers, HeatmapsAtShowTranslationWithCellWidth) {
  DisplayOptions options;
  options.showCellWidth = 0.1;
  options.showTranslation = {{1.0, 2.0, 3.0}};
  options.heatmap_max_rows = 5;
  const auto markers = buildMarkers(scene_.contacts.header, c_.frames, c_.problem, result_, mu_, options);
  const auto* w = find(markers, kNsComplianceHeatmap);
  const auto* lambda = find(markers, kNsLambdaHeatmap);
  ASSERT_NE(w, nullptr);
  ASSERT_NE(lambda, nullptr);
  EXPECT_EQ(w->points.size(), 25u);  // the leading 5 x 5 rows only
  EXPECT_EQ(lambda->points.size(), 5u);
  EXPECT_NEAR((toEigen(w->points[0]) - Eigen::Vector3d(1.0, 2.0, 3.0)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((toEigen(w->points[6]) - Eigen::Vector3d(1.1, 1.9, 3.0)).norm(), 0.0, 1e-12);  // row 1, col 1
  EXPECT_NEAR((toEigen(lambda->points[0]) - Eigen::Vector3d(1.6, 2.0, 3.0)).norm(), 0.0, 1e-12);
  EXPECT_NEAR(w->scale.x, 0.095, 1e-12);

  options.show_w_heatmap = false;
  const auto hidden = buildMarkers(scene_.contacts.header, c_.frames, c_.problem, result_, mu_, options);
  EXPECT_EQ(find(hidden, kNsComplianceHeatmap), nullptr);
}

TEST(HeatColor, DivergesAroundZero) {
  EXPECT_EQ(heatColor(0.0, 1.0).g, 1.0f);  // white
  EXPECT_EQ(heatColor(1.0, 1.0).r, 1.0f);
  EXPECT_EQ(heatColor(1.0, 1.0).b, 0.0f);  // red
  EXPECT_EQ(heatColor(-2.0, 1.0).b, 1.0f);
  EXPECT_EQ(heatColor(-2.0, 1.0).r, 0.0f);  // clamped blue
  EXPECT_EQ(heatColor(5.0, 0.0).g, 1.0f);   // no scale: white
}

// ---- pairing and debug summary --------------------------------------------------------

namespace {

lcs::ContactArray::ConstPtr arrayAt(double t) {
  auto a = boost::make_shared<lcs::ContactArray>();
  a->header.stamp = ros::Time(t);
  return a;
}

lcs::Compliance::ConstPtr complianceAt(double t) {
  auto c = boost::make_shared<lcs::Compliance>();
  c->header.stamp = ros::Time(t);
  return c;
}

// Every array received is in exactly one outcome.
void expectAccounted(const InputCounts& c) {
  EXPECT_EQ(c.arrays_received, c.taken + c.unpaired + c.dropped + c.waiting());
}

}  // namespace

TEST(InputQueue, PairsByStampInEitherOrderAndReportsOnlyArraysWaitingPastTheWindow) {
  InputQueue queue(OverloadPolicy::kQueue, 10);
  const ros::Time now(10, 0);
  // Stamps increase on each topic (going back would mean a restart).
  queue.addContacts(arrayAt(1), now);
  queue.addContacts(arrayAt(2), now);
  queue.addCompliance(complianceAt(2), now);  // array first
  queue.addCompliance(complianceAt(3), now);  // compliance first: its array comes next
  queue.addContacts(arrayAt(3), now);
  EXPECT_TRUE(queue.takeExpired(ros::Time(10, 400000000), 0.5).empty());
  const auto expired = queue.takeExpired(ros::Time(10, 600000000), 0.5);
  ASSERT_EQ(expired.size(), 1u);
  EXPECT_EQ(expired[0].header.stamp, ros::Time(1));
  EXPECT_FALSE(expired[0].behind);
  std::vector<UnsolvedInput> dropped;
  InputPair pair;
  ASSERT_TRUE(queue.take(std::chrono::milliseconds(0), &pair, &dropped));
  EXPECT_EQ(pair.contacts->header.stamp, ros::Time(2));
  EXPECT_EQ(pair.compliance->header.stamp, ros::Time(2));
  ASSERT_TRUE(queue.take(std::chrono::milliseconds(0), &pair, &dropped));
  EXPECT_EQ(pair.contacts->header.stamp, ros::Time(3));
  EXPECT_FALSE(queue.take(std::chrono::milliseconds(0), &pair, &dropped));
  EXPECT_TRUE(dropped.empty());
  const InputCounts c = queue.counts();
  EXPECT_EQ(c.arrays_received, 3u);
  EXPECT_EQ(c.taken, 2u);
  EXPECT_EQ(c.unpaired, 1u);
  EXPECT_EQ(c.waiting(), 0u);
  expectAccounted(c);
}

TEST(InputQueue, DropOldestSolvesTheNewestAndCountsTheRestAsBehind) {
  InputQueue queue(OverloadPolicy::kDropOldest, 10);
  for (int k = 1; k <= 5; ++k) {
    queue.addContacts(arrayAt(k), ros::Time(100));
    queue.addCompliance(complianceAt(k), ros::Time(100));
  }
  std::vector<UnsolvedInput> dropped;
  InputPair pair;
  ASSERT_TRUE(queue.take(std::chrono::milliseconds(0), &pair, &dropped));
  EXPECT_EQ(pair.contacts->header.stamp, ros::Time(5));
  ASSERT_EQ(dropped.size(), 4u);
  for (const UnsolvedInput& d : dropped) {
    EXPECT_TRUE(d.behind);
    EXPECT_NE(d.reason.find("drop_oldest"), std::string::npos);
  }
  const InputCounts c = queue.counts();
  EXPECT_EQ(c.dropped, 4u);
  EXPECT_EQ(c.unpaired, 0u);  // the node's backlog is never blamed on the simulator
  expectAccounted(c);
}

TEST(InputQueue, QueuePolicyKeepsOrderAndDropsTheOldestPastItsCapacity) {
  InputQueue queue(OverloadPolicy::kQueue, 3);
  for (int k = 1; k <= 5; ++k) {
    queue.addCompliance(complianceAt(k), ros::Time(100));  // compliance first this time
    queue.addContacts(arrayAt(k), ros::Time(100));
  }
  std::vector<UnsolvedInput> dropped;
  InputPair pair;
  std::vector<double> solved;
  while (queue.take(std::chrono::milliseconds(0), &pair, &dropped))
    solved.push_back(pair.contacts->header.stamp.toSec());
  EXPECT_EQ(solved, (std::vector<double>{3, 4, 5}));
  ASSERT_EQ(dropped.size(), 2u);
  EXPECT_EQ(dropped[0].header.stamp, ros::Time(1));
  EXPECT_TRUE(dropped[0].behind);
  expectAccounted(queue.counts());
  EXPECT_EQ(queue.counts().waiting(), 0u);
}

TEST(InputQueue, RepeatedStampAndLoneCompliancesAreAccounted) {
  InputQueue queue(OverloadPolicy::kQueue, 10);
  queue.addContacts(arrayAt(1), ros::Time(100));
  queue.addContacts(arrayAt(1), ros::Time(100));  // a restarted simulator reuses the stamp
  queue.addCompliance(complianceAt(7), ros::Time(100));
  std::vector<UnsolvedInput> dropped;
  InputPair pair;
  EXPECT_FALSE(queue.take(std::chrono::milliseconds(0), &pair, &dropped));
  ASSERT_EQ(dropped.size(), 1u);
  EXPECT_FALSE(dropped[0].behind);
  EXPECT_NE(dropped[0].reason.find("same stamp"), std::string::npos);
  queue.addCompliance(complianceAt(1), ros::Time(100));
  ASSERT_TRUE(queue.take(std::chrono::milliseconds(0), &pair, &dropped));
  EXPECT_TRUE(queue.takeExpired(ros::Time(200), 0.5).empty());  // the lone compliance goes quietly
  const InputCounts c = queue.counts();
  EXPECT_EQ(c.compliances_unpaired, 1u);
  EXPECT_EQ(c.arrays_received, 2u);
  expectAccounted(c);
}

TEST(InputQueue, StopWakesAWaitingTake) {
  InputQueue queue(OverloadPolicy::kQueue, 10);
  std::thread stopper([&queue] {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    queue.stop();
  });
  std::vector<UnsolvedInput> dropped;
  InputPair pair;
  EXPECT_FALSE(queue.take(std::chrono::seconds(30), &pair, &dropped));
  stopper.join();
}

TEST(CycleLog, NamesTheWorstContact) {
  const Scene scene = makeScene(10, kStamp);
  const Converted c = convert(scene);
  lcs::core::SolverParams params = defaultSolverParams();
  params.maxIt = 1;  // far from converged: some contact has a clear error
  const lcs::core::SolveResult result = lcs::core::solveProblem(c.problem, params);
  const std::vector<double> mu = lcs::core::effectiveMu(c.problem, params.mu);
  double worst_error = 0.0;
  const int worst = worstContact(c.problem, result, mu, &worst_error);
  ASSERT_GE(worst, 0);
  // The per-contact errors add up (squared) to the core's unnormalised residual.
  const double total = result.residual * c.problem.d_free.norm();
  EXPECT_LE(worst_error, total + 1e-12);
  EXPECT_GE(worst_error * std::sqrt(4.0), total - 1e-12);
  const std::string line = cycleSummary(c.problem, result, mu);
  EXPECT_NE(line.find("4 contacts, 9 rows (dense W)"), std::string::npos) << line;
  EXPECT_NE(line.find("worst contact " + std::to_string(worst)), std::string::npos) << line;
}

namespace {

std::string summaryOf(lcp_contact_solver_ros::SolveRateStatus& task, std::uint8_t* level) {
  diagnostic_updater::DiagnosticStatusWrapper status;
  task.run(status);
  *level = status.level;
  return status.message;
}

}  // namespace

TEST(SolveRateStatus, IdleIsWaitingNotAnError) {
  lcp_contact_solver_ros::SolveRateStatus task(0.0, 1e12);  // no bound a real rate can cross
  std::uint8_t level = 255;
  EXPECT_NE(summaryOf(task, &level).find("waiting for contacts"), std::string::npos);
  EXPECT_EQ(level, diagnostic_msgs::DiagnosticStatus::OK);
  task.contactsReceived();
  task.solved();
  summaryOf(task, &level);
  EXPECT_EQ(level, diagnostic_msgs::DiagnosticStatus::OK);
  const std::string idle_again = summaryOf(task, &level);  // nothing new since
  EXPECT_NE(idle_again.find("last received"), std::string::npos) << idle_again;
  EXPECT_EQ(level, diagnostic_msgs::DiagnosticStatus::OK);
}

TEST(SolveRateStatus, WarnsWhenContactsComeButSolvingIsTooSlow) {
  lcp_contact_solver_ros::SolveRateStatus task(1e9, 2e9);  // no machine solves this fast
  task.contactsReceived();
  std::uint8_t level = 0;
  EXPECT_NE(summaryOf(task, &level).find("below"), std::string::npos);
  EXPECT_EQ(level, diagnostic_msgs::DiagnosticStatus::WARN);
}
