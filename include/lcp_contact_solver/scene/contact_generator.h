// Contact generation with FCL: broadphase (two dynamic AABB trees, one for the dynamic
// bodies' shapes and one for the static ones) then narrowphase (fcl::collide on primitive
// shapes), producing contact frames with persistent ids.
//
// Which pairs are tested:
//   - links without collision geometry are never registered with the broadphase;
//   - static–static pairs are never tested: the static tree is only ever queried against
//     the dynamic tree, never against itself;
//   - shapes of one body never collide with each other;
//   - disabled body pairs (SceneParams::disable_collisions) are dropped when the broadphase
//     reports them, before any narrowphase test.
// narrowphaseTests() counts the narrowphase (fcl::collide) calls.
//
// Speculative contacts: every shape is inflated by contact_margin / 2 for FCL, so shape
// pairs closer than the margin are reported; the true gap is contact_margin − (FCL's depth
// of the inflated shapes). This is exact for sphere and face contacts (the only ones a
// resting scene has) and slightly underestimates the gap of a tilted box's corner (by at
// most margin/2 · (|a₁·n| + |a₂·n| + |a₃·n| − 1)), which only matters while it is in flight.
//
// Conventions (documented once, here):
//   - body A and body B of a pair: if exactly one is static, A is the dynamic one;
//     otherwise A has the lower body index;
//   - the normal points from body B into body A; n·λ_n is the force on A (−n·λ_n on B);
//   - `position` is midway between the two surfaces along the normal (FCL's convention);
//   - depth > 0 is penetration, gap = −depth;
//   - tangents: t1 = normalize(n × a) with a the world axis least aligned with n (first
//     one on ties, with a 1e-6 tie tolerance: see core/contact_frame.h), t2 = n × t1;
//   - rows of a contact: normal, t1, t2 (frictional, μ > 0) or normal only (μ = 0: one row).
//
// Persistent ids: id = (A << 40) | (B << 16) | slot, A and B body indices, slot a per-pair
// feature slot (16 bits). A contact keeps the slot of the previous step's contact of the same
// pair whose point in A's frame is nearest, within id_match_tolerance (greedy, nearest
// first, ties by index: deterministic); others get fresh slots from a per-pair counter.
// Contacts are ordered by body pair (A, B), then slot.
#pragma once

#include "lcp_contact_solver/core/contact_frame.h"
#include "lcp_contact_solver/core/problem.h"
#include "lcp_contact_solver/scene/scene.h"

#include <Eigen/Core>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace lcp_contact_solver {
namespace scene {

// Everything known about one contact, kept beside the core Problem (same order) so a
// ROS layer can fill its messages without recomputing: the core's ContactFrame (world frame:
// `position` in m, `normal` from B into A, the rule's tangents, given explicitly so
// derived_tangents stays false) plus what the scene knows.
struct SceneContact : core::ContactFrame {
  std::int64_t id = 0;
  int body_a = -1, body_b = -1;  // indices into Scene::bodies
  std::string body_a_name, body_b_name;
  double depth = 0.0;  // m; > 0 penetration, < 0 gap (speculative contact)
  double mu = 0.0;
  double mu_torsional = 0.0;  // m
  double mu_rolling = 0.0;    // m
  double restitution = 0.0;
  core::ContactType type = core::ContactType::kFrictional;
  int rows = 3;
  Eigen::Vector3d point_local_a = Eigen::Vector3d::Zero();  // point in A's link frame

  double gap() const { return -depth; }
};

// id = (A << 40) | (B << 16) | slot.
std::int64_t makeContactId(int body_a, int body_b, int slot);

struct ContactGenerationStats {
  int broadphase_pairs = 0;   // shape pairs whose AABBs overlap
  int skipped_disabled = 0;   // of those, dropped as disabled pairs
  int narrowphase_tests = 0;  // fcl::collide calls
  int contacts = 0;
  int new_ids = 0;  // contacts that got a fresh slot
};

class ContactGenerator {
 public:
  // Registers the scene's collision shapes. The scene must outlive the generator and keep
  // its bodies (poses may change).
  explicit ContactGenerator(const Scene& scene);
  ~ContactGenerator();
  ContactGenerator(const ContactGenerator&) = delete;
  ContactGenerator& operator=(const ContactGenerator&) = delete;

  // Contacts at the scene's current poses. Updates the id memory (call once per step).
  std::vector<SceneContact> generate();

  const ContactGenerationStats& lastStats() const { return last_; }
  // Narrowphase tests since construction (or resetCounters()).
  long long narrowphaseTests() const { return total_narrowphase_; }
  void resetCounters() { total_narrowphase_ = 0; }
  // Forgets the previous step's contacts (all contacts get fresh ids next time).
  void resetIds();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  ContactGenerationStats last_;
  long long total_narrowphase_ = 0;
};

}  // namespace scene
}  // namespace lcp_contact_solver
