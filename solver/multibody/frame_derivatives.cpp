#include "solver/multibody/frame_derivatives.hpp"

namespace stride {

namespace {
SE3 framePlacement(const Model& model, const Data& data, int frame) {
  const Frame& f = model.frames[frame];
  return data.oMi[f.parentJoint] * f.placement;
}
}  // namespace

Vector6d frameVelocityFromSweep(const Model& model, const Data& data, int frame) {
  return framePlacement(model, data, frame).actInv(data.ov[model.frames[frame].parentJoint]);
}

Vector6d frameAccelerationFromSweep(const Model& model, const Data& data, int frame) {
  // data.oa[0] holds the gravity term the sweep used; a frame's acceleration excludes it.
  const int i = model.frames[frame].parentJoint;
  return framePlacement(model, data, frame).actInv(data.oa[i] - data.oa[0]);
}

void getFrameAccelerationDerivatives(const Model& model, const Data& data, int frame,
                                     Eigen::Ref<Matrix6Xd> dv_dq, Eigen::Ref<Matrix6Xd> dv_dv,
                                     Eigen::Ref<Matrix6Xd> da_dq, Eigen::Ref<Matrix6Xd> da_dv) {
  if (frame < 0 || frame >= model.nframes())
    throw std::invalid_argument("getFrameAccelerationDerivatives: frame index out of range");
  for (auto* m : {&dv_dq, &dv_dv, &da_dq, &da_dv}) {
    if (m->cols() != model.nv)
      throwSizeError("getFrameAccelerationDerivatives", "output (columns)", model.nv, m->cols());
    m->setZero();
  }
  const int i = model.frames[frame].parentJoint;
  const SE3 Xf = framePlacement(model, data, frame);
  const Vector6d& vi = data.ov[i];
  for (int jj = i; jj > 0; jj = model.joints[jj].parent) {
    const Joint& joint = model.joints[jj];
    const Vector6d& vp = data.ov[joint.parent];
    const Vector6d ap = data.oa[joint.parent] - data.oa[0];
    for (int k = joint.idx_v; k < joint.idx_v + joint.nv; ++k) {
      const Vector6d S = data.J.col(k);
      const Vector6d w = data.dW.col(k);
      dv_dq.col(k) = Xf.actInv(w);
      da_dq.col(k) = Xf.actInv(motionCross(ap, S) + motionCross(w, vi - vp));
      dv_dv.col(k) = Xf.actInv(S);
      da_dv.col(k) = Xf.actInv(motionCross(S, vi) + Vector6d(data.dE.col(k)));
    }
  }
}

}  // namespace stride
