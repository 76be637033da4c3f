#pragma once
// Frames: placements in the world, spatial velocity and acceleration, and the classical
// acceleration of the frame origin (what a point contact constrains).

#include "solver/multibody/data.hpp"

namespace stride {

// oMf for every frame, from data.oMi (call forwardKinematics first).
void updateFramePlacements(const Model& model, Data& data);
// forwardKinematics(q) then updateFramePlacements.
void framesForwardKinematics(const Model& model, Data& data,
                             const Eigen::Ref<const Eigen::VectorXd>& q);
// Placement of one frame from data.oMi (also stored in data.oMf[frame]).
const SE3& updateFramePlacement(const Model& model, Data& data, int frame);

// Spatial velocity [linear; angular] of a frame, from data.v (forwardKinematics with v).
// Local: frame axes, velocity of the frame origin. LocalWorldAligned: world axes, velocity of the
// origin. World: world axes, velocity of the point at the world origin. Needs data.oMi.
Vector6d getFrameVelocity(const Model& model, const Data& data, int frame, ReferenceFrame rf);
// Spatial acceleration of a frame, from data.v and data.a (forwardKinematics with v, a).
Vector6d getFrameAcceleration(const Model& model, const Data& data, int frame, ReferenceFrame rf);
// Classical acceleration: the second time derivative of the frame origin (linear part),
// a_lin + w x v_lin with the frame's own velocity; the angular part is the angular acceleration.
// Local or LocalWorldAligned axes (World is not meaningful for a point and is rejected).
Vector6d getFrameClassicalAcceleration(const Model& model, const Data& data, int frame,
                                       ReferenceFrame rf);

}  // namespace stride
