// Debug markers of one solve: contact points, normals, force arrows, friction cones
// coloured by state, and heat maps of W and lambda. Each namespace below keeps its ids
// from cycle to cycle; markers carry a short lifetime so stale ones vanish.
#pragma once

#include "lcp_contact_solver/core/problem.h"
#include "lcp_contact_solver/core/solve_result.h"
#include "lcp_contact_solver/ros/msg_conversion/msg_conversion.h"
#include "lcp_contact_solver/ros/node/solver_params_ros.h"

#include <std_msgs/ColorRGBA.h>
#include <std_msgs/Header.h>
#include <visualization_msgs/MarkerArray.h>

#include <vector>

namespace lcp_contact_solver_ros {

// Marker namespaces; all but kNsForces hold one marker with id 0. Force arrows have the
// contact's index in the array as id.
constexpr const char* kNsContactPoints = "contact_points";
constexpr const char* kNsNormals = "normals";
constexpr const char* kNsForces = "forces";
constexpr const char* kNsFrictionCones = "friction_cones";
constexpr const char* kNsComplianceHeatmap = "compliance_heatmap";
constexpr const char* kNsLambdaHeatmap = "lambda_heatmap";

// Markers are built only when somebody listens: building them costs more than small solves.
inline bool shouldBuildMarkers(std::uint32_t subscribers) { return subscribers > 0; }

// `mu` is each contact's effective friction coefficient (core effectiveMu).
visualization_msgs::MarkerArray buildMarkers(const std_msgs::Header& header,
                                             const std::vector<ContactFrame>& frames,
                                             const lcs::core::Problem& problem,
                                             const lcs::core::SolveResult& result,
                                             const std::vector<double>& mu, const DisplayOptions& options);

// Open grey, stick green, slip orange, ignored blue.
std_msgs::ColorRGBA stateColor(lcs::core::ContactState state);

// Diverging heat colour: blue for -scale, white for 0, red for +scale.
std_msgs::ColorRGBA heatColor(double value, double scale);

}  // namespace lcp_contact_solver_ros
