#pragma once
// Jacobians. computeJointJacobians fills data.J, the motion subspace of every dof in the world
// frame (6 x nv); a joint's or frame's Jacobian is then read from the columns of the dofs that
// support it, expressed in the requested frame. Rows are [linear; angular].

#include "solver/multibody/data.hpp"

namespace stride {

// Forward kinematics (placements) and data.J.
const Matrix6Xd& computeJointJacobians(const Model& model, Data& data,
                                       const Eigen::Ref<const Eigen::VectorXd>& q);
// data.J from data.oMi (forward kinematics already done).
const Matrix6Xd& updateJointJacobians(const Model& model, Data& data);

// 6 x nv Jacobian of a joint's frame / of a frame, from data.J and data.oMi
// (computeJointJacobians first). Columns of dofs that do not support it are zero.
void getJointJacobian(const Model& model, const Data& data, int joint, ReferenceFrame rf,
                      Eigen::Ref<Matrix6Xd> J);
void getFrameJacobian(const Model& model, const Data& data, int frame, ReferenceFrame rf,
                      Eigen::Ref<Matrix6Xd> J);

}  // namespace stride
