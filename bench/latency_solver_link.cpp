// The link with the running solver: the callbacks that pair its answers with what was sent,
// the publisher of the pairs, the nodelet loaded in this process, the solver's CPU time, and
// the marker sink.
#include "latency_live.h"

#include <visualization_msgs/MarkerArray.h>

#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <sstream>

namespace lcs_bench::latency {

void Tracker::reset() {
  std::lock_guard<std::mutex> lock(m);
  pending.clear();
  in_flight = 0;
  completed = failed = 0;
  lat_forces.clear();
  lat_stats.clear();
  solve_time.clear();
  iterations.clear();
  overhead.clear();
  node_overhead.clear();
  statuses.clear();
}

std::map<std::uint64_t, Pending>::iterator Tracker::claim(std::uint64_t stamp, bool Pending::*answer) {
  auto it = pending.find(stamp);
  if (it == pending.end() || it->second.*answer) return pending.end();
  it->second.*answer = true;
  return it;
}

void Tracker::onForces(const lcs::ConstraintForces::ConstPtr& f) {
  const auto now = Clock::now();
  std::lock_guard<std::mutex> lock(m);
  const auto it = claim(f->header.stamp.toNSec(), &Pending::forces);
  if (it == pending.end()) return;
  it->second.lat_forces = std::chrono::duration<double>(now - it->second.sent).count();
  lat_forces.push_back(it->second.lat_forces);
  --in_flight;
  ++completed;
  if (it->second.stats) pending.erase(it);
  cv.notify_all();
}

void Tracker::onStats(const lcs::SolverStats::ConstPtr& s) {
  const auto now = Clock::now();
  std::lock_guard<std::mutex> lock(m);
  const auto it = claim(s->header.stamp.toNSec(), &Pending::stats);
  if (it == pending.end()) return;
  lat_stats.push_back(std::chrono::duration<double>(now - it->second.sent).count());
  if (s->success) {  // a dropped or unpaired array has no solve (solve_time 0)
    solve_time.push_back(s->solve_time);
    iterations.push_back(s->iterations);
  }
  ++statuses[s->status];
  if (std::isfinite(it->second.lat_forces)) overhead.push_back(it->second.lat_forces - s->solve_time);
  if (s->success) node_overhead.push_back(s->latency - s->solve_time);
  if (!s->success && !it->second.forces) {  // no forces will come
    it->second.forces = true;
    --in_flight;
    ++failed;
  }
  if (it->second.forces) pending.erase(it);
  cv.notify_all();
}

long Tracker::expire(double timeout) {
  const auto now = Clock::now();
  long lost = 0;
  for (auto it = pending.begin(); it != pending.end();) {
    if (std::chrono::duration<double>(now - it->second.sent).count() > timeout) {
      if (!it->second.forces) {
        --in_flight;
        ++lost;
      }
      it = pending.erase(it);
    } else {
      ++it;
    }
  }
  return lost;
}

Sender::Sender(ros::NodeHandle& nh, Tracker& tracker, bool shared_ptrs)
    : tracker_(tracker), shared_(shared_ptrs) {
  contacts_pub_ = nh.advertise<lcs::ContactArray>("contacts", 100);
  compliance_pub_ = nh.advertise<lcs::Compliance>("compliance", 100);
}

void Sender::send(Case& p) {
  ros::WallTime now = ros::WallTime::now();
  ros::Time stamp(now.sec, now.nsec);
  if (stamp <= last_) stamp = last_ + ros::Duration(0, 1);
  last_ = stamp;
  p.contacts.header.stamp = p.compliance.header.stamp = stamp;
  boost::shared_ptr<lcs::Compliance> w;
  boost::shared_ptr<lcs::ContactArray> c;
  if (shared_) {  // fresh messages: a published shared pointer must not change afterwards
    w = boost::make_shared<lcs::Compliance>(p.compliance);
    c = boost::make_shared<lcs::ContactArray>(p.contacts);
  }
  {
    std::lock_guard<std::mutex> lock(tracker_.m);
    tracker_.pending[stamp.toNSec()] = Pending{Clock::now()};
    ++tracker_.in_flight;
  }
  if (shared_) {
    compliance_pub_.publish(w);
    contacts_pub_.publish(c);
  } else {
    compliance_pub_.publish(p.compliance);
    contacts_pub_.publish(p.contacts);
  }
}

double cpuSeconds(int pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string line;
  std::getline(in, line);
  const std::size_t close = line.rfind(')');
  if (close == std::string::npos) return std::nan("");
  std::istringstream rest(line.substr(close + 2));
  std::string field;
  double utime = 0, stime = 0;
  for (int k = 3; rest >> field; ++k) {
    if (k == 14) utime = std::stod(field);
    if (k == 15) {
      stime = std::stod(field);
      break;
    }
  }
  return (utime + stime) / sysconf(_SC_CLK_TCK);
}

std::unique_ptr<nodelet::Loader> loadNodelet() {
  auto loader = std::make_unique<nodelet::Loader>(false);
  if (!loader->load("/contact_solver", "lcp_contact_solver/ContactSolverNodelet", {}, {})) {
    std::fprintf(stderr, "latency: could not load lcp_contact_solver/ContactSolverNodelet\n");
    return nullptr;
  }
  return loader;
}

bool waitForSolver(const Sender& sender, const ros::Subscriber& forces_sub,
                   const ros::Subscriber& stats_sub) {
  const ros::WallTime give_up = ros::WallTime::now() + ros::WallDuration(30.0);
  while (ros::ok() &&
         (!sender.connected() || forces_sub.getNumPublishers() == 0 || stats_sub.getNumPublishers() == 0)) {
    if (ros::WallTime::now() > give_up) {
      std::fprintf(stderr, "latency: no contact solver connected within 30 s\n");
      return false;
    }
    ros::WallDuration(0.05).sleep();
  }
  ros::WallDuration(0.5).sleep();
  return true;
}

int runSink(const Options& o) {
  ros::NodeHandle nh;
  std::atomic<long> count{0};
  std::atomic<long> bytes{0};
  ros::Subscriber sub = nh.subscribe<visualization_msgs::MarkerArray>(
      o.sink, 10,
      [&](const visualization_msgs::MarkerArray::ConstPtr& m) {
        ++count;
        bytes += ros::serialization::serializationLength(*m);
      },
      ros::VoidConstPtr(), ros::TransportHints().tcpNoDelay());
  const ros::WallTime start = ros::WallTime::now();
  ros::WallTime last = start;
  long last_count = 0;
  while (ros::ok() && (ros::WallTime::now() - start).toSec() < o.duration) {
    ros::spinOnce();
    ros::WallDuration(0.001).sleep();
    if ((ros::WallTime::now() - last).toSec() >= 10.0) {
      std::printf("sink %s: %ld messages (%.1f/s), %.1f MB\n", o.sink.c_str(), count.load(),
                  (count - last_count) / (ros::WallTime::now() - last).toSec(), bytes.load() / 1e6);
      std::fflush(stdout);
      last = ros::WallTime::now();
      last_count = count;
    }
  }
  std::printf("sink %s: %ld messages in total, %.1f MB\n", o.sink.c_str(), count.load(), bytes.load() / 1e6);
  return 0;
}

}  // namespace lcs_bench::latency
