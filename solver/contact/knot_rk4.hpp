#pragma once
// A fourth-order alternative to the semi-implicit Euler knot (knot_dynamics.hpp): the classical
// Runge-Kutta 4 tableau lifted to the configuration manifold by the Runge-Kutta-Munthe-Kaas
// construction (H. Munthe-Kaas, "High order Runge-Kutta methods on manifolds", Applied Numerical
// Mathematics 29, 1999; RKMK). Why RKMK rather than RK4 on the coordinates: a free-flyer's
// configuration is an element of SE(3), and RK4 applied to (p, quaternion) coordinates leaves the
// group and is not 4th order in the body-frame velocity the dynamics use. RKMK integrates in the
// Lie algebra around the knot's own configuration, q(t) = q ⊕ θ(t), where θ obeys an ordinary
// ODE in a vector space, θ̇ = dexp⁻¹_θ(v), and maps back with the exponential: it stays on the
// group and keeps the order of the tableau.
//
// With τ held over the knot and a(q, v) the KKT contact acceleration of the knot's active
// contacts (contact_dynamics.hpp):
//   θ1 = 0,          v1 = v,              a1 = a(q, v)
//   θ2 = dt/2 k1,    v2 = v + dt/2 a1,    a2 = a(q ⊕ θ2, v2)
//   θ3 = dt/2 k2,    v3 = v + dt/2 a2,    a3 = a(q ⊕ θ3, v3)
//   θ4 = dt k3,      v4 = v + dt a3,      a4 = a(q ⊕ θ4, v4)
//   q⁺ = q ⊕ dt/6 (k1 + 2k2 + 2k3 + k4),  v⁺ = v + dt/6 (a1 + 2a2 + 2a3 + a4),
// k_i = dexp⁻¹_θi(v_i). Our ⊕ multiplies on the right (q ⊕ ξ = M(q) exp(ξ), ξ in the base frame:
// lie_group.hpp), so dexp⁻¹ is the inverse RIGHT Jacobian, Jr⁻¹(θ) v = v + ½ ad_θ v +
// 1/12 ad_θ² v + O(|θ|⁴) (the left-trivialized form of the literature has -½). RKMK needs only
// the terms up to ad² for order 4 (the ad³ coefficient, a Bernoulli number, is zero), and the
// truncated series is a polynomial whose derivative is cheap. It acts only on a free-flyer's 6
// components; revolute and prismatic joints are a vector space, k_i = v_i there.
//
// The knot's forces are stage 1's, λ = g(x, u) at the knot's own state (what the force costs and
// the friction cone constrain), so Gx, Gu are stage 1's force Jacobians, as with Euler. Fx, Fu
// are analytical: forward-mode differentiation through the four stages (each stage's contact
// dynamics derivatives, dIntegrate's Jacobians at θ_i and the derivative of the truncated
// dexp⁻¹), in the tangent space dx = [dq; dv] as every Jacobian of the project.
//
// Stage 1 runs in the caller's Data and Rk4Data::contact, which keep its kinematics and λ at x
// afterwards (the knot's costs read them there); stages 2-4 run in Rk4Data's own Data and
// ContactData. Everything is allocated at construction: the calls do not allocate.

#include "solver/contact/knot_dynamics.hpp"

namespace stride {

struct Rk4Data {
  Rk4Data(const Model& model, const ContactSet& contacts);
  int nu;
  Eigen::VectorXd tau;             // τ(u) = [0; u] (free-flyer) or u
  Eigen::VectorXd q_next, v_next;  // x⁺
  Eigen::VectorXd step;            // dt/6 (k1 + 2k2 + 2k3 + k4): q⁺ = q ⊕ step
  Eigen::MatrixXd Fx, Fu;          // 2nv x 2nv, 2nv x nu
  Eigen::MatrixXd Gx, Gu;          // maxNc x 2nv, maxNc x nu (top nc rows), stage 1's
  // Stage 1 (the knot's state): v̇ (contact.ddq), λ (contact.lambda), ... After
  // knotDynamicsRk4Derivatives, contact.lambda_dtau holds only its actuated columns and the
  // derivatives of v̇ are in contact.rhs3 (PrimalDerivatives::Rows), as with KnotData.
  ContactData contact;

  // ---- Workspace ----
  Data stage_data;            // stages 2-4
  ContactData stage_contact;  // stages 2-4
  Eigen::VectorXd q_stage;    // q ⊕ θ_i
  Eigen::VectorXd v_stage;    // v_i
  Eigen::VectorXd theta;      // θ_i
  Eigen::VectorXd k;          // k_i
  Eigen::VectorXd k_sum;      // Σ w_i k_i (w = 1/6, 2/6, 2/6, 1/6)
  Eigen::VectorXd a_sum;      // Σ w_i a_i
  // Forward-mode tangents, one column per input direction [dq | dv | du] (2nv + nu columns).
  Eigen::MatrixXd W;       // [∂q_i; ∂v_i] of the current stage (∂q_i in the tangent of q_i)
  Eigen::MatrixXd A;       // ∂a_i
  Eigen::MatrixXd SA, SK;  // Σ w_i ∂a_i, Σ w_i ∂k_i
  Matrix6Xd K6, dtheta6;   // a free-flyer's rows of ∂k_i and ∂θ_i
};

// The truncated inverse right Jacobian of SE(3)'s exponential (see above):
// v + ½ ad_θ v + 1/12 ad_θ² v, with ad of θ = (ρ, φ) [[φ×, ρ×], [0, φ×]].
Vector6d dexpInvTruncated(const Vector6d& theta, const Vector6d& v);
// Its Jacobians with respect to θ and v.
void dexpInvTruncatedJacobians(const Vector6d& theta, const Vector6d& v, Matrix6d& d_theta,
                               Matrix6d& d_v);

// x⁺ and λ (stage 1's, in rd.contact and data); returns the first non-Ok status of the four
// stages. Unless Ok, the state is held (x⁺ = x), λ is zero and the Jacobians are not updated, as
// with knotDynamics.
ContactStatus knotDynamicsRk4(const Model& model, Data& data, const ContactSet& contacts,
                              Rk4Data& rd, const Eigen::Ref<const Eigen::VectorXd>& q,
                              const Eigen::Ref<const Eigen::VectorXd>& v,
                              const Eigen::Ref<const Eigen::VectorXd>& u, double dt,
                              double damping = 0.0);
// knotDynamicsRk4 and Fx, Fu, Gx, Gu (one pass: each stage's derivatives follow its solve).
ContactStatus knotDynamicsRk4Derivatives(const Model& model, Data& data, const ContactSet& contacts,
                                         Rk4Data& rd, const Eigen::Ref<const Eigen::VectorXd>& q,
                                         const Eigen::Ref<const Eigen::VectorXd>& v,
                                         const Eigen::Ref<const Eigen::VectorXd>& u, double dt,
                                         double damping = 0.0);

}  // namespace stride
