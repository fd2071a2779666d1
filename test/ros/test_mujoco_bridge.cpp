// Runs beside mujoco_bridge and contact_solver_node (test/ros/mujoco_bridge.test): reads the
// bridge's ~step_report of every step with contacts and checks
//   - the forces of every step came from the solver (no timeout, failure or mismatch);
//   - our residual is tight and, when ~max_rel_diff >= 0, every step's forces agree with
//     MuJoCo's efc_force within it (the pyramidal cone: an LCP with a unique solution);
//   - with ~max_position_diff >= 0 (drive with the bridge's ~reference: MuJoCo's own run of the
//     same model beside ours), the physics agree where the forces differ by design: every
//     body within ~max_position_diff of its place in MuJoCo's run, the energies within
//     ~max_energy_diff, the same geom pairs in contact on all but ~max_pair_differ_steps steps;
//   - MuJoCo's own forces, published on ~reference_forces for every step with contacts, come
//     in the node's layout (the ids and rows of the node's constraint_forces of that stamp)
//     and, when ~max_rel_diff >= 0, agree with the node's within it, as the report says;
//   - the humanoid stays on the floor (penetration below 2 cm: MuJoCo's soft contacts give
//     ~1.2 cm on the landing).
#include <diagnostic_msgs/DiagnosticStatus.h>
#include <gtest/gtest.h>
#include <lcp_contact_solver/ConstraintForces.h>
#include <ros/ros.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

namespace {

using Report = std::map<std::string, std::string>;

double number(const Report& r, const std::string& key) {
  const auto it = r.find(key);
  EXPECT_NE(it, r.end()) << "report without " << key;
  return it == r.end() ? 0.0 : std::strtod(it->second.c_str(), nullptr);
}

TEST(MujocoBridge, EveryStepSolvedAndMatched) {
  ros::NodeHandle nh, pnh("~");
  int min_reports = 60;
  double max_rel_diff = 1e-6;
  pnh.getParam("min_reports", min_reports);
  pnh.getParam("max_rel_diff", max_rel_diff);
  double max_position_diff = -1.0, max_energy_diff = -1.0;
  int max_pair_differ_steps = 0;
  pnh.getParam("max_position_diff", max_position_diff);
  pnh.getParam("max_energy_diff", max_energy_diff);
  pnh.getParam("max_pair_differ_steps", max_pair_differ_steps);

  std::vector<Report> reports;
  ros::Subscriber sub = nh.subscribe<diagnostic_msgs::DiagnosticStatus>(
      "/mujoco_bridge/step_report", 1000, [&reports](const diagnostic_msgs::DiagnosticStatus::ConstPtr& msg) {
        Report r;
        for (const auto& kv : msg->values) r[kv.key] = kv.value;
        r["_message"] = msg->message;
        reports.push_back(r);
      });
  using lcp_contact_solver::ConstraintForces;
  std::map<ros::Time, ConstraintForces::ConstPtr> ours, mujocos;
  ros::Subscriber ours_sub = nh.subscribe<ConstraintForces>(
      "/constraint_forces", 1000,
      [&ours](const ConstraintForces::ConstPtr& msg) { ours[msg->header.stamp] = msg; });
  ros::Subscriber mujoco_sub = nh.subscribe<ConstraintForces>(
      "/mujoco_bridge/reference_forces", 1000,
      [&mujocos](const ConstraintForces::ConstPtr& msg) { mujocos[msg->header.stamp] = msg; });
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(100.0);
  while (ros::ok() && ros::WallTime::now() < end && static_cast<int>(reports.size()) < min_reports) {
    ros::spinOnce();
    ros::WallDuration(0.005).sleep();
  }
  ASSERT_GE(static_cast<int>(reports.size()), min_reports) << "too few step reports from the bridge";

  double worst_rel = 0.0, worst_residual = 0.0, deepest = 0.0;
  int max_contacts = 0, pair_differ_steps = 0;
  double worst_position = 0.0, worst_energy = 0.0;
  for (const Report& r : reports) {
    if (max_position_diff >= 0.0) {  // before the forces' check: the reference runs regardless
      const double position = number(r, "ref_position_diff");
      const double energy = std::abs(number(r, "energy") - number(r, "ref_energy"));
      EXPECT_LE(position, max_position_diff) << "step " << r.at("step");
      EXPECT_LE(energy, max_energy_diff) << "step " << r.at("step");
      worst_position = std::max(worst_position, position);
      worst_energy = std::max(worst_energy, energy);
      if (number(r, "ref_contact_pairs_differ") > 0) ++pair_differ_steps;
    }
    ASSERT_EQ(r.count("forces"), 1u);
    EXPECT_EQ(r.at("forces"), "received") << "step " << r.at("step") << ": " << r.at("_message");
    if (r.at("forces") != "received") continue;
    max_contacts = std::max(max_contacts, static_cast<int>(number(r, "contacts")));
    worst_residual = std::max(worst_residual, number(r, "residual"));
    deepest = std::max(deepest, number(r, "penetration"));
    if (max_rel_diff >= 0.0) {
      const double rel = number(r, "max_rel_diff");
      EXPECT_LE(rel, max_rel_diff) << "step " << r.at("step");
      worst_rel = std::max(worst_rel, rel);
    }
  }
  std::printf(
      "%zu step reports: up to %d contacts, max residual %.2e, max relative difference to MuJoCo %.2e, "
      "max penetration %.4f m\n",
      reports.size(), max_contacts, worst_residual, worst_rel, deepest);
  if (max_position_diff >= 0.0) {
    std::printf(
        "against MuJoCo's own run: bodies up to %.2e m apart, energies up to %.2e J, contact pairs differ on "
        "%d steps\n",
        worst_position, worst_energy, pair_differ_steps);
    EXPECT_LE(pair_differ_steps, max_pair_differ_steps);
  }
  // The reference: a subscriber that joined late misses the first steps, so most, not all.
  EXPECT_GE(mujocos.size(), reports.size() / 2);
  double worst_reference_rel = 0.0;
  std::size_t matched = 0;
  for (const auto& [stamp, theirs] : mujocos) {
    const auto it = ours.find(stamp);
    if (it == ours.end()) continue;  // the node's forces of that step were missed
    const ConstraintForces& mine = *it->second;
    ASSERT_EQ(mine.forces.size(), theirs->forces.size()) << "stamp " << stamp;
    double scale = 0.0, diff = 0.0;
    for (std::size_t i = 0; i < mine.forces.size(); ++i) {
      ASSERT_EQ(mine.forces[i].id, theirs->forces[i].id) << "stamp " << stamp << ", contact " << i;
      ASSERT_EQ(mine.forces[i].lambda.size(), theirs->forces[i].lambda.size()) << "stamp " << stamp;
      for (std::size_t k = 0; k < mine.forces[i].lambda.size(); ++k) {
        scale = std::max({scale, std::abs(mine.forces[i].lambda[k]), std::abs(theirs->forces[i].lambda[k])});
        diff = std::max(diff, std::abs(mine.forces[i].lambda[k] - theirs->forces[i].lambda[k]));
      }
    }
    ++matched;
    const double rel = scale > 0.0 ? diff / scale : 0.0;
    worst_reference_rel = std::max(worst_reference_rel, rel);
    if (max_rel_diff >= 0.0) {
      EXPECT_LE(rel, max_rel_diff) << "stamp " << stamp;
    }
  }
  EXPECT_GE(matched, mujocos.size() / 2);
  std::printf("%zu reference forces from MuJoCo, %zu matched with the node's: max relative difference %.2e\n",
              mujocos.size(), matched, worst_reference_rel);
  EXPECT_GT(max_contacts, 0);
  EXPECT_LT(worst_residual, 1e-9);
  EXPECT_LT(deepest, 0.02);
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_mujoco_bridge");
  return RUN_ALL_TESTS();
}
