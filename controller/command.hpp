#pragma once
// What the controller makes of the body commands it receives (command_t, controller/README.md,
// "Commands"): limits, a deadman and smoothing, on the controller's own clock.
//
//   receive  a decoded, checked message: an unknown gait is rejected; values beyond the limits are
//            clamped (the message is counted once as clamped); the gait "stand" means zero
//            velocity whatever the message says; "" keeps the gait.
//            A new jump_id (other than the last message's) is a jump asked for, taken once
//            (takeJump) whatever the velocity's limits and deadman do.
//   update   advances the command in force to `now`: each velocity moves toward the target at most
//            by its acceleration limit times the time elapsed (the body height at its rate). With
//            no valid command for `timeout` seconds (or none yet), the target is zero velocity
//            and a stand: a lost teleop never leaves the robot running.
// The gait in force changes as soon as the target asks for one, except a stand, which waits until
// the smoothed velocity has come to zero (a robot stops stepping once it has stopped).
//
// Nothing here allocates or throws after construction.

#include <cstdint>
#include <string>
#include <vector>

#include "locomotion/gait_generator.hpp"
#include "stride/command_t.hpp"

namespace stride {

struct CommandConfig {
  double timeout = 0.5;  // s without a valid command before the deadman stops the robot
  // Limits: |vx|, |vy| [m/s], |yaw rate| [rad/s], |body height offset| [m].
  double max_vx = 0.5, max_vy = 0.3, max_yaw_rate = 1.0, max_height = 0.05;
  // Smoothing: vx, vy [m/s²], yaw rate [rad/s²]; body height [m/s].
  double accel_x = 1.0, accel_y = 1.0, accel_yaw = 2.0, height_rate = 0.1;
};

struct CommandCounters {
  std::int64_t accepted = 0;
  std::int64_t rejected = 0;  // unknown gait (the node counts malformed or out-of-order ones)
  std::int64_t clamped = 0;   // accepted with at least one value clamped
  std::int64_t timeouts = 0;  // the deadman took over (once per silence)
};

class CommandFilter {
 public:
  // gaits: the names the robot can walk with; gaits[0] must be "stand" (std::invalid_argument).
  CommandFilter(const CommandConfig& config, const std::vector<std::string>& gaits);

  // A message that passed msg::checkCommand, received at `now` [s, the controller's clock].
  // False (counted) for a gait the robot does not have.
  bool receive(const command_t& m, double now);
  // Advances the command in force to `now` (never backwards).
  void update(double now);

  const BodyCommand& command() const { return smoothed_; }  // in force (smoothed)
  const BodyCommand& target() const { return target_; }     // where it is heading
  int gait() const { return gait_; }                        // index into the gaits given
  const std::string& gaitName() const { return gaits_[gait_]; }
  const std::vector<std::string>& gaits() const { return gaits_; }
  int gaitIndex(const std::string& name) const;  // -1 when unknown
  bool timedOut() const { return timed_out_; }   // at the last update
  // No command accepted within `timeout` before `now` (or none at all).
  bool silentAt(double now) const { return !any_ || now - last_arrival_ > config_.timeout; }
  const CommandCounters& counters() const { return counters_; }
  const CommandConfig& config() const { return config_; }
  // A jump received since the last call (command_t.jump_id, a new id): true once per jump.
  bool takeJump(int& id, JumpTarget& target) {
    if (!jump_pending_) return false;
    jump_pending_ = false;
    id = jump_id_;
    target = jump_;
    return true;
  }

 private:
  CommandConfig config_;
  std::vector<std::string> gaits_;
  BodyCommand received_;  // the last accepted command, clamped
  int received_gait_ = 0;
  BodyCommand smoothed_, target_;
  int gait_ = 0;
  double last_arrival_ = 0.0, last_update_ = 0.0;
  bool any_ = false, updated_ = false, timed_out_ = true;
  CommandCounters counters_;
  int last_jump_id_ = 0, jump_id_ = 0;
  bool jump_pending_ = false;
  JumpTarget jump_;
};

}  // namespace stride
