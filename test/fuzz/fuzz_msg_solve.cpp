// Fuzz target: ContactArray + Compliance messages → problem (toProblem) → solve, through
// the node's own CycleSolver, plus the markers the node would draw. The messages are built
// from the bytes (fuzz_input.h) rather than deserialized: a structured decoder reaches the
// conversion's checks and the solvers far more often than random serialized bytes, whose
// array lengths would mostly overrun. Layout of the bytes, in order:
//   parameters (solver, maxIt, tolerance, μ, regularization, minW, maxF, friction model,
//   sor, stopping rule, max_rows, warm start), a "shape" byte (bit 0: rows consistent with
//   the types, bit 1: d_free sized to the rows, bit 2: W sized to the rows, bit 3: W a
//   positive semidefinite J Jᵀ + δI, bit 4: moderate numbers only), the contacts (count,
//   then per contact id, type, rows, position, normal, tangents, d_free, μ), the
//   compliance (storage, rows, values or blocks), then display options.
// Invariants (fuzz_targets.h): rejection with a one-line reason, or a finite, honest
// result; published messages (forces, stats, markers) finite; two runs bit-identical.
#include "fuzz_check.h"
#include "fuzz_input.h"
#include "fuzz_targets.h"

#include "lcp_contact_solver/ros/node/cycle_solver.h"
#include "lcp_contact_solver/ros/node/markers.h"
#include "lcp_contact_solver/ros/node/solver_params_ros.h"

#include <cstdlib>
#include <exception>

namespace lcs_fuzz {

namespace {

using lcp_contact_solver::Compliance;
using lcp_contact_solver::ContactArray;
using lcp_contact_solver::ContactPoint;

struct Shape {
  bool consistent_rows, sized_d_free, sized_w, psd_w, moderate;
};

double value(FuzzInput& in, const Shape& shape) { return shape.moderate ? in.moderate() : in.number(); }

geometry_msgs::Vector3 vec(double x, double y, double z) {
  geometry_msgs::Vector3 v;
  v.x = x;
  v.y = y;
  v.z = z;
  return v;
}

lcs::core::SolverParams readParams(FuzzInput& in) {
  lcs::core::SolverParams p = lcp_contact_solver_ros::defaultSolverParams();
  p.solver = static_cast<lcs::core::SolverKind>(in.below(6));
  p.maxIt = 1 + in.below(40);
  const double tolerances[] = {1e-3, 1e-6, 1e-10, 0.5};
  p.tolerance = tolerances[in.below(4)];
  if (in.flag()) p.mu = in.number();  // may be invalid: the core must refuse it
  if (in.flag()) p.regularizationTerm = std::abs(in.number());
  if (in.flag()) p.minW = in.number();
  if (in.flag()) p.maxF = in.number();
  p.friction_model = static_cast<lcs::core::FrictionModel>(in.below(3));
  if (in.flag()) p.sor = 0.5 + in.below(150) / 100.0;
  p.stopping_rule = in.flag() ? lcs::core::StoppingRule::kSofa : lcs::core::StoppingRule::kResidual;
  p.max_rows = in.flag() ? in.below(40) : 0;
  p.initial_guess = in.flag();
  return p;
}

int rowsOf(const ContactPoint& c) {
  if (c.type == ContactPoint::FRICTIONAL) return 3;
  if (c.type == ContactPoint::FRICTIONLESS) return 1;
  return static_cast<int>(c.rows);
}

ContactArray readContacts(FuzzInput& in, const Shape& shape) {
  ContactArray msg;
  msg.header.frame_id = "world";
  msg.header.stamp.sec = 1;
  const int count = in.below(7);
  for (int i = 0; i < count; ++i) {
    ContactPoint c;
    c.id = in.below(6);
    c.type = static_cast<std::uint8_t>(in.below(4));  // 3 is unknown
    c.rows = static_cast<std::uint32_t>(in.below(8));
    if (shape.consistent_rows) {
      if (c.type > ContactPoint::BILATERAL) c.type = ContactPoint::FRICTIONAL;
      c.rows = c.type == ContactPoint::BILATERAL ? 1 + c.rows % 6 : 0;
    }
    c.body_a = "a" + std::to_string(in.below(3));
    c.body_b = "b" + std::to_string(in.below(3));
    c.position.x = value(in, shape);
    c.position.y = value(in, shape);
    c.position.z = value(in, shape);
    switch (in.below(4)) {
      case 0: c.normal = vec(0, 0, 1); break;
      case 1: c.normal = vec(value(in, shape), value(in, shape), value(in, shape)); break;
      case 2: c.normal = vec(0, 0, 0); break;
      default: c.normal = vec(0.6, 0.0, 0.8); break;
    }
    switch (in.below(4)) {
      case 0: break;  // derived
      case 1:         // given, orthonormal to (0, 0, 1)
        c.tangent1 = vec(1, 0, 0);
        c.tangent2 = vec(0, 1, 0);
        break;
      case 2: c.tangent1 = vec(value(in, shape), value(in, shape), value(in, shape)); break;
      default:
        c.tangent1 = vec(value(in, shape), value(in, shape), value(in, shape));
        c.tangent2 = vec(value(in, shape), value(in, shape), value(in, shape));
        break;
    }
    const int rows = shape.sized_d_free ? rowsOf(c) : in.below(8);
    for (int k = 0; k < std::max(0, rows) && k < 8; ++k) c.d_free.push_back(value(in, shape));
    switch (in.below(4)) {
      case 0: c.mu = ContactPoint::MU_DEFAULT; break;
      case 1: c.mu = 0.0; break;
      case 2: c.mu = 0.5; break;
      default: c.mu = in.number(); break;
    }
    msg.contacts.push_back(c);
  }
  return msg;
}

Compliance readCompliance(FuzzInput& in, const Shape& shape, const ContactArray& contacts) {
  Compliance msg;
  msg.header = contacts.header;
  std::vector<int> sizes;
  int total = 0;
  for (const ContactPoint& c : contacts.contacts) {
    sizes.push_back(std::max(0, std::min(8, rowsOf(c))));
    total += sizes.back();
  }
  msg.storage = static_cast<std::uint8_t>(in.below(3));  // 2: the body form, here without bodies (refused)
  msg.rows = shape.sized_w ? static_cast<std::uint32_t>(total) : static_cast<std::uint32_t>(in.below(40));
  const int n = static_cast<int>(std::min<std::uint32_t>(msg.rows, 48));
  Eigen::MatrixXd W = Eigen::MatrixXd::Zero(n, n);
  if (shape.psd_w) {
    const int k = 1 + in.below(8);  // rank of J: often below n (rank-deficient, like real stacks)
    Eigen::MatrixXd J(n, k);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < k; ++j) J(i, j) = in.moderate();
    const double deltas[] = {0.0, 1e-12, 1e-3, 1.0};
    W = J * J.transpose() / k + deltas[in.below(4)] * Eigen::MatrixXd::Identity(n, n);
  } else {
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) W(i, j) = value(in, shape);
  }
  if (msg.storage != Compliance::STORAGE_BLOCK_SPARSE) {
    const int values = shape.sized_w ? n * n : in.below(n * n + 3);
    for (int v = 0; v < values; ++v) msg.data.push_back(v < n * n ? W(v / n, v % n) : value(in, shape));
    return msg;
  }
  const int nb = static_cast<int>(sizes.size());
  std::vector<int> offsets(1, 0);
  for (int s : sizes) offsets.push_back(offsets.back() + s);
  const bool all_blocks = shape.sized_w && in.flag();
  const int blocks = all_blocks ? nb * nb : in.below(12);
  for (int b = 0; b < blocks; ++b) {
    const int i = all_blocks ? b / nb : in.below(nb + 2), j = all_blocks ? b % nb : in.below(nb + 2);
    msg.block_rows.push_back(static_cast<std::uint32_t>(i));
    msg.block_cols.push_back(static_cast<std::uint32_t>(j));
    if (i < nb && j < nb && offsets[nb] <= n) {
      for (int r = offsets[i]; r < offsets[i + 1]; ++r)
        for (int c = offsets[j]; c < offsets[j + 1]; ++c) msg.block_data.push_back(W(r, c));
    }
  }
  if (!shape.sized_w)
    for (int extra = in.below(4); extra > 0; --extra) msg.block_data.push_back(value(in, shape));
  return msg;
}

bool finite(const geometry_msgs::Point& p) {
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
}

std::string checkMarkers(const visualization_msgs::MarkerArray& markers) {
  for (const visualization_msgs::Marker& m : markers.markers) {
    const auto& pose = m.pose;
    if (!finite(pose.position) || !std::isfinite(pose.orientation.x) || !std::isfinite(pose.orientation.y) ||
        !std::isfinite(pose.orientation.z) || !std::isfinite(pose.orientation.w) ||
        !std::isfinite(m.scale.x) || !std::isfinite(m.scale.y) || !std::isfinite(m.scale.z))
      return "marker " + m.ns + " has a non-finite pose or scale";
    for (const geometry_msgs::Point& p : m.points)
      if (!finite(p)) return "marker " + m.ns + " has a non-finite point";
    for (const std_msgs::ColorRGBA& c : m.colors)
      if (!std::isfinite(c.r) || !std::isfinite(c.g) || !std::isfinite(c.b) || !std::isfinite(c.a))
        return "marker " + m.ns + " has a non-finite colour";
  }
  return "";
}

std::string run(FuzzInput& in) {
  const lcs::core::SolverParams params = readParams(in);
  const std::uint8_t shape_bits = in.byte();
  const Shape shape{(shape_bits & 1) != 0, (shape_bits & 2) != 0, (shape_bits & 4) != 0,
                    (shape_bits & 8) != 0, (shape_bits & 16) != 0};
  const ContactArray contacts = readContacts(in, shape);
  const Compliance compliance = readCompliance(in, shape, contacts);
  lcp_contact_solver_ros::DisplayOptions display;
  display.showCellWidth = in.flag() ? 0.05 : 0.0;
  display.force_arrow_scale = in.flag() ? 0.01 : std::abs(in.moderate()) + 1e-3;

  lcp_contact_solver_ros::CycleSolver first(params), second(params);
  const lcp_contact_solver_ros::CycleOutput a = first.solve(contacts, compliance);
  const lcp_contact_solver_ros::CycleOutput b = second.solve(contacts, compliance);
  if (a.error != b.error) return "two conversions of the same messages differ";
  if (!lcp_contact_solver_ros::allFinite(a.stats)) return "stats with a non-finite number";
  if (a.rejected()) {
    if (a.error.find('\n') != std::string::npos) return "rejection reason is not one line: " + a.error;
    if (a.stats.success || a.stats.status != "invalid_input") return "a rejection's stats say success";
    if (a.has_forces || !a.forces.forces.empty()) return "a rejected input has forces";
    return "";
  }
  if (std::string err = checkResult(a.problem, first.params(), a.result); !err.empty()) return err;
  if (std::string err = checkDeterministic(a.result, b.result); !err.empty()) return err;
  if (a.gave_forces && a.has_forces && !lcp_contact_solver_ros::allFinite(a.forces))
    return "non-finite forces message";
  if (a.has_forces && a.forces.forces.size() != contacts.contacts.size()) return "forces message size";
  const visualization_msgs::MarkerArray markers = lcp_contact_solver_ros::buildMarkers(
      contacts.header, a.frames, a.problem, a.result, lcs::core::effectiveMu(a.problem, params.mu), display);
  if (std::string err = checkMarkers(markers); !err.empty()) return err;
  // The next cycle, warm-started from this one (the node's path).
  const lcp_contact_solver_ros::CycleOutput again = first.solve(contacts, compliance);
  if (again.rejected()) return "the same messages were rejected on the second cycle: " + again.error;
  return checkResult(again.problem, first.params(), again.result);
}

}  // namespace

std::string msgSolveOneInput(const std::uint8_t* data, std::size_t size) {
  FuzzInput in(data, size);
  try {
    return run(in);
  } catch (const std::exception& e) {
    return std::string("exception: ") + e.what();
  }
}

}  // namespace lcs_fuzz

#ifdef LCS_LIBFUZZER
#include <cstdio>
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string fault = lcs_fuzz::msgSolveOneInput(data, size);
  if (!fault.empty()) {
    std::fprintf(stderr, "fuzz_msg_solve: %s\n", fault.c_str());
    std::abort();
  }
  return 0;
}
#endif
