#include "solver/contact/knot_dynamics.hpp"

#include <cmath>

#include "solver/multibody/lie_group.hpp"

namespace stride {

int actuatedDimension(const Model& model) {
  return model.hasFreeFlyer() ? model.nv - 6 : model.nv;
}

KnotData::KnotData(const Model& model, const ContactSet& contacts)
    : nu(actuatedDimension(model)), contact(model, contacts) {
  const int nv = model.nv, m = contacts.maxNc();
  tau = Eigen::VectorXd::Zero(nv);
  q_next = Eigen::VectorXd::Zero(model.nq);
  v_next = step = Eigen::VectorXd::Zero(nv);
  Fx = Eigen::MatrixXd::Zero(2 * nv, 2 * nv);
  Fu = Eigen::MatrixXd::Zero(2 * nv, nu);
  Gx = Eigen::MatrixXd::Zero(m, 2 * nv);
  Gu = Eigen::MatrixXd::Zero(m, nu);
  // dIntegrate is the identity but for a free-flyer's 6 x 6 block: only that block is updated.
  Jq = Jv = Eigen::MatrixXd::Identity(nv, nv);
  rows6 = Matrix6Xd::Zero(6, nv);
}

namespace {
ContactStatus step(const Model& model, Data& data, const ContactSet& contacts, KnotData& kd,
                   const Eigen::Ref<const Eigen::VectorXd>& q,
                   const Eigen::Ref<const Eigen::VectorXd>& v,
                   const Eigen::Ref<const Eigen::VectorXd>& u, double dt, double damping,
                   bool derivatives) {
  if (u.size() != kd.nu) throwSizeError("knotDynamics", "u", kd.nu, u.size());
  if (!std::isfinite(dt) || !u.allFinite()) {
    kd.q_next = q;
    kd.v_next = v;
    kd.contact.lambda.setZero();
    return ContactStatus::NonFinite;
  }
  const int off = model.nv - kd.nu;
  kd.tau.head(off).setZero();
  kd.tau.tail(kd.nu) = u;
  ContactStatus status =
      derivatives ? contactDynamicsDerivatives(model, data, contacts, kd.contact, q, v, kd.tau,
                                               damping, off)
                  : contactDynamics(model, data, contacts, kd.contact, q, v, kd.tau, damping);
  if (status != ContactStatus::Ok) {
    kd.q_next = q;
    kd.v_next = v;
    return status;
  }
  kd.v_next = v + dt * kd.contact.ddq;
  // Through a stored vector: an expression bound to a Ref<const VectorXd> would be evaluated
  // into a heap temporary.
  kd.step = dt * kd.v_next;
  integrate(model, q, kd.step, kd.q_next);
  return status;
}
}  // namespace

ContactStatus knotDynamics(const Model& model, Data& data, const ContactSet& contacts, KnotData& kd,
                           const Eigen::Ref<const Eigen::VectorXd>& q,
                           const Eigen::Ref<const Eigen::VectorXd>& v,
                           const Eigen::Ref<const Eigen::VectorXd>& u, double dt, double damping) {
  return step(model, data, contacts, kd, q, v, u, dt, damping, false);
}

ContactStatus knotDynamicsDerivatives(const Model& model, Data& data, const ContactSet& contacts,
                                      KnotData& kd, const Eigen::Ref<const Eigen::VectorXd>& q,
                                      const Eigen::Ref<const Eigen::VectorXd>& v,
                                      const Eigen::Ref<const Eigen::VectorXd>& u, double dt,
                                      double damping) {
  const ContactStatus status = step(model, data, contacts, kd, q, v, u, dt, damping, true);
  if (status != ContactStatus::Ok) return status;
  const int nv = model.nv, nu = kd.nu, nc = kd.contact.nc;
  const ContactData& cd = kd.contact;
  // Velocity rows: v⁺ = v + dt v̇.
  auto dvq = kd.Fx.bottomLeftCorner(nv, nv);
  auto dvv = kd.Fx.bottomRightCorner(nv, nv);
  auto dvu = kd.Fu.bottomRows(nv);
  dvq = dt * cd.ddq_dq;
  dvv = dt * cd.ddq_dv;
  dvv.diagonal().array() += 1.0;
  dvu = dt * cd.ddq_dtau.rightCols(nu);
  // Configuration rows: q⁺ = q ⊕ dt v⁺, so ∂q⁺ = Jq dq + Jv dt ∂v⁺. Jq and Jv are the identity
  // except for a free-flyer's 6 x 6 block, so only those rows need a product.
  // dIntegrate(q, dt v⁺) without rewriting its identity part (set at construction).
  if (model.hasFreeFlyer()) {
    const Vector6d step6 = kd.step.head<6>();
    kd.Jq.topLeftCorner<6, 6>() = exp6(step6).inverse().toActionMatrix();
    kd.Jv.topLeftCorner<6, 6>() = Jexp6(step6);
  }
  auto dqq = kd.Fx.topLeftCorner(nv, nv);
  auto dqv = kd.Fx.topRightCorner(nv, nv);
  auto dqu = kd.Fu.topRows(nv);
  dqq = dt * dvq;
  dqv = dt * dvv;
  dqu = dt * dvu;
  if (model.hasFreeFlyer()) {
    const Matrix6d Jv6 = kd.Jv.topLeftCorner<6, 6>();
    // Through a preallocated 6-row workspace: the in-place product would need a heap temporary.
    for (auto block : {dqq, dqv, dqu}) {
      kd.rows6.leftCols(block.cols()).noalias() = Jv6 * block.topRows<6>();
      block.topRows<6>() = kd.rows6.leftCols(block.cols());
    }
    dqq.topLeftCorner<6, 6>() += kd.Jq.topLeftCorner<6, 6>();
    dqq.bottomRightCorner(nv - 6, nv - 6).diagonal().array() += 1.0;
  } else {
    dqq.diagonal().array() += 1.0;
  }
  // Forces: λ = g(x, u).
  kd.Gx.topLeftCorner(nc, nv) = cd.lambda_dq.topRows(nc);
  kd.Gx.topRightCorner(nc, nv) = cd.lambda_dv.topRows(nc);
  kd.Gu.topRows(nc) = cd.lambda_dtau.topRows(nc).rightCols(nu);
  return status;
}

}  // namespace stride
