#include "controller/command.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace stride {

namespace {
// Clamps x to [-limit, limit]; sets `clamped` when it had to.
double limit(double x, double limit, bool& clamped) {
  const double y = std::clamp(x, -limit, limit);
  clamped = clamped || y != x;
  return y;
}
// Moves x toward `to` by at most `step`.
double approach(double x, double to, double step) {
  return x + std::clamp(to - x, -step, step);
}
}  // namespace

CommandFilter::CommandFilter(const CommandConfig& config, const std::vector<std::string>& gaits)
    : config_(config), gaits_(gaits) {
  if (gaits_.empty() || gaits_[0] != "stand")
    throw std::invalid_argument("CommandFilter: the first gait must be 'stand'");
}

int CommandFilter::gaitIndex(const std::string& name) const {
  for (int i = 0; i < static_cast<int>(gaits_.size()); ++i)
    if (gaits_[i] == name) return i;
  return -1;
}

bool CommandFilter::receive(const command_t& m, double now) {
  const int gait = m.gait.empty() ? received_gait_ : gaitIndex(m.gait);
  if (gait < 0) {
    ++counters_.rejected;
    return false;
  }
  bool clamped = false;
  received_.vx = limit(m.vx, config_.max_vx, clamped);
  received_.vy = limit(m.vy, config_.max_vy, clamped);
  received_.yaw_rate = limit(m.yaw_rate, config_.max_yaw_rate, clamped);
  received_.height = limit(m.body_height, config_.max_height, clamped);
  received_gait_ = gait;
  if (gait == 0) received_.vx = received_.vy = received_.yaw_rate = 0.0;  // a stand stands
  // A jump is made once per id: a new one is an id other than the last message's (a restarted
  // sender counts from 1 again after its first command, 0).
  if (m.jump_id > 0 && m.jump_id != last_jump_id_) {
    jump_pending_ = true;
    jump_id_ = m.jump_id;
    jump_ = {m.jump[0], m.jump[1], m.jump[2], m.jump[3]};
  }
  last_jump_id_ = m.jump_id;
  counters_.clamped += clamped ? 1 : 0;
  ++counters_.accepted;
  last_arrival_ = std::max(last_arrival_, now);
  any_ = true;
  return true;
}

void CommandFilter::update(double now) {
  const double dt = updated_ ? std::max(0.0, now - last_update_) : 0.0;
  if (!updated_ || now > last_update_) last_update_ = now;
  updated_ = true;
  // The clock never goes backwards: an earlier `now` is the latest time seen, else it would
  // release the deadman (and count the same silence again) without any new command
  // (tests/controller/test_commands.cpp, TimeNeverGoesBackwards).
  now = last_update_;

  const bool silent = !any_ || now - last_arrival_ > config_.timeout;
  if (silent && !timed_out_ && any_) ++counters_.timeouts;
  timed_out_ = silent;
  int want_gait = received_gait_;
  if (silent) {
    target_ = BodyCommand{};
    target_.height = 0.0;
    want_gait = 0;
  } else {
    target_ = received_;
  }
  smoothed_.vx = approach(smoothed_.vx, target_.vx, config_.accel_x * dt);
  smoothed_.vy = approach(smoothed_.vy, target_.vy, config_.accel_y * dt);
  smoothed_.yaw_rate = approach(smoothed_.yaw_rate, target_.yaw_rate, config_.accel_yaw * dt);
  smoothed_.height = approach(smoothed_.height, target_.height, config_.height_rate * dt);
  const bool still = smoothed_.vx == 0.0 && smoothed_.vy == 0.0 && smoothed_.yaw_rate == 0.0;
  if (want_gait != 0 || still) gait_ = want_gait;
}

}  // namespace stride
