// Soak feeder (bench/soak.sh, docs/BENCHMARKS.md "Soak"; a benchmark, not a test).
//
// Replays the ContactArray/Compliance pairs of a recorded bag to a live contact_solver node
// in a loop, at a fixed wall-clock rate, for a fixed time, and counts what comes back. Each
// pair is sent with a fresh stamp, the same on both messages: the node pairs them by exact
// stamp, so a repeated stamp would pair with the wrong partner. The contact ids are kept, so
// the node warm-starts as it would in a running simulation.
//
//   soak_feeder BAG [--rate HZ] [--duration S] [--stats TOPIC]
//
// Defaults: 1000 Hz, 300 s, stats from contact_solver/stats; the topics are remappable.
// Prints a line per second (bench/soak.sh reads `forces N` from it) and a summary; the
// failures are stats with success false, by status. Latency: each pair's stamp is the wall
// time it was published, so a ConstraintForces message received carries its own start time;
// the summary gives the percentiles of (arrival − stamp) over all forces received, and each
// per-second line the median and p99 of that second.
#include <lcp_contact_solver/Compliance.h>
#include <lcp_contact_solver/ConstraintForces.h>
#include <lcp_contact_solver/ContactArray.h>
#include <lcp_contact_solver/SolverStats.h>
#include <ros/ros.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <map>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using lcp_contact_solver::Compliance;
using lcp_contact_solver::ConstraintForces;
using lcp_contact_solver::ContactArray;
using lcp_contact_solver::SolverStats;

struct Pair {
  ContactArray contacts;
  Compliance compliance;
};

// A message recorded with an older definition of its type does not instantiate (its MD5
// differs): say so, or an outdated bag would look empty.
template <class M>
void checkDefinition(const rosbag::MessageInstance& m) {
  if (m.getDataType() == ros::message_traits::datatype<M>() &&
      m.getMD5Sum() != ros::message_traits::md5sum<M>())
    throw std::runtime_error(m.getDataType() + " was recorded with another definition of the message (MD5 " +
                             m.getMD5Sum() + ", built " + ros::message_traits::md5sum<M>() +
                             "): re-record the bag");
}

// Matched by stamp, whatever the topics were called when recorded; the other types in the
// bag (the recorded forces and stats) are skipped. Sorted by stamp, i.e. in recording order.
std::vector<Pair> readPairs(const std::string& path) {
  rosbag::Bag bag(path, rosbag::bagmode::Read);
  std::map<ros::Time, ContactArray::ConstPtr> contacts;
  std::map<ros::Time, Compliance::ConstPtr> compliance;
  for (const rosbag::MessageInstance& m : rosbag::View(bag)) {
    checkDefinition<ContactArray>(m);
    checkDefinition<Compliance>(m);
    if (auto c = m.instantiate<ContactArray>())
      contacts[c->header.stamp] = c;
    else if (auto w = m.instantiate<Compliance>())
      compliance[w->header.stamp] = w;
  }
  std::vector<Pair> pairs;
  for (const auto& [stamp, c] : contacts) {
    auto w = compliance.find(stamp);
    if (w != compliance.end()) pairs.push_back({*c, *w->second});
  }
  return pairs;
}

// The q-quantile (nearest rank) of *values, reordered in place; NaN when empty.
double percentile(std::vector<double>* values, double q) {
  if (values->empty()) return std::numeric_limits<double>::quiet_NaN();
  const std::size_t k = std::min(values->size() - 1, static_cast<std::size_t>(q * values->size()));
  std::nth_element(values->begin(), values->begin() + k, values->end());
  return (*values)[k];
}

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "soak_feeder", ros::init_options::AnonymousName);
  std::string bag, stats_topic = "contact_solver/stats";
  double rate = 1000.0, duration = 300.0;
  CLI::App app{"soak_feeder: replays a bag's ContactArray/Compliance pairs to a live contact_solver"};
  app.option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  app.add_option("bag", bag, "the bag of ContactArray/Compliance pairs")->required();
  app.add_option("--rate", rate, "pairs per second (wall clock)")->capture_default_str();
  app.add_option("--duration", duration, "how long to feed (s)")->capture_default_str();
  app.add_option("--stats", stats_topic, "the node's SolverStats topic")->capture_default_str();
  try {
    app.parse(argc, argv);  // ros::init has removed the remappings
    if (!(rate > 0.0) || !(duration > 0.0)) throw CLI::ValidationError("--rate and --duration must be > 0");
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }

  std::vector<Pair> pairs;
  try {
    pairs = readPairs(bag);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "soak_feeder: %s: %s\n", bag.c_str(), e.what());
    return 2;
  }
  if (pairs.empty()) {
    std::fprintf(stderr, "soak_feeder: %s holds no ContactArray/Compliance pair\n", bag.c_str());
    return 2;
  }

  ros::NodeHandle nh;  // the first handle contacts the master: only once the input is good
  // Subscribing to constraint_forces also makes the node publish them (it does so only
  // with a subscriber unless computeConstraintForces is set), so the soak covers that path.
  // TCP_NODELAY: the answers arrive as sent, not batched by Nagle's algorithm, so the
  // per-second counts are those of that second.
  std::atomic<long> forces{0}, stats{0}, failures{0};
  std::map<std::string, long> failed_by_status;  // written by the spinner thread only, read after it stops
  const ros::TransportHints no_delay = ros::TransportHints().tcpNoDelay();
  std::mutex latency_mutex;
  std::vector<double> latencies, second_latencies;  // s; all, and since the last report line
  ros::Subscriber forces_sub = nh.subscribe<ConstraintForces>(
      "constraint_forces", 1000,
      [&](const ConstraintForces::ConstPtr& f) {
        const ros::WallTime now = ros::WallTime::now();
        const double latency = now.toSec() - f->header.stamp.toSec();
        ++forces;
        std::lock_guard<std::mutex> lock(latency_mutex);
        latencies.push_back(latency);
        second_latencies.push_back(latency);
      },
      ros::VoidConstPtr(), no_delay);
  ros::Subscriber stats_sub = nh.subscribe<SolverStats>(
      stats_topic, 1000,
      [&](const SolverStats::ConstPtr& s) {
        ++stats;
        if (!s->success) {
          ++failures;
          ++failed_by_status[s->status];
        }
      },
      ros::VoidConstPtr(), no_delay);
  // A second of input on each queue: a message lost here, at the sender, would reach the node
  // as an unpaired half and be counted against it.
  ros::Publisher contacts_pub = nh.advertise<ContactArray>("contacts", 1000);
  ros::Publisher compliance_pub = nh.advertise<Compliance>("compliance", 1000);
  // Callbacks in their own thread, so counting never delays the publishing loop.
  ros::AsyncSpinner spinner(1);
  spinner.start();

  // Messages sent before the connections are up would be lost and counted as failures.
  const ros::WallTime give_up = ros::WallTime::now() + ros::WallDuration(30.0);
  while (ros::ok() && (contacts_pub.getNumSubscribers() == 0 || compliance_pub.getNumSubscribers() == 0 ||
                       forces_sub.getNumPublishers() == 0 || stats_sub.getNumPublishers() == 0)) {
    if (ros::WallTime::now() > give_up) {
      std::fprintf(stderr, "soak_feeder: no contact solver connected within 30 s\n");
      return 1;
    }
    ros::WallDuration(0.05).sleep();
  }
  ros::WallDuration(0.5).sleep();  // connections are counted before the header exchange ends

  std::printf("soak_feeder: %zu pairs from %s (%zu contacts in the first), %.0f Hz for %.0f s\n",
              pairs.size(), bag.c_str(), pairs.front().contacts.contacts.size(), rate, duration);
  std::fflush(stdout);

  // Wall time throughout: the soak runs without /clock, and its rate is a real-time one.
  const ros::WallTime start = ros::WallTime::now();
  ros::WallRate loop(rate);  // a late cycle restarts the schedule instead of bursting to catch up
  ros::Time last_stamp;
  long sent = 0, sent_at_report = 0;
  double last_report = 0.0, elapsed = 0.0;
  while (ros::ok() && (elapsed = (ros::WallTime::now() - start).toSec()) < duration) {
    Pair& p = pairs[sent % pairs.size()];
    const ros::WallTime now = ros::WallTime::now();
    ros::Time stamp(now.sec, now.nsec);
    if (stamp <= last_stamp) stamp = last_stamp + ros::Duration(0, 1);  // strictly increasing
    last_stamp = p.contacts.header.stamp = p.compliance.header.stamp = stamp;
    // Compliance first, so the pair is complete when the ContactArray arrives.
    compliance_pub.publish(p.compliance);
    contacts_pub.publish(p.contacts);
    ++sent;
    if (elapsed - last_report >= 1.0) {
      std::vector<double> second;
      {
        std::lock_guard<std::mutex> lock(latency_mutex);
        second.swap(second_latencies);
      }
      std::printf(
          "t %5.0f s  sent %9ld  rate %7.1f Hz  forces %9ld  stats %9ld  failures %6ld  latency p50 %.3f p99 "
          "%.3f ms\n",
          elapsed, sent, (sent - sent_at_report) / (elapsed - last_report), forces.load(), stats.load(),
          failures.load(), 1e3 * percentile(&second, 0.5), 1e3 * percentile(&second, 0.99));
      std::fflush(stdout);
      sent_at_report = sent;
      last_report = elapsed;
    }
    loop.sleep();
  }
  const double total = (ros::WallTime::now() - start).toSec();

  // The last answers are still on their way.
  const ros::WallTime drain_end = ros::WallTime::now() + ros::WallDuration(2.0);
  while (ros::ok() && ros::WallTime::now() < drain_end && stats.load() < sent)
    ros::WallDuration(0.01).sleep();
  spinner.stop();

  std::printf(
      "summary: sent %ld pairs in %.1f s (%.1f Hz achieved, %.0f Hz asked); forces received %ld, "
      "stats received %ld, failures %ld, unanswered %ld\n",
      sent, total, sent / total, rate, forces.load(), stats.load(), failures.load(), sent - stats.load());
  for (const auto& [status, n] : failed_by_status) std::printf("failures: %ld %s\n", n, status.c_str());
  std::lock_guard<std::mutex> lock(latency_mutex);
  std::printf(
      "latency (publish to forces received, ms, %zu forces): p50 %.3f  p90 %.3f  p99 %.3f  p99.9 %.3f  max "
      "%.3f\n",
      latencies.size(), 1e3 * percentile(&latencies, 0.5), 1e3 * percentile(&latencies, 0.9),
      1e3 * percentile(&latencies, 0.99), 1e3 * percentile(&latencies, 0.999),
      1e3 * percentile(&latencies, 1.0));
  return stats.load() > 0 ? 0 : 1;
}
