// The robot leaves the ground (issue 45), closed loop (drive::run, lock-step, memq): solo12 pronks
// in place (every foot in the air at once, again and again), lands each time and stands again
// when the pronk ends. Without flights in the timeline, a base reference of their own and zero
// torque in the air, it never left the ground (every knot had a foot down).
//
// The flight's pieces alone: ContactTimeline.PerFootSwitchNeverCutsASwing,
// GaitGenerator.FlightsFollowTheBallisticArc (tests/locomotion/test_gait_generator.cpp),
// LocomotionProblem.FlightHoldsAPostureWithZeroTorque and
// LocomotionSolve.FlightKnotsConserveCentroidalMomentum (tests/locomotion/test_locomotion.cpp).

#include <gtest/gtest.h>

#include <algorithm>
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

}  // namespace test_flight
}  // namespace stride
