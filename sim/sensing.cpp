#include "sim/sensing.hpp"

#include <cmath>
#include <stdexcept>

#include <Eigen/Geometry>

namespace stride::sim {

bool SensingOptions::enabled() const {
  return encoder_resolution > 0.0 || encoder_noise > 0.0 || joint_velocity_noise > 0.0 ||
         joint_velocity_filter > 0.0 || orientation_noise > 0.0 || gyro_noise > 0.0 ||
         gyro_bias_walk > 0.0 || base_position_noise > 0.0 || base_velocity_noise > 0.0 ||
         base_drift > 0.0 || velocity_estimator > 0.0 || accel_noise > 0.0 || latency > 0 ||
         sample_drop > 0.0;
}

void SensingOptions::check() const {
  const double values[] = {
      encoder_resolution,  encoder_noise, joint_velocity_noise, joint_velocity_filter,
      orientation_noise,   gyro_noise,    gyro_bias_walk,       base_position_noise,
      base_velocity_noise, base_drift,    velocity_estimator,   accel_noise};
  for (double x : values)
    if (!(x >= 0.0) || !std::isfinite(x))
      throw std::invalid_argument(
          "sensing: noises, resolutions and cutoffs must be finite and >= 0");
  if (latency < 0) throw std::invalid_argument("sensing: the latency must be >= 0 steps");
  if (!(sample_drop >= 0.0 && sample_drop <= 1.0))
    throw std::invalid_argument("sensing: the drop probability must be in [0, 1]");
}

Sensing::Sensing(const Model& model, const SensingOptions& options, double dt, std::uint64_t seed)
    : model_(model),
      options_(options),
      dt_(dt),
      enabled_(options.enabled()),
      floating_(model.hasFreeFlyer()),
      first_q_(floating_ ? 7 : 0),
      first_v_(floating_ ? 6 : 0),
      rng_(seed) {
  options_.check();
  // The discrete first-order low-pass: y += α (u − y), α = 1 − exp(−2π f dt).
  alpha_ = options.joint_velocity_filter > 0.0
               ? 1.0 - std::exp(-2.0 * M_PI * options.joint_velocity_filter * dt)
               : 1.0;
  kappa_ = options.velocity_estimator > 0.0
               ? 1.0 - std::exp(-2.0 * M_PI * options.velocity_estimator * dt)
               : 1.0;
  q_hist_.setZero(model.nq, options.latency + 1);
  v_hist_.setZero(model.nv, options.latency + 1);
  q_hat_.setZero(model.nq);
  v_hat_.setZero(model.nv);
  enc_prev_.setZero(model.nq);
  filtered_.setZero(model.nv);
}

void Sensing::reset(const Eigen::Ref<const Eigen::VectorXd>& q,
                    const Eigen::Ref<const Eigen::VectorXd>& v) {
  q_hist_.colwise() = q;
  v_hist_.colwise() = v;
  head_ = 0;
  bias_.setZero();
  drift_.setZero();
  yaw_ = 0.0;
  have_prev_ = false;
  have_base_ = false;
  dropped_ = 0;
  gap_ = 1;
  q_hat_ = q;
  v_hat_ = v;
}

void Sensing::sample(const Eigen::Ref<const Eigen::VectorXd>& q,
                     const Eigen::Ref<const Eigen::VectorXd>& v) {
  if (!enabled_) return;
  // The ring: write now's state over the oldest; the oldest left is latency steps old.
  q_hist_.col(head_) = q;
  v_hist_.col(head_) = v;
  head_ = (head_ + 1) % (options_.latency + 1);
  // Biases and drifts walk whether or not the sample arrives.
  const double sqrt_dt = std::sqrt(dt_);
  if (options_.gyro_bias_walk > 0.0)
    for (int i = 0; i < 3; ++i) bias_[i] += options_.gyro_bias_walk * sqrt_dt * normal();
  yaw_ += bias_.z() * dt_;
  if (options_.base_drift > 0.0)
    for (int i = 0; i < 2; ++i) drift_[i] += options_.base_drift * sqrt_dt * normal();
  if (options_.sample_drop > 0.0 && uniform_(rng_) < options_.sample_drop) {
    ++dropped_;
    ++gap_;
    return;
  }
  sense(q_hist_.col(head_), v_hist_.col(head_));
}

void Sensing::sense(const Eigen::Ref<const Eigen::VectorXd>& q,
                    const Eigen::Ref<const Eigen::VectorXd>& v) {
  const SensingOptions& o = options_;
  const int gap = gap_;  // steps since the last sample that arrived
  // Encoders, then the joint velocities.
  const int nj = model_.nq - first_q_;
  for (int j = 0; j < nj; ++j) {
    double reading = q[first_q_ + j];
    if (o.encoder_noise > 0.0) reading += o.encoder_noise * normal();
    if (o.encoder_resolution > 0.0)
      reading = o.encoder_resolution * std::round(reading / o.encoder_resolution);
    double rate = v[first_v_ + j];
    if (o.joint_velocity_filter > 0.0) {
      // The finite difference of the readings since the last sample that arrived, low-passed.
      const int k = first_v_ + j;
      const double fd = have_prev_ ? (reading - enc_prev_[first_q_ + j]) / (gap_ * dt_) : rate;
      filtered_[k] = have_prev_ ? filtered_[k] + alpha_ * (fd - filtered_[k]) : rate;
      enc_prev_[first_q_ + j] = reading;
      rate = filtered_[k];
    }
    if (o.joint_velocity_noise > 0.0) rate += o.joint_velocity_noise * normal();
    q_hat_[first_q_ + j] = reading;
    v_hat_[first_v_ + j] = rate;
  }
  have_prev_ = true;
  gap_ = 1;
  if (!floating_) return;
  // The base: position, orientation (IMU + estimator), velocities in the base frame.
  for (int i = 0; i < 3; ++i) {
    double p = q[i] + (i < 2 ? drift_[i] : 0.0);
    if (o.base_position_noise > 0.0) p += o.base_position_noise * normal();
    q_hat_[i] = p;
  }
  Eigen::Quaterniond R(q[6], q[3], q[4], q[5]);
  if (o.orientation_noise > 0.0) {
    const Eigen::Vector3d n(o.orientation_noise * normal(), o.orientation_noise * normal(),
                            o.orientation_noise * normal());
    const double angle = n.norm();
    if (angle > 0.0) R = R * Eigen::Quaterniond(Eigen::AngleAxisd(angle, n / angle));
  }
  if (yaw_ != 0.0) R = Eigen::Quaterniond(Eigen::AngleAxisd(yaw_, Eigen::Vector3d::UnitZ())) * R;
  R.normalize();
  q_hat_[3] = R.x();
  q_hat_[4] = R.y();
  q_hat_[5] = R.z();
  q_hat_[6] = R.w();
  Eigen::Vector3d lin = v.head<3>();
  if (o.velocity_estimator > 0.0) {
    // The complementary filter, in world axes (sensing.hpp).
    const Eigen::Quaterniond R_true(q[6], q[3], q[4], q[5]);
    const Eigen::Vector3d v_world = R_true * lin;
    if (!have_base_) {
      v_world_ = v_world;
    } else {
      Eigen::Vector3d accel = (v_world - v_world_prev_) / (gap * dt_);
      if (o.accel_noise > 0.0)
        for (int i = 0; i < 3; ++i) accel[i] += o.accel_noise * normal();
      v_world_ += gap * dt_ * accel;
      Eigen::Vector3d legs = v_world;
      if (o.base_velocity_noise > 0.0)
        for (int i = 0; i < 3; ++i) legs[i] += o.base_velocity_noise * normal();
      v_world_ += kappa_ * (legs - v_world_);
    }
    v_world_prev_ = v_world;
    lin = R.conjugate() * v_world_;
  } else if (o.base_velocity_noise > 0.0) {
    for (int i = 0; i < 3; ++i) lin[i] += o.base_velocity_noise * normal();
  }
  have_base_ = true;
  for (int i = 0; i < 3; ++i) {
    double ang = v[3 + i] + bias_[i];
    if (o.gyro_noise > 0.0) ang += o.gyro_noise * normal();
    v_hat_[i] = lin[i];
    v_hat_[3 + i] = ang;
  }
}

}  // namespace stride::sim
