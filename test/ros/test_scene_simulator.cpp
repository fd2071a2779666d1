// Runs beside the scene_simulator and contact_solver nodes (test/ros/scene_simulator.test):
// records what the closed loop publishes (contacts, forces, tf), then replays the same scene
// in-process (SceneSimulator::step() with the solver node's own parameters) and checks
//   - every step with contacts got its forces (no timeouts, no failures);
//   - resting bodies carry their weight: net contact force = m·g within 1 %;
//   - the trajectory through the node equals the in-process one (poses and λ within 1e-9).
#include "lcp_contact_solver/ros/msg_conversion/scene_msg_conversion.h"
#include "lcp_contact_solver/ros/node/solver_params_ros.h"
#include "lcp_contact_solver/ros/sim/scene_simulator_node.h"
#include "lcp_contact_solver/scene/scene.h"
#include "lcp_contact_solver/scene/scene_simulator.h"

#include <gtest/gtest.h>
#include <lcp_contact_solver/Compliance.h>
#include <lcp_contact_solver/ConstraintForces.h>
#include <lcp_contact_solver/ContactArray.h>
#include <lcp_contact_solver/SolverStats.h>
#include <ros/ros.h>
#include <tf2_msgs/TFMessage.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <map>
#include <memory>
#include <sstream>
#include <string>

namespace lcs = lcp_contact_solver;
namespace scene = lcp_contact_solver::scene;
using lcp_contact_solver_ros::stepStamp;

namespace {

const std::string kSimulator = "/scene_simulator";
const std::string kSolver = "/contact_solver";

struct Pose {
  Eigen::Vector3d position;
  Eigen::Quaterniond orientation;
};

// Everything the closed loop published, by stamp.
struct Recording {
  std::map<ros::Time, lcs::ContactArray> contacts;
  std::map<ros::Time, lcs::ConstraintForces> forces;
  std::map<ros::Time, lcs::SolverStats> stats;
  std::map<ros::Time, std::map<std::string, Pose>> poses;  // stamp → child frame → pose
};

template <typename Predicate>
bool waitFor(Predicate done, double timeout) {
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(timeout);
  while (ros::ok() && ros::WallTime::now() < end) {
    ros::spinOnce();
    if (done()) return true;
    ros::WallDuration(0.002).sleep();
  }
  return done();
}

template <typename T>
T param(const std::string& name, const T& fallback) {
  T value = fallback;
  ros::param::get(name, value);
  return value;
}

class SceneSimulatorTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    recording_ = std::make_unique<Recording>();
    ros::NodeHandle nh;
    Recording* rec = recording_.get();
    // tf and the forces first; contacts and compliance last: the simulator starts stepping
    // once they have this node as their second subscriber, so nothing is missed.
    subs_.push_back(
        nh.subscribe<tf2_msgs::TFMessage>("/tf", 1000, [rec](const tf2_msgs::TFMessage::ConstPtr& m) {
          for (const auto& t : m->transforms) {
            Pose p;
            p.position = {t.transform.translation.x, t.transform.translation.y, t.transform.translation.z};
            p.orientation = Eigen::Quaterniond(t.transform.rotation.w, t.transform.rotation.x,
                                               t.transform.rotation.y, t.transform.rotation.z);
            rec->poses[t.header.stamp][t.child_frame_id] = p;
          }
        }));
    subs_.push_back(nh.subscribe<lcs::ConstraintForces>(
        "constraint_forces", 1000,
        [rec](const lcs::ConstraintForces::ConstPtr& m) { rec->forces[m->header.stamp] = *m; }));
    subs_.push_back(nh.subscribe<lcs::SolverStats>(
        "contact_solver/stats", 1000,
        [rec](const lcs::SolverStats::ConstPtr& m) { rec->stats[m->header.stamp] = *m; }));
    connected_ =
        waitFor([] { return subs_[0].getNumPublishers() > 0 && subs_[1].getNumPublishers() > 0; }, 30.0);
    subs_.push_back(nh.subscribe<lcs::ContactArray>(
        "contacts", 1000,
        [rec](const lcs::ContactArray::ConstPtr& m) { rec->contacts[m->header.stamp] = *m; }));
    subs_.push_back(nh.subscribe<lcs::Compliance>("compliance", 1000,
                                                  [rec](const lcs::Compliance::ConstPtr&) { (void)rec; }));

    // The run ends with the tf of the last step.
    dt_ = param<double>(kSimulator + "/dt", 0.0);
    scene_ = loadTestScene();
    steps_ = std::llround(param<double>(kSimulator + "/duration", 0.0) / scene_.params.dt);
    const ros::Time last = stepStamp(steps_, scene_.params.dt);
    finished_ = waitFor([rec, last] { return rec->poses.count(last) > 0; }, 60.0);
    // Forces and stats of the last step may trail its tf by a moment.
    waitFor([] { return false; }, 0.3);
  }

  static void TearDownTestSuite() {
    subs_.clear();
    recording_.reset();
  }

  // The scene the simulator loaded, with the solver node's parameters for the in-process
  // solver: those are what must match for the two loops to agree (tolerance, maxIt, solver,
  // warm start by id, regularization, ...).
  static scene::Scene loadTestScene() {
    const std::string dir = param<std::string>(kSimulator + "/scene_dir", "");
    const std::string name = param<std::string>(kSimulator + "/scene", "");
    scene::Scene s = scene::loadNamedScene(dir, name);
    if (dt_ > 0.0) s.params.dt = dt_;
    lcp_contact_solver_ros::NodeSettings settings;
    const std::string error = lcp_contact_solver_ros::loadSettings(ros::NodeHandle(kSolver), &settings);
    EXPECT_EQ(error, "");
    s.params.solver = settings.solver;
    return s;
  }

  // Net contact force on each body from one ConstraintForces message.
  static std::map<std::string, Eigen::Vector3d> netContactForces(const lcs::ConstraintForces& forces) {
    std::map<std::string, Eigen::Vector3d> net;
    for (const lcs::ContactForce& f : forces.forces) {
      const Eigen::Vector3d v(f.force.x, f.force.y, f.force.z);
      net.emplace(f.body_a, Eigen::Vector3d::Zero()).first->second += v;
      net.emplace(f.body_b, Eigen::Vector3d::Zero()).first->second -= v;
    }
    return net;
  }

  static std::unique_ptr<Recording> recording_;
  static std::vector<ros::Subscriber> subs_;
  static bool connected_, finished_;
  static double dt_;
  static scene::Scene scene_;
  static long long steps_;
};

std::unique_ptr<Recording> SceneSimulatorTest::recording_;
std::vector<ros::Subscriber> SceneSimulatorTest::subs_;
bool SceneSimulatorTest::connected_ = false;
bool SceneSimulatorTest::finished_ = false;
double SceneSimulatorTest::dt_ = 0.0;
scene::Scene SceneSimulatorTest::scene_;
long long SceneSimulatorTest::steps_ = 0;

TEST_F(SceneSimulatorTest, RunCompletes) {
  ASSERT_TRUE(connected_) << "the simulator's tf or the solver's forces never connected";
  ASSERT_GT(steps_, 0);
  ASSERT_TRUE(finished_) << "no tf for the last step (" << steps_ << ") arrived; the last seen: "
                         << (recording_->poses.empty()
                                 ? std::string("none")
                                 : std::to_string(recording_->poses.rbegin()->first.toSec()) + " s");
  EXPECT_EQ(static_cast<long long>(recording_->poses.size()), steps_ + 1)
      << "tf stamps (initial pose + one per step)";
}

TEST_F(SceneSimulatorTest, ForcesArriveEveryStep) {
  ASSERT_TRUE(finished_);
  ASSERT_FALSE(recording_->contacts.empty()) << "the scene never had contacts";
  for (const auto& [stamp, contacts] : recording_->contacts) {
    ASSERT_EQ(recording_->forces.count(stamp), 1u) << "no forces for the contacts at " << stamp;
    const lcs::ConstraintForces& forces = recording_->forces.at(stamp);
    EXPECT_EQ(forces.forces.size(), contacts.contacts.size());
    ASSERT_EQ(recording_->stats.count(stamp), 1u) << "no solver stats for " << stamp;
    const lcs::SolverStats& stats = recording_->stats.at(stamp);
    EXPECT_TRUE(stats.success) << stats.status << ": " << stats.message;
    EXPECT_TRUE(stats.converged) << "step at " << stamp << ": " << stats.status << ", residual "
                                 << stats.residual;
  }
  EXPECT_EQ(recording_->forces.size(), recording_->contacts.size()) << "forces without contacts";
}

// Bodies at rest at the end carry their weight; every body in steady contact (resting or
// sliding on a plane) at least its vertical weight.
TEST_F(SceneSimulatorTest, RestingBodiesCarryTheirWeight) {
  ASSERT_TRUE(finished_);
  ASSERT_FALSE(recording_->forces.empty());
  const lcs::ConstraintForces& last = recording_->forces.rbegin()->second;
  const auto net = netContactForces(last);
  // The body states at the end, from the in-process run (equal to the node's: see below).
  scene::Scene s = scene_;
  scene::SceneSimulator sim(std::move(s));
  for (long long k = 0; k < steps_; ++k) sim.step();
  int checked = 0;
  for (const scene::RigidBody& b : sim.scene().bodies) {
    if (b.is_static) continue;
    const Eigen::Vector3d weight = -b.mass * sim.params().gravity;  // support needed, N
    const auto it = net.find(b.name);
    ASSERT_NE(it, net.end()) << b.name << " has no contact at the end";
    const bool at_rest = b.linear_velocity.norm() < 1e-3 && b.angular_velocity.norm() < 1e-2;
    EXPECT_NEAR(it->second.z(), weight.z(), 0.01 * weight.norm()) << b.name << " vertical contact force";
    if (at_rest) {
      EXPECT_NEAR((it->second - weight).norm(), 0.0, 0.01 * weight.norm()) << b.name << " is at rest";
      ++checked;
    }
  }
  EXPECT_GT(checked, 0) << "no body came to rest";
  // The solver's normal forces of the bottom layer hold everything: Σ λ_n against the
  // ground = total weight (the ground's normal is vertical in these scenes).
  double ground = 0.0, total_weight = 0.0;
  for (const lcs::ContactForce& f : last.forces)
    if (f.body_b == "ground_plane") ground += f.normal_force;
  for (const scene::RigidBody& b : sim.scene().bodies)
    if (!b.is_static) total_weight += b.mass * sim.params().gravity.norm();
  EXPECT_NEAR(ground, total_weight, 0.01 * total_weight) << "normal forces against the ground";
}

TEST_F(SceneSimulatorTest, ClosedLoopMatchesInProcessSimulator) {
  ASSERT_TRUE(finished_);
  scene::Scene s = scene_;
  scene::SceneSimulator sim(std::move(s));
  constexpr double kTolerance = 1e-9;
  double worst_pose = 0.0, worst_force = 0.0;
  for (long long k = 0; k < steps_; ++k) {
    const ros::Time stamp = stepStamp(k, sim.params().dt);
    const scene::StepStats stats = sim.step();
    const lcs::core::Problem& problem = sim.lastProblem().problem;
    // Same contacts (ids, order) and the same forces by id.
    const auto contacts = recording_->contacts.find(stamp);
    if (problem.contacts.empty()) {
      EXPECT_EQ(contacts, recording_->contacts.end())
          << "step " << k << " published contacts without having any";
    } else {
      ASSERT_NE(contacts, recording_->contacts.end()) << "step " << k << " has contacts in-process only";
      ASSERT_EQ(contacts->second.contacts.size(), problem.contacts.size()) << "step " << k;
      for (std::size_t i = 0; i < problem.contacts.size(); ++i)
        ASSERT_EQ(contacts->second.contacts[i].id, problem.contacts[i].id)
            << "step " << k << " contact " << i;
      ASSERT_EQ(recording_->forces.count(stamp), 1u) << "step " << k;
      Eigen::VectorXd lambda;
      ASSERT_EQ(lcp_contact_solver_ros::toStepForces(recording_->forces.at(stamp), problem, &lambda), "");
      const double scale = 1.0 + sim.lastForces().lpNorm<Eigen::Infinity>();
      const double diff = (lambda - sim.lastForces()).lpNorm<Eigen::Infinity>() / scale;
      worst_force = std::max(worst_force, diff);
      ASSERT_LE(diff, kTolerance) << "forces differ at step " << k;
      EXPECT_EQ(recording_->stats.at(stamp).iterations, sim.lastSolve().iterations) << "step " << k;
    }
    // Same poses after the step.
    const auto poses = recording_->poses.find(stepStamp(stats.step_index + 1, sim.params().dt));
    ASSERT_NE(poses, recording_->poses.end()) << "no tf after step " << k;
    for (const scene::RigidBody& b : sim.scene().bodies) {
      if (b.is_static) continue;
      const auto pose = poses->second.find(b.name);
      ASSERT_NE(pose, poses->second.end()) << b.name << " missing from the tf after step " << k;
      const double dp = (pose->second.position - b.position).norm();
      const double dq = std::min((pose->second.orientation.coeffs() - b.orientation.coeffs()).norm(),
                                 (pose->second.orientation.coeffs() + b.orientation.coeffs()).norm());
      worst_pose = std::max({worst_pose, dp, dq});
      ASSERT_LE(dp, kTolerance) << b.name << " position after step " << k;
      ASSERT_LE(dq, kTolerance) << b.name << " orientation after step " << k;
    }
  }
  auto text = [](double v) {
    std::ostringstream out;
    out << std::setprecision(3) << v;
    return out.str();
  };
  RecordProperty("worst_pose_difference", text(worst_pose));
  RecordProperty("worst_force_difference", text(worst_force));
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_scene_simulator");
  ros::NodeHandle nh;  // keeps the node alive for the whole run
  return RUN_ALL_TESTS();
}
