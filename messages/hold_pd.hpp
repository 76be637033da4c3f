#pragma once
// The standing hold: the one joint PD law of Stride, written once (issue 43).
//
//   τ_i = u_i + kp_i (q_ref_i − q_i) − kd_i v_i     on each actuated joint i (1 dof),
//
// the floating base unactuated. Two programs hold a robot with it, each in its own form:
// - the mock robot applies it directly (sim::HoldPolicy before the first policy, sim::StandDown
//   when its controller is lost): jointPd();
// - the controller sends it as a policy (its Hold fallback, PolicyWriter::hold):
//   x_ref = (q_ref, 0), u_ff = u and K diagonal on the joints, which the robot's policy evaluation
//   (policy_interpolation.hpp: u_ff + K (x_ref ⊖ x)) turns into the same law: writeJointPdRow().
// Header-only and free of the model: the controller's configuration takes its default gains from
// here without linking anything.

#include <algorithm>

namespace stride::msg {

// The default hold gains [N m/rad, N m s/rad], for a robot whose configuration gives none: the
// mock robot's when the robot YAML has no `joint_pd`, the controller's when its YAML has no
// `safety.hold_kp/hold_kd`. One pair: the controller's default damping was 0.2 and the robot's 0.1
// with no reason given for the difference; every shipped controller YAML sets its own gains (the
// quadrupeds' 5 and 0.1), so only a configuration without them sees the default.
constexpr double kDefaultHoldKp = 5.0;
constexpr double kDefaultHoldKd = 0.1;

// The law on one joint: the feed-forward u plus the torque that pulls q to q_ref and damps v.
inline double jointPd(double u, double kp, double kd, double q_ref, double q, double v) {
  return u + kp * (q_ref - q) - kd * v;
}

// The same law as row i of a policy knot's K (nu × 2nv, row-major on the wire; `row` holds its
// 2nv entries): kp on joint i's configuration error, kd on its velocity error, nothing else. With
// x_ref = (q_ref, 0), u_ff + K (x_ref ⊖ x) is then jointPd(u_ff_i, kp, kd, q_ref, q, v) on that
// joint. joint_v: the joint's velocity index (its actuated index plus 6 for a floating base).
inline void writeJointPdRow(double* row, int nv, int joint_v, double kp, double kd) {
  std::fill(row, row + 2 * nv, 0.0);
  row[joint_v] = kp;
  row[nv + joint_v] = kd;
}

}  // namespace stride::msg
