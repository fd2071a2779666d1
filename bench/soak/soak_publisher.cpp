// Soak feeder (bench/soak/run-soak; not a test): replays the contact/compliance pairs of a
// recorded bag to a live contact_solver node at a fixed rate, over and over, each pair with
// a fresh stamp (the contact ids stay, so the node warm-starts as in a real run), and counts
// what the node answers on ~stats. Prints one line per second and a summary.
//
//   soak_publisher BAG [--rate HZ] [--duration S] [--solver-ns NS]
#include <lcp_contact_solver/Compliance.h>
#include <lcp_contact_solver/ContactArray.h>
#include <lcp_contact_solver/SolverStats.h>
#include <ros/ros.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>

#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

namespace {

using lcp_contact_solver::Compliance;
using lcp_contact_solver::ContactArray;
using lcp_contact_solver::SolverStats;

struct Pair {
  ContactArray contacts;
  Compliance compliance;
};

std::vector<Pair> readPairs(const std::string& path) {
  rosbag::Bag bag(path, rosbag::bagmode::Read);
  std::map<ros::Time, Pair> by_stamp;
  std::map<ros::Time, int> have;
  for (const rosbag::MessageInstance& m : rosbag::View(bag)) {
    if (ContactArray::ConstPtr c = m.instantiate<ContactArray>()) {
      by_stamp[c->header.stamp].contacts = *c;
      have[c->header.stamp] |= 1;
    } else if (Compliance::ConstPtr w = m.instantiate<Compliance>()) {
      by_stamp[w->header.stamp].compliance = *w;
      have[w->header.stamp] |= 2;
    }
  }
  std::vector<Pair> pairs;
  for (const auto& entry : by_stamp)
    if (have[entry.first] == 3) pairs.push_back(entry.second);
  return pairs;
}

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "soak_publisher", ros::init_options::AnonymousName);
  std::string bag;
  double rate = 1000.0, duration = 300.0;
  std::string solver_ns = "contact_solver";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--rate" && i + 1 < argc) rate = std::atof(argv[++i]);
    else if (a == "--duration" && i + 1 < argc) duration = std::atof(argv[++i]);
    else if (a == "--solver-ns" && i + 1 < argc) solver_ns = argv[++i];
    else if (bag.empty() && a[0] != '-') bag = a;
    else {
      std::fprintf(stderr, "usage: soak_publisher BAG [--rate HZ] [--duration S] [--solver-ns NS]\n");
      return 2;
    }
  }
  if (bag.empty() || !(rate > 0.0) || !(duration > 0.0)) {
    std::fprintf(stderr, "usage: soak_publisher BAG [--rate HZ] [--duration S] [--solver-ns NS]\n");
    return 2;
  }
  std::vector<Pair> pairs;
  try {
    pairs = readPairs(bag);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "soak_publisher: %s: %s\n", bag.c_str(), e.what());
    return 2;
  }
  if (pairs.empty()) {
    std::fprintf(stderr, "soak_publisher: %s holds no contacts/compliance pairs\n", bag.c_str());
    return 2;
  }
  ros::NodeHandle nh;
  ros::Publisher contacts_pub = nh.advertise<ContactArray>("contacts", 100);
  ros::Publisher compliance_pub = nh.advertise<Compliance>("compliance", 100);
  long stats_received = 0, stats_success = 0, stats_converged = 0;
  double solve_time = 0.0;
  ros::Subscriber stats_sub = nh.subscribe<SolverStats>(
      solver_ns + "/stats", 1000, [&](const SolverStats::ConstPtr& s) {
        ++stats_received;
        stats_success += s->success ? 1 : 0;
        stats_converged += s->converged ? 1 : 0;
        solve_time += s->solve_time;
      });
  const ros::WallTime wait_end = ros::WallTime::now() + ros::WallDuration(10.0);
  while (ros::ok() && ros::WallTime::now() < wait_end &&
         (contacts_pub.getNumSubscribers() == 0 || compliance_pub.getNumSubscribers() == 0 || stats_sub.getNumPublishers() == 0)) {
    ros::WallDuration(0.05).sleep();
    ros::spinOnce();
  }
  if (contacts_pub.getNumSubscribers() == 0) {
    std::fprintf(stderr, "soak_publisher: no contact solver subscribed within 10 s\n");
    return 1;
  }
  std::printf("soak_publisher: %zu pairs from %s (%zu contacts in the first), %.0f Hz for %.0f s\n", pairs.size(),
              bag.c_str(), pairs.front().contacts.contacts.size(), rate, duration);
  std::fflush(stdout);
  const ros::WallTime start = ros::WallTime::now();
  const ros::WallDuration period(1.0 / rate);
  ros::WallTime next = start;
  long published = 0;
  double next_report = 1.0;
  long last_received = 0;
  while (ros::ok()) {
    const double elapsed = (ros::WallTime::now() - start).toSec();
    if (elapsed >= duration) break;
    Pair& p = pairs[published % pairs.size()];
    ros::Time stamp = ros::Time::now();
    static ros::Time last;
    if (stamp <= last) stamp = last + ros::Duration(0, 1000);  // stamps must differ to pair
    last = stamp;
    p.contacts.header.stamp = stamp;
    p.compliance.header.stamp = stamp;
    compliance_pub.publish(p.compliance);
    contacts_pub.publish(p.contacts);
    ++published;
    ros::spinOnce();
    if (elapsed >= next_report) {
      std::printf("t %6.0f s  published %9ld  answered %9ld  (%5ld /s)\n", elapsed, published, stats_received,
                  stats_received - last_received);
      std::fflush(stdout);
      last_received = stats_received;
      next_report += 1.0;
    }
    next += period;
    const ros::WallDuration wait = next - ros::WallTime::now();
    if (wait > ros::WallDuration(0)) wait.sleep();
    else if (wait < ros::WallDuration(-0.1)) next = ros::WallTime::now();  // fell behind: do not burst
  }
  const double total = (ros::WallTime::now() - start).toSec();
  const ros::WallTime drain_end = ros::WallTime::now() + ros::WallDuration(2.0);
  while (ros::ok() && ros::WallTime::now() < drain_end && stats_received < published) {
    ros::spinOnce();
    ros::WallDuration(0.01).sleep();
  }
  std::printf("summary: published %ld pairs in %.1f s (%.1f Hz); stats received %ld, success %ld, converged %ld, "
              "mean solve %.1f us\n",
              published, total, published / total, stats_received, stats_success, stats_converged,
              stats_received > 0 ? 1e6 * solve_time / stats_received : 0.0);
  return 0;
}
