#include "lcp_contact_solver/ros/replay/bag_replay.h"

#include "lcp_contact_solver/ros/msg_conversion/msg_conversion.h"
#include "lcp_contact_solver/ros/replay/bag_topics.h"
#include "lcp_contact_solver/ros/replay/stats_csv.h"
#include "lcp_contact_solver/ros/replay/text.h"

#include <rosbag/bag.h>
#include <rosbag/view.h>

#include <algorithm>
#include <exception>
#include <filesystem>
#include <map>
#include <memory>
#include <set>

namespace lcp_contact_solver_ros {

namespace {

using lcp_contact_solver::Compliance;
using lcp_contact_solver::ConstraintForces;
using lcp_contact_solver::ContactArray;
using lcp_contact_solver::SolverStats;

constexpr const char* kDefaultContacts = "contacts";
constexpr const char* kDefaultCompliance = "compliance";
constexpr const char* kDefaultForces = "constraint_forces";
constexpr const char* kDefaultStats = "contact_solver/stats";

struct Reference {
  std::map<ros::Time, ConstraintForces::ConstPtr> forces;
  std::map<ros::Time, SolverStats::ConstPtr> stats;
  std::set<ros::Time> used_forces;
  std::map<ros::Time, ConstraintForces::ConstPtr> outside;  // reference_topic
  std::set<ros::Time> used_outside;
};

class Replayer {
 public:
  Replayer(const ReplayOptions& options, const lcs::core::SolverParams& params, ReplayResult* result)
      : options_(options), cycle_(params), r_(*result) {}

  void run() {
    if (!std::filesystem::exists(options_.bag)) {
      r_.error = "no such file";
      return;
    }
    if (std::filesystem::is_directory(options_.bag)) {
      r_.error = "is a directory, not a bag";
      return;
    }
    rosbag::Bag bag;
    bag.open(options_.bag, rosbag::bagmode::Read);
    if (!chooseTopics(bag)) return;
    if (!readReference(bag)) return;
    if (!openOutputs()) return;
    replay(bag);
    if (!r_.error.empty()) return;
    finishUnpaired();
    countUnusedReference();
    if (out_ && options_.copy_inputs && !r_.reference_topic.empty()) {  // the output stays a reference bag
      rosbag::View view(bag, rosbag::TopicQuery(r_.reference_topic));
      for (const rosbag::MessageInstance& m : view)
        out_->write(m.getTopic(), m.getTime(), m, m.getConnectionHeader());
    }
    if (out_) {
      out_->close();
      out_.reset();
    }
    if (!options_.csv.empty() && !csv_.good()) r_.error = options_.csv + ": write failed";
  }

 private:
  bool chooseTopics(rosbag::Bag& bag) {
    rosbag::View all(bag);
    const std::vector<const rosbag::ConnectionInfo*> connections = all.getConnections();
    std::string& error = r_.error;
    r_.contacts_topic = chooseTopic<ContactArray>(connections, options_.contacts_topic, kDefaultContacts,
                                                  "--contacts-topic", true, &r_.notes, &error);
    if (error.empty())
      r_.compliance_topic =
          chooseTopic<Compliance>(connections, options_.compliance_topic, kDefaultCompliance,
                                  "--compliance-topic", true, &r_.notes, &error);
    if (error.empty() && !options_.reference_topic.empty())
      r_.reference_topic = chooseTopic<ConstraintForces>(connections, options_.reference_topic, "",
                                                         "--reference-topic", true, &r_.notes, &error);
    if (error.empty())
      r_.forces_topic =
          chooseTopic<ConstraintForces>(connections, options_.forces_topic, kDefaultForces, "--forces-topic",
                                        false, &r_.notes, &error, r_.reference_topic);
    if (error.empty() && !r_.reference_topic.empty() && r_.reference_topic == r_.forces_topic)
      error = r_.reference_topic + " cannot be both the recorded output and the reference";
    if (error.empty())
      r_.stats_topic = chooseTopic<SolverStats>(connections, options_.stats_topic, kDefaultStats,
                                                "--stats-topic", false, &r_.notes, &error);
    if (!error.empty()) return false;
    if (r_.forces_topic.empty())
      r_.notes.push_back(r_.reference_topic.empty()
                             ? "no recorded ConstraintForces in the bag: nothing to compare with"
                             : "no recorded output of the node in the bag: only the reference "
                               "is compared with");
    r_.out_forces_topic = r_.forces_topic.empty() ? normalizeTopic(kDefaultForces) : r_.forces_topic;
    r_.out_stats_topic = r_.stats_topic.empty() ? normalizeTopic(kDefaultStats) : r_.stats_topic;
    rosbag::View contacts(bag, rosbag::TopicQuery(r_.contacts_topic));
    total_ = contacts.size();
    return true;
  }

  bool readReference(rosbag::Bag& bag) {
    std::vector<std::string> topics;
    if (!r_.forces_topic.empty()) topics.push_back(r_.forces_topic);
    if (!r_.stats_topic.empty()) topics.push_back(r_.stats_topic);
    if (!r_.reference_topic.empty()) topics.push_back(r_.reference_topic);
    if (topics.empty()) return true;
    rosbag::View view(bag, rosbag::TopicQuery(topics));
    for (const rosbag::MessageInstance& m : view) {
      if (m.getTopic() == r_.forces_topic || m.getTopic() == r_.reference_topic) {
        ConstraintForces::ConstPtr msg = m.instantiate<ConstraintForces>();
        if (!msg) return fail("a message on " + m.getTopic() + " cannot be read");
        (m.getTopic() == r_.forces_topic ? ref_.forces : ref_.outside)[msg->header.stamp] = msg;
      } else {
        SolverStats::ConstPtr msg = m.instantiate<SolverStats>();
        if (!msg) return fail("a message on " + r_.stats_topic + " cannot be read");
        if (msg->status_code >= SolverStats::NO_COMPLIANCE) continue;  // node-side pairing, not a solve
        ref_.stats[msg->header.stamp] = msg;
      }
    }
    return true;
  }

  bool openOutputs() {
    if (!options_.csv.empty()) {
      const std::string error = csv_.open(options_.csv);
      if (!error.empty()) return fail(error);
    }
    if (!options_.out_bag.empty()) {
      std::error_code ec;
      if (std::filesystem::exists(options_.out_bag) &&
          std::filesystem::equivalent(options_.out_bag, options_.bag, ec))
        return fail(options_.out_bag + ": the output bag would overwrite the input");
      out_ = std::make_unique<rosbag::Bag>();
      try {
        out_->open(options_.out_bag, rosbag::bagmode::Write);
      } catch (const std::exception& e) {
        out_.reset();
        return fail(options_.out_bag + ": cannot write (" + e.what() + ")");
      }
      out_->setCompression(rosbag::compression::LZ4);
    }
    return true;
  }

  void replay(rosbag::Bag& bag) {
    rosbag::View view(bag,
                      rosbag::TopicQuery(std::vector<std::string>{r_.contacts_topic, r_.compliance_topic}));
    StampPairer::Pair pair;
    for (const rosbag::MessageInstance& m : view) {
      last_time_ = m.getTime();
      if (m.getTopic() == r_.contacts_topic) {
        ContactArray::ConstPtr msg = m.instantiate<ContactArray>();
        if (!msg) {
          fail("a message on " + r_.contacts_topic + " cannot be read");
          break;
        }
        ++r_.contact_messages;
        if (options_.progress) options_.progress(r_.contact_messages, total_);
        if (out_ && options_.copy_inputs) out_->write(m.getTopic(), m.getTime(), m, m.getConnectionHeader());
        contacts_time_[msg->header.stamp] = m.getTime();
        if (pairer_.addContacts(msg, &pair)) solve(pair, m.getTime());
      } else {
        Compliance::ConstPtr msg = m.instantiate<Compliance>();
        if (!msg) {
          fail("a message on " + r_.compliance_topic + " cannot be read");
          break;
        }
        ++r_.compliance_messages;
        if (out_ && options_.copy_inputs) out_->write(m.getTopic(), m.getTime(), m, m.getConnectionHeader());
        if (pairer_.addCompliance(msg, &pair)) solve(pair, m.getTime());
      }
    }
  }

  void solve(const StampPairer::Pair& pair, const ros::Time& bag_time) {
    const ros::Time stamp = pair.contacts->header.stamp;
    contacts_time_.erase(stamp);
    CycleOutput cycle = cycle_.solve(*pair.contacts, *pair.compliance, true);
    ++r_.cycles;
    if (cycle.rejected()) {
      ++r_.rejected;
    } else {
      ++r_.solved;
      if (cycle.result.converged) ++r_.converged;
      r_.sum_residual += cycle.result.residual;
      if (cycle.result.residual > r_.max_residual || r_.solved == 1) {
        r_.max_residual = cycle.result.residual;
        r_.worst_residual_stamp = stamp;
      }
      r_.total_iterations += cycle.result.iterations;
      r_.max_iterations = std::max(r_.max_iterations, cycle.result.iterations);
      r_.total_solve_time += cycle.result.solve_time;
    }
    cycle.stats.forces_published = cycle.has_forces;
    if (cycle.has_forces) ++r_.with_forces;
    emit(cycle.stats, cycle.has_forces ? &cycle.forces : nullptr, bag_time);
    compare(cycle, stamp);
    if (options_.keep_cycles) {
      ReplayCycle kept;
      kept.stamp = stamp;
      kept.bag_time = bag_time;
      kept.stats = cycle.stats;
      kept.has_forces = cycle.has_forces;
      if (cycle.has_forces) kept.forces = std::move(cycle.forces);
      r_.cycles_kept.push_back(std::move(kept));
    }
  }

  void emit(const SolverStats& stats, const ConstraintForces* forces, const ros::Time& bag_time) {
    if (out_) {
      if (forces != nullptr) out_->write(r_.out_forces_topic, bag_time, *forces);
      out_->write(r_.out_stats_topic, bag_time, stats);
    }
    if (!options_.csv.empty()) csv_.write(stats);
  }

  void compare(const CycleOutput& cycle, const ros::Time& stamp) {
    Comparison& c = r_.comparison;
    const long index = static_cast<long>(r_.cycles) - 1;
    const ConstraintForces* replayed = cycle.has_forces ? &cycle.forces : nullptr;
    const ConstraintForces* recorded =
        r_.forces_topic.empty() ? nullptr : take(ref_.forces, &ref_.used_forces, stamp);
    if (!r_.forces_topic.empty()) c.add(replayed, recorded, stamp, index, cycle.stats.status);
    if (recorded != nullptr && options_.recorded_params) {
      const auto stats = ref_.stats.find(stamp);
      r_.answers.add(checkAnswer(cycle.problem, *options_.recorded_params, *recorded),
                     stats == ref_.stats.end() ? nullptr : stats->second.get(), *options_.recorded_params,
                     stamp);
    }
    if (!r_.reference_topic.empty()) {
      const ConstraintForces* outside = take(ref_.outside, &ref_.used_outside, stamp);
      if (replayed != nullptr || outside != nullptr)
        r_.reference_cycles.push_back(r_.reference.add(replayed, outside, stamp, index, cycle.stats.status));
    }
    const auto ref_stats = ref_.stats.find(stamp);
    if (ref_stats != ref_.stats.end()) {
      const SolverStats& s = *ref_stats->second;
      ++c.stats_compared;
      if (s.iterations != cycle.stats.iterations) {
        if (c.iteration_differences == 0) c.first_iteration_difference = stamp;
        ++c.iteration_differences;
      }
      if (s.status_code != cycle.stats.status_code) ++c.status_differences;
      c.max_residual_relative =
          std::max(c.max_residual_relative, relativeDifference(s.residual, cycle.stats.residual));
    }
  }

  void finishUnpaired() {
    r_.duplicates = pairer_.duplicates();
    r_.unused_compliance = pairer_.waitingCompliance();
    for (const StampPairer::ContactsPtr& contacts : pairer_.waitingContacts()) {
      ++r_.unpaired;
      const auto it = contacts_time_.find(contacts->header.stamp);
      const ros::Time when = it == contacts_time_.end() ? last_time_ : it->second;
      const SolverStats stats =
          rejectedStatsMsg(contacts->header, SolverStats::NO_COMPLIANCE,
                           "no compliance with stamp " + stampDigits(contacts->header.stamp) + " in the bag");
      emit(stats, nullptr, when);
    }
  }

  // The forces of `stamp` in `forces` (null when none), marked used.
  static const ConstraintForces* take(const std::map<ros::Time, ConstraintForces::ConstPtr>& forces,
                                      std::set<ros::Time>* used, const ros::Time& stamp) {
    const auto it = forces.find(stamp);
    if (it == forces.end()) return nullptr;
    used->insert(stamp);
    return it->second.get();
  }

  void countUnusedReference() {
    for (const auto& entry : ref_.forces)
      if (ref_.used_forces.count(entry.first) == 0)
        r_.comparison.add(nullptr, entry.second.get(), entry.first, -1);
    for (const auto& entry : ref_.outside)
      if (ref_.used_outside.count(entry.first) == 0)
        r_.reference_cycles.push_back(r_.reference.add(nullptr, entry.second.get(), entry.first, -1));
  }

  bool fail(const std::string& error) {
    if (r_.error.empty()) r_.error = error;
    return false;
  }

  const ReplayOptions& options_;
  CycleSolver cycle_;
  ReplayResult& r_;
  Reference ref_;
  StampPairer pairer_;
  std::map<ros::Time, ros::Time> contacts_time_;  // bag time of contact arrays waiting for compliance
  ros::Time last_time_;
  std::size_t total_ = 0;
  StatsCsvWriter csv_;
  std::unique_ptr<rosbag::Bag> out_;
};

}  // namespace

ReplayResult replayBag(const ReplayOptions& options, const lcs::core::SolverParams& params) {
  ReplayResult result;
  if (const std::string error = lcs::core::validateParams(params); !error.empty()) {
    result.error = "invalid parameters: " + error;
    return result;
  }
  if (options.recorded_params) {
    if (const std::string error = lcs::core::validateParams(*options.recorded_params); !error.empty()) {
      result.error = "invalid recorded parameters: " + error;
      return result;
    }
  }
  try {
    Replayer(options, params, &result).run();
  } catch (const std::exception& e) {
    std::string what = e.what();
    while (!what.empty() && (what.back() == '\n' || what.back() == ' ')) what.pop_back();
    result.error = "cannot read the bag: " + what;
  }
  if (!result.error.empty()) result.cycles_kept.clear();
  return result;
}
}  // namespace lcp_contact_solver_ros
