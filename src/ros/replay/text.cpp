#include "lcp_contact_solver/ros/replay/text.h"

#include <cstdio>
#include <cstdlib>

namespace lcp_contact_solver_ros {

std::string stampDigits(const ros::Time& stamp) {
  char text[32];
  std::snprintf(text, sizeof(text), "%u.%09u", stamp.sec, stamp.nsec);
  return text;
}

std::string exactNumber(double value) {
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

}  // namespace lcp_contact_solver_ros
