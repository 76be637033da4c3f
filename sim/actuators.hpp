#pragma once
// The mock robot's actuators (sim/README.md, "Actuators"): between the torque the low-level loop
// commands and the torque on the joint, per actuated joint i, in this order:
// - latency: the command acts `latency` physics steps later;
// - bandwidth: a first-order lag of cutoff f, τ += α (τ_cmd − τ), α = 1 − exp(−2π f dt);
// - torque_scale: the motor gives F τ (a torque constant, a gear efficiency off by F);
// - torque-speed envelope (velocity_limits): a motor turning at ω in the direction it pushes has
//   τ_max (1 − |ω| / ω_max) left (the DC motor's line from stall torque to no-load speed), none
//   past ω_max; braking keeps τ_max. τ_max and ω_max are the joint's effort and velocity limits
//   (URDF); a joint without a velocity limit has no envelope;
// - friction and damping: −f sign(ω) − d ω, each capped so that it cannot reverse the joint's
//   velocity within one step (|τ| ≤ m_i |ω| / dt, m_i = 1 / (M⁻¹)_ii at the default posture): an
//   explicit Coulomb friction would chatter around ω = 0.
// The simulator then clamps to the effort limits as always. Default (every option off): the
// command passes through untouched (bit-identical). Allocates nothing after construction.

#include "solver/multibody/model.hpp"

namespace stride::sim {

struct ActuatorOptions {
  int latency = 0;               // [physics steps]
  double bandwidth = 0.0;        // [Hz]; 0: instant
  double torque_scale = 1.0;     // applied = F × commanded
  bool velocity_limits = false;  // the torque-speed envelope from the joints' velocity limits
  double friction = 0.0;         // Coulomb [Nm, N]
  double damping = 0.0;          // viscous [Nm s/rad, N s/m]

  bool enabled() const;
  // Throws std::invalid_argument for negative values or a non-positive torque scale.
  void check() const;
};

class Actuators {
 public:
  // default_q: where the joints' inertias for the friction cap are taken.
  Actuators(const Model& model, const Eigen::VectorXd& default_q, const ActuatorOptions& options,
            double dt);
  void reset();
  // τ on the joints from the commanded τ_cmd (both nu) at joint velocities v (the model's v).
  void apply(const Eigen::Ref<const Eigen::VectorXd>& tau_cmd,
             const Eigen::Ref<const Eigen::VectorXd>& v, Eigen::Ref<Eigen::VectorXd> tau);
  bool enabled() const { return enabled_; }
  // Steps where the envelope cut a command (at least one joint).
  std::int64_t envelopeSteps() const { return envelope_steps_; }

 private:
  ActuatorOptions options_;
  double dt_;
  bool enabled_;
  int first_v_;
  double alpha_;
  Eigen::VectorXd effort_, speed_, inertia_;  // per actuated joint
  Eigen::MatrixXd queue_;                     // nu x (latency + 1) commands
  int head_ = 0;
  Eigen::VectorXd lagged_;
  std::int64_t envelope_steps_ = 0;
};

}  // namespace stride::sim
