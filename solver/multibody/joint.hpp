#pragma once
// Per-joint-type kernels ("jcalc"): the joint's placement relative to its parent for a given q,
// and its motion subspace S (v_J = S qd, constant in the joint frame for all our joint types, so
// the joint bias acceleration c_J is zero). One switch over the joint type, in one place.

#include <cmath>

#include "solver/multibody/model.hpp"

namespace stride {

// Rotation about a unit axis by angle (Rodrigues), cheap for an aligned axis.
inline Eigen::Matrix3d axisRotation(const Joint& j, double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  Eigen::Matrix3d R;
  switch (j.alignedAxis) {
    case 0:
      R << 1, 0, 0, 0, c, -s, 0, s, c;
      return R;
    case 1:
      R << c, 0, s, 0, 1, 0, -s, 0, c;
      return R;
    case 2:
      R << c, -s, 0, s, c, 0, 0, 0, 1;
      return R;
    default: {
      const Eigen::Vector3d& a = j.axis;
      R.noalias() = (1.0 - c) * (a * a.transpose());
      R.diagonal().array() += c;
      R(0, 1) -= s * a.z();
      R(1, 0) += s * a.z();
      R(0, 2) += s * a.y();
      R(2, 0) -= s * a.y();
      R(1, 2) -= s * a.x();
      R(2, 1) += s * a.x();
      return R;
    }
  }
}

// liMi(q) = placement * X_J(q).
inline void jointPlacement(const Joint& j, const double* qj, SE3& liMi) {
  switch (j.type) {
    case JointType::FreeFlyer: {
      const Eigen::Map<const Eigen::Quaterniond> quat(qj + 3);
      liMi.R = quat.toRotationMatrix();
      liMi.p = Eigen::Map<const Eigen::Vector3d>(qj);
      return;  // a free-flyer always hangs from the universe with an identity placement
    }
    case JointType::Revolute: {
      const double c = std::cos(qj[0]), s = std::sin(qj[0]);
      const Eigen::Matrix3d& P = j.placement.R;
      switch (j.alignedAxis) {  // R = P * Rot(axis): only two columns of P mix
        case 0:
          liMi.R.col(0) = P.col(0);
          liMi.R.col(1) = c * P.col(1) + s * P.col(2);
          liMi.R.col(2) = c * P.col(2) - s * P.col(1);
          break;
        case 1:
          liMi.R.col(1) = P.col(1);
          liMi.R.col(0) = c * P.col(0) - s * P.col(2);
          liMi.R.col(2) = s * P.col(0) + c * P.col(2);
          break;
        case 2:
          liMi.R.col(2) = P.col(2);
          liMi.R.col(0) = c * P.col(0) + s * P.col(1);
          liMi.R.col(1) = c * P.col(1) - s * P.col(0);
          break;
        default:
          liMi.R.noalias() = P * axisRotation(j, qj[0]);
      }
      liMi.p = j.placement.p;
      return;
    }
    case JointType::Prismatic:
      liMi.R = j.placement.R;
      liMi.p = j.placement.p + j.placement.R * (j.axis * qj[0]);
      return;
    case JointType::Universe:
      liMi = SE3::Identity();
      return;
  }
}

// Column k of the motion subspace S of joint j, in the joint frame.
inline Vector6d jointSubspaceColumn(const Joint& j, int k) {
  Vector6d s = Vector6d::Zero();
  switch (j.type) {
    case JointType::FreeFlyer:
      s[k] = 1.0;
      break;
    case JointType::Revolute:
      s.tail<3>() = j.axis;
      break;
    case JointType::Prismatic:
      s.head<3>() = j.axis;
      break;
    case JointType::Universe:
      break;
  }
  return s;
}

// The motion subspace of a 1-dof joint in the world frame, oMi.act(S): for an aligned axis the
// rotation axis is a column of R, with no product at all.
inline Vector6d jointSubspaceWorld(const Joint& j, const SE3& oMi) {
  Vector6d s;
  if (j.type == JointType::Revolute) {
    const Eigen::Vector3d w = j.alignedAxis >= 0 ? Eigen::Vector3d(oMi.R.col(j.alignedAxis))
                                                 : Eigen::Vector3d(oMi.R * j.axis);
    s.head<3>() = oMi.p.cross(w);
    s.tail<3>() = w;
  } else {  // prismatic
    s.head<3>().noalias() = oMi.R * j.axis;
    s.tail<3>().setZero();
  }
  return s;
}

// v_J = S * qd_j, in the joint frame.
inline Vector6d jointMotion(const Joint& j, const double* vj) {
  Vector6d m;
  switch (j.type) {
    case JointType::FreeFlyer:
      m = Eigen::Map<const Vector6d>(vj);
      break;
    case JointType::Revolute:
      m << 0, 0, 0, j.axis * vj[0];
      break;
    case JointType::Prismatic:
      m << j.axis * vj[0], 0, 0, 0;
      break;
    default:
      m.setZero();
  }
  return m;
}

// S^T f for a force f in the joint frame, written to tau_j.
inline void jointForceProjection(const Joint& j, const Vector6d& f, double* tau_j) {
  switch (j.type) {
    case JointType::FreeFlyer:
      Eigen::Map<Vector6d>{tau_j} = f;
      break;
    case JointType::Revolute:
      tau_j[0] = j.axis.dot(f.tail<3>());
      break;
    case JointType::Prismatic:
      tau_j[0] = j.axis.dot(f.head<3>());
      break;
    default:
      break;
  }
}

}  // namespace stride
