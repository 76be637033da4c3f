#include "solver/contact/knot_rk4.hpp"

#include <cmath>

#include "solver/multibody/lie_group.hpp"

namespace stride {

namespace {

// The RK4 tableau: stage i is evaluated at θ_i = c_i dt k_{i-1}, v_i = v + c_i dt a_{i-1}, and
// enters the step with weight w_i.
constexpr double kC[4] = {0.0, 0.5, 0.5, 1.0};
constexpr double kW[4] = {1.0 / 6.0, 2.0 / 6.0, 2.0 / 6.0, 1.0 / 6.0};

// ad_x as a matrix, x = (ρ, φ): ad_x y = motionCross(x, y).
Matrix6d adMatrix(const Vector6d& x) {
  Matrix6d X;
  X.topLeftCorner<3, 3>() = skew(x.tail<3>());
  X.topRightCorner<3, 3>() = skew(x.head<3>());
  X.bottomLeftCorner<3, 3>().setZero();
  X.bottomRightCorner<3, 3>() = X.topLeftCorner<3, 3>();
  return X;
}

// The state is held and λ zeroed on any failure, as knotDynamics does: stage 1's λ is the knot's
// force output, and a failed later stage leaves no usable step.
ContactStatus hold(Rk4Data& rd, const Eigen::Ref<const Eigen::VectorXd>& q,
                   const Eigen::Ref<const Eigen::VectorXd>& v, ContactStatus status) {
  rd.q_next = q;
  rd.v_next = v;
  rd.contact.lambda.setZero();
  return status;
}

ContactStatus run(const Model& model, Data& data, const ContactSet& contacts, Rk4Data& rd,
                  const Eigen::Ref<const Eigen::VectorXd>& q,
                  const Eigen::Ref<const Eigen::VectorXd>& v,
                  const Eigen::Ref<const Eigen::VectorXd>& u, double dt, double damping,
                  bool derivatives) {
  if (u.size() != rd.nu) throwSizeError("knotDynamicsRk4", "u", rd.nu, u.size());
  if (!std::isfinite(dt) || !u.allFinite()) return hold(rd, q, v, ContactStatus::NonFinite);
  const int nv = model.nv, nu = rd.nu, tau_first = nv - nu, ncol = 2 * nv + nu;
  const int nb = model.hasFreeFlyer() ? 6 : 0, nj = nv - nb;
  rd.tau.head(tau_first).setZero();
  rd.tau.tail(nu) = u;

  Matrix6d Dtheta, Dv;
  for (int i = 0; i < 4; ++i) {
    // Stage 1 at the knot's own state, in the caller's workspaces; the others in ours.
    Data& d = i == 0 ? data : rd.stage_data;
    ContactData& cd = i == 0 ? rd.contact : rd.stage_contact;
    using ConstRef = Eigen::Ref<const Eigen::VectorXd>;
    const ConstRef qi = i == 0 ? q : ConstRef(rd.q_stage);
    const ConstRef vi = i == 0 ? v : ConstRef(rd.v_stage);
    const ContactStatus status =
        derivatives ? contactDynamicsDerivatives(model, d, contacts, cd, qi, vi, rd.tau, damping,
                                                 tau_first, PrimalDerivatives::Rows)
                    : contactDynamics(model, d, contacts, cd, qi, vi, rd.tau, damping);
    if (status != ContactStatus::Ok) return hold(rd, q, v, status);

    // k_i = dexp⁻¹_θi(v_i): v_i itself on the vector-space joints (and at θ1 = 0).
    rd.k = vi;
    if (nb && i > 0) rd.k.head<6>() = dexpInvTruncated(rd.theta.head<6>(), vi.head<6>());
    if (i == 0) {
      rd.k_sum = kW[0] * rd.k;
      rd.a_sum = kW[0] * cd.ddq;
    } else {
      rd.k_sum += kW[i] * rd.k;
      rd.a_sum += kW[i] * cd.ddq;
    }

    if (derivatives) {
      // ∂a_i = [a_q a_v] [∂q_i; ∂v_i] + [0 0 a_u], the stage's Jacobians read from the rows the
      // solve with M left in rhs3 ([∂v̇/∂q | ∂v̇/∂v | ∂v̇/∂u]).
      if (i == 0) {
        // ∂q_1 = [I 0 0], ∂v_1 = [0 I 0]: the stage's own Jacobians.
        rd.W.setIdentity();
        rd.A = cd.rhs3.leftCols(ncol);
      } else {
        rd.A.noalias() = cd.rhs3.leftCols(2 * nv) * rd.W;
        rd.A.rightCols(nu) += cd.rhs3.middleCols(2 * nv, nu);
      }
      // ∂k_i: the free-flyer rows through the truncated dexp⁻¹ (θ1 ≡ 0: ∂k_1 = ∂v_1 there),
      // the joint rows are ∂v_i's.
      if (nb) {
        if (i == 0) {
          rd.K6 = rd.W.middleRows<6>(nv);
        } else {
          dexpInvTruncatedJacobians(rd.theta.head<6>(), vi.head<6>(), Dtheta, Dv);
          rd.K6.noalias() = Dtheta * rd.dtheta6;
          rd.K6.noalias() += Dv * rd.W.middleRows<6>(nv);
        }
      }
      if (i == 0) {
        rd.SA = kW[0] * rd.A;
        if (nb) rd.SK.topRows<6>() = kW[0] * rd.K6;
        rd.SK.bottomRows(nj) = kW[0] * rd.W.bottomRows(nj);
      } else {
        rd.SA += kW[i] * rd.A;
        if (nb) rd.SK.topRows<6>() += kW[i] * rd.K6;
        rd.SK.bottomRows(nj) += kW[i] * rd.W.bottomRows(nj);
      }
    }

    if (i == 3) break;
    // The next stage's point: θ = c dt k_i, v = v + c dt a_i, q ⊕ θ.
    const double h = kC[i + 1] * dt;
    rd.theta = h * rd.k;
    rd.v_stage = v + h * cd.ddq;
    integrate(model, q, rd.theta, rd.q_stage);
    if (derivatives) {
      // ∂q_{i+1} = dIntegrate_q(q, θ) [I 0 0] + dIntegrate_θ(q, θ) h ∂k_i: the identity on the
      // joints, exp(θ)⁻¹'s adjoint and the right Jacobian on a free-flyer's block. The joint rows
      // of ∂k_i are ∂v_i's, still in W's lower half: the configuration rows are written first.
      rd.W.middleRows(nb, nj) = h * rd.W.bottomRows(nj);
      for (int j = nb; j < nv; ++j) rd.W(j, j) += 1.0;
      if (nb) {
        const Vector6d theta6 = rd.theta.head<6>();
        rd.dtheta6 = h * rd.K6;
        rd.W.topRows<6>().noalias() = Jexp6(theta6) * rd.dtheta6;
        rd.W.topLeftCorner<6, 6>() += exp6(theta6).inverse().toActionMatrix();
      }
      // ∂v_{i+1} = [0 I 0] + h ∂a_i.
      rd.W.bottomRows(nv) = h * rd.A;
      for (int j = 0; j < nv; ++j) rd.W(nv + j, nv + j) += 1.0;
    }
  }

  // Through stored vectors: an expression bound to a Ref<const VectorXd> would be evaluated into
  // a heap temporary.
  rd.step = dt * rd.k_sum;
  integrate(model, q, rd.step, rd.q_next);
  rd.v_next = v + dt * rd.a_sum;
  if (!derivatives) return ContactStatus::Ok;

  // x⁺'s Jacobians: v⁺ = v + dt Σ w a_i, q⁺ = q ⊕ dt Σ w k_i (dIntegrate at the step, as above).
  rd.Fx.bottomRows(nv) = dt * rd.SA.leftCols(2 * nv);
  rd.Fu.bottomRows(nv) = dt * rd.SA.rightCols(nu);
  for (int j = 0; j < nv; ++j) rd.Fx(nv + j, nv + j) += 1.0;
  rd.Fx.middleRows(nb, nj) = dt * rd.SK.bottomRows(nj).leftCols(2 * nv);
  rd.Fu.middleRows(nb, nj) = dt * rd.SK.bottomRows(nj).rightCols(nu);
  for (int j = nb; j < nv; ++j) rd.Fx(j, j) += 1.0;
  if (nb) {
    const Vector6d step6 = rd.step.head<6>();
    const Matrix6d Jv6 = dt * Jexp6(step6);
    rd.Fx.topRows<6>().noalias() = Jv6 * rd.SK.topRows<6>().leftCols(2 * nv);
    rd.Fu.topRows<6>().noalias() = Jv6 * rd.SK.topRows<6>().rightCols(nu);
    rd.Fx.topLeftCorner<6, 6>() += exp6(step6).inverse().toActionMatrix();
  }
  // Forces: stage 1's λ = g(x, u).
  const ContactData& cd = rd.contact;
  const int nc = cd.nc;
  rd.Gx.topLeftCorner(nc, nv) = cd.lambda_dq.topRows(nc);
  rd.Gx.topRightCorner(nc, nv) = cd.lambda_dv.topRows(nc);
  rd.Gu.topRows(nc) = cd.lambda_dtau.topRows(nc).rightCols(nu);
  return ContactStatus::Ok;
}

}  // namespace

Rk4Data::Rk4Data(const Model& model, const ContactSet& contacts)
    : nu(actuatedDimension(model)),
      contact(model, contacts),
      stage_data(model),
      stage_contact(model, contacts) {
  const int nv = model.nv, m = contacts.maxNc(), ncol = 2 * nv + nu;
  tau = Eigen::VectorXd::Zero(nv);
  q_next = q_stage = Eigen::VectorXd::Zero(model.nq);
  v_next = step = v_stage = theta = k = k_sum = a_sum = Eigen::VectorXd::Zero(nv);
  Fx = Eigen::MatrixXd::Zero(2 * nv, 2 * nv);
  Fu = Eigen::MatrixXd::Zero(2 * nv, nu);
  Gx = Eigen::MatrixXd::Zero(m, 2 * nv);
  Gu = Eigen::MatrixXd::Zero(m, nu);
  W = Eigen::MatrixXd::Zero(2 * nv, ncol);
  A = SA = SK = Eigen::MatrixXd::Zero(nv, ncol);
  K6 = dtheta6 = Matrix6Xd::Zero(6, ncol);
}

Vector6d dexpInvTruncated(const Vector6d& theta, const Vector6d& v) {
  const Vector6d ad = motionCross(theta, v);
  return v + 0.5 * ad + (1.0 / 12.0) * motionCross(theta, ad);
}

void dexpInvTruncatedJacobians(const Vector6d& theta, const Vector6d& v, Matrix6d& d_theta,
                               Matrix6d& d_v) {
  // k = v + ½ ad_θ v + 1/12 ad_θ ad_θ v and ad_θ v = -ad_v θ, so
  //   ∂k/∂θ = -½ ad_v - 1/12 (ad_{ad_θ v} + ad_θ ad_v),   ∂k/∂v = I + ½ ad_θ + 1/12 ad_θ².
  const Matrix6d ad_theta = adMatrix(theta), ad_v = adMatrix(v);
  const Matrix6d ad_ad = adMatrix(motionCross(theta, v));
  d_theta.noalias() = -0.5 * ad_v - (1.0 / 12.0) * ad_ad;
  d_theta.noalias() -= (1.0 / 12.0) * ad_theta * ad_v;
  d_v.setIdentity();
  d_v += 0.5 * ad_theta;
  d_v.noalias() += (1.0 / 12.0) * ad_theta * ad_theta;
}

ContactStatus knotDynamicsRk4(const Model& model, Data& data, const ContactSet& contacts,
                              Rk4Data& rd, const Eigen::Ref<const Eigen::VectorXd>& q,
                              const Eigen::Ref<const Eigen::VectorXd>& v,
                              const Eigen::Ref<const Eigen::VectorXd>& u, double dt,
                              double damping) {
  return run(model, data, contacts, rd, q, v, u, dt, damping, false);
}

ContactStatus knotDynamicsRk4Derivatives(const Model& model, Data& data, const ContactSet& contacts,
                                         Rk4Data& rd, const Eigen::Ref<const Eigen::VectorXd>& q,
                                         const Eigen::Ref<const Eigen::VectorXd>& v,
                                         const Eigen::Ref<const Eigen::VectorXd>& u, double dt,
                                         double damping) {
  return run(model, data, contacts, rd, q, v, u, dt, damping, true);
}

}  // namespace stride
