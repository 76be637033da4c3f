#pragma once
// Derivatives of a frame's spatial velocity and acceleration (LOCAL) with respect to q (tangent),
// v and a, read from the world-frame sweep of computeRNEADerivatives(q, v, a) (which must run
// first, with the same q, v, a). Moving dof j turns its subtree by S_j, so in the frame's own
// coordinates only the relative terms remain (see rnea_derivatives.cpp):
//   ∂v_f/∂q_j = X_f^-1 w_j,   ∂a_f/∂q_j = X_f^-1 (u_j + w_j x (v_i - v_λ)),
//   ∂v_f/∂v_j = ∂a_f/∂a_j = X_f^-1 S_j,   ∂a_f/∂v_j = X_f^-1 (S_j x v_i + e_j),
// with w_j = v_λ x S_j, u_j = a_λ x S_j (no gravity), e_j = (v_λ + v_J) x S_j, where v_J is
// the spatial velocity of the body of j's own joint (not the joint rate S_j q̇_j).
// The derivative of the placement with respect to q is the LOCAL frame Jacobian.

#include "solver/multibody/data.hpp"

namespace stride {

// 6 x nv outputs; columns of dofs not supporting the frame are zero. da_da equals dv_dv.
void getFrameAccelerationDerivatives(const Model& model, const Data& data, int frame,
                                     Eigen::Ref<Matrix6Xd> dv_dq, Eigen::Ref<Matrix6Xd> dv_dv,
                                     Eigen::Ref<Matrix6Xd> da_dq, Eigen::Ref<Matrix6Xd> da_dv);

// The frame's LOCAL velocity and acceleration at the sweep's (q, v, a).
Vector6d frameVelocityFromSweep(const Model& model, const Data& data, int frame);
Vector6d frameAccelerationFromSweep(const Model& model, const Data& data, int frame);

}  // namespace stride
