#include "locomotion/jump.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace stride {

namespace {
constexpr double kFreeFall = 9.81;
}

bool planJump(const JumpTarget& target, const JumpLimits& limits, JumpPlan& plan, char* reason,
              std::size_t n) {
  auto refuse = [&](const char* format, double a, double b) {
    if (n > 0) std::snprintf(reason, n, format, a, b);
    return false;
  };
  auto say = [&](const char* text) {
    if (n > 0) std::snprintf(reason, n, "%s", text);
    return false;
  };
  if (n > 0) reason[0] = '\0';
  if (!std::isfinite(target.dx) || !std::isfinite(target.dy) || !std::isfinite(target.dz) ||
      !std::isfinite(target.yaw))
    return say("the jump's target is not finite");
  if (!(limits.max_distance > 0.0))
    return say("this robot does not jump (no jump: section in its controller YAML)");
  const double d = std::hypot(target.dx, target.dy);
  if (d > limits.max_distance)
    return refuse("a jump of %.2f m is beyond the robot's reach (jump.max_distance %.2f m)", d,
                  limits.max_distance);
  if (std::abs(target.dz) > limits.max_rise)
    return refuse("a landing %.2f m higher is beyond the robot's rise (jump.max_rise %.2f m)",
                  target.dz, limits.max_rise);
  if (std::abs(target.yaw) > limits.max_turn)
    return refuse("a turn of %.2f rad in the air is beyond the robot's (jump.max_turn %.2f rad)",
                  target.yaw, limits.max_turn);
  const double best = std::sqrt(2.0 * std::sqrt(d * d + target.dz * target.dz) / kFreeFall);
  double T = std::clamp(best, limits.min_flight, limits.max_flight);
  if (limits.flight_step > 0.0)
    T = limits.min_flight +
        limits.flight_step * std::round((T - limits.min_flight) / limits.flight_step);
  plan.flight = T;
  plan.vx = target.dx / T;
  plan.vy = target.dy / T;
  plan.vz = target.dz / T + 0.5 * kFreeFall * T;
  plan.speed = std::sqrt(plan.vx * plan.vx + plan.vy * plan.vy + plan.vz * plan.vz);
  if (plan.speed > limits.max_speed)
    return refuse(
        "the jump needs a take-off speed of %.2f m/s, more than the robot's legs give "
        "(jump.max_speed %.2f m/s)",
        plan.speed, limits.max_speed);
  return true;
}

}  // namespace stride
