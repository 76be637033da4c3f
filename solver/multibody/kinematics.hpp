#pragma once
// Forward kinematics: joint placements (liMi, oMi), and with v and a the joint spatial velocities
// and accelerations in the joint frames (data.v, data.a; gravity not included).

#include "solver/multibody/data.hpp"

namespace stride {

void forwardKinematics(const Model& model, Data& data, const Eigen::Ref<const Eigen::VectorXd>& q);
void forwardKinematics(const Model& model, Data& data, const Eigen::Ref<const Eigen::VectorXd>& q,
                       const Eigen::Ref<const Eigen::VectorXd>& v);
void forwardKinematics(const Model& model, Data& data, const Eigen::Ref<const Eigen::VectorXd>& q,
                       const Eigen::Ref<const Eigen::VectorXd>& v,
                       const Eigen::Ref<const Eigen::VectorXd>& a);

}  // namespace stride
