#pragma once
// Analytical first-order derivatives of inverse dynamics, ∂τ/∂q and ∂τ/∂v of τ = RNEA(q, v, a)
// (∂τ/∂a = M, from crba). Derivatives with respect to q are in the tangent space: column j is
// d/dε τ(q ⊕ ε e_j, v, a). The method follows Carpentier & Mansard (RSS 2018): everything in the
// world frame, where moving dof j turns its whole subtree by the twist S_j, so each derivative
// becomes a 6-vector dot product along the tree; the derivation is in rnea_derivatives.cpp.

#include "solver/multibody/data.hpp"

namespace stride {

// Fills data.dtau_dq and data.dtau_dv (nv x nv), and data.tau = rnea(q, v, a).
void computeRNEADerivatives(const Model& model, Data& data,
                            const Eigen::Ref<const Eigen::VectorXd>& q,
                            const Eigen::Ref<const Eigen::VectorXd>& v,
                            const Eigen::Ref<const Eigen::VectorXd>& a);

// The same with external forces and a choice of gravity: τ = M a + b - Σ J_i^T f_i, where
// fext[i] is the wrench on joint i's body, in the joint's frame, held fixed in that frame as q
// moves (a contact force expressed in a contact frame). Impulse dynamics uses gravity off.
void computeRNEADerivatives(const Model& model, Data& data,
                            const Eigen::Ref<const Eigen::VectorXd>& q,
                            const Eigen::Ref<const Eigen::VectorXd>& v,
                            const Eigen::Ref<const Eigen::VectorXd>& a,
                            const std::vector<Vector6d>& fext, bool with_gravity);

// The same, without recomputing the kinematics of q: PRECONDITION data.oMi, data.J and
// data.oYbody hold the joint placements, world motion subspaces and world body inertias of the
// configuration to differentiate at, as crba(model, data, q) leaves them (nothing checks it; a
// stale Data gives silently wrong derivatives). Saves the placement sweep (trigonometry, SE3
// products, inertia transforms) when the caller has just run crba for the same q, as contact
// dynamics does. Writes data.tau and the derivative workspaces, but neither oMi, liMi, J nor
// oYbody.
void computeRNEADerivativesFromKinematics(const Model& model, Data& data,
                                          const Eigen::Ref<const Eigen::VectorXd>& v,
                                          const Eigen::Ref<const Eigen::VectorXd>& a,
                                          const std::vector<Vector6d>& fext, bool with_gravity);
// Without external forces, with gravity (as computeRNEADerivatives(q, v, a)); same precondition.
void computeRNEADerivativesFromKinematics(const Model& model, Data& data,
                                          const Eigen::Ref<const Eigen::VectorXd>& v,
                                          const Eigen::Ref<const Eigen::VectorXd>& a);

}  // namespace stride
