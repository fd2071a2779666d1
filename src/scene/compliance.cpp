// W = dt² J M⁻¹ Jᵀ, d_free and force application for rigid bodies (see compliance.h).
#include "lcp_contact_solver/scene/compliance.h"

#include <algorithm>
#include <memory>

namespace lcp_contact_solver {
namespace scene {

double gapTerm(double gap) { return gap > 0.0 ? gap : 0.0; }

std::vector<Vector6d> freeVelocities(const Scene& scene, double dt) {
  std::vector<Vector6d> v(scene.bodies.size(), Vector6d::Zero());
  for (std::size_t i = 0; i < scene.bodies.size(); ++i) {
    const RigidBody& b = scene.bodies[i];
    if (b.is_static) continue;
    Eigen::Vector3d torque = b.external_torque;
    if (scene.params.gyroscopic) torque -= b.angular_velocity.cross(b.inertiaWorld() * b.angular_velocity);
    v[i].head<3>() = b.linear_velocity + dt * (scene.params.gravity + b.external_force / b.mass);
    v[i].tail<3>() = b.angular_velocity + dt * (b.inverseInertiaWorld() * torque);
  }
  return v;
}

RigidContactModel::RigidContactModel(const Scene& scene, const std::vector<SceneContact>& frames) {
  body_count_ = static_cast<int>(scene.bodies.size());
  inverse_mass_.assign(scene.bodies.size(), Eigen::Matrix<double, 6, 6>::Zero());
  for (std::size_t i = 0; i < scene.bodies.size(); ++i) {
    const RigidBody& b = scene.bodies[i];
    if (b.is_static) continue;
    inverse_mass_[i].topLeftCorner<3, 3>() = Eigen::Matrix3d::Identity() / b.mass;
    inverse_mass_[i].bottomRightCorner<3, 3>() = b.inverseInertiaWorld();
  }
  body_contacts_.assign(scene.bodies.size(), {});
  contacts_.resize(frames.size());
  offsets_.assign(frames.size() + 1, 0);
  for (std::size_t c = 0; c < frames.size(); ++c) {
    const SceneContact& f = frames[c];
    ContactData& cd = contacts_[c];
    cd.rows = f.rows;
    cd.gap = f.gap();
    offsets_[c + 1] = offsets_[c] + f.rows;
    const Eigen::Vector3d dirs[3] = {f.normal, f.tangent1, f.tangent2};
    const int bodies[2] = {f.body_a, f.body_b};
    for (int s = 0; s < 2; ++s) {
      Side& side = cd.side[s];
      side.J.setZero();
      side.MinvJt.setZero();
      const RigidBody& body = scene.bodies[bodies[s]];
      if (body.is_static) continue;
      side.body = bodies[s];
      const double sign = s == 0 ? 1.0 : -1.0;
      const Eigen::Vector3d r = f.position - body.comWorld();
      for (int k = 0; k < std::min(f.rows, 3); ++k) {
        side.J.block<1, 3>(k, 0) = sign * dirs[k].transpose();
        side.J.block<1, 3>(k, 3) = sign * r.cross(dirs[k]).transpose();
      }
      for (int k = 3; k < f.rows; ++k)  // spin about n, then rolling about t1, t2
        side.J.block<1, 3>(k, 3) = sign * dirs[k - 3].transpose();
      side.MinvJt = inverse_mass_[side.body] * side.J.transpose();
      body_contacts_[side.body].push_back(static_cast<int>(c));
    }
  }
}

core::ComplianceMatrix RigidContactModel::compliance(double dt, ComplianceStorage storage) const {
  const int nc = contactCount();
  const double dt2 = dt * dt;
  // Block (i, j) = dt² Σ_{dynamic bodies b shared by i and j} J_ib M_b⁻¹ J_jbᵀ.
  auto addShared = [&](int i, int j, Eigen::Matrix<double, 6, 6>* block) {
    for (const Side& si : contacts_[i].side) {
      if (si.body < 0) continue;
      for (const Side& sj : contacts_[j].side)
        if (sj.body == si.body)  // only the rows each contact has (3 for most)
          block->topLeftCorner(contacts_[i].rows, contacts_[j].rows).noalias() +=
              si.J.topRows(contacts_[i].rows) * sj.MinvJt.leftCols(contacts_[j].rows);
    }
  };
  if (storage == ComplianceStorage::kDense) {
    Eigen::MatrixXd W = Eigen::MatrixXd::Zero(rowCount(), rowCount());
    for (int i = 0; i < nc; ++i) {
      for (int j : neighbours(i)) {
        Eigen::Matrix<double, 6, 6> block = Eigen::Matrix<double, 6, 6>::Zero();
        addShared(i, j, &block);
        W.block(offsets_[i], offsets_[j], contacts_[i].rows, contacts_[j].rows) =
            dt2 * block.topLeftCorner(contacts_[i].rows, contacts_[j].rows);
      }
    }
    return W;
  }
  std::vector<int> sizes(nc);
  for (int i = 0; i < nc; ++i) sizes[i] = contacts_[i].rows;
  core::BlockSparseMatrix W = core::BlockSparseMatrix::withBlockSizes(sizes);
  for (int i = 0; i < nc; ++i) {
    W.beginRow();
    for (int j : neighbours(i)) {
      Eigen::Matrix<double, 6, 6> block = Eigen::Matrix<double, 6, 6>::Zero();
      addShared(i, j, &block);
      W.addBlock(j, dt2 * block.topLeftCorner(contacts_[i].rows, contacts_[j].rows));
    }
  }
  return W;
}

core::BodyCompliance RigidContactModel::bodyCompliance(double dt) const {
  core::BodyCompliance out;
  const double dt2 = dt * dt;
  out.body_compliance.reserve(inverse_mass_.size());
  for (const Eigen::Matrix<double, 6, 6>& m : inverse_mass_) out.body_compliance.push_back(dt2 * m);
  out.contacts.resize(contacts_.size());
  for (std::size_t c = 0; c < contacts_.size(); ++c) {
    const ContactData& cd = contacts_[c];
    core::ContactJacobian& cj = out.contacts[c];
    cj.rows = cd.rows;
    cj.body_a = cd.side[0].body;
    cj.body_b = cd.side[1].body;
    if (cj.body_a >= 0) cj.jacobian_a = cd.side[0].J.topRows(cd.rows);
    if (cj.body_b >= 0) cj.jacobian_b = cd.side[1].J.topRows(cd.rows);
  }
  return out;
}

std::vector<int> RigidContactModel::neighbours(int i) const {
  // Contacts sharing a dynamic body with contact i (i included), ascending. Each body's
  // list is ascending, so this is a merge of at most two sorted lists.
  const int a = contacts_[i].side[0].body, b = contacts_[i].side[1].body;
  static const std::vector<int> kEmpty;
  const std::vector<int>& la = a >= 0 ? body_contacts_[a] : kEmpty;
  const std::vector<int>& lb = b >= 0 ? body_contacts_[b] : kEmpty;
  std::vector<int> out;
  out.reserve(la.size() + lb.size());
  std::set_union(la.begin(), la.end(), lb.begin(), lb.end(), std::back_inserter(out));
  return out;
}

Eigen::VectorXd RigidContactModel::freeViolation(const std::vector<Vector6d>& v_free, double dt) const {
  Eigen::VectorXd d = Eigen::VectorXd::Zero(rowCount());
  for (int c = 0; c < contactCount(); ++c) {
    const ContactData& cd = contacts_[c];
    for (const Side& s : cd.side) {
      if (s.body < 0) continue;
      d.segment(offsets_[c], cd.rows) += dt * (s.J.topRows(cd.rows) * v_free[s.body]);
    }
    d[offsets_[c]] += gapTerm(cd.gap);
  }
  return d;
}

Eigen::VectorXd RigidContactModel::normalVelocities(const std::vector<Vector6d>& v) const {
  Eigen::VectorXd vn = Eigen::VectorXd::Zero(contactCount());
  for (int c = 0; c < contactCount(); ++c)
    for (const Side& s : contacts_[c].side)
      if (s.body >= 0) vn[c] += s.J.row(0).dot(v[s.body]);
  return vn;
}

std::vector<Vector6d> RigidContactModel::bodyWrenches(const Eigen::VectorXd& lambda) const {
  std::vector<Vector6d> w(body_count_, Vector6d::Zero());
  for (int c = 0; c < contactCount(); ++c) {
    const ContactData& cd = contacts_[c];
    for (const Side& s : cd.side) {
      if (s.body < 0) continue;
      w[s.body] += s.J.topRows(cd.rows).transpose() * lambda.segment(offsets_[c], cd.rows);
    }
  }
  return w;
}

void RigidContactModel::applyForces(const Eigen::VectorXd& lambda, double dt,
                                    std::vector<Vector6d>* velocities) const {
  const std::vector<Vector6d> w = bodyWrenches(lambda);
  for (int b = 0; b < body_count_; ++b) (*velocities)[b] += dt * (inverse_mass_[b] * w[b]);
}

Eigen::MatrixXd RigidContactModel::denseJacobian() const {
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(rowCount(), 6 * body_count_);
  for (int c = 0; c < contactCount(); ++c) {
    const ContactData& cd = contacts_[c];
    for (const Side& s : cd.side)
      if (s.body >= 0) J.block(offsets_[c], 6 * s.body, cd.rows, 6) += s.J.topRows(cd.rows);
  }
  return J;
}

Eigen::MatrixXd RigidContactModel::denseInverseMass() const {
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(6 * body_count_, 6 * body_count_);
  for (int b = 0; b < body_count_; ++b) M.block<6, 6>(6 * b, 6 * b) = inverse_mass_[b];
  return M;
}

std::vector<core::Contact> problemContacts(const Scene& scene, const std::vector<SceneContact>& frames) {
  std::vector<core::Contact> contacts(frames.size());
  for (std::size_t c = 0; c < frames.size(); ++c) {
    contacts[c].id = frames[c].id;
    contacts[c].type = frames[c].type;
    contacts[c].rows = frames[c].rows;
    contacts[c].mu = frames[c].mu;
    contacts[c].mu_torsional = frames[c].mu_torsional;
    contacts[c].mu_rolling = frames[c].mu_rolling;
    contacts[c].gap = frames[c].gap();
    contacts[c].erp = scene.params.erp;
    contacts[c].softness = scene.params.softness;
  }
  return contacts;
}

core::Problem buildProblem(const Scene& scene, const std::vector<SceneContact>& frames,
                           const std::vector<Vector6d>& v_free, double dt, ComplianceStorage storage) {
  const RigidContactModel model(scene, frames);
  core::Problem p;
  p.name = scene.name;
  p.contacts = problemContacts(scene, frames);
  if (storage == ComplianceStorage::kBodies) {
    p.bodies = std::make_shared<const core::BodyCompliance>(model.bodyCompliance(dt));
  } else {
    p.W = model.compliance(dt, storage);
  }
  p.d_free = model.freeViolation(v_free, dt);
  return p;
}

}  // namespace scene
}  // namespace lcp_contact_solver
