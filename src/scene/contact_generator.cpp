// FCL broadphase + narrowphase → SceneContacts with persistent ids (see contact_generator.h).
#include "lcp_contact_solver/scene/contact_generator.h"

#include <fcl/broadphase/broadphase_dynamic_AABB_tree.h>
#include <fcl/geometry/shape/box.h>
#include <fcl/geometry/shape/cylinder.h>
#include <fcl/geometry/shape/sphere.h>
#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/collision_object.h>
#include <fcl/narrowphase/collision_request.h>
#include <fcl/narrowphase/collision_result.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <set>
#include <tuple>
#include <utility>

namespace lcp_contact_solver {
namespace scene {

std::int64_t makeContactId(int body_a, int body_b, int slot) {
  return (static_cast<std::int64_t>(body_a) << 40) | (static_cast<std::int64_t>(body_b) << 16) |
         static_cast<std::int64_t>(slot & 0xffff);
}

namespace {

constexpr int kMaxSlots = 1 << 16;
// Points of one body pair closer than this are the same point (FCL's clipping can repeat a
// corner); the deeper one is kept.
constexpr double kDuplicatePoint = 1e-9;

struct Geom {
  int body = -1;
  int shape = -1;
  std::unique_ptr<fcl::CollisionObjectd> object;
};

struct PrevContact {
  int slot = 0;
  Eigen::Vector3d local_a;
};

struct PairMemory {
  std::vector<PrevContact> contacts;  // previous step
  int next_slot = 0;
};

using PairKey = std::pair<int, int>;  // (A, B)

std::shared_ptr<fcl::CollisionGeometryd> makeGeometry(const CollisionShape& s, double h) {
  switch (s.type) {
    case ShapeType::kBox:
      return std::make_shared<fcl::Boxd>(s.size.x() + 2 * h, s.size.y() + 2 * h, s.size.z() + 2 * h);
    case ShapeType::kSphere: return std::make_shared<fcl::Sphered>(s.size.x() + h);
    case ShapeType::kCylinder: return std::make_shared<fcl::Cylinderd>(s.size.x() + h, s.size.y() + 2 * h);
  }
  return nullptr;
}

// The inflated shapes put a box's face-contact corners margin/2 outside the true box (and a
// cylinder's rim outside the true rim). For face contacts — a box axis or a cylinder's
// axis within ~2.5° of the normal, or a cylinder's side — the point is moved back within
// the true shape, across the normal only; other contacts (tumbling edges and corners) keep
// FCL's point, off by at most margin/2 sideways.
Eigen::Vector3d clampToShape(const CollisionShape& shape, const Eigen::Isometry3d& world_T_shape,
                             const Eigen::Vector3d& n, const Eigen::Vector3d& p) {
  constexpr double kAligned = 0.999;
  const Eigen::Vector3d n_l = world_T_shape.linear().transpose() * n;
  Eigen::Vector3d q = world_T_shape.inverse() * p;
  switch (shape.type) {
    case ShapeType::kSphere: return p;  // inflated radially: no sideways error
    case ShapeType::kBox: {
      Eigen::Index k = 0;
      if (n_l.cwiseAbs().maxCoeff(&k) < kAligned) return p;
      for (int i = 0; i < 3; ++i)
        if (i != k) q[i] = std::clamp(q[i], -0.5 * shape.size[i], 0.5 * shape.size[i]);
      break;
    }
    case ShapeType::kCylinder: {
      const double r = shape.size.x(), half = 0.5 * shape.size.y();
      if (std::abs(n_l.z()) >= kAligned) {  // flat face
        const double radial = std::hypot(q.x(), q.y());
        if (radial > r) {
          q.x() *= r / radial;
          q.y() *= r / radial;
        }
      } else if (std::abs(n_l.z()) <= 1.0 - kAligned) {  // side
        q.z() = std::clamp(q.z(), -half, half);
      } else {
        return p;
      }
      break;
    }
  }
  return world_T_shape * q;
}

bool collectPair(fcl::CollisionObjectd* o1, fcl::CollisionObjectd* o2, void* data) {
  auto* pairs = static_cast<std::vector<std::pair<int, int>>*>(data);
  const int a = static_cast<int>(reinterpret_cast<std::intptr_t>(o1->getUserData()));
  const int b = static_cast<int>(reinterpret_cast<std::intptr_t>(o2->getUserData()));
  pairs->emplace_back(std::min(a, b), std::max(a, b));
  return false;  // keep going
}

}  // namespace

struct ContactGenerator::Impl {
  const Scene& scene;
  double inflation = 0.0;  // per shape: contact_margin / 2
  std::vector<Geom> geoms;
  fcl::DynamicAABBTreeCollisionManagerd dynamic_tree, static_tree;
  std::set<PairKey> disabled;  // (min, max) body indices
  std::map<PairKey, PairMemory> memory;

  explicit Impl(const Scene& s) : scene(s) {
    inflation = 0.5 * s.params.contact_margin;
    for (std::size_t b = 0; b < s.bodies.size(); ++b) {
      const RigidBody& body = s.bodies[b];
      for (std::size_t k = 0; k < body.shapes.size(); ++k) {
        Geom g;
        g.body = static_cast<int>(b);
        g.shape = static_cast<int>(k);
        g.object = std::make_unique<fcl::CollisionObjectd>(makeGeometry(body.shapes[k], inflation));
        g.object->setUserData(reinterpret_cast<void*>(static_cast<std::intptr_t>(geoms.size())));
        geoms.push_back(std::move(g));
      }
    }
    std::vector<fcl::CollisionObjectd*> dyn, stat;
    for (Geom& g : geoms) {
      place(g);
      (scene.bodies[g.body].is_static ? stat : dyn).push_back(g.object.get());
    }
    if (!dyn.empty()) dynamic_tree.registerObjects(dyn);
    if (!stat.empty()) static_tree.registerObjects(stat);
    dynamic_tree.setup();
    static_tree.setup();
    for (const auto& d : s.params.disable_collisions) {
      const int a = s.bodyIndex(d.first), b = s.bodyIndex(d.second);
      if (a >= 0 && b >= 0) disabled.emplace(std::min(a, b), std::max(a, b));
    }
  }

  void place(Geom& g) {
    const RigidBody& body = scene.bodies[g.body];
    const Eigen::Isometry3d T = body.pose() * body.shapes[g.shape].origin;
    g.object->setTransform(fcl::Transform3d(T.matrix()));
    g.object->computeAABB();
  }
};

ContactGenerator::ContactGenerator(const Scene& scene) : impl_(std::make_unique<Impl>(scene)) {}
ContactGenerator::~ContactGenerator() = default;

void ContactGenerator::resetIds() { impl_->memory.clear(); }

std::vector<SceneContact> ContactGenerator::generate() {
  Impl& im = *impl_;
  const Scene& scene = im.scene;
  last_ = ContactGenerationStats();

  // 1. Broadphase: dynamic tree against itself and against the static tree. Static–static
  //    pairs are never queried.
  for (Geom& g : im.geoms)
    if (!scene.bodies[g.body].is_static) im.place(g);
  im.dynamic_tree.update();
  std::vector<std::pair<int, int>> candidates;
  im.dynamic_tree.collide(&candidates, collectPair);
  im.dynamic_tree.collide(&im.static_tree, &candidates, collectPair);
  std::sort(candidates.begin(), candidates.end());
  candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());

  // 2. Filter, then narrowphase. Raw contacts grouped by body pair (A, B).
  struct Raw {
    Eigen::Vector3d point, normal;
    double depth;
  };
  std::map<PairKey, std::vector<Raw>> raw;
  fcl::CollisionRequestd request(/*num_max_contacts=*/16, /*enable_contact=*/true);
  const double margin = 2.0 * im.inflation;
  for (const auto& [gi, gj] : candidates) {
    const int bi = im.geoms[gi].body, bj = im.geoms[gj].body;
    if (bi == bj) continue;  // shapes of one body
    ++last_.broadphase_pairs;
    if (im.disabled.count({std::min(bi, bj), std::max(bi, bj)})) {
      ++last_.skipped_disabled;
      continue;
    }
    // A: the dynamic body if exactly one is static, else the lower index.
    const bool si = scene.bodies[bi].is_static, sj = scene.bodies[bj].is_static;
    const bool i_is_a = (si != sj) ? !si : (bi < bj);
    const Geom& ga = im.geoms[i_is_a ? gi : gj];
    const Geom& gb = im.geoms[i_is_a ? gj : gi];
    fcl::CollisionResultd result;
    fcl::collide(ga.object.get(), gb.object.get(), request, result);
    ++last_.narrowphase_tests;
    ++total_narrowphase_;
    if (!result.isCollision()) continue;
    std::vector<fcl::Contactd> contacts;
    result.getContacts(contacts);
    std::vector<Raw>& bucket = raw[{ga.body, gb.body}];
    const RigidBody& body_a = scene.bodies[ga.body];
    const RigidBody& body_b = scene.bodies[gb.body];
    const Eigen::Isometry3d pose_a = body_a.pose() * body_a.shapes[ga.shape].origin;
    const Eigen::Isometry3d pose_b = body_b.pose() * body_b.shapes[gb.shape].origin;
    for (const fcl::Contactd& c : contacts) {
      // FCL's normal points from o1 (A) to o2 (B); ours from B into A.
      Eigen::Vector3d n = -c.normal;
      const double len = n.norm();
      if (!std::isfinite(len) || len < 1e-12 || !c.pos.allFinite() || !std::isfinite(c.penetration_depth))
        continue;
      n /= len;
      const double gap = margin - c.penetration_depth;
      Eigen::Vector3d point = clampToShape(body_a.shapes[ga.shape], pose_a, n, c.pos);
      point = clampToShape(body_b.shapes[gb.shape], pose_b, n, point);
      bucket.push_back({point, n, -gap});
    }
  }

  // 3. Per pair: drop duplicates, match ids with the previous step, build frames.
  std::vector<SceneContact> frames;
  std::map<PairKey, PairMemory> next_memory;
  for (auto& [key, list] : raw) {
    // Stable order of FCL's points for deterministic matching.
    std::vector<Raw> points;
    for (const Raw& r : list) {
      bool dup = false;
      for (Raw& q : points) {
        if ((q.point - r.point).norm() < kDuplicatePoint) {
          if (r.depth > q.depth) q = r;
          dup = true;
          break;
        }
      }
      if (!dup) points.push_back(r);
    }
    if (points.empty()) continue;
    const RigidBody& A = scene.bodies[key.first];
    const RigidBody& B = scene.bodies[key.second];
    const Eigen::Isometry3d a_inv = A.pose().inverse();
    std::vector<Eigen::Vector3d> local(points.size());
    for (std::size_t i = 0; i < points.size(); ++i) local[i] = a_inv * points[i].point;

    PairMemory& mem_next = next_memory[key];
    auto prev_it = im.memory.find(key);
    const PairMemory* prev = prev_it == im.memory.end() ? nullptr : &prev_it->second;
    mem_next.next_slot = prev ? prev->next_slot : 0;

    std::vector<int> slot(points.size(), -1);
    std::set<int> used;
    if (prev) {
      std::vector<std::tuple<double, int, int>> cand;  // (distance, new, old)
      const double tol = scene.params.id_match_tolerance;
      for (std::size_t i = 0; i < points.size(); ++i)
        for (std::size_t k = 0; k < prev->contacts.size(); ++k) {
          const double d = (local[i] - prev->contacts[k].local_a).norm();
          if (d <= tol) cand.emplace_back(d, static_cast<int>(i), static_cast<int>(k));
        }
      std::sort(cand.begin(), cand.end());
      std::vector<bool> old_taken(prev->contacts.size(), false);
      for (const auto& [d, i, k] : cand) {
        if (slot[i] >= 0 || old_taken[k]) continue;
        slot[i] = prev->contacts[k].slot;
        old_taken[k] = true;
        used.insert(slot[i]);
      }
    }
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (slot[i] >= 0) continue;
      int s = mem_next.next_slot;
      for (int tries = 0; tries < kMaxSlots && used.count(s); ++tries) s = (s + 1) % kMaxSlots;
      slot[i] = s;
      used.insert(s);
      mem_next.next_slot = (s + 1) % kMaxSlots;
      ++last_.new_ids;
    }

    const PairContactModel model = scene.params.contactModelFor(A.name, B.name);
    std::vector<std::size_t> order(points.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](std::size_t x, std::size_t y) { return slot[x] < slot[y]; });
    for (std::size_t i : order) {
      SceneContact f;
      f.id = makeContactId(key.first, key.second, slot[i]);
      f.body_a = key.first;
      f.body_b = key.second;
      f.body_a_name = A.name;
      f.body_b_name = B.name;
      f.position = points[i].point;
      f.normal = points[i].normal;
      core::tangentsFromNormal(f.normal, &f.tangent1, &f.tangent2);
      f.depth = points[i].depth;
      // Only the rows the pair asks for (MuJoCo's condim 1 / 3 / 4 / 6).
      f.mu = model.mu;
      f.restitution = model.restitution;
      if (model.mu <= 0.0) {
        f.type = core::ContactType::kFrictionless;
      } else if (model.rolling > 0.0) {
        f.type = core::ContactType::kRolling;
        f.mu_torsional = model.torsional;
        f.mu_rolling = model.rolling;
      } else if (model.torsional > 0.0) {
        f.type = core::ContactType::kTorsional;
        f.mu_torsional = model.torsional;
      } else {
        f.type = core::ContactType::kFrictional;
      }
      f.rows = core::rowsForType(f.type);
      f.point_local_a = local[i];
      frames.push_back(f);
      mem_next.contacts.push_back({slot[i], local[i]});
    }
  }
  im.memory = std::move(next_memory);
  last_.contacts = static_cast<int>(frames.size());
  return frames;
}

}  // namespace scene
}  // namespace lcp_contact_solver
