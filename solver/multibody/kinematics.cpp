#include "solver/multibody/kinematics.hpp"

#include "solver/multibody/joint.hpp"

namespace stride {

void forwardKinematics(const Model& model, Data& data, const Eigen::Ref<const Eigen::VectorXd>& q) {
  model.checkConfiguration(q, "forwardKinematics");
  for (int i = 1; i < model.njoints(); ++i) {
    const Joint& j = model.joints[i];
    jointPlacement(j, q.data() + j.idx_q, data.liMi[i]);
    data.oMi[i] = data.oMi[j.parent] * data.liMi[i];
  }
}

void forwardKinematics(const Model& model, Data& data, const Eigen::Ref<const Eigen::VectorXd>& q,
                       const Eigen::Ref<const Eigen::VectorXd>& v) {
  model.checkConfiguration(q, "forwardKinematics");
  model.checkVelocity(v, "forwardKinematics");
  data.v[0].setZero();
  for (int i = 1; i < model.njoints(); ++i) {
    const Joint& j = model.joints[i];
    jointPlacement(j, q.data() + j.idx_q, data.liMi[i]);
    data.oMi[i] = data.oMi[j.parent] * data.liMi[i];
    data.v[i] = data.liMi[i].actInv(data.v[j.parent]) + jointMotion(j, v.data() + j.idx_v);
  }
}

void forwardKinematics(const Model& model, Data& data, const Eigen::Ref<const Eigen::VectorXd>& q,
                       const Eigen::Ref<const Eigen::VectorXd>& v,
                       const Eigen::Ref<const Eigen::VectorXd>& a) {
  model.checkConfiguration(q, "forwardKinematics");
  model.checkVelocity(v, "forwardKinematics");
  if (a.size() != model.nv) throwSizeError("forwardKinematics", "a", model.nv, a.size());
  data.v[0].setZero();
  data.a[0].setZero();
  for (int i = 1; i < model.njoints(); ++i) {
    const Joint& j = model.joints[i];
    jointPlacement(j, q.data() + j.idx_q, data.liMi[i]);
    data.oMi[i] = data.oMi[j.parent] * data.liMi[i];
    const Vector6d vJ = jointMotion(j, v.data() + j.idx_v);
    data.v[i] = data.liMi[i].actInv(data.v[j.parent]) + vJ;
    // a_i = X a_parent + S qdd + v_i x v_J (S is constant in the joint frame).
    data.a[i] = data.liMi[i].actInv(data.a[j.parent]) + jointMotion(j, a.data() + j.idx_v) +
                motionCross(data.v[i], vJ);
  }
}

}  // namespace stride
