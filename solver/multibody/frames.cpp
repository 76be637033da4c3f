#include "solver/multibody/frames.hpp"

#include "solver/multibody/kinematics.hpp"

namespace stride {

namespace {
void checkFrame(const Model& model, int frame, const char* fn) {
  if (frame < 0 || frame >= model.nframes())
    throw std::invalid_argument(std::string(fn) + ": frame index " + std::to_string(frame) +
                                " is out of range");
}

// A motion in the frame's LOCAL coordinates expressed in the requested reference frame.
Vector6d expressLocalMotion(const Vector6d& local, const SE3& oMf, ReferenceFrame rf) {
  switch (rf) {
    case ReferenceFrame::Local:
      return local;
    case ReferenceFrame::LocalWorldAligned: {
      Vector6d r;
      r.head<3>().noalias() = oMf.R * local.head<3>();
      r.tail<3>().noalias() = oMf.R * local.tail<3>();
      return r;
    }
    case ReferenceFrame::World:
      return oMf.act(local);
  }
  return local;
}
}  // namespace

void updateFramePlacements(const Model& model, Data& data) {
  for (int f = 0; f < model.nframes(); ++f) {
    const Frame& fr = model.frames[f];
    data.oMf[f] = data.oMi[fr.parentJoint] * fr.placement;
  }
}

void framesForwardKinematics(const Model& model, Data& data,
                             const Eigen::Ref<const Eigen::VectorXd>& q) {
  forwardKinematics(model, data, q);
  updateFramePlacements(model, data);
}

const SE3& updateFramePlacement(const Model& model, Data& data, int frame) {
  checkFrame(model, frame, "updateFramePlacement");
  const Frame& fr = model.frames[frame];
  data.oMf[frame] = data.oMi[fr.parentJoint] * fr.placement;
  return data.oMf[frame];
}

Vector6d getFrameVelocity(const Model& model, const Data& data, int frame, ReferenceFrame rf) {
  checkFrame(model, frame, "getFrameVelocity");
  const Frame& fr = model.frames[frame];
  const Vector6d local = fr.placement.actInv(data.v[fr.parentJoint]);
  return expressLocalMotion(local, data.oMi[fr.parentJoint] * fr.placement, rf);
}

Vector6d getFrameAcceleration(const Model& model, const Data& data, int frame, ReferenceFrame rf) {
  checkFrame(model, frame, "getFrameAcceleration");
  const Frame& fr = model.frames[frame];
  const Vector6d local = fr.placement.actInv(data.a[fr.parentJoint]);
  return expressLocalMotion(local, data.oMi[fr.parentJoint] * fr.placement, rf);
}

Vector6d getFrameClassicalAcceleration(const Model& model, const Data& data, int frame,
                                       ReferenceFrame rf) {
  checkFrame(model, frame, "getFrameClassicalAcceleration");
  if (rf == ReferenceFrame::World)
    throw std::invalid_argument(
        "getFrameClassicalAcceleration: use Local or LocalWorldAligned (a point has no "
        "world-origin classical acceleration)");
  const Frame& fr = model.frames[frame];
  const Vector6d vf = fr.placement.actInv(data.v[fr.parentJoint]);
  Vector6d af = fr.placement.actInv(data.a[fr.parentJoint]);
  af.head<3>() += vf.tail<3>().cross(vf.head<3>());
  return expressLocalMotion(af, data.oMi[fr.parentJoint] * fr.placement, rf);
}

}  // namespace stride
