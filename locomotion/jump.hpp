#pragma once
// A jump (issue 45): a discrete command, its target relative to the robot at take-off, and what
// the robot can jump. The planner makes it as a contact pattern of its own (a push on every foot,
// a flight, a landing on every foot; locomotion/planner.hpp) and the gait generator flies the base
// along its ballistic arc (gait_generator.hpp); this file decides whether it can be made at all
// and how long the flight lasts.
//
// The flight time is the one that needs the least take-off speed: for a horizontal distance d and
// a landing dz higher, the take-off velocity is (d / T, dz / T + g T / 2), whose square
// (d² + dz²) / T² + g dz + g² T² / 4 is least at T⁴ = 4 (d² + dz²) / g², within the limits' flight
// times.

#include <cstddef>

namespace stride {

struct JumpTarget {
  double dx = 0.0, dy = 0.0;  // the landing, forward and left of the take-off, heading frame [m]
  double dz = 0.0;            // the landing surface's height above the take-off one [m]
  double yaw = 0.0;           // the turn in the air [rad, counter-clockwise]
};

// What a robot can jump: the controller YAML's `jump:` section (config/README.md). A robot without
// one does not jump (max_distance 0).
struct JumpLimits {
  double max_distance = 0.0;  // |(dx, dy)| [m]
  double max_rise = 0.0;      // |dz| [m]
  double max_turn = 0.0;      // |yaw| [rad]
  double max_speed = 0.0;     // take-off speed [m/s]: what its legs give at their torque limits
  double min_flight = 0.15, max_flight = 0.4;  // [s]
  double flight_step = 0.01;  // flight times are multiples of it above min_flight [s]
  double push = 0.3;          // on every foot before the take-off [s]
  double landing = 0.4;       // on every foot after the touch-down, before the gait resumes [s]
};

struct JumpPlan {
  double flight = 0.0;        // [s]
  double vx = 0.0, vy = 0.0;  // take-off velocity, heading frame [m/s]
  double vz = 0.0;            // [m/s]
  double speed = 0.0;         // |v| [m/s]
};

// The flight of `target` within `limits`. False, with the reason in `reason` (a sentence, naming
// the limit and its value; at most n - 1 characters, NUL-terminated), for a jump the robot cannot
// make: it does not jump, or the target is beyond a limit (distance, rise, turn, take-off speed),
// or not finite. Allocates nothing (the controller's tick calls it).
bool planJump(const JumpTarget& target, const JumpLimits& limits, JumpPlan& plan, char* reason,
              std::size_t n);

}  // namespace stride
