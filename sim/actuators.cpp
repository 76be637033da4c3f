#include "sim/actuators.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "solver/multibody/crba.hpp"
#include "solver/multibody/data.hpp"

namespace stride::sim {

bool ActuatorOptions::enabled() const {
  return latency > 0 || bandwidth > 0.0 || torque_scale != 1.0 || velocity_limits ||
         friction > 0.0 || damping > 0.0;
}

void ActuatorOptions::check() const {
  if (latency < 0) throw std::invalid_argument("actuators: the latency must be >= 0 steps");
  if (!(bandwidth >= 0.0) || !(friction >= 0.0) || !(damping >= 0.0) || !std::isfinite(bandwidth) ||
      !std::isfinite(friction) || !std::isfinite(damping))
    throw std::invalid_argument("actuators: bandwidth, friction and damping must be finite, >= 0");
  if (!(torque_scale > 0.0) || !std::isfinite(torque_scale))
    throw std::invalid_argument("actuators: the torque scale must be finite and > 0");
}

Actuators::Actuators(const Model& model, const Eigen::VectorXd& default_q,
                     const ActuatorOptions& options, double dt)
    : options_(options), dt_(dt), enabled_(options.enabled()) {
  options_.check();
  first_v_ = model.hasFreeFlyer() ? 6 : 0;
  const int nu = model.nv - first_v_;
  alpha_ = options.bandwidth > 0.0 ? 1.0 - std::exp(-2.0 * M_PI * options.bandwidth * dt) : 1.0;
  effort_ = model.effortLimit.tail(nu);
  speed_ = model.velocityLimit.tail(nu);
  inertia_.setZero(nu);
  if (options.friction > 0.0 || options.damping > 0.0) {
    Data data(model);
    const Eigen::MatrixXd Minv =
        crba(model, data, default_q).llt().solve(Eigen::MatrixXd::Identity(model.nv, model.nv));
    for (int i = 0; i < nu; ++i) inertia_[i] = 1.0 / Minv(first_v_ + i, first_v_ + i);
  }
  queue_.setZero(nu, options.latency + 1);
  lagged_.setZero(nu);
}

void Actuators::reset() {
  queue_.setZero();
  head_ = 0;
  lagged_.setZero();
  envelope_steps_ = 0;
}

void Actuators::apply(const Eigen::Ref<const Eigen::VectorXd>& tau_cmd,
                      const Eigen::Ref<const Eigen::VectorXd>& v, Eigen::Ref<Eigen::VectorXd> tau) {
  if (!enabled_) {
    tau = tau_cmd;
    return;
  }
  const ActuatorOptions& o = options_;
  // Latency: a ring of latency + 1 commands; after writing now's, the next slot is the oldest.
  queue_.col(head_) = tau_cmd;
  head_ = (head_ + 1) % (o.latency + 1);
  const auto delayed = queue_.col(head_);
  lagged_ += alpha_ * (delayed - lagged_);
  bool cut = false;
  for (Eigen::Index i = 0; i < tau.size(); ++i) {
    double t = o.torque_scale * lagged_[i];
    const double w = v[first_v_ + i];
    if (o.velocity_limits && std::isfinite(speed_[i]) && speed_[i] > 0.0 && t * w > 0.0) {
      const double available = effort_[i] * std::max(0.0, 1.0 - std::abs(w) / speed_[i]);
      if (std::abs(t) > available) {
        t = std::copysign(available, t);
        cut = true;
      }
    }
    // Passive torques, capped together not to reverse the velocity within one step.
    if (o.friction > 0.0 || o.damping > 0.0)
      t -= std::copysign(
          std::min(o.friction + o.damping * std::abs(w), inertia_[i] * std::abs(w) / dt_), w);
    tau[i] = t;
  }
  if (cut) ++envelope_steps_;
}

}  // namespace stride::sim
