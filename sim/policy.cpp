#include "sim/policy.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/Cholesky>

#include "messages/hold_pd.hpp"
#include "solver/multibody/center_of_mass.hpp"
#include "solver/multibody/crba.hpp"
#include "solver/multibody/frames.hpp"
#include "solver/multibody/jacobian.hpp"

namespace stride::sim {

HoldPolicy::HoldPolicy(const Model& model, const Eigen::VectorXd& q_ref_, double kp_, double kd_,
                       double step_dt)
    : q_ref(q_ref_) {
  model.checkConfiguration(q_ref, "q_ref");
  const int first = model.hasFreeFlyer() ? 6 : 0;
  const int nu = model.nv - first;
  kp = Eigen::VectorXd::Constant(nu, kp_);
  kd = Eigen::VectorXd::Constant(nu, kd_);
  if (step_dt > 0.0) {
    // The inertia a joint's PD drives when every other joint (and the base) moves freely:
    // 1 / (M⁻¹)_ii, smaller than M_ii wherever links couple (an elbow swinging with its shoulder).
    Data data(model);
    const Eigen::MatrixXd Minv =
        crba(model, data, q_ref).llt().solve(Eigen::MatrixXd::Identity(model.nv, model.nv));
    for (int i = 0; i < nu; ++i) {
      const double m = 1.0 / Minv(first + i, first + i);
      kd[i] = std::min(kd[i], 0.5 * m / step_dt);
      kp[i] = std::min(kp[i], 0.25 * m / (step_dt * step_dt));
    }
  }
}

void HoldPolicy::torque(const Model& model, const Eigen::Ref<const Eigen::VectorXd>& q,
                        const Eigen::Ref<const Eigen::VectorXd>& v,
                        Eigen::Ref<Eigen::VectorXd> tau) const {
  const int first = model.hasFreeFlyer() ? 6 : 0;
  for (int j = 1; j < model.njoints(); ++j) {
    const Joint& jt = model.joints[j];
    if (jt.type == JointType::FreeFlyer) continue;
    // 1-dof joints: one configuration and one velocity entry.
    const int i = jt.idx_v - first;
    tau[i] = msg::jointPd(0.0, kp[i], kd[i], q_ref[jt.idx_q], q[jt.idx_q], v[jt.idx_v]);
  }
}

StandDown::StandDown(const Model& model, const HoldPolicy& hold,
                     const std::vector<StandDownContact>& contacts, const StandDownOptions& options)
    : model_(model),
      hold_(hold),
      options_(options),
      in_leg_(hold.kp.size(), 0),
      data_(model),
      dv_(Eigen::VectorXd::Zero(model.nv)),
      q_start_(hold.q_ref),
      u_start_(Eigen::VectorXd::Zero(hold.kp.size())) {
  if (!model.hasFreeFlyer()) return;  // a fixed base has nothing to level: default posture only
  const int first = 6;
  // How many contacts each actuated joint moves: a leg is the joints that move one contact only.
  std::vector<int> users(hold.kp.size(), 0);
  std::vector<std::vector<int>> chains(contacts.size());
  for (std::size_t c = 0; c < contacts.size(); ++c)
    for (int j = model.frames.at(contacts[c].frame).parentJoint; j > 0; j = model.joints[j].parent)
      if (model.joints[j].type != JointType::FreeFlyer) {
        chains[c].push_back(j);
        ++users[model.joints[j].idx_v - first];
      }
  framesForwardKinematics(model, data_, hold.q_ref);
  const SE3 base = data_.oMi[freeFlyerJoint()];
  for (std::size_t c = 0; c < contacts.size(); ++c) {
    Leg leg;
    leg.frame = contacts[c].frame;
    leg.dim = contacts[c].dim == 6 ? 6 : 3;
    for (int j : chains[c]) {
      const int i = model.joints[j].idx_v - first;
      if (users[i] != 1) continue;
      leg.joints.push_back(i);
      leg.columns.push_back(model.joints[j].idx_v);
      in_leg_[i] = 1;
    }
    if (leg.joints.empty() || leg.joints.size() > kMaxLegJoints)
      throw std::invalid_argument("stand-down: contact frame '" + model.frames[leg.frame].name +
                                  "' has " + std::to_string(leg.joints.size()) +
                                  " joints of its own (1 to " + std::to_string(kMaxLegJoints) +
                                  " expected)");
    leg.base_to_foot = base.actInv(data_.oMf[leg.frame]);
    // The foot's position (a sole's placement, its orientation error first order in world axes,
    // as the step is taken afresh every physics step) by the leg's joints; one step each time,
    // its error capped at max_step.
    InverseKinematicsOptions ik;
    ik.damping = kDamping * kDamping;
    ik.max_error = options.max_step;
    ik_.emplace_back(model,
                     std::vector<IkTarget>{{leg.frame, leg.dim, ReferenceFrame::LocalWorldAligned,
                                            data_.oMf[leg.frame]}},
                     leg.columns, ik);
    legs_.push_back(std::move(leg));
  }
  // Where the centre of mass stands over the feet in the default posture (base frame, horizontal):
  // where the stand-down puts it back.
  if (legs_.empty()) return;
  Eigen::Vector2d feet = Eigen::Vector2d::Zero();
  for (const Leg& leg : legs_) feet += leg.base_to_foot.p.head<2>();
  const Eigen::Vector3d com =
      base.R.transpose() * (centerOfMass(model, data_, hold.q_ref) - base.p);
  com_over_feet_ = com.head<2>() - feet / static_cast<double>(legs_.size());
}

int StandDown::freeFlyerJoint() const {
  for (int j = 1; j < model_.njoints(); ++j)
    if (model_.joints[j].type == JointType::FreeFlyer) return j;
  return 0;
}

void StandDown::begin(double t, const Eigen::Ref<const Eigen::VectorXd>& q,
                      const Eigen::Ref<const Eigen::VectorXd>& u_last) {
  t0_ = t;
  q_start_ = q;
  u_start_ = u_last;
  for (Leg& leg : legs_) leg.latched = false;
}

void StandDown::torque(double t, const Eigen::Ref<const Eigen::VectorXd>& q,
                       const Eigen::Ref<const Eigen::VectorXd>& v, unsigned on_ground,
                       Eigen::Ref<Eigen::VectorXd> tau) {
  const double s = options_.ramp > 0.0 ? std::clamp((t - t0_) / options_.ramp, 0.0, 1.0) : 1.0;
  const int first = model_.hasFreeFlyer() ? 6 : 0;
  // Joints outside the legs: linearly to the default posture.
  for (int j = 1; j < model_.njoints(); ++j) {
    const Joint& jt = model_.joints[j];
    if (jt.type == JointType::FreeFlyer) continue;
    const int i = jt.idx_v - first;  // 1-dof joints, as HoldPolicy
    if (in_leg_[i]) continue;
    const double start = q_start_[jt.idx_q];
    const double target = start + s * (hold_.q_ref[jt.idx_q] - start);
    tau[i] = msg::jointPd((1.0 - s) * u_start_[i], hold_.kp[i], hold_.kd[i], target, q[jt.idx_q],
                          v[jt.idx_v]);
  }
  if (legs_.empty()) return;

  // The legs: where each foot belongs under a level base placed over the feet on the ground.
  computeJointJacobians(model_, data_, q);
  const SE3& base = data_.oMi[freeFlyerJoint()];
  // Feet on the ground stay where they touched down, and the base is placed over them: every
  // planted leg then moves with one rigid displacement of the base (they never pull against each
  // other through the ground), and a base that turns away from its feet is turned back. The
  // heading:
  // - planted soles say it by their own yaw (the mean of the headings each asks): two soles a
  //   stride apart, fitted by their places alone, asked a humanoid to turn by up to ~25 degrees
  //   and it fell backwards 3 s into the stand-down;
  // - three or more planted point feet by their places: the least-squares fit of the default
  //   feet onto them (2-D Procrustes). At the present heading nothing held it, and a quadruped
  //   stood down on four feet spun up to 4 rad/s and 87 degrees (a kill at 2.918 s of the trot);
  // - two point feet or fewer: the present heading (a trot's diagonal pair a stride apart gives a
  //   poor fit; the feet in the air come down under the hips, and then there are four).
  // The horizontal place: below, by the capture point.
  Eigen::Vector2d sum_anchor = Eigen::Vector2d::Zero(), sum_offset = Eigen::Vector2d::Zero();
  double sum_dot = 0.0, sum_cross = 0.0, sole_cos = 0.0, sole_sin = 0.0, sum_z = 0.0;
  int planted = 0, soles = 0;
  for (std::size_t c = 0; c < legs_.size(); ++c) {
    Leg& leg = legs_[c];
    const bool down = c < 32 && (on_ground >> c & 1u);
    if (down && !leg.latched) {
      const SE3& foot = updateFramePlacement(model_, data_, leg.frame);
      leg.anchor = foot.p;
      const Eigen::Matrix3d base_of_foot = foot.R * leg.base_to_foot.R.transpose();
      leg.anchor_heading = std::atan2(base_of_foot(1, 0), base_of_foot(0, 0));
    }
    leg.latched = down;
    if (!down) continue;
    const Eigen::Vector2d a = leg.anchor.head<2>(), o = leg.base_to_foot.p.head<2>();
    sum_anchor += a;
    sum_z += leg.anchor.z();
    sum_offset += o;
    sum_dot += o.dot(a);
    sum_cross += o.x() * a.y() - o.y() * a.x();
    ++planted;
    if (leg.dim == 6) {
      sole_cos += std::cos(leg.anchor_heading);
      sole_sin += std::sin(leg.anchor_heading);
      ++soles;
    }
  }
  double yaw = std::atan2(base.R(1, 0), base.R(0, 0));
  Eigen::Vector2d base_xy = base.p.head<2>();
  if (planted > 0) {
    const Eigen::Vector2d a_mean = sum_anchor / planted, o_mean = sum_offset / planted;
    // The centred sums: Σ o'·a' and Σ o'×a' (the rotation taking o' onto a').
    const double dot = sum_dot - planted * o_mean.dot(a_mean);
    const double cross = sum_cross - planted * (o_mean.x() * a_mean.y() - o_mean.y() * a_mean.x());
    if (soles > 0)
      yaw = std::atan2(sole_sin, sole_cos);
    else if (planted >= 3 && std::hypot(dot, cross) > 1e-9)
      yaw = std::atan2(cross, dot);
    // Over the support: the base moves by what puts the capture point (the centre of mass ahead
    // by its velocity times sqrt(h / g)) where the centre of mass stands over the feet in the
    // default posture, here over the planted feet's centre. With the base merely where the feet's
    // default places put it, a humanoid stood on two feet a stride apart leaned back, slowly and
    // then faster, and fell 3 s into the stand-down (3 kills of 10).
    const Eigen::Vector3d& com = centerOfMass(model_, data_, q, v);
    const double h = std::max(com.z() - sum_z / planted, 0.05);
    const Eigen::Vector2d capture = com.head<2>() + data_.vcom.head<2>() * std::sqrt(h / 9.81);
    base_xy = base.p.head<2>() + (a_mean + Eigen::Rotation2Dd(yaw) * com_over_feet_ - capture);
  }
  const Eigen::Matrix3d level = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Vector3d base_target(base_xy.x(), base_xy.y(), base.p.z());
  for (std::size_t c = 0; c < legs_.size(); ++c) {
    Leg& leg = legs_[c];
    // Where the foot belongs in a level base frame at base_target: a planted foot at its place on
    // the ground at the default's depth (the base's height), a foot in the air under its hip.
    // Compared with where the foot is in the real base frame: a tilted base shows as the feet's
    // height differences, which the legs then undo. A sole: as at the default posture relative to
    // the base.
    Eigen::Vector3d target = leg.base_to_foot.p;
    if (leg.latched) target.head<2>() = (level.transpose() * (leg.anchor - base_target)).head<2>();
    // One damped least-squares step of the leg's inverse kinematics (base held where it is), to
    // that target carried into the world by the real base.
    ik_[c].setTarget(0, SE3(base.R * leg.base_to_foot.R, base.p + base.R * target));
    ik_[c].stepFromKinematics(data_, dv_);
    for (std::size_t k = 0; k < leg.joints.size(); ++k) {
      const int i = leg.joints[k];
      // The PD on the IK step: q_ref − q = dq.
      tau[i] = msg::jointPd((1.0 - s) * u_start_[i], hold_.kp[i], hold_.kd[i], dv_[leg.columns[k]],
                            0.0, v[leg.columns[k]]);
    }
  }
}

}  // namespace stride::sim
