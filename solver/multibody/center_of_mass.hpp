#pragma once
// Centre of mass of the moving bodies, its velocity and its Jacobian.

#include "solver/multibody/data.hpp"

namespace stride {

// com(q) in the world frame (data.com). Also runs forward kinematics.
const Eigen::Vector3d& centerOfMass(const Model& model, Data& data,
                                    const Eigen::Ref<const Eigen::VectorXd>& q);
// com(q) and its velocity (data.vcom).
const Eigen::Vector3d& centerOfMass(const Model& model, Data& data,
                                    const Eigen::Ref<const Eigen::VectorXd>& q,
                                    const Eigen::Ref<const Eigen::VectorXd>& v);
// d com / dq in the tangent space (3 x nv, data.Jcom); also sets data.com.
const Eigen::Matrix3Xd& jacobianCenterOfMass(const Model& model, Data& data,
                                             const Eigen::Ref<const Eigen::VectorXd>& q);

}  // namespace stride
