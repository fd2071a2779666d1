#include "lcp_contact_solver/ros/replay.h"

#include "lcp_contact_solver/ros/msg_conversion.h"
#include "lcp_contact_solver/ros/solver_params_ros.h"

#include <ros/message_traits.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <yaml-cpp/yaml.h>

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <iomanip>
#include <memory>
#include <set>
#include <sstream>

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

std::string stampText(const ros::Time& stamp) {
  char text[32];
  std::snprintf(text, sizeof(text), "%u.%09u", stamp.sec, stamp.nsec);
  return text;
}

// The shortest of %.15g..%.17g that reads back as the same double.
std::string number(double value) {
  char text[32];
  for (int digits = 15; digits <= 17; ++digits) {
    std::snprintf(text, sizeof(text), "%.*g", digits, value);
    if (std::strtod(text, nullptr) == value) break;
  }
  return text;
}

std::string shortNumber(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.3g", value);
  return text;
}

std::string lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return std::tolower(c); });
  return text;
}

// ---- parameter files -------------------------------------------------------------------

// The node's parameters that do not change the forces: accepted in a parameter file and
// ignored offline.
const std::set<std::string>& nodeOnlyParams() {
  static const std::set<std::string> names = {
      "computeConstraintForces", "showCellWidth", "showTranslation", "showTranslation_x", "showTranslation_y",
      "showTranslation_z",  // the last three: dynamic_reconfigure's copies (rosparam dump of a running node)
      "pairing_window", "queue_size",
      "force_arrow_scale", "show_w_heatmap", "heatmap_max_rows", "cone_height", "marker_lifetime",
      "diagnostics_min_rate", "diagnostics_max_rate"};
  return names;
}

bool isSolverParam(const std::string& name) {
  if (name == "initial_guess") return true;
  const std::vector<std::string> names = overridableNames();
  return std::find(names.begin(), names.end(), name) != names.end();
}

// YAML 1.1 booleans (what rosparam accepts) as the override parser's true/false.
std::string scalarText(const std::string& name, const std::string& value) {
  static const std::set<std::string> bools = {"initial_guess", "build_lcp", "displayDebug"};
  if (bools.count(name) == 0) return value;
  const std::string v = lower(value);
  if (v == "true" || v == "yes" || v == "on") return "true";
  if (v == "false" || v == "no" || v == "off") return "false";
  return value;
}

// ---- topics ----------------------------------------------------------------------------

template <typename M>
struct TopicChoice {
  static const char* type() { return ros::message_traits::DataType<M>::value(); }
  static const char* md5() { return ros::message_traits::MD5Sum<M>::value(); }
};

std::string joined(const std::vector<std::string>& items) {
  std::string out;
  for (const std::string& item : items) out += (out.empty() ? "" : ", ") + item;
  return out;
}

// Finds the topic of type M: `requested` (exact, leading '/' optional), else the default
// name, else the only topic of that type. "" when there is none and it is optional.
template <typename M>
std::string chooseTopic(const std::vector<const rosbag::ConnectionInfo*>& connections, const std::string& requested,
                        const std::string& default_name, const std::string& option, bool required,
                        std::vector<std::string>* notes, std::string* error) {
  const std::string type = TopicChoice<M>::type();
  std::set<std::string> all_topics, typed_topics;
  for (const rosbag::ConnectionInfo* c : connections) {
    all_topics.insert(c->topic);
    if (c->datatype == type) typed_topics.insert(c->topic);
  }
  auto check = [&](const std::string& topic) -> std::string {
    for (const rosbag::ConnectionInfo* c : connections) {
      if (c->topic != topic) continue;
      if (c->datatype != type) {
        *error = "topic " + topic + " holds " + c->datatype + ", not " + type;
        return "";
      }
      if (c->md5sum != TopicChoice<M>::md5()) {
        *error = "topic " + topic + " was recorded with another definition of " + type + " (md5 " + c->md5sum +
                 ", this build has " + TopicChoice<M>::md5() + ")";
        return "";
      }
    }
    return topic;
  };
  const std::string wanted = normalizeTopic(requested.empty() ? default_name : requested);
  for (const std::string& topic : all_topics)
    if (normalizeTopic(topic) == wanted) return check(topic);
  if (!requested.empty()) {
    *error = "no topic " + wanted + " in the bag (topics: " +
             joined(std::vector<std::string>(all_topics.begin(), all_topics.end())) + ")";
    return "";
  }
  if (typed_topics.size() == 1) {
    const std::string topic = *typed_topics.begin();
    notes->push_back("using " + topic + " (the only " + type + " topic; " + option + " chooses another)");
    return check(topic);
  }
  if (typed_topics.size() > 1) {
    *error = "several " + type + " topics (" +
             joined(std::vector<std::string>(typed_topics.begin(), typed_topics.end())) + "): choose one with " +
             option;
    return "";
  }
  if (required) *error = "no " + type + " topic in the bag (expected " + wanted + ")";
  return "";
}

}  // namespace

// ---- topics, parameters ------------------------------------------------------------------

std::string normalizeTopic(const std::string& name) {
  if (name.empty()) return name;
  const std::size_t start = name.find_first_not_of('/');
  return start == std::string::npos ? "/" : "/" + name.substr(start);
}

std::string applyReplayOverride(const std::string& assignment, lcs::SolverParams* params) {
  const std::size_t eq = assignment.find('=');
  if (eq != std::string::npos && assignment.compare(0, eq, "initial_guess") == 0) {
    const std::string value = assignment.substr(eq + 1);
    if (value == "true" || value == "1") {
      params->initial_guess = true;
    } else if (value == "false" || value == "0") {
      params->initial_guess = false;
    } else {
      return "override initial_guess='" + value + "' must be true or false";
    }
    return "";
  }
  return applyOverride(assignment, params);
}

std::string loadParamsFile(const std::string& path, lcs::SolverParams* params) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    return path + ": cannot read the file";
  } catch (const YAML::Exception& e) {
    return path + ": not valid YAML (" + e.what() + ")";
  }
  if (root.IsNull()) return "";
  if (!root.IsMap()) return path + ": expected a map of parameter names to values";
  lcs::SolverParams next = *params;
  for (const auto& entry : root) {
    const std::string name = entry.first.Scalar();
    if (nodeOnlyParams().count(name) > 0) continue;
    if (!isSolverParam(name)) return path + ": unknown parameter '" + name + "'";
    if (!entry.second.IsScalar()) return path + ": parameter " + name + " must be a single value";
    const std::string error = applyReplayOverride(name + "=" + scalarText(name, entry.second.Scalar()), &next);
    if (!error.empty()) return path + ": " + error;
  }
  if (const std::string error = lcs::validateParams(next); !error.empty()) return path + ": " + error;
  *params = next;
  return "";
}

std::string writeParamsFile(const std::string& path, const lcs::SolverParams& p) {
  std::ofstream out(path);
  if (!out) return path + ": cannot write (" + std::strerror(errno) + ")";
  auto flag = [](bool b) { return b ? "true" : "false"; };
  out << "# Solver parameters of contact_solver_node (private ~names), as used for the forces of the\n"
         "# bag beside this file. `replay BAG` reads them; see the README, \"Replaying recorded traffic\".\n"
      << "tolerance: " << number(p.tolerance) << "\n"
      << "maxIt: " << p.maxIt << "\n"
      << "mu: " << number(p.mu) << "\n"
      << "initial_guess: " << flag(p.initial_guess) << "\n"
      << "build_lcp: " << flag(p.build_lcp) << "\n"
      << "regularizationTerm: " << number(p.regularizationTerm) << "\n"
      << "minW: " << number(p.minW) << "\n"
      << "maxF: " << number(p.maxF) << "\n"
      << "displayDebug: " << flag(p.displayDebug) << "\n"
      << "solver: " << lcs::solverName(p.solver) << "\n"
      << "stopping_rule: " << lcs::stoppingRuleName(p.stopping_rule) << "\n"
      << "friction_model: " << lcs::frictionModelName(p.friction_model) << "\n"
      << "sor: " << number(p.sor) << "\n"
      << "time_budget: " << number(p.time_budget) << "\n"
      << "max_rows: " << p.max_rows << "\n";
  out.close();
  if (!out) return path + ": write failed";
  return "";
}

std::string paramsFileBeside(const std::string& bag_path) {
  std::string base = bag_path;
  if (base.size() > 4 && base.compare(base.size() - 4, 4, ".bag") == 0) base.resize(base.size() - 4);
  return base + ".params.yaml";
}

// ---- pairing ---------------------------------------------------------------------------

bool StampPairer::addContacts(const ContactsPtr& contacts, Pair* pair) {
  const ros::Time stamp = contacts->header.stamp;
  const auto partner = compliance_.find(stamp);
  if (partner != compliance_.end()) {
    pair->contacts = contacts;
    pair->compliance = partner->second;
    compliance_.erase(partner);
    return true;
  }
  auto [it, inserted] = contacts_.emplace(stamp, contacts);
  if (!inserted) {
    ++duplicates_;
    it->second = contacts;
  }
  return false;
}

bool StampPairer::addCompliance(const CompliancePtr& compliance, Pair* pair) {
  const ros::Time stamp = compliance->header.stamp;
  const auto partner = contacts_.find(stamp);
  if (partner != contacts_.end()) {
    pair->contacts = partner->second;
    pair->compliance = compliance;
    contacts_.erase(partner);
    return true;
  }
  auto [it, inserted] = compliance_.emplace(stamp, compliance);
  if (!inserted) {
    ++duplicates_;
    it->second = compliance;
  }
  return false;
}

std::vector<StampPairer::ContactsPtr> StampPairer::waitingContacts() const {
  std::vector<ContactsPtr> out;
  for (const auto& entry : contacts_) out.push_back(entry.second);
  return out;
}

// ---- comparison ------------------------------------------------------------------------

double relativeDifference(double a, double b) {
  const double scale = std::max(std::abs(a), std::abs(b));
  if (scale == 0.0) return 0.0;
  return std::abs(a - b) / scale;
}

ForceDifference compareForces(const ConstraintForces& forces, const ConstraintForces& reference) {
  ForceDifference diff;
  auto mismatch = [&diff](const std::string& why) {
    diff.mismatch = why;
    diff.relative = std::numeric_limits<double>::infinity();
    return diff;
  };
  if (forces.forces.size() != reference.forces.size())
    return mismatch(std::to_string(forces.forces.size()) + " contacts, recorded " +
                    std::to_string(reference.forces.size()));
  double scale = 0.0;
  for (std::size_t i = 0; i < forces.forces.size(); ++i) {
    const auto& f = forces.forces[i];
    const auto& r = reference.forces[i];
    if (f.id != r.id)
      return mismatch("contact " + std::to_string(i) + " has id " + std::to_string(f.id) + ", recorded " +
                      std::to_string(r.id));
    if (f.lambda.size() != r.lambda.size())
      return mismatch("contact " + std::to_string(i) + " has " + std::to_string(f.lambda.size()) + " rows, recorded " +
                      std::to_string(r.lambda.size()));
    for (std::size_t k = 0; k < f.lambda.size(); ++k) {
      const double d = std::abs(f.lambda[k] - r.lambda[k]);
      diff.max_abs = std::max(diff.max_abs, d);
      diff.sum_sq += d * d;
      ++diff.values;
      scale = std::max({scale, std::abs(f.lambda[k]), std::abs(r.lambda[k])});
    }
  }
  diff.relative = scale > 0.0 ? diff.max_abs / scale : 0.0;
  return diff;
}

bool Comparison::exceeds(double tolerance) const {
  return compared == 0 || mismatched > 0 || missing_reference > 0 || missing_replay > 0 || !(max_relative <= tolerance);
}

// ---- output helpers --------------------------------------------------------------------

const char* StatsCsvWriter::header() { return "stamp,contacts,rows,iterations,residual,converged,status,solve_time"; }

std::string StatsCsvWriter::row(const SolverStats& s) {
  return stampText(s.header.stamp) + "," + std::to_string(s.num_contacts) + "," + std::to_string(s.num_rows) + "," +
         std::to_string(s.iterations) + "," + number(s.residual) + "," + (s.converged ? "true" : "false") + "," +
         s.status + "," + number(s.solve_time);
}

std::string StatsCsvWriter::open(const std::string& path) {
  out_.open(path);
  if (!out_) return path + ": cannot write (" + std::strerror(errno) + ")";
  out_ << header() << "\n";
  return "";
}

void StatsCsvWriter::write(const SolverStats& stats) { out_ << row(stats) << "\n"; }

bool isTerminal(std::FILE* stream) { return stream != nullptr && ::isatty(::fileno(stream)) == 1; }

ProgressBar::ProgressBar(std::FILE* stream, std::size_t total, bool enabled)
    : stream_(stream), total_(total), enabled_(enabled && stream != nullptr && total > 0) {}

void ProgressBar::update(std::size_t done) {
  if (!enabled_) return;
  const int permille = static_cast<int>(std::min<std::size_t>(1000, done * 1000 / total_));
  if (permille / 10 == last_permille_ / 10 && done != total_) return;  // redraw each percent
  last_permille_ = permille;
  constexpr int kWidth = 40;
  const int filled = permille * kWidth / 1000;
  std::fprintf(stream_, "\rreplay [%.*s%*s] %3d%%  %zu/%zu", filled, "########################################",
               kWidth - filled, "", permille / 10, done, total_);
  std::fflush(stream_);
}

void ProgressBar::finish() {
  if (!enabled_ || last_permille_ < 0) return;
  std::fprintf(stream_, "\n");
  std::fflush(stream_);
  enabled_ = false;
}

// ---- replay ----------------------------------------------------------------------------

namespace {

struct Reference {
  std::map<ros::Time, ConstraintForces::ConstPtr> forces;
  std::map<ros::Time, SolverStats::ConstPtr> stats;
  std::set<ros::Time> used_forces;
};

class Replayer {
 public:
  Replayer(const ReplayOptions& options, const lcs::SolverParams& params, ReplayResult* result)
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
      r_.compliance_topic = chooseTopic<Compliance>(connections, options_.compliance_topic, kDefaultCompliance,
                                                    "--compliance-topic", true, &r_.notes, &error);
    if (error.empty())
      r_.forces_topic = chooseTopic<ConstraintForces>(connections, options_.forces_topic, kDefaultForces,
                                                      "--forces-topic", false, &r_.notes, &error);
    if (error.empty())
      r_.stats_topic = chooseTopic<SolverStats>(connections, options_.stats_topic, kDefaultStats, "--stats-topic",
                                                false, &r_.notes, &error);
    if (!error.empty()) return false;
    if (r_.forces_topic.empty()) r_.notes.push_back("no recorded ConstraintForces in the bag: nothing to compare with");
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
    if (topics.empty()) return true;
    rosbag::View view(bag, rosbag::TopicQuery(topics));
    for (const rosbag::MessageInstance& m : view) {
      if (m.getTopic() == r_.forces_topic) {
        ConstraintForces::ConstPtr msg = m.instantiate<ConstraintForces>();
        if (!msg) return fail("a message on " + r_.forces_topic + " cannot be read");
        ref_.forces[msg->header.stamp] = msg;
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
    ProgressBar progress(options_.progress, total_, options_.progress != nullptr);
    rosbag::View view(bag, rosbag::TopicQuery(std::vector<std::string>{r_.contacts_topic, r_.compliance_topic}));
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
        progress.update(r_.contact_messages);
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
    progress.finish();
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
    if (!r_.forces_topic.empty()) {
      const auto ref = ref_.forces.find(stamp);
      if (ref == ref_.forces.end()) {
        if (cycle.has_forces) {
          ++c.missing_reference;
          if (c.first_mismatch.empty()) c.first_mismatch = "stamp " + stampText(stamp) + ": no recorded forces";
        }
      } else {
        ref_.used_forces.insert(stamp);
        if (!cycle.has_forces) {
          ++c.missing_replay;
          if (c.first_mismatch.empty())
            c.first_mismatch = "stamp " + stampText(stamp) + ": recorded forces, the replay gave none (" +
                               cycle.stats.status + ")";
        } else {
          const ForceDifference d = compareForces(cycle.forces, *ref->second);
          if (!d.mismatch.empty()) {
            ++c.mismatched;
            if (c.first_mismatch.empty()) c.first_mismatch = "stamp " + stampText(stamp) + ": " + d.mismatch;
          } else {
            ++c.compared;
            c.max_abs = std::max(c.max_abs, d.max_abs);
            c.sum_sq += d.sum_sq;
            c.values += d.values;
            if (d.relative > c.max_relative || c.worst_cycle < 0) {
              c.max_relative = std::max(c.max_relative, d.relative);
              c.worst_stamp = stamp;
              c.worst_cycle = index;
            }
          }
        }
      }
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
      c.max_residual_relative = std::max(c.max_residual_relative, relativeDifference(s.residual, cycle.stats.residual));
    }
  }

  void finishUnpaired() {
    r_.duplicates = pairer_.duplicates();
    r_.unused_compliance = pairer_.waitingCompliance();
    for (const StampPairer::ContactsPtr& contacts : pairer_.waitingContacts()) {
      ++r_.unpaired;
      const auto it = contacts_time_.find(contacts->header.stamp);
      const ros::Time when = it == contacts_time_.end() ? last_time_ : it->second;
      const SolverStats stats = rejectedStatsMsg(contacts->header, SolverStats::NO_COMPLIANCE,
                                                 "no compliance with stamp " + stampText(contacts->header.stamp) +
                                                     " in the bag");
      emit(stats, nullptr, when);
    }
  }

  void countUnusedReference() {
    for (const auto& entry : ref_.forces) {
      if (ref_.used_forces.count(entry.first) > 0) continue;
      ++r_.comparison.missing_replay;
      if (r_.comparison.first_mismatch.empty())
        r_.comparison.first_mismatch = "stamp " + stampText(entry.first) + ": recorded forces, but no such cycle";
    }
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

ReplayResult replayBag(const ReplayOptions& options, const lcs::SolverParams& params) {
  ReplayResult result;
  if (const std::string error = lcs::validateParams(params); !error.empty()) {
    result.error = "invalid parameters: " + error;
    return result;
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

std::string formatSummary(const ReplayResult& r) {
  std::ostringstream out;
  out << "cycles: " << r.cycles << " from " << r.contacts_topic << " (" << r.contact_messages << ") + "
      << r.compliance_topic << " (" << r.compliance_messages << "): " << r.solved << " solved, " << r.rejected
      << " rejected, " << r.unpaired << " contact arrays without compliance";
  if (r.unused_compliance > 0) out << ", " << r.unused_compliance << " compliances without contacts";
  if (r.duplicates > 0) out << ", " << r.duplicates << " duplicate stamps (the later message kept)";
  out << "\n";
  if (r.solved > 0) {
    out << "solves: " << r.converged << "/" << r.solved << " converged, " << r.with_forces
        << " with forces; iterations " << r.total_iterations << " in all, max " << r.max_iterations
        << "; residual max " << shortNumber(r.max_residual) << " (stamp " << stampText(r.worst_residual_stamp)
        << "), mean " << shortNumber(r.meanResidual()) << "; solve time " << shortNumber(r.total_solve_time)
        << " s\n";
  }
  const Comparison& c = r.comparison;
  if (r.forces_topic.empty()) {
    out << "forces: no recorded forces in the bag, nothing compared\n";
  } else {
    out << "forces vs recorded " << r.forces_topic << ": " << c.compared << " cycles compared";
    if (c.compared > 0) {
      out << "; max |dlambda| " << shortNumber(c.max_abs) << " N, RMS " << shortNumber(c.rms())
          << " N, max relative " << shortNumber(c.max_relative) << " (worst cycle #" << c.worst_cycle << ", stamp "
          << stampText(c.worst_stamp) << ")";
    }
    out << "\n";
    if (c.mismatched + c.missing_reference + c.missing_replay > 0) {
      out << "forces not comparable: " << c.mismatched << " cycles with other contacts, " << c.missing_reference
          << " replayed without a recorded counterpart, " << c.missing_replay
          << " recorded without a replayed counterpart; first: " << c.first_mismatch << "\n";
    }
  }
  if (!r.stats_topic.empty()) {
    out << "stats vs recorded " << r.stats_topic << ": " << c.stats_compared << " cycles; iterations differ in "
        << c.iteration_differences;
    if (c.iteration_differences > 0) out << " (first at stamp " << stampText(c.first_iteration_difference) << ")";
    out << ", status differs in " << c.status_differences << "; max relative residual difference "
        << shortNumber(c.max_residual_relative) << "\n";
  }
  return out.str();
}

// ---- command line ----------------------------------------------------------------------

namespace {

const char* kUsage =
    "usage: replay IN.bag [--out OUT.bag] [--csv STATS.csv] [--params FILE.yaml | --no-params-file]\n"
    "              [name=value ...] [--tolerance-compare X] [--contacts-topic T] [--compliance-topic T]\n"
    "              [--forces-topic T] [--stats-topic T] [--no-inputs] [--no-progress] [--quiet]\n"
    "\n"
    "Solves every ContactArray/Compliance pair of a recorded bag (no roscore needed) the way\n"
    "contact_solver_node does, in the same order with the same warm start, and compares the\n"
    "forces with the ones recorded in the bag.\n"
    "\n"
    "  --out OUT.bag          write the forces and stats (the node's topic names and stamps), and\n"
    "                         the input topics unless --no-inputs; OUT.params.yaml beside it\n"
    "  --csv STATS.csv        per-cycle stats: stamp,contacts,rows,iterations,residual,converged,\n"
    "                         status,solve_time\n"
    "  --params FILE.yaml     node parameters (as config/default.yaml); default: the file beside\n"
    "                         the bag (IN.params.yaml) if there is one, else the node's defaults\n"
    "  name=value             override one parameter: initial_guess or any of the service's\n"
    "                         param_overrides (tolerance, maxIt, mu, solver, ...)\n"
    "  --tolerance-compare X  exit 1 when the forces differ from the recorded ones by more than\n"
    "                         X relative (max |dlambda| / max |lambda| per cycle), or cannot be\n"
    "                         compared\n"
    "  --contacts-topic T, --compliance-topic T, --forces-topic T, --stats-topic T\n"
    "                         topics in the bag (default contacts, compliance, constraint_forces,\n"
    "                         contact_solver/stats; else the only topic of the type)\n"
    "  --no-progress          no progress bar (shown only on a terminal anyway)\n"
    "  --quiet                print only the verdict and errors\n"
    "exit: 0 done, 1 comparison beyond --tolerance-compare, 2 usage or input error\n";

}  // namespace

int runReplayCommand(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  ReplayOptions options;
  std::string params_file;
  bool no_params_file = false, quiet = false, progress = true, have_tolerance = false;
  double tolerance = 0.0;
  std::vector<std::string> overrides;
  auto usage_error = [&err](const std::string& message) {
    err << "replay: " << message << " (replay --help for usage)\n";
    return 2;
  };
  for (std::size_t i = 0; i < args.size(); ++i) {
    std::string arg = args[i], value;
    bool has_inline_value = false;
    if (arg.rfind("--", 0) == 0) {
      const std::size_t eq = arg.find('=');
      if (eq != std::string::npos) {
        value = arg.substr(eq + 1);
        arg.resize(eq);
        has_inline_value = true;
      }
    }
    auto take = [&](std::string* target) {
      if (has_inline_value) {
        *target = value;
        return true;
      }
      if (i + 1 >= args.size()) return false;
      *target = args[++i];
      return true;
    };
    if (arg == "-h" || arg == "--help") {
      out << kUsage;
      return 0;
    } else if (arg == "--out" || arg == "-o") {
      if (!take(&options.out_bag)) return usage_error(arg + " needs a file name");
    } else if (arg == "--csv") {
      if (!take(&options.csv)) return usage_error(arg + " needs a file name");
    } else if (arg == "--params") {
      if (!take(&params_file)) return usage_error(arg + " needs a file name");
    } else if (arg == "--no-params-file") {
      no_params_file = true;
    } else if (arg == "--contacts-topic") {
      if (!take(&options.contacts_topic)) return usage_error(arg + " needs a topic");
    } else if (arg == "--compliance-topic") {
      if (!take(&options.compliance_topic)) return usage_error(arg + " needs a topic");
    } else if (arg == "--forces-topic") {
      if (!take(&options.forces_topic)) return usage_error(arg + " needs a topic");
    } else if (arg == "--stats-topic") {
      if (!take(&options.stats_topic)) return usage_error(arg + " needs a topic");
    } else if (arg == "--tolerance-compare") {
      std::string text;
      if (!take(&text)) return usage_error(arg + " needs a number");
      char* end = nullptr;
      tolerance = std::strtod(text.c_str(), &end);
      if (text.empty() || *end != '\0' || !std::isfinite(tolerance) || tolerance < 0.0)
        return usage_error("--tolerance-compare '" + text + "' must be a finite number >= 0");
      have_tolerance = true;
    } else if (arg == "--no-inputs") {
      options.copy_inputs = false;
    } else if (arg == "--no-progress") {
      progress = false;
    } else if (arg == "--quiet" || arg == "-q") {
      quiet = true;
    } else if (arg.rfind("-", 0) == 0 && arg.size() > 1) {
      return usage_error("unknown option " + arg);
    } else if (options.bag.empty()) {
      options.bag = arg;
    } else if (arg.find('=') != std::string::npos) {
      overrides.push_back(arg);
    } else {
      return usage_error("unexpected argument '" + arg + "' (one bag; parameter overrides are name=value)");
    }
  }
  if (options.bag.empty()) return usage_error("no input bag given");
  if (!params_file.empty() && no_params_file) return usage_error("--params and --no-params-file exclude each other");

  // Parameters: the node's defaults, the parameter file, the overrides.
  lcs::SolverParams params = defaultSolverParams();
  std::string params_source = "the node's defaults";
  if (params_file.empty() && !no_params_file && std::filesystem::exists(paramsFileBeside(options.bag)))
    params_file = paramsFileBeside(options.bag);
  if (!params_file.empty()) {
    if (const std::string error = loadParamsFile(params_file, &params); !error.empty()) {
      err << "replay: " << error << "\n";
      return 2;
    }
    params_source = params_file;
  }
  for (const std::string& assignment : overrides) {
    if (const std::string error = applyReplayOverride(assignment, &params); !error.empty()) {
      err << "replay: " << error << "\n";
      return 2;
    }
    params_source += " + " + assignment;
  }
  if (const std::string error = lcs::validateParams(params); !error.empty()) {
    err << "replay: invalid parameters: " << error << "\n";
    return 2;
  }

  if (progress && !quiet && isTerminal(stderr)) options.progress = stderr;
  if (!quiet) {
    out << "replay " << options.bag << "\n"
        << "parameters: " << params_source << " (solver " << lcs::solverName(params.solver) << ", tolerance "
        << shortNumber(params.tolerance) << ", maxIt " << params.maxIt << ", mu " << shortNumber(params.mu)
        << ", initial_guess " << (params.initial_guess ? "true" : "false") << ")\n";
    out.flush();
  }
  const ReplayResult result = replayBag(options, params);
  if (!result.error.empty()) {
    err << "replay: " << options.bag << ": " << result.error << "\n";
    return 2;
  }
  if (!options.out_bag.empty()) {
    if (const std::string error = writeParamsFile(paramsFileBeside(options.out_bag), params); !error.empty()) {
      err << "replay: " << error << "\n";
      return 2;
    }
  }
  if (!quiet) {
    for (const std::string& note : result.notes) out << "note: " << note << "\n";
    out << formatSummary(result);
    if (!options.out_bag.empty())
      out << "wrote " << options.out_bag << " (" << result.out_forces_topic << ", " << result.out_stats_topic
          << (options.copy_inputs ? ", inputs" : "") << ") and " << paramsFileBeside(options.out_bag) << "\n";
    if (!options.csv.empty()) out << "wrote " << options.csv << "\n";
  }
  if (!have_tolerance) return 0;
  const Comparison& c = result.comparison;
  if (!c.hasReference()) {
    out << "FAIL: no recorded forces to compare with (--tolerance-compare " << shortNumber(tolerance) << ")\n";
    return 1;
  }
  if (c.exceeds(tolerance)) {
    out << "FAIL: forces differ from the recording: max relative " << shortNumber(c.max_relative)
        << (c.max_relative > tolerance ? " > " : " <= ") << shortNumber(tolerance);
    if (c.mismatched + c.missing_reference + c.missing_replay > 0)
      out << "; " << (c.mismatched + c.missing_reference + c.missing_replay) << " cycles not comparable ("
          << c.first_mismatch << ")";
    out << "\n";
    return 1;
  }
  out << "OK: forces match the recording within " << shortNumber(tolerance) << " relative (max "
      << shortNumber(c.max_relative) << " over " << c.compared << " cycles)\n";
  return 0;
}

}  // namespace lcp_contact_solver_ros
