#pragma once
// What the mock robot senses (sim/README.md, "Sensing"): its joint encoders, its IMU and the base
// estimate its estimator would give, each sample taken `latency` physics steps after the state it
// measures. The robot's own low-level loop (the policy's feedback, the hold PD, the stand-down)
// and the estimates published to the controller both use this, never the truth: on hardware the
// feedback K (x_ref ⊖ x̂) acts on x̂.
//
// The model, per physics step, from the true state (q, v) latency steps ago:
// - encoders: q̂_j = r round((q_j + n) / r), n ~ N(0, encoder_noise²), r = encoder_resolution
//   (0: no quantisation);
// - joint velocities: v_j + N(0, joint_velocity_noise²), or with joint_velocity_filter > 0 the
//   encoders' finite difference through a first-order low-pass of that cutoff (what a drive
//   without a velocity sensor does), plus the same noise;
// - IMU: the base orientation estimate is R_z(ψ) R exp(n_o), n_o ~ N(0, orientation_noise²) per
//   axis; the gyro adds a bias b (a random walk, gyro_bias_walk [rad/s/√s]) and white noise to the
//   angular velocity. An estimator holds roll and pitch with gravity but not yaw: ψ is the
//   integral of the bias's z, a yaw drift;
// - base position: p + d + N(0, base_position_noise²), d a random walk on x and y of
//   base_drift [m/√s] (leg odometry: x, y and yaw are unobservable); base linear velocity:
//   v + N(0, base_velocity_noise²) (base frame, like v). With velocity_estimator f > 0 that noisy
//   velocity is the legs' odometry, and the estimate is what a complementary filter makes of it
//   and of the IMU's accelerometer (the true acceleration plus N(0, accel_noise²)): in world axes
//   v̂ ← v̂ + dt a; v̂ ← v̂ + κ (v_legs − v̂), κ = 1 − exp(−2π f dt), turned into the base frame by
//   the estimated orientation. The legs' noise is filtered above f, the accelerometer's integrated
//   below it (what a leg-odometry + IMU estimator does).
// A dropped sample (sample_drop) leaves the previous estimate in place.
// All seeded; allocates nothing after construction. Disabled (every option 0): the estimate IS
// the true state, and no random number is drawn (bit-identical to a robot without this model).

#include <cstdint>
#include <random>

#include "solver/multibody/model.hpp"

namespace stride::sim {

struct SensingOptions {
  double encoder_resolution = 0.0;     // [rad, m] one count; 0: exact
  double encoder_noise = 0.0;          // std [rad, m]
  double joint_velocity_noise = 0.0;   // std [rad/s, m/s]
  double joint_velocity_filter = 0.0;  // [Hz] > 0: velocities from the encoders, low-passed
  double orientation_noise = 0.0;      // std [rad] per axis
  double gyro_noise = 0.0;             // std [rad/s]
  double gyro_bias_walk = 0.0;         // [rad/s/√s]
  double base_position_noise = 0.0;    // std [m]
  double base_velocity_noise = 0.0;    // std [m/s]
  double base_drift = 0.0;             // [m/√s] on x and y
  double velocity_estimator = 0.0;     // [Hz] the filter's crossover; 0: the legs' velocity as is
  double accel_noise = 0.0;            // std [m/s²] (the estimator's accelerometer)
  int latency = 0;                     // [physics steps]
  double sample_drop = 0.0;            // probability that a sample is lost

  bool enabled() const;
  // Throws std::invalid_argument for a negative value or a probability outside [0, 1].
  void check() const;
};

class Sensing {
 public:
  Sensing(const Model& model, const SensingOptions& options, double dt, std::uint64_t seed);

  // Restarts at (q, v): the history is filled with it, biases and drifts are zero.
  void reset(const Eigen::Ref<const Eigen::VectorXd>& q,
             const Eigen::Ref<const Eigen::VectorXd>& v);
  // One physics step: the true state now; the estimate becomes the sensing of the state latency
  // steps ago (the oldest one held until that many steps passed). No-op when disabled.
  void sample(const Eigen::Ref<const Eigen::VectorXd>& q,
              const Eigen::Ref<const Eigen::VectorXd>& v);

  bool enabled() const { return enabled_; }
  int latency() const { return options_.latency; }
  const Eigen::VectorXd& q() const { return q_hat_; }
  const Eigen::VectorXd& v() const { return v_hat_; }
  std::int64_t dropped() const { return dropped_; }
  double yawDrift() const { return yaw_; }
  const Eigen::Vector3d& gyroBias() const { return bias_; }

 private:
  void sense(const Eigen::Ref<const Eigen::VectorXd>& q,
             const Eigen::Ref<const Eigen::VectorXd>& v);
  double normal() { return normal_(rng_); }

  const Model& model_;
  SensingOptions options_;
  double dt_;
  bool enabled_;
  bool floating_;
  int first_q_, first_v_;  // the first joint coordinate and velocity (after the free-flyer's)
  double alpha_;           // the velocity filter's gain per step
  Eigen::MatrixXd q_hist_, v_hist_;  // a ring of latency + 1 true states
  int head_ = 0;
  Eigen::VectorXd q_hat_, v_hat_, enc_prev_, filtered_;  // filtered_: the low-pass's state
  bool have_prev_ = false, have_base_ = false;
  int gap_ = 1;  // steps since the last sample that arrived
  Eigen::Vector3d bias_ = Eigen::Vector3d::Zero();
  Eigen::Vector2d drift_ = Eigen::Vector2d::Zero();
  // The velocity estimator: its world-frame estimate, the true world velocity it last saw, and
  // its gain per step.
  Eigen::Vector3d v_world_ = Eigen::Vector3d::Zero(), v_world_prev_ = Eigen::Vector3d::Zero();
  double kappa_ = 1.0;
  double yaw_ = 0.0;
  std::int64_t dropped_ = 0;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  std::uniform_real_distribution<double> uniform_{0.0, 1.0};
};

}  // namespace stride::sim
