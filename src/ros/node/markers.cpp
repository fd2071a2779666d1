#include "lcp_contact_solver/ros/node/markers.h"

#include "lcp_contact_solver/core/body_compliance.h"
#include "lcp_contact_solver/ros/msg_conversion/msg_primitives.h"

#include <algorithm>
#include <cmath>

namespace lcp_contact_solver_ros {

namespace {

constexpr int kConeSegments = 12;

bool finitePoint(const geometry_msgs::Point& p) {
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
}

bool finiteMarker(const visualization_msgs::Marker& m) {
  if (!finitePoint(m.pose.position) || !std::isfinite(m.scale.x) || !std::isfinite(m.scale.y) ||
      !std::isfinite(m.scale.z))
    return false;
  return std::all_of(m.points.begin(), m.points.end(), finitePoint);
}

// Force arrows: magenta, apart from every state colour and every body colour.
const std_msgs::ColorRGBA kForceArrowColor = rgba(1.0f, 0.0f, 1.0f);

visualization_msgs::Marker baseMarker(const std_msgs::Header& header, const char* ns, int id, int type,
                                      const DisplayOptions& options) {
  visualization_msgs::Marker m;
  m.header = header;
  m.ns = ns;
  m.id = id;
  m.type = type;
  m.action = visualization_msgs::Marker::ADD;
  m.pose.orientation.w = 1.0;
  m.lifetime = ros::Duration(options.marker_lifetime);
  m.color = rgba(1.0f, 1.0f, 1.0f);
  return m;
}

visualization_msgs::Marker contactPoints(const std_msgs::Header& header,
                                         const std::vector<ContactFrame>& frames,
                                         const lcs::core::SolveResult& result,
                                         const DisplayOptions& options) {
  auto m = baseMarker(header, kNsContactPoints, 0, visualization_msgs::Marker::SPHERE_LIST, options);
  const double size = 0.2 * options.cone_height;
  m.scale.x = m.scale.y = m.scale.z = size;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    m.points.push_back(toPoint(frames[i].position));
    m.colors.push_back(stateColor(result.states[i]));
  }
  return m;
}

visualization_msgs::Marker normals(const std_msgs::Header& header, const std::vector<ContactFrame>& frames,
                                   const DisplayOptions& options) {
  auto m = baseMarker(header, kNsNormals, 0, visualization_msgs::Marker::LINE_LIST, options);
  m.scale.x = 0.05 * options.cone_height;  // line width
  m.color = rgba(0.2f, 0.6f, 1.0f);
  for (const ContactFrame& f : frames) {
    m.points.push_back(toPoint(f.position));
    m.points.push_back(toPoint(f.position + options.cone_height * f.normal));
  }
  return m;
}

void addForceArrows(const std_msgs::Header& header, const std::vector<ContactFrame>& frames,
                    const lcs::core::Problem& problem, const lcs::core::SolveResult& result,
                    const DisplayOptions& options, visualization_msgs::MarkerArray* markers) {
  const std::vector<int> offsets = problem.rowOffsets();
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const ContactFrame& f = frames[i];
    const double* l = result.forces.data() + offsets[i];
    const int rows = problem.contacts[i].rows;
    Eigen::Vector3d force = l[0] * f.normal;
    if (rows > 1) force += l[1] * f.tangent1;
    if (rows > 2) force += l[2] * f.tangent2;
    if (force.norm() == 0.0) continue;  // an arrow of length zero is invisible anyway
    // A finite but huge force times the scale can overflow: no arrow then, never an inf
    // point (found by fuzzing).
    const Eigen::Vector3d tip = f.position + options.force_arrow_scale * force;
    if (!tip.allFinite()) continue;
    auto m = baseMarker(header, kNsForces, static_cast<int>(i), visualization_msgs::Marker::ARROW, options);
    m.points.push_back(toPoint(f.position));
    m.points.push_back(toPoint(tip));
    // One colour for every arrow, none of the state colours: the sphere at its foot says
    // the state, the arrow only the force. Thick enough to read from a metre away.
    m.scale.x = 0.2 * options.cone_height;  // shaft diameter
    m.scale.y = 0.4 * options.cone_height;  // head diameter
    m.scale.z = 0.5 * options.cone_height;  // head length
    m.color = kForceArrowColor;
    markers->markers.push_back(m);
  }
}

// Cones of admissible forces: apex at the contact, opening along the normal, radius μ h.
visualization_msgs::Marker frictionCones(const std_msgs::Header& header,
                                         const std::vector<ContactFrame>& frames,
                                         const lcs::core::Problem& problem,
                                         const lcs::core::SolveResult& result, const std::vector<double>& mu,
                                         const DisplayOptions& options) {
  auto m = baseMarker(header, kNsFrictionCones, 0, visualization_msgs::Marker::TRIANGLE_LIST, options);
  m.scale.x = m.scale.y = m.scale.z = 1.0;
  const double h = options.cone_height;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    if (!lcs::core::hasSlidingFriction(problem.contacts[i].type) || mu[i] <= 0.0) continue;
    const ContactFrame& f = frames[i];
    std_msgs::ColorRGBA color = stateColor(result.states[i]);
    color.a = 0.4f;
    const Eigen::Vector3d centre = f.position + h * f.normal;
    auto rim = [&](int k) -> Eigen::Vector3d {
      const double angle = 2.0 * M_PI * k / kConeSegments;
      return centre + mu[i] * h * (std::cos(angle) * f.tangent1 + std::sin(angle) * f.tangent2);
    };
    for (int k = 0; k < kConeSegments; ++k) {
      for (const Eigen::Vector3d& v : {f.position, rim(k), rim(k + 1)}) {
        m.points.push_back(toPoint(v));
        m.colors.push_back(color);
      }
    }
  }
  return m;
}

// One cell per value at showTranslation + (column, -row) * showCellWidth, in the xy plane.
visualization_msgs::Marker heatmap(const std_msgs::Header& header, const char* ns,
                                   const Eigen::MatrixXd& values, int first_column,
                                   const DisplayOptions& options) {
  auto m = baseMarker(header, ns, 0, visualization_msgs::Marker::CUBE_LIST, options);
  const double w = options.showCellWidth;
  m.scale.x = m.scale.y = 0.95 * w;
  m.scale.z = 0.1 * w;
  const Eigen::Vector3d origin(options.showTranslation[0], options.showTranslation[1],
                               options.showTranslation[2]);
  const double scale = values.size() > 0 ? values.cwiseAbs().maxCoeff() : 0.0;
  for (Eigen::Index r = 0; r < values.rows(); ++r) {
    for (Eigen::Index c = 0; c < values.cols(); ++c) {
      m.points.push_back(toPoint(origin + Eigen::Vector3d((first_column + c) * w, -r * w, 0.0)));
      m.colors.push_back(heatColor(values(r, c), scale));
    }
  }
  return m;
}

void addHeatmaps(const std_msgs::Header& header, const lcs::core::Problem& problem,
                 const lcs::core::SolveResult& result, const DisplayOptions& options,
                 visualization_msgs::MarkerArray* markers) {
  if (!options.show_w_heatmap || options.showCellWidth <= 0.0) return;
  const int n = std::min(problem.rowCount(), options.heatmap_max_rows);
  const Eigen::MatrixXd w =
      lcs::core::leadingComplianceWindow(problem, n);  // the leading n x n window (W or bodies)
  markers->markers.push_back(heatmap(header, kNsComplianceHeatmap, w, 0, options));
  // λ as one column right of W, one empty column between.
  markers->markers.push_back(heatmap(header, kNsLambdaHeatmap, result.forces.head(n), n + 1, options));
}

}  // namespace

// Saturated hues that the scene simulator's muted body palette does not use.
std_msgs::ColorRGBA stateColor(lcs::core::ContactState state) {
  switch (state) {
    case lcs::core::ContactState::kOpen: return rgba(0.6f, 0.6f, 0.6f);
    case lcs::core::ContactState::kStick: return rgba(0.1f, 1.0f, 0.1f);
    case lcs::core::ContactState::kSlip: return rgba(1.0f, 0.0f, 0.0f);
    case lcs::core::ContactState::kIgnored: return rgba(0.2f, 0.3f, 1.0f);
    case lcs::core::ContactState::kClosed: return rgba(0.0f, 0.9f, 1.0f);
  }
  return rgba(1.0f, 0.0f, 1.0f);
}

std_msgs::ColorRGBA heatColor(double value, double scale) {
  const double t = scale > 0.0 ? std::clamp(value / scale, -1.0, 1.0) : 0.0;
  const float fade = static_cast<float>(1.0 - std::abs(t));
  return t >= 0.0 ? rgba(1.0f, fade, fade) : rgba(fade, fade, 1.0f);
}

visualization_msgs::MarkerArray buildMarkers(const std_msgs::Header& header,
                                             const std::vector<ContactFrame>& frames,
                                             const lcs::core::Problem& problem,
                                             const lcs::core::SolveResult& result,
                                             const std::vector<double>& mu, const DisplayOptions& options) {
  visualization_msgs::MarkerArray markers;
  markers.markers.push_back(contactPoints(header, frames, result, options));
  markers.markers.push_back(normals(header, frames, options));
  addForceArrows(header, frames, problem, result, options, &markers);
  markers.markers.push_back(frictionCones(header, frames, problem, result, mu, options));
  addHeatmaps(header, problem, result, options, &markers);
  // The last guard: a marker with a non-finite number (finite inputs whose products
  // overflow, e.g. a huge μ times the cone height) is left out, never published.
  auto& list = markers.markers;
  list.erase(std::remove_if(list.begin(), list.end(),
                            [](const visualization_msgs::Marker& m) { return !finiteMarker(m); }),
             list.end());
  return markers;
}

}  // namespace lcp_contact_solver_ros
