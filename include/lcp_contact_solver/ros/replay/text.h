// Number and stamp formats of the replay's files and reports.
#pragma once

#include <ros/time.h>

#include <string>

namespace lcp_contact_solver_ros {

// "sec.nanosec" with nine digits: exact, and sorts as text.
std::string stampDigits(const ros::Time& stamp);
// The shortest of %.15g..%.17g that reads back as the same double.
std::string exactNumber(double value);
// %.3g, for summaries.
std::string shortNumber(double value);

}  // namespace lcp_contact_solver_ros
