#pragma once
// What the mock robot applies besides the controller's policy: the fallback for when no policy has
// arrived yet (a joint PD holding a posture) and the stand-down when the controller goes silent.
// The policy itself, τ = u_ff(t) + K(t) (x_ref(t) ⊖ x) between knots, is the wire's
// (messages/policy_interpolation.hpp: msg::Policy, msg::PolicyEvaluator).

#include <cstdint>
#include <vector>

#include "solver/multibody/data.hpp"
#include "solver/multibody/inverse_kinematics.hpp"
#include "solver/multibody/model.hpp"

namespace stride::sim {

// The fallback policy: a joint PD holding q_ref, τ = Kp (q_ref − q) − Kd v on the actuated joints
// (the base is not actuated). Gains per actuated joint. The law is the one of messages/hold_pd.hpp
// (msg::jointPd), which the controller's hold fallback sends as a policy; the gains are the robot's
// own (its YAML's joint_pd, else msg::kDefaultHoldKp/Kd), capped for the explicit step below.
struct HoldPolicy {
  Eigen::VectorXd q_ref;   // nq: only its joint entries are used
  Eigen::VectorXd kp, kd;  // nu

  HoldPolicy() = default;
  // The same gains on every joint. With step_dt > 0 they are capped per joint for the simulator's
  // explicit step: kd_i ≤ m_i / (2 dt) and kp_i ≤ m_i / (4 dt²), m_i = 1 / (M⁻¹)_ii the inertia
  // the joint drives at q_ref when everything else moves freely. A PD evaluated once per step on a
  // light link (a humanoid's forearm coupled with its shoulder) oscillates step to step above
  // kd ~ 2 m_i / dt, whatever the physics integrator does.
  HoldPolicy(const Model& model, const Eigen::VectorXd& q_ref, double kp, double kd,
             double step_dt = 0.0);
  // τ (size nu). Allocates nothing.
  void torque(const Model& model, const Eigen::Ref<const Eigen::VectorXd>& q,
              const Eigen::Ref<const Eigen::VectorXd>& v, Eigen::Ref<Eigen::VectorXd> tau) const;
};

// What the robot does when its controller goes silent (sim/README.md, "Controller loss"): past
// the last policy's end (plus a grace period, 0 by default), a stand-down that levels the body over
// its feet, as a robot's low level would with its IMU and joint encoders:
// - each leg (the joints that move one contact's frame, and no other) is given the joint angles
//   that put its foot where it belongs under a LEVEL base at the default posture's depth: a foot
//   on the ground at the place where it is (latched at touch-down, so planted feet are not dragged
//   across the ground against each other), a foot in the air under its hip (so it comes down where
//   it supports the body). The base's heading is the one the planted feet ask (soles: their yaw;
//   three or more point feet: a least-squares fit of their places), its horizontal place the one
//   that brings the capture point where the centre of mass stands over the feet in the default
//   posture. A tilted body then has its low side's legs extended and its high side's shortened: the
//   body levels itself. Those angles are one damped least-squares step of the leg's inverse
//   kinematics each physics step (the PD tracks a target that is recomputed as the robot moves);
// - the other joints (arms, torso, joints shared by several contacts) move linearly to the default
//   posture over `ramp` seconds;
// - the last policy's feed-forward (the torques that carried the robot's weight) fades out over the
//   same time while the PD takes the load.
// Then the PD alone, leveling, until a controller is back.
struct StandDownOptions {
  // [s] past the policy's end, its last knot held (feed-forward and feedback) before standing
  // down. 0: that hold diverges within tens of ms (sim/README.md, "Controller loss").
  double grace = 0.0;
  double ramp = 0.3;       // [s] for the feed-forward to fade and the other joints to reach default
  double max_step = 0.05;  // [m] (and rad): the largest foot error one IK step corrects
};

// A contact of the robot as the stand-down sees it: its frame and its dimension (3: a point foot,
// position only; 6: a sole, position and orientation).
struct StandDownContact {
  int frame = -1;
  int dim = 3;
};

class StandDown {
 public:
  // hold: the PD and the default posture (whose forward kinematics gives each foot's place under
  // the base); contacts in the order of the on-ground masks. Allocates.
  StandDown(const Model& model, const HoldPolicy& hold,
            const std::vector<StandDownContact>& contacts, const StandDownOptions& options);

  const StandDownOptions& options() const { return options_; }
  // Starts at time t from configuration q, with u_last the feed-forward the robot was applying.
  // Allocates nothing.
  void begin(double t, const Eigen::Ref<const Eigen::VectorXd>& q,
             const Eigen::Ref<const Eigen::VectorXd>& u_last);
  // τ (size nu) at time t ≥ the start; bit c of `on_ground` set when contact c carries load
  // (what the robot's contact sensing or its estimator says). Allocates nothing.
  void torque(double t, const Eigen::Ref<const Eigen::VectorXd>& q,
              const Eigen::Ref<const Eigen::VectorXd>& v, unsigned on_ground,
              Eigen::Ref<Eigen::VectorXd> tau);

 private:
  static constexpr std::size_t kMaxLegJoints = 12;
  static constexpr double kDamping = 0.01;  // [m] of the damped least squares: near a straight
                                            // knee the step stays bounded
  int freeFlyerJoint() const;

  struct Leg {
    int frame = -1, dim = 3;
    std::vector<int> joints;   // actuated indices (0..nu-1) of the leg's own joints
    std::vector<int> columns;  // their velocity indices (columns of the Jacobian)
    SE3 base_to_foot;          // the foot in the base frame at the default posture
    bool latched = false;      // on the ground since `anchor` was taken
    Eigen::Vector3d anchor = Eigen::Vector3d::Zero();  // where it touched down (world)
    double anchor_heading = 0.0;  // a sole's: the base heading it asks, from its yaw then
  };
  const Model& model_;
  const HoldPolicy& hold_;
  StandDownOptions options_;
  std::vector<Leg> legs_;
  // Per leg: one damped least-squares step towards its foot's target, on its own joints'
  // columns (solver/multibody/inverse_kinematics.hpp; workspaces allocated at construction).
  std::vector<InverseKinematics> ik_;
  std::vector<char> in_leg_;  // per actuated joint: belongs to a leg
  Data data_;
  Eigen::VectorXd dv_;                                       // nv: a leg's step
  Eigen::Vector2d com_over_feet_ = Eigen::Vector2d::Zero();  // default posture, base frame
  double t0_ = 0.0;
  Eigen::VectorXd q_start_, u_start_;
};

}  // namespace stride::sim
