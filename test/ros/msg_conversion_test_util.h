// Conversion of a test scene to a problem, shared by the test_msg_conversion*.cpp files.
#pragma once

#include "lcp_contact_solver/core/body_compliance.h"
#include "lcp_contact_solver/core/contact_solver.h"
#include "lcp_contact_solver/core/residual.h"
#include "lcp_contact_solver/ros/msg_conversion/msg_conversion.h"
#include "lcp_contact_solver/ros/node/cycle_log.h"
#include "lcp_contact_solver/ros/node/cycle_solver.h"
#include "lcp_contact_solver/ros/node/input_queue.h"
#include "lcp_contact_solver/ros/node/markers.h"
#include "lcp_contact_solver/ros/node/solve_rate_status.h"
#include "lcp_contact_solver/ros/node/solver_params_ros.h"
#include "test_scene.h"

#include <gtest/gtest.h>
#include <Eigen/Geometry>
#include <boost/make_shared.hpp>

#include <cmath>
#include <functional>
#include <limits>
#include <set>
#include <thread>

namespace lcs = lcp_contact_solver;
using namespace lcp_contact_solver_ros;
using lcp_contact_solver_test::makeScene;
using lcp_contact_solver_test::Scene;

namespace msg_conversion_test {

inline Eigen::Vector3d toEigen(const geometry_msgs::Vector3& v) { return {v.x, v.y, v.z}; }
inline Eigen::Vector3d toEigen(const geometry_msgs::Point& p) { return {p.x, p.y, p.z}; }

struct Converted {
  lcs::core::Problem problem;
  std::vector<ContactFrame> frames;
  std::string error;
};

inline Converted convert(const Scene& scene, int max_rows = 0) {
  Converted c;
  c.error = toProblem(scene.contacts, scene.compliance, max_rows, &c.problem, &c.frames);
  return c;
}

const ros::Time kStamp(100, 0);
const double kNaN = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();

}  // namespace msg_conversion_test
