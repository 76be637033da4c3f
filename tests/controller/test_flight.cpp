// The robot leaves the ground (issue 45), closed loop (drive::run, lock-step, memq): solo12 pronks
// in place (every foot in the air at once, again and again), lands each time and stands again
// when the pronk ends; it jumps 30 cm forward and turns 90° in the air as commanded, and refuses
// a jump beyond its reach. Without flights in the timeline, a base reference of their own and zero
// torque in the air, it never left the ground (every knot had a foot down).
//
// The flight's pieces alone: ContactTimeline.PerFootSwitchNeverCutsASwing,
// GaitGenerator.FlightsFollowTheBallisticArc (tests/locomotion/test_gait_generator.cpp),
// LocomotionProblem.FlightHoldsAPostureWithZeroTorque and
// LocomotionSolve.FlightKnotsConserveCentroidalMomentum (tests/locomotion/test_locomotion.cpp).

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "controller_cases.hpp"
#include "tools/drive/closed_loop.hpp"

namespace stride {
namespace test_flight {

using controller_cases::configPath;

ScriptedCommand entry(double at, const std::string& gait) {
  ScriptedCommand c;
  c.at = at;
  c.gait = gait;
  return c;
}

// 3 s of pronk (0.3 s down, 0.24 s up: config/controller/solo12.yaml), then a stand.
TEST(FlightClosedLoop, Solo12PronksInPlaceAndStandsAgain) {
  ControllerConfig config = loadControllerConfig(configPath("solo12"));
  config.robots_dirs = {STRIDE_ROBOT_PACKAGES};
  drive::Options o;
  o.duration = 6.0;
  o.script = {entry(0.0, "stand"), entry(0.5, "pronk"), entry(3.5, "stand")};
  const drive::Run r = drive::run(config, o);
  ASSERT_FALSE(r.fell());
  const double standing = r.samples.front().q[2];
  // Flights: runs of states with no foot carrying load; shorter than 0.1 s, a bounce.
  int flights = 0, bounces = 0;
  double flight_start = -1.0, longest = 0.0, highest = 0.0, drift = 0.0;
  for (const drive::Sample& s : r.samples) {
    if (s.t < 0.1) continue;  // the first states, before the mock robot's first contact forces
    drift = std::max(drift, (s.q.head<2>() - r.samples.front().q.head<2>()).norm());
    if (s.feet_down == 0 && flight_start < 0.0) flight_start = s.t;
    if (s.feet_down == 0) highest = std::max(highest, s.q[2] - standing);
    if (s.feet_down > 0 && flight_start >= 0.0) {
      const double length = s.t - flight_start;
      if (length >= 0.1) {
        ++flights;
        longest = std::max(longest, length);
      } else {
        ++bounces;
        std::printf("a bounce of %.3f s at %.3f s\n", length, flight_start);
      }
      flight_start = -1.0;
    }
    if (s.t > 5.0) {
      EXPECT_EQ(s.feet_down, 4) << "t " << s.t;  // standing again
    }
  }
  std::printf(
      "%d flights (longest %.3f s), %d bounces, base up to %.3f m above standing, drift "
      "%.3f m\n",
      flights, longest, bounces, highest, drift);
  // 3 s of 0.54 s cycles: five flights at least, the longest most of its planned 0.24 s.
  EXPECT_GE(flights, 5);
  EXPECT_GE(longest, 0.18);
  EXPECT_LE(bounces, 1);
  EXPECT_GT(highest, 0.0);
  EXPECT_LT(drift, 0.15);
  EXPECT_EQ(r.mpc.fallbacks, 0);
}

// Jumps as commands (issue 45): 30 cm forward, landing within 5 cm of its target; a 90° turn in
// the air, landing within 10° of its heading (the legs shape the momentum in flight: the paper's
// point); then one beyond the robot's reach, refused with its reason, the robot standing on.
TEST(FlightClosedLoop, Solo12Jumps30CmTurns90DegreesAndRefusesTooFar) {
  ControllerConfig config = loadControllerConfig(configPath("solo12"));
  config.robots_dirs = {STRIDE_ROBOT_PACKAGES};
  drive::Options o;
  o.duration = 6.0;
  ScriptedCommand forward = entry(1.0, "stand"), turn = entry(2.5, "stand"),
                  far = entry(4.0, "stand");
  forward.jump_id = 2;
  forward.jump.dx = 0.3;
  turn.jump_id = 4;
  turn.jump.yaw = 1.57;
  far.jump_id = 6;
  far.jump.dx = 0.5;
  o.script = {entry(0.0, "stand"), forward, entry(1.5, "stand"), turn,
              entry(3.0, "stand"), far,     entry(4.5, "stand")};
  const drive::Run r = drive::run(config, o);
  ASSERT_FALSE(r.fell());
  ASSERT_EQ(r.jumps.size(), 3u);
  for (const logs::JumpOutcome& j : r.jumps)
    std::printf("jump #%d: %s\n", j.id, logs::describe(j).c_str());
  EXPECT_EQ(r.jumps[0].id, 2);
  EXPECT_EQ(r.jumps[0].state, 3);  // landed
  EXPECT_EQ(r.jumps[1].state, 3);
  EXPECT_EQ(r.jumps[2].state, 4);  // refused
  EXPECT_EQ(r.jumps[2].refusal,
            "a jump of 0.50 m is beyond the robot's reach (jump.max_distance 0.30 m)");
  // Where each went, from the ask to the end of its landing (jump.landing after the touch-down).
  const drive::Run::Motion a = r.motion(r.jumps[0].t, r.jumps[0].t_landed + config.jump.landing);
  const drive::Run::Motion b = r.motion(r.jumps[1].t, r.jumps[1].t_landed + config.jump.landing);
  ASSERT_TRUE(a.valid && b.valid);
  std::printf("forward: %+.3f %+.3f m, %+.1f deg; turn: %+.3f %+.3f m, %+.1f deg\n", a.dx, a.dy,
              a.yaw * 180 / M_PI, b.dx, b.dy, b.yaw * 180 / M_PI);
  EXPECT_LT(std::hypot(a.dx - 0.3, a.dy), 0.05);
  EXPECT_LT(std::abs(b.yaw - 1.57), 10.0 * M_PI / 180.0);
  EXPECT_LT(std::hypot(b.dx, b.dy), 0.05);
  // The refused one left the robot where it stood.
  const drive::Run::Motion c = r.motion(r.jumps[2].t, o.duration - 0.01);
  ASSERT_TRUE(c.valid);
  EXPECT_LT(std::hypot(c.dx, c.dy), 0.02);
  EXPECT_EQ(r.mpc.fallbacks, 0);
}

}  // namespace test_flight
}  // namespace stride
