#include "sim/disturbances.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace stride::sim {

StateDelay::StateDelay(int nq, int nv, int delay) : delay_(delay) {
  if (delay < 0) throw std::invalid_argument("StateDelay: delay must be >= 0");
  q_.setZero(nq, delay + 1);
  v_.setZero(nv, delay + 1);
  t_.setZero(delay + 1);
}

void StateDelay::push(double time, const Eigen::Ref<const Eigen::VectorXd>& q,
                      const Eigen::Ref<const Eigen::VectorXd>& v) {
  q_.col(head_) = q;
  v_.col(head_) = v;
  t_[head_] = time;
  head_ = (head_ + 1) % (delay_ + 1);
  count_ = std::min(count_ + 1, delay_ + 1);
}

bool StateDelay::delayed(double& time, Eigen::Ref<Eigen::VectorXd> q,
                         Eigen::Ref<Eigen::VectorXd> v) const {
  if (count_ < delay_ + 1) return false;
  // Full ring: the next slot to be overwritten holds the oldest state.
  time = t_[head_];
  q = q_.col(head_);
  v = v_.col(head_);
  return true;
}

MessageDropper::MessageDropper(double probability, std::uint64_t seed)
    : probability_(probability), rng_(seed) {
  if (!(probability >= 0.0 && probability <= 1.0))
    throw std::invalid_argument("MessageDropper: probability must be in [0, 1]");
}

bool MessageDropper::drop() {
  // Always draw, so the sequence of decisions for a seed does not depend on the probability's
  // being zero.
  const bool d = uniform_(rng_) < probability_;
  if (d) ++dropped_;
  return d;
}

Vector6d PushSchedule::wrenchAt(double t) const {
  Vector6d w = Vector6d::Zero();
  for (const Push& p : pushes) {
    if (t >= p.start && t < p.start + p.duration) {
      w.head<3>() += p.force;
      w.tail<3>() += p.moment;
    }
  }
  return w;
}

double PushSchedule::activeUntil(double t) const {
  double until = t;
  for (const Push& p : pushes)
    if (t >= p.start && t < p.start + p.duration) until = std::max(until, p.start + p.duration);
  return until;
}

bool parsePush(const std::string& text, Push& push) {
  std::istringstream in(text);
  char c1, c2, c3, c4;
  double fx, fy, fz;
  if (!(in >> push.start >> c1 >> push.duration >> c2 >> fx >> c3 >> fy >> c4 >> fz)) return false;
  if (c1 != ':' || c2 != ':' || c3 != ',' || c4 != ',' || !(push.duration > 0.0)) return false;
  if (!(in >> std::ws).eof()) return false;  // nothing may follow
  push.force = Eigen::Vector3d(fx, fy, fz);
  return push.force.allFinite() && std::isfinite(push.start) && std::isfinite(push.duration);
}

}  // namespace stride::sim
