#pragma once
// The discrete dynamics of one knot (paper eq. 11): KKT contact dynamics, then semi-implicit
// Euler on the manifold,
//   v̇, λ = contact dynamics(q, v, τ(u)),   v⁺ = v + dt v̇,   q⁺ = q ⊕ dt v⁺,
// so x⁺ = f(x, u) and λ = g(x, u), with the Jacobians Fx, Fu, Gx, Gu in the tangent space
// (dx = [dq; dv], dq in the tangent space of q). Actuation: a floating base is unactuated,
// τ = [0_6; u]; a fixed base is fully actuated, τ = u.

#include "solver/contact/contact_dynamics.hpp"

namespace stride {

// actuatedDimension(model), the size of u: solver/multibody/model.hpp.

struct KnotData {
  KnotData(const Model& model, const ContactSet& contacts);
  int nu;
  Eigen::VectorXd tau;             // τ(u)
  Eigen::VectorXd q_next, v_next;  // x⁺
  Eigen::VectorXd step;            // dt v⁺
  Eigen::MatrixXd Fx, Fu;          // 2nv x 2nv, 2nv x nu
  Eigen::MatrixXd Gx, Gu;          // maxNc x 2nv, maxNc x nu (top nc rows)
  Eigen::MatrixXd Jq, Jv;          // dIntegrate at (q, dt v⁺)
  // v̇ (contact.ddq), λ (contact.lambda), ... After knotDynamicsDerivatives, contact.lambda_dtau
  // holds only its actuated columns (the last nu: the knot skips the rest), and the derivatives of
  // v̇ are only in Fx, Fu: contact.ddq_dq, ddq_dv, ddq_dtau are not written
  // (PrimalDerivatives::Rows).
  ContactData contact;
};

// x⁺ and λ (data in kd); returns the contact dynamics status. Unless Ok, the state is held
// (x⁺ = x), λ is zero and the Jacobians are not updated: the caller must not use them.
ContactStatus knotDynamics(const Model& model, Data& data, const ContactSet& contacts, KnotData& kd,
                           const Eigen::Ref<const Eigen::VectorXd>& q,
                           const Eigen::Ref<const Eigen::VectorXd>& v,
                           const Eigen::Ref<const Eigen::VectorXd>& u, double dt,
                           double damping = 0.0);
// knotDynamics and Fx, Fu, Gx, Gu.
ContactStatus knotDynamicsDerivatives(const Model& model, Data& data, const ContactSet& contacts,
                                      KnotData& kd, const Eigen::Ref<const Eigen::VectorXd>& q,
                                      const Eigen::Ref<const Eigen::VectorXd>& v,
                                      const Eigen::Ref<const Eigen::VectorXd>& u, double dt,
                                      double damping = 0.0);
// Only the Jacobians, for data and kd exactly as knotDynamics (same q, v, u, dt, damping) left
// them: contactDynamicsDerivativesAtSolution's inputs, and kd.step.
void knotDerivativesAtSolution(const Model& model, Data& data, const ContactSet& contacts,
                               KnotData& kd, const Eigen::Ref<const Eigen::VectorXd>& v, double dt);

}  // namespace stride
