#include "solver/multibody/jacobian.hpp"

#include "solver/multibody/joint.hpp"
#include "solver/multibody/kinematics.hpp"

namespace stride {

const Matrix6Xd& updateJointJacobians(const Model& model, Data& data) {
  for (int i = 1; i < model.njoints(); ++i) {
    const Joint& j = model.joints[i];
    const SE3& oMi = data.oMi[i];
    if (j.type == JointType::FreeFlyer) {
      data.J.middleCols<6>(j.idx_v) = oMi.toActionMatrix();
    } else {
      data.J.col(j.idx_v) = jointSubspaceWorld(j, oMi);
    }
  }
  return data.J;
}

const Matrix6Xd& computeJointJacobians(const Model& model, Data& data,
                                       const Eigen::Ref<const Eigen::VectorXd>& q) {
  forwardKinematics(model, data, q);
  return updateJointJacobians(model, data);
}

namespace {
// Fill J with the world columns of the dofs supporting `joint`, expressed at placement oMf.
void supportedColumns(const Model& model, const Data& data, int joint, const SE3& oMf,
                      ReferenceFrame rf, Eigen::Ref<Matrix6Xd> J) {
  J.setZero();
  if (joint == 0) return;
  const Joint& jt = model.joints[joint];
  for (int k = jt.idx_v + jt.nv - 1; k >= 0; k = model.parentDof[k]) {
    const Vector6d col = data.J.col(k);
    switch (rf) {
      case ReferenceFrame::World:
        J.col(k) = col;
        break;
      case ReferenceFrame::Local:
        J.col(k) = oMf.actInv(col);
        break;
      case ReferenceFrame::LocalWorldAligned:
        // Velocity of the frame origin: nu_o + w x p.
        J.col(k).head<3>() = col.head<3>() - oMf.p.cross(col.tail<3>());
        J.col(k).tail<3>() = col.tail<3>();
        break;
    }
  }
}

void checkJacobianOut(const Model& model, const Eigen::Ref<Matrix6Xd>& J, const char* fn) {
  if (J.cols() != model.nv) throwSizeError(fn, "J (columns)", model.nv, J.cols());
}
}  // namespace

void getJointJacobian(const Model& model, const Data& data, int joint, ReferenceFrame rf,
                      Eigen::Ref<Matrix6Xd> J) {
  if (joint < 0 || joint >= model.njoints())
    throw std::invalid_argument("getJointJacobian: joint index out of range");
  checkJacobianOut(model, J, "getJointJacobian");
  supportedColumns(model, data, joint, data.oMi[joint], rf, J);
}

void getFrameJacobian(const Model& model, const Data& data, int frame, ReferenceFrame rf,
                      Eigen::Ref<Matrix6Xd> J) {
  if (frame < 0 || frame >= model.nframes())
    throw std::invalid_argument("getFrameJacobian: frame index out of range");
  checkJacobianOut(model, J, "getFrameJacobian");
  const Frame& fr = model.frames[frame];
  supportedColumns(model, data, fr.parentJoint, data.oMi[fr.parentJoint] * fr.placement, rf, J);
}

}  // namespace stride
