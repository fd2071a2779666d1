// Adversarial input against a live contact_solver node (test/ros/adversarial.test, with
// ~max_rows = 1000), through the topics AND through ~solve_contacts: NaN and Inf in every
// field that carries a number, mismatched sizes, negative and non-finite μ, zero and
// non-unit normals, duplicated ids, empty arrays, W with the wrong row count, unknown
// types and storages, and an array far over the row limit (100 000 contacts, 100 × the
// limit, ~14 MB on the wire: the node refuses it on the contact count, before allocating
// anything per contact; the 10⁶-row hard limit of max_rows = 0 is checked without a master
// in test_adversarial_input). For each:
//   - a clear error: stats with success = false, status invalid_input and a message naming
//     the fault (the service: success = false and the same sentence);
//   - nothing published on constraint_forces for that stamp, nothing non-finite published
//     on any topic the node writes (forces, stats, markers) during the whole test;
//   - the node then solves the next good message correctly (forces = a direct core solve).
#include "lcp_contact_solver/core/contact_solver.h"
#include "lcp_contact_solver/ros/msg_conversion/msg_conversion.h"
#include "lcp_contact_solver/ros/node/solver_params_ros.h"
#include "test_scene.h"

#include <gtest/gtest.h>
#include <lcp_contact_solver/ConstraintForces.h>
#include <lcp_contact_solver/SolveContacts.h>
#include <lcp_contact_solver/SolverStats.h>
#include <ros/ros.h>
#include <visualization_msgs/MarkerArray.h>

#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <memory>

namespace lcs = lcp_contact_solver;
using lcp_contact_solver_test::makeScene;
using lcp_contact_solver_test::Scene;
using lcp_contact_solver_test::vec;

namespace {

const std::string kSolver = "contact_solver";
const double kNaN = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();
std::int64_t g_next_id = 5000;

std::int64_t freshIds() { return g_next_id += 100; }

ros::Time freshStamp() {
  static ros::Time last;
  ros::Time now = ros::Time::now();
  if (now <= last) now = last + ros::Duration(0, 1000);
  last = now;
  return now;
}

template <typename Predicate>
bool waitFor(Predicate done, double timeout = 10.0) {
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(timeout);
  while (ros::ok() && ros::WallTime::now() < end) {
    ros::spinOnce();
    if (done()) return true;
    ros::WallDuration(0.005).sleep();
  }
  return done();
}

bool finite(const geometry_msgs::Point& p) {
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
}

// Everything the node publishes, checked for non-finite numbers as it arrives.
class Watch {
 public:
  explicit Watch(ros::NodeHandle& nh) {
    forces_sub_ = nh.subscribe<lcs::ConstraintForces>("constraint_forces", 100,
                                                      [this](const lcs::ConstraintForces::ConstPtr& m) {
                                                        forces_[m->header.stamp] = *m;
                                                        if (!lcp_contact_solver_ros::allFinite(*m))
                                                          ++non_finite_;
                                                      });
    stats_sub_ =
        nh.subscribe<lcs::SolverStats>(kSolver + "/stats", 100, [this](const lcs::SolverStats::ConstPtr& m) {
          stats_[m->header.stamp] = *m;
          if (!lcp_contact_solver_ros::allFinite(*m)) ++non_finite_;
        });
    markers_sub_ = nh.subscribe<visualization_msgs::MarkerArray>(
        kSolver + "/markers", 100, [this](const visualization_msgs::MarkerArray::ConstPtr& m) {
          ++markers_;
          for (const auto& marker : m->markers) {
            if (!finite(marker.pose.position) || !std::isfinite(marker.scale.x)) ++non_finite_;
            for (const auto& p : marker.points)
              if (!finite(p)) ++non_finite_;
          }
        });
  }
  bool connected() const {
    return forces_sub_.getNumPublishers() > 0 && stats_sub_.getNumPublishers() > 0 &&
           markers_sub_.getNumPublishers() > 0;
  }
  const lcs::SolverStats* stats(const ros::Time& stamp) const {
    const auto it = stats_.find(stamp);
    return it == stats_.end() ? nullptr : &it->second;
  }
  const lcs::ConstraintForces* forces(const ros::Time& stamp) const {
    const auto it = forces_.find(stamp);
    return it == forces_.end() ? nullptr : &it->second;
  }
  int nonFinite() const { return non_finite_; }
  int markers() const { return markers_; }

 private:
  ros::Subscriber forces_sub_, stats_sub_, markers_sub_;
  std::map<ros::Time, lcs::ConstraintForces> forces_;
  std::map<ros::Time, lcs::SolverStats> stats_;
  int non_finite_ = 0;
  int markers_ = 0;
};

struct Fault {
  std::string name;
  std::function<void(Scene*)> spoil;
  std::string expected;  // part of the error sentence
};

// The faults, on the known 4-contact scene of test_scene.h (ids first_id .. first_id + 3;
// contact 1 gives tangents, contact 3 is a 2-row bilateral; 9 rows).
std::vector<Fault> faults() {
  std::vector<Fault> list = {
      {"NaN position", [](Scene* s) { s->contacts.contacts[0].position.x = kNaN; }, "non-finite position"},
      {"Inf position", [](Scene* s) { s->contacts.contacts[2].position.z = -kInf; }, "non-finite position"},
      {"NaN normal", [](Scene* s) { s->contacts.contacts[0].normal.y = kNaN; }, "non-finite direction"},
      {"Inf normal", [](Scene* s) { s->contacts.contacts[3].normal.x = kInf; }, "non-finite direction"},
      {"NaN tangent", [](Scene* s) { s->contacts.contacts[1].tangent1.x = kNaN; }, "non-finite direction"},
      {"Inf tangent", [](Scene* s) { s->contacts.contacts[1].tangent2.z = kInf; }, "non-finite direction"},
      {"NaN d_free", [](Scene* s) { s->contacts.contacts[1].d_free[2] = kNaN; },
       "d_free holds a non-finite value"},
      {"Inf d_free", [](Scene* s) { s->contacts.contacts[3].d_free[0] = -kInf; },
       "d_free holds a non-finite value"},
      {"NaN mu", [](Scene* s) { s->contacts.contacts[1].mu = kNaN; }, "non-finite mu"},
      {"Inf mu", [](Scene* s) { s->contacts.contacts[1].mu = kInf; }, "non-finite mu"},
      {"negative mu", [](Scene* s) { s->contacts.contacts[0].mu = -0.5; }, "negative mu"},
      {"negative mu_torsional", [](Scene* s) { s->contacts.contacts[0].mu_torsional = -0.1; },
       "negative or non-finite mu_torsional"},
      {"NaN mu_rolling", [](Scene* s) { s->contacts.contacts[1].mu_rolling = kNaN; },
       "negative or non-finite mu_rolling"},
      {"torsional with 3 values",
       [](Scene* s) { s->contacts.contacts[0].type = lcs::ContactPoint::TORSIONAL; },
       "3 d_free values for 4 rows"},
      {"rolling rows 4",
       [](Scene* s) {
         s->contacts.contacts[0].type = lcs::ContactPoint::ROLLING;
         s->contacts.contacts[0].rows = 4;
       },
       "rows=4 but its type has 6"},
      {"NaN gap", [](Scene* s) { s->contacts.contacts[0].gap = kNaN; }, "non-finite gap"},
      {"Inf gap", [](Scene* s) { s->contacts.contacts[2].gap = -kInf; }, "non-finite gap"},
      {"erp above 1", [](Scene* s) { s->contacts.contacts[1].erp = 1.5; }, "outside [0, 1]"},
      {"NaN erp", [](Scene* s) { s->contacts.contacts[1].erp = kNaN; }, "outside [0, 1]"},
      {"negative softness", [](Scene* s) { s->contacts.contacts[0].softness = -1e-3; },
       "negative or non-finite softness"},
      {"Inf softness", [](Scene* s) { s->contacts.contacts[0].softness = kInf; },
       "negative or non-finite softness"},
      {"NaN W", [](Scene* s) { s->compliance.data[10] = kNaN; }, "W holds a non-finite value"},
      {"Inf W", [](Scene* s) { s->compliance.data[80] = kInf; }, "W holds a non-finite value"},
      {"zero normal", [](Scene* s) { s->contacts.contacts[2].normal = vec(0, 0, 0); }, "zero normal"},
      {"tiny normal", [](Scene* s) { s->contacts.contacts[2].normal = vec(1e-12, 0, 0); }, "zero normal"},
      {"duplicated id", [](Scene* s) { s->contacts.contacts[2].id = s->contacts.contacts[0].id; },
       "repeats an id"},
      {"empty array", [](Scene* s) { s->contacts.contacts.clear(); }, "empty"},
      {"d_free size", [](Scene* s) { s->contacts.contacts[0].d_free.push_back(0.0); },
       "4 d_free values for 3 rows"},
      {"W row count", [](Scene* s) { s->compliance.rows = 10; }, "rows=10, the contacts have 9"},
      {"W values for another size",
       [](Scene* s) {
         s->compliance.rows = 9;
         s->compliance.data.resize(100, 0.1);
       },
       "100 values, 9x9 expected"},
      {"empty W", [](Scene* s) { s->compliance.data.clear(); }, "0 values, 9x9 expected"},
      {"unknown type", [](Scene* s) { s->contacts.contacts[1].type = 9; }, "unknown type 9"},
      {"bilateral rows 7",
       [](Scene* s) {
         s->contacts.contacts[3].rows = 7;
         s->contacts.contacts[3].d_free.resize(7, 0.0);
       },
       "bilateral with rows=7"},
      {"rows field", [](Scene* s) { s->contacts.contacts[0].rows = 1; }, "rows=1 but its type has 3"},
      {"one tangent", [](Scene* s) { s->contacts.contacts[1].tangent2 = vec(0, 0, 0); }, "one tangent"},
      {"unknown storage", [](Scene* s) { s->compliance.storage = 7; }, "unknown storage 7"},
      {"over the row limit",
       [](Scene* s) {
         lcs::ContactPoint c;
         c.type = lcs::ContactPoint::FRICTIONLESS;
         c.normal = vec(0, 0, 1);
         c.d_free = {-0.01};
         c.mu = 0.0;
         s->contacts.contacts.assign(100000, c);
         for (std::size_t i = 0; i < s->contacts.contacts.size(); ++i)
           s->contacts.contacts[i].id = static_cast<std::int64_t>(i);
         s->compliance.rows = 100000;
         s->compliance.data.clear();
       },
       "100000 contacts, more than the row limit of 1000"},
  };
  return list;
}

// Block-sparse faults (on the block-sparse version of the scene).
std::vector<Fault> blockFaults() {
  return {
      {"NaN block", [](Scene* s) { s->compliance.block_data[5] = kNaN; }, "W holds a non-finite value"},
      {"block index", [](Scene* s) { s->compliance.block_rows[2] = 4000000000u; }, "beyond the 4 contacts"},
      {"block twice", [](Scene* s) { s->compliance.block_cols[1] = s->compliance.block_cols[0]; },
       "given twice"},
      {"block data size", [](Scene* s) { s->compliance.block_data.pop_back(); }, "its blocks need"},
      {"block index lists", [](Scene* s) { s->compliance.block_rows.push_back(0); }, "block_cols"},
  };
}

class AdversarialTest : public ::testing::Test {
 protected:
  void SetUp() override {
    contacts_pub_ = nh_.advertise<lcs::ContactArray>("contacts", 10);
    compliance_pub_ = nh_.advertise<lcs::Compliance>("compliance", 10);
    watch_ = std::make_unique<Watch>(nh_);
    ASSERT_TRUE(waitFor([&] {
      return contacts_pub_.getNumSubscribers() > 0 && compliance_pub_.getNumSubscribers() > 0 &&
             watch_->connected();
    })) << "the solver did not connect";
  }

  const lcs::SolverStats* solve(const Scene& scene, double timeout = 10.0) {
    compliance_pub_.publish(scene.compliance);
    contacts_pub_.publish(scene.contacts);
    if (!waitFor([&] { return watch_->stats(scene.contacts.header.stamp) != nullptr; }, timeout))
      return nullptr;
    return watch_->stats(scene.contacts.header.stamp);
  }

  // The good scene after a fault: solved, forces published and equal to the core's.
  void expectGoodSolve(const std::string& after) {
    const Scene good = makeScene(freshIds(), freshStamp());
    const lcs::SolverStats* stats = solve(good);
    ASSERT_NE(stats, nullptr) << "no stats for the good message after " << after;
    EXPECT_TRUE(stats->success) << after << ": " << stats->message;
    EXPECT_TRUE(stats->converged) << after;
    ASSERT_TRUE(waitFor([&] { return watch_->forces(good.contacts.header.stamp) != nullptr; }))
        << "no forces for the good message after " << after;
    lcs::core::Problem problem;
    std::vector<lcp_contact_solver_ros::ContactFrame> frames;
    ASSERT_EQ(lcp_contact_solver_ros::toProblem(good.contacts, good.compliance, 0, &problem, &frames), "");
    const lcs::core::SolveResult expected =
        lcs::core::solveProblem(problem, lcp_contact_solver_ros::defaultSolverParams());
    const lcs::ConstraintForces& got = *watch_->forces(good.contacts.header.stamp);
    ASSERT_EQ(got.forces.size(), problem.contacts.size());
    const std::vector<int> off = problem.rowOffsets();
    for (std::size_t i = 0; i < problem.contacts.size(); ++i)
      for (int k = 0; k < problem.contacts[i].rows; ++k)
        EXPECT_NEAR(got.forces[i].lambda[k], expected.forces[off[i] + k], 1e-12)
            << after << ": contact " << i;
  }

  ros::NodeHandle nh_;
  ros::Publisher contacts_pub_, compliance_pub_;
  std::unique_ptr<Watch> watch_;
};

TEST_F(AdversarialTest, TheRowLimitIsTheTestsOne) {
  int max_rows = 0;
  ASSERT_TRUE(ros::param::get(kSolver + "/max_rows", max_rows));
  EXPECT_EQ(max_rows, 1000);
}

TEST_F(AdversarialTest, TopicsRejectEveryFaultAndGoOn) {
  for (bool block_sparse : {false, true}) {
    for (const Fault& fault : block_sparse ? blockFaults() : faults()) {
      Scene scene = makeScene(freshIds(), freshStamp(), block_sparse);
      fault.spoil(&scene);
      const lcs::SolverStats* stats = solve(scene, 30.0);
      ASSERT_NE(stats, nullptr) << fault.name << ": no stats";
      EXPECT_FALSE(stats->success) << fault.name;
      EXPECT_EQ(stats->status, "invalid_input") << fault.name;
      EXPECT_EQ(stats->status_code, lcs::SolverStats::INVALID_INPUT) << fault.name;
      EXPECT_NE(stats->message.find(fault.expected), std::string::npos)
          << fault.name << ": '" << stats->message << "' should contain '" << fault.expected << "'";
      EXPECT_EQ(stats->message.find('\n'), std::string::npos) << fault.name;
      // Nothing for the bad stamp: give a late message time to arrive, then look.
      expectGoodSolve(fault.name);
      EXPECT_EQ(watch_->forces(scene.contacts.header.stamp), nullptr)
          << fault.name << ": forces were published";
    }
  }
  EXPECT_EQ(watch_->nonFinite(), 0);
  EXPECT_GT(watch_->markers(), 0);  // markers were built (we subscribe) and checked
}

TEST_F(AdversarialTest, ServiceRejectsEveryFaultAndGoesOn) {
  // One persistent connection for the ~80 calls: a fresh lookup and connection per call
  // failed now and then on a loaded CI machine (call() false with nothing on the node's side).
  ros::ServiceClient service = nh_.serviceClient<lcs::SolveContacts>(kSolver + "/solve_contacts", true);
  ASSERT_TRUE(service.waitForExistence(ros::Duration(10.0)));
  for (bool block_sparse : {false, true}) {
    for (const Fault& fault : block_sparse ? blockFaults() : faults()) {
      Scene scene = makeScene(freshIds(), freshStamp(), block_sparse);
      fault.spoil(&scene);
      lcs::SolveContacts srv;
      srv.request.contacts = scene.contacts;
      srv.request.compliance = scene.compliance;
      ASSERT_TRUE(service.call(srv)) << fault.name;
      EXPECT_FALSE(srv.response.success) << fault.name;
      EXPECT_NE(srv.response.message.find(fault.expected), std::string::npos)
          << fault.name << ": '" << srv.response.message << "'";
      EXPECT_EQ(srv.response.stats.status, "invalid_input") << fault.name;
      EXPECT_TRUE(srv.response.forces.forces.empty()) << fault.name;
      EXPECT_TRUE(lcp_contact_solver_ros::allFinite(srv.response.stats)) << fault.name;

      const Scene good = makeScene(freshIds(), freshStamp(), block_sparse);
      lcs::SolveContacts ok;
      ok.request.contacts = good.contacts;
      ok.request.compliance = good.compliance;
      ASSERT_TRUE(service.call(ok)) << fault.name;
      EXPECT_TRUE(ok.response.success) << fault.name << ": " << ok.response.message;
      EXPECT_EQ(ok.response.forces.forces.size(), 4u) << fault.name;
      EXPECT_TRUE(lcp_contact_solver_ros::allFinite(ok.response.forces)) << fault.name;
    }
  }
}

// Bad parameter overrides through the service: named, refused, the node unchanged.
TEST_F(AdversarialTest, ServiceRejectsBadOverrides) {
  const Scene scene = makeScene(freshIds(), freshStamp());
  for (const char* bad :
       {"tolerance=nan", "tolerance=-1", "maxIt=0", "mu=-2", "mu=inf", "sor=2", "regularizationTerm=-1",
        "solver=simplex", "max_rows=-5", "maxIt=1e99", "nonsense", "=1", "time_budget=nan", "erp=1.5",
        "erp=-0.1", "softness=-1", "softness=inf", "constraint_level=acceleration", "time_step=-0.01"}) {
    lcs::SolveContacts srv;
    srv.request.contacts = scene.contacts;
    srv.request.compliance = scene.compliance;
    srv.request.param_overrides = {bad};
    ASSERT_TRUE(ros::service::call(kSolver + "/solve_contacts", srv)) << bad;
    EXPECT_FALSE(srv.response.success) << bad << ": " << srv.response.message;
    EXPECT_FALSE(srv.response.message.empty()) << bad;
    EXPECT_TRUE(srv.response.forces.forces.empty()) << bad;
  }
  expectGoodSolve("bad overrides");
}

// Valid but extreme numbers: a nearly rigid W (1e-300) pressed by 1 m gives forces of
// 1e300 N; at positions of 1e10 m their torques overflow. The node must either publish
// finite forces or nothing (with stats saying why), never an Inf.
TEST_F(AdversarialTest, ExtremeButValidNumbersPublishNothingNonFinite) {
  for (double position : {1.0, 1e10}) {
    Scene scene = makeScene(freshIds(), freshStamp());
    for (auto& c : scene.contacts.contacts) {
      c.position.x = position;
      for (double& d : c.d_free) d = -1.0;
    }
    for (std::size_t i = 0; i < scene.compliance.data.size(); ++i)
      scene.compliance.data[i] = i % 10 == 0 ? 1e-300 : 0.0;
    const lcs::SolverStats* stats = solve(scene);
    ASSERT_NE(stats, nullptr);
    EXPECT_TRUE(lcp_contact_solver_ros::allFinite(*stats));
    waitFor([] { return false; }, 0.2);
    const lcs::ConstraintForces* forces = watch_->forces(scene.contacts.header.stamp);
    if (forces != nullptr) {
      EXPECT_TRUE(lcp_contact_solver_ros::allFinite(*forces)) << "position " << position;
    }
    std::printf("  extreme numbers at position %g: status %s, forces %s\n", position, stats->status.c_str(),
                forces ? "published" : "not published");
    expectGoodSolve("extreme numbers");
  }
  EXPECT_EQ(watch_->nonFinite(), 0);
}

// Non-unit normals are accepted and normalized: the forces of normals scaled by 1e-6 and
// 1e6 are those of the unit normals.
TEST_F(AdversarialTest, NonUnitNormalsAreNormalized) {
  const std::int64_t ids = freshIds();
  Scene unit = makeScene(ids, freshStamp());
  unit.contacts.contacts[2].normal = vec(0, 0, 1);
  lcs::SolveContacts reference;
  reference.request.contacts = unit.contacts;
  reference.request.compliance = unit.compliance;
  ASSERT_TRUE(ros::service::call(kSolver + "/solve_contacts", reference));
  ASSERT_TRUE(reference.response.success);
  for (double scale : {1e-6, 1e6}) {
    Scene scaled = unit;
    for (auto& c : scaled.contacts.contacts) {
      if (c.tangent1.x != 0.0 || c.tangent1.y != 0.0 || c.tangent1.z != 0.0)
        continue;  // given tangents: keep n
      c.normal.x *= scale;
      c.normal.y *= scale;
      c.normal.z *= scale;
    }
    lcs::SolveContacts srv;
    srv.request.contacts = scaled.contacts;
    srv.request.compliance = scaled.compliance;
    ASSERT_TRUE(ros::service::call(kSolver + "/solve_contacts", srv));
    ASSERT_TRUE(srv.response.success) << srv.response.message;
    for (std::size_t i = 0; i < srv.response.forces.forces.size(); ++i) {
      const auto& a = srv.response.forces.forces[i];
      const auto& b = reference.response.forces.forces[i];
      EXPECT_EQ(a.lambda, b.lambda) << "scale " << scale << " contact " << i;
      EXPECT_NEAR(a.normal.z, b.normal.z, 1e-15) << "scale " << scale << " contact " << i;
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_adversarial");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
