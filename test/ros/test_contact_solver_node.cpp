// Runs against a live contact_solver (node, or with --nodelet a nodelet loaded in this
// process): publishes known problems and checks what comes back against a direct core
// solve of the same problem.
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

namespace {

const std::string kSolver = "contact_solver";  // node or nodelet name
bool g_nodelet = false;
std::int64_t g_next_id = 1000;  // fresh contact ids per test: no warm start between tests

std::int64_t freshIds() {
  g_next_id += 100;
  return g_next_id;
}

ros::Time freshStamp() {
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

TEST_F(ContactSolverNodeTest, DefaultParametersAreSofas) {
  lcp_contact_solver_ros::NodeSettings loaded;
  ASSERT_EQ(lcp_contact_solver_ros::loadSettings(ros::NodeHandle(kSolver), &loaded), "");
  const lcp_contact_solver_ros::NodeSettings defaults;
  EXPECT_EQ(loaded.solver.tolerance, defaults.solver.tolerance);
  EXPECT_EQ(loaded.solver.maxIt, defaults.solver.maxIt);
  EXPECT_EQ(loaded.solver.mu, defaults.solver.mu);
  EXPECT_EQ(loaded.solver.initial_guess, defaults.solver.initial_guess);
  EXPECT_EQ(loaded.solver.computeConstraintForces, defaults.solver.computeConstraintForces);
  EXPECT_EQ(loaded.display.showCellWidth, defaults.display.showCellWidth);
  EXPECT_EQ(loaded.solver.max_rows, defaults.solver.max_rows);
}

TEST_F(ContactSolverNodeTest, PublishedForcesEqualTheCores) {
  Inbox<lcs::ConstraintForces> forces(nh_, "constraint_forces");
  ASSERT_TRUE(waitFor([&] { return forces.connected(); }));
  for (bool block_sparse : {false, true}) {
    const Scene scene = makeScene(freshIds(), freshStamp(), block_sparse);
    const lcs::SolverStats* stats = solve(scene);
    ASSERT_NE(stats, nullptr);
    ASSERT_TRUE(forces.wait(scene.contacts.header.stamp));
    lcs::core::Problem problem;
    const lcs::core::SolveResult expected = directSolve(scene, &problem);
    ASSERT_TRUE(expected.converged);
    expectForcesEqual(*forces.get(scene.contacts.header.stamp), problem, expected);
    EXPECT_TRUE(stats->success);
    EXPECT_TRUE(stats->converged);
    EXPECT_TRUE(stats->forces_published);  // somebody subscribes
    EXPECT_EQ(stats->iterations, expected.iterations);
    EXPECT_NEAR(stats->residual, expected.residual, 1e-12);
    EXPECT_EQ(stats->num_rows, 9);
  }
}

TEST_F(ContactSolverNodeTest, ServiceReturnsTheSameForces) {
  const Scene scene = makeScene(freshIds(), freshStamp(), true);
  lcs::SolveContacts srv;
  srv.request.contacts = scene.contacts;
  srv.request.compliance = scene.compliance;
  ASSERT_TRUE(ros::service::call(kSolver + "/solve_contacts", srv));
  EXPECT_TRUE(srv.response.success) << srv.response.message;
  EXPECT_EQ(srv.response.message, "converged");
  lcs::core::Problem problem;
  const lcs::core::SolveResult expected = directSolve(scene, &problem);
  expectForcesEqual(srv.response.forces, problem, expected);
  EXPECT_EQ(srv.response.stats.iterations, expected.iterations);

  srv.request.param_overrides = {"maxIt=1"};
  ASSERT_TRUE(ros::service::call(kSolver + "/solve_contacts", srv));
  EXPECT_TRUE(srv.response.success);
  EXPECT_EQ(srv.response.stats.iterations, 1);
  EXPECT_EQ(srv.response.stats.status, "max_iterations");

  srv.request.param_overrides = {"maxIt=lots"};
  ASSERT_TRUE(ros::service::call(kSolver + "/solve_contacts", srv));
  EXPECT_FALSE(srv.response.success);
  EXPECT_NE(srv.response.message.find("maxIt"), std::string::npos) << srv.response.message;

  srv.request.param_overrides.clear();
  srv.request.contacts.contacts[2].mu = -0.4;
  ASSERT_TRUE(ros::service::call(kSolver + "/solve_contacts", srv));
  EXPECT_FALSE(srv.response.success);
  EXPECT_NE(srv.response.message.find("negative mu"), std::string::npos) << srv.response.message;
  EXPECT_TRUE(srv.response.forces.forces.empty());
}

// Baumgarte β and softness: per solve as overrides (the node's ~erp/~softness for contacts
// with USE_DEFAULT), per contact in the message; the same forces as the core with those.
TEST_F(ContactSolverNodeTest, ServiceAppliesErpAndSoftnessPerSolveAndPerContact) {
  Scene scene = makeScene(freshIds(), freshStamp(), true);
  for (lcs::ContactPoint& c : scene.contacts.contacts) {
    c.gap = -0.02;
    c.erp = lcs::ContactPoint::USE_DEFAULT;
    c.softness = lcs::ContactPoint::USE_DEFAULT;
  }
  scene.contacts.contacts[1].erp = 0.5;       // its own β
  scene.contacts.contacts[2].softness = 0.3;  // its own softness
  lcs::SolveContacts srv;
  srv.request.contacts = scene.contacts;
  srv.request.compliance = scene.compliance;
  srv.request.param_overrides = {"erp=0.2", "softness=0.05", "tolerance=1e-10"};
  ASSERT_TRUE(ros::service::call(kSolver + "/solve_contacts", srv));
  ASSERT_TRUE(srv.response.success) << srv.response.message;
  lcs::core::Problem problem;
  std::vector<lcp_contact_solver_ros::ContactFrame> frames;
  ASSERT_EQ(lcp_contact_solver_ros::toProblem(scene.contacts, scene.compliance, 0, &problem, &frames), "");
  EXPECT_EQ(problem.contacts[1].erp, 0.5);
  EXPECT_EQ(problem.contacts[0].gap, -0.02);
  lcs::core::SolverParams params = lcp_contact_solver_ros::defaultSolverParams();
  params.erp = 0.2;
  params.softness = 0.05;
  params.tolerance = 1e-10;
  const lcs::core::SolveResult expected = lcs::core::solveProblem(problem, params);
  ASSERT_TRUE(expected.converged) << expected.message;
  expectForcesEqual(srv.response.forces, problem, expected);
  // The node's defaults (erp 0, softness 0) give the uncorrected forces: different ones.
  srv.request.param_overrides = {"tolerance=1e-10"};
  ASSERT_TRUE(ros::service::call(kSolver + "/solve_contacts", srv));
  ASSERT_TRUE(srv.response.success) << srv.response.message;
  params.erp = 0.0;
  params.softness = 0.0;
  const lcs::core::SolveResult plain = lcs::core::solveProblem(problem, params);
  expectForcesEqual(srv.response.forces, problem, plain);
  EXPECT_GT((plain.forces - expected.forces).norm(), 1e-3);
  // Velocity level without a step: refused, naming the parameter.
  srv.request.param_overrides = {"erp=0.2", "constraint_level=velocity"};
  ASSERT_TRUE(ros::service::call(kSolver + "/solve_contacts", srv));
  EXPECT_FALSE(srv.response.success);
  EXPECT_NE(srv.response.message.find("time_step"), std::string::npos) << srv.response.message;
}

// The body form of the compliance (STORAGE_BODIES): build_lcp=false runs the unbuilt
// Gauss-Seidel and gives the forces of the built solve on the assembled W; build_lcp=true
// (the node's default) assembles W; the topics take the body form too.
TEST_F(ContactSolverNodeTest, BodyFormSolvesUnbuiltWithBuildLcpFalse) {
  const Scene scene = lcp_contact_solver_test::makeBodyFormScene(freshIds(), freshStamp());
  lcs::core::Problem problem;
  std::vector<lcp_contact_solver_ros::ContactFrame> frames;
  ASSERT_EQ(lcp_contact_solver_ros::toProblem(scene.contacts, scene.compliance, 0, &problem, &frames), "");
  ASSERT_TRUE(problem.bodies);
  lcs::core::Problem assembled = problem;  // the built problem: the same W, assembled and dense
  assembled.bodies.reset();
  assembled.W = problem.bodies->toDense();
  lcs::core::SolverParams params = lcp_contact_solver_ros::defaultSolverParams();
  params.tolerance = 1e-10;
  const lcs::core::SolveResult built = lcs::core::solveProblem(assembled, params);
  ASSERT_TRUE(built.converged) << built.message;

  lcs::SolveContacts srv;
  srv.request.contacts = scene.contacts;
  srv.request.compliance = scene.compliance;
  srv.request.param_overrides = {"build_lcp=false", "tolerance=1e-10"};
  ASSERT_TRUE(ros::service::call(kSolver + "/solve_contacts", srv));
  ASSERT_TRUE(srv.response.success) << srv.response.message;
  EXPECT_TRUE(srv.response.stats.converged);
  EXPECT_NE(srv.response.message.find("unbuilt solve on the body form (3 bodies)"), std::string::npos)
      << srv.response.message;
  ASSERT_EQ(srv.response.forces.forces.size(), problem.contacts.size());
  const std::vector<int> offsets = problem.rowOffsets();
  const double scale = built.forces.cwiseAbs().maxCoeff();
  for (std::size_t i = 0; i < problem.contacts.size(); ++i) {
    EXPECT_EQ(srv.response.forces.forces[i].state, static_cast<std::uint8_t>(built.states[i])) << i;
    for (int k = 0; k < problem.contacts[i].rows; ++k)
      EXPECT_NEAR(srv.response.forces.forces[i].lambda[k], built.forces[offsets[i] + k], 1e-8 * scale)
          << i << ", " << k;
  }

  // build_lcp=true: W assembled once, the same forces, no unbuilt note.
  srv.request.param_overrides = {"build_lcp=true", "tolerance=1e-10"};
  ASSERT_TRUE(ros::service::call(kSolver + "/solve_contacts", srv));
  ASSERT_TRUE(srv.response.success) << srv.response.message;
  EXPECT_EQ(srv.response.message.find("unbuilt"), std::string::npos) << srv.response.message;
  for (std::size_t i = 0; i < problem.contacts.size(); ++i)
    for (int k = 0; k < problem.contacts[i].rows; ++k)
      EXPECT_NEAR(srv.response.forces.forces[i].lambda[k], built.forces[offsets[i] + k], 1e-8 * scale);

  // Other solvers assemble W and say so.
  srv.request.param_overrides = {"build_lcp=false", "solver=newton", "tolerance=1e-10"};
  ASSERT_TRUE(ros::service::call(kSolver + "/solve_contacts", srv));
  ASSERT_TRUE(srv.response.success) << srv.response.message;
  EXPECT_NE(srv.response.message.find("newton needs the assembled W"), std::string::npos)
      << srv.response.message;

  // A malformed body form is refused with its sentence.
  srv.request.compliance.contact_bodies[4] = 7;
  srv.request.param_overrides = {"build_lcp=false"};
  ASSERT_TRUE(ros::service::call(kSolver + "/solve_contacts", srv));
  EXPECT_FALSE(srv.response.success);
  EXPECT_NE(srv.response.message.find("names body_a 7"), std::string::npos) << srv.response.message;

  // The topics: paired and solved like any compliance (the node's build_lcp: assembled).
  const lcs::SolverStats* stats = solve(scene);
  ASSERT_NE(stats, nullptr);
  EXPECT_TRUE(stats->success) << stats->message;
  EXPECT_EQ(stats->num_rows, 9);
}

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

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_contact_solver_node");
  for (int i = 1; i < argc; ++i) g_nodelet = g_nodelet || std::strcmp(argv[i], "--nodelet") == 0;
  ros::NodeHandle nh;
  // With --nodelet the solver runs in this process, as in a simulator's nodelet manager.
  std::unique_ptr<nodelet::Loader> loader;
  if (g_nodelet) {
    loader = std::make_unique<nodelet::Loader>(false);
    if (!loader->load("/" + kSolver, "lcp_contact_solver/ContactSolverNodelet", {}, {})) {
      ADD_FAILURE() << "could not load the nodelet";
      return 1;
    }
  }
  const int result = RUN_ALL_TESTS();
  loader.reset();
  return result;
}
