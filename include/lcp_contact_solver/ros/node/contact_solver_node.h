// The ROS face of the solver, shared by the node and the nodelet: pairs `contacts` with
// `compliance` by stamp, solves each pair once, publishes `constraint_forces`, `~stats`,
// `~markers` (when subscribed) and /diagnostics, serves `~solve_contacts`, and takes
// parameter changes through dynamic_reconfigure between solves.
#pragma once

#include "lcp_contact_solver/core/contact_solver.h"
#include "lcp_contact_solver/ros/msg_conversion/msg_conversion.h"
#include "lcp_contact_solver/ros/node/cycle_solver.h"
#include "lcp_contact_solver/ros/node/input_queue.h"
#include "lcp_contact_solver/ros/node/solve_rate_status.h"
#include "lcp_contact_solver/ros/node/solver_params_ros.h"

#include <diagnostic_updater/diagnostic_updater.h>
#include <diagnostic_updater/update_functions.h>
#include <dynamic_reconfigure/server.h>
#include <lcp_contact_solver/Compliance.h>
#include <lcp_contact_solver/ContactArray.h>
#include <lcp_contact_solver/ContactSolverConfig.h>
#include <lcp_contact_solver/SolveContacts.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>

#include <boost/thread/recursive_mutex.hpp>

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

namespace lcp_contact_solver_ros {

class ContactSolverNode {
 public:
  // Reads the private parameters; throws std::invalid_argument naming the bad one.
  ContactSolverNode(const ros::NodeHandle& nh, const ros::NodeHandle& pnh);
  ~ContactSolverNode();
  ContactSolverNode(const ContactSolverNode&) = delete;
  ContactSolverNode& operator=(const ContactSolverNode&) = delete;

 private:
  using ContactArray = lcp_contact_solver::ContactArray;
  using Compliance = lcp_contact_solver::Compliance;
  using Config = lcp_contact_solver::ContactSolverConfig;

  // Counts behind /diagnostics.
  struct Health {
    std::uint64_t solves = 0;
    std::uint64_t not_converged = 0;
    std::uint64_t rejected = 0;
    double max_latency = 0.0;                 // since the last report, s
    double max_queue_time = 0.0;              // since the last report, s
    std::uint64_t problems_since_report = 0;  // rejections, unpaired, failed solves
    double last_residual = 0.0;
    std::string last_status = "no solve yet";
    bool last_converged = true;
  };

  void setUpTopics();
  void setUpReconfigure();
  void setUpDiagnostics();

  // `arrival`: wall time when roscpp had the message (arrivalOf), for pairing and latency.
  void onContacts(const ContactArray::ConstPtr& contacts, const ros::Time& arrival);
  void onCompliance(const Compliance::ConstPtr& compliance, const ros::Time& arrival);
  // The solver thread: takes complete pairs from inputs_ and solves them one at a time.
  void solverLoop();
  void onPair(const InputPair& pair);
  bool onSolveService(lcp_contact_solver::SolveContacts::Request& request,
                      lcp_contact_solver::SolveContacts::Response& response);
  void onReconfigure(Config& config, std::uint32_t level);
  void onTimer(const ros::WallTimerEvent& event);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);

  // Cycle steps; the caller holds solve_mutex_.
  void applyAcceptedSettings();
  void recordSolve(const lcs::core::SolveResult& result);
  void reject(const std_msgs::Header& header, std::uint8_t status_code, const std::string& message);
  bool publishForces(const std_msgs::Header& header, CycleOutput* cycle);
  bool publishMarkers(const std_msgs::Header& header, const std::vector<ContactFrame>& frames,
                      const lcs::core::Problem& problem, const lcs::core::SolveResult& result);
  void logCycle(const lcs::core::Problem& problem, const lcs::core::SolveResult& result);
  void reportUnsolved(const UnsolvedInput& input);

  NodeSettings latestSettings();

  ros::NodeHandle nh_;
  ros::NodeHandle pnh_;

  std::mutex settings_mutex_;  // guards accepted_ and settings_changed_
  NodeSettings accepted_;      // latest valid settings; the next cycle applies them
  bool settings_changed_ = false;

  std::mutex solve_mutex_;  // guards active_ and cycle_ (the solver thread and the service)
  NodeSettings active_;     // settings of the current cycle
  CycleSolver cycle_;       // messages → problem → solve (warm start) → messages
  ros::Time last_stamp_;    // of the last pair taken for a solve

  std::mutex health_mutex_;  // guards health_ (read by diagnostics while a solve runs)
  Health health_;
  InputQueue inputs_;
  std::atomic<bool> running_{true};
  std::thread solver_thread_;

  ros::Publisher forces_pub_;
  ros::Publisher stats_pub_;
  ros::Publisher markers_pub_;
  ros::ServiceServer solve_service_;
  ros::CallbackQueue input_callbacks_;  // contacts and compliance only, served by input_spinner_
  std::unique_ptr<ros::AsyncSpinner> input_spinner_;
  ros::Subscriber contacts_sub_;
  ros::Subscriber compliance_sub_;

  boost::recursive_mutex reconfigure_mutex_;
  std::unique_ptr<dynamic_reconfigure::Server<Config>> reconfigure_;

  diagnostic_updater::Updater updater_;
  std::unique_ptr<SolveRateStatus> solve_rate_;
  ros::WallTimer timer_;
};

}  // namespace lcp_contact_solver_ros
