#include "solver/contact/knot_dynamics.hpp"

#include <cmath>

#include "solver/multibody/lie_group.hpp"

namespace stride {

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
}

ContactStatus knotDynamics(const Model& model, Data& data, const ContactSet& contacts, KnotData& kd,
                           const Eigen::Ref<const Eigen::VectorXd>& q,
                           const Eigen::Ref<const Eigen::VectorXd>& v,
                           const Eigen::Ref<const Eigen::VectorXd>& u, double dt, double damping) {
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
  const ContactStatus status =
      contactDynamics(model, data, contacts, kd.contact, q, v, kd.tau, damping);
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

ContactStatus knotDynamicsDerivatives(const Model& model, Data& data, const ContactSet& contacts,
                                      KnotData& kd, const Eigen::Ref<const Eigen::VectorXd>& q,
                                      const Eigen::Ref<const Eigen::VectorXd>& v,
                                      const Eigen::Ref<const Eigen::VectorXd>& u, double dt,
                                      double damping) {
  const ContactStatus status = knotDynamics(model, data, contacts, kd, q, v, u, dt, damping);
  if (status == ContactStatus::Ok) knotDerivativesAtSolution(model, data, contacts, kd, v, dt);
  return status;
}

void knotDerivativesAtSolution(const Model& model, Data& data, const ContactSet& contacts,
                               KnotData& kd, const Eigen::Ref<const Eigen::VectorXd>& v,
                               double dt) {
  const int nv = model.nv, nu = kd.nu;
  contactDynamicsDerivativesAtSolution(model, data, contacts, kd.contact, v, nv - nu,
                                       PrimalDerivatives::Rows);
  const int nc = kd.contact.nc;
  const ContactData& cd = kd.contact;
  // dIntegrate(q, dt v⁺) without rewriting its identity part (set at construction).
  const int nb = model.hasFreeFlyer() ? 6 : 0;
  if (nb) {
    const Vector6d step6 = kd.step.head<6>();
    kd.Jq.topLeftCorner<6, 6>() = exp6(step6).inverse().toActionMatrix();
    kd.Jv.topLeftCorner<6, 6>() = Jexp6(step6);
  }
  const Matrix6d Jq6 = kd.Jq.topLeftCorner<6, 6>(), Jv6 = kd.Jv.topLeftCorner<6, 6>();
  // Column by column, straight from the rows of the solve with M (cd.rhs3: [∂v̇/∂q | ∂v̇/∂v |
  // ∂v̇/∂u], PrimalDerivatives::Rows), each column of Fx, Fu written once:
  //   velocity rows: v⁺ = v + dt v̇, so dt ∂v̇ (+ I on the v block);
  //   configuration rows: q⁺ = q ⊕ dt v⁺, so ∂q⁺ = Jq dq + Jv dt ∂v⁺, where Jq and Jv are the
  //   identity except a free-flyer's 6 x 6 block: only those rows need a product.
  const double* P = cd.rhs3.data();
  const Eigen::Index ld = cd.rhs3.outerStride();
  for (int j = 0; j < 2 * nv + nu; ++j) {
    double* col = j < 2 * nv ? kd.Fx.col(j).data() : kd.Fu.col(j - 2 * nv).data();
    const double* p = P + j;
    double* vel = col + nv;
    for (int i = 0; i < nv; ++i) vel[i] = dt * p[i * ld];
    if (j >= nv && j < 2 * nv) vel[j - nv] += 1.0;
    for (int i = nb; i < nv; ++i) col[i] = dt * vel[i];
    if (nb) {
      const Vector6d dv6 = dt * Eigen::Map<const Vector6d>(vel);
      Eigen::Map<Vector6d>(col).noalias() = Jv6 * dv6;
    }
    if (j < nb)
      Eigen::Map<Vector6d>(col) += Jq6.col(j);
    else if (j < nv)
      col[j] += 1.0;
  }
  // Forces: λ = g(x, u).
  kd.Gx.topLeftCorner(nc, nv) = cd.lambda_dq.topRows(nc);
  kd.Gx.topRightCorner(nc, nv) = cd.lambda_dv.topRows(nc);
  kd.Gu.topRows(nc) = cd.lambda_dtau.topRows(nc).rightCols(nu);
}

}  // namespace stride
