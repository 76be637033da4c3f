// Faults around a healthy controller (issue 19), each in lock-step in one process, so each outcome
// is deterministic: the quadruped trots forward at 0.5 m/s while states go bad (NaN, stamps going
// back, a 1 s gap), another robot's policies flood the policy channel, or the mock robot itself is
// restarted. Each asserts that the robot did not fall, that it walks on, and the counters that
// say the fault was seen. The controller killed and restarted: test_controller_loss.cpp; a rival
// controller: test_closed_loop.cpp; drops, delay and noise: ClosedLoop.QuadrupedTrotsWith...
#include <gtest/gtest.h>

#include <cstdio>

#include <cmath>
#include <limits>

#include "controller_cases.hpp"
#include "drive_cases.hpp"
#include "tools/drive/closed_loop.hpp"
#include "tools/log/segments.hpp"

namespace stride {
namespace {

using drive::tiltDeg;

// Stand, trot from 1 s, forward at 0.5 m/s from 2 s, for `duration` seconds.
drive::Options trotForward(double duration) {
  return drive_cases::trotForward(duration, 1.0, 2.0);
}

// Issue 33: surviving is not recovering. trotForward, then from 2 s after the fault's end a turn
// while trotting on (0.3 rad/s) for 2.5 s: a command segment that starts after the fault, which
// the robot must track (logs::recovery).
drive::Options recoveryDrive(double fault_end) {
  drive::Options o = trotForward(fault_end + 4.5);
  o.script.push_back(o.script.back());
  o.script.back().at = fault_end + 2.0;
  o.script.back().yaw_rate = 0.3;
  return o;
}

// Control came back: every segment starting 2 s after the fault's end tracked (there is one at
// least), and the command in force tracked within 2 s of the fault's end.
void expectRecovered(const drive::Run& r, double fault_end) {
  const logs::Recovery rec = logs::recovery(r.segments(), r.baseSamples(), fault_end);
  std::printf("recovery after %.2f s: %d of %d segments tracked, command tracked %.2f s after\n",
              fault_end, rec.segments_after - rec.missed_after, rec.segments_after,
              rec.time_to_tracking);
  EXPECT_GE(rec.segments_after, 1);
  EXPECT_TRUE(rec.recovered);
  EXPECT_GE(rec.time_to_tracking, 0.0);
  EXPECT_LE(rec.time_to_tracking, 2.0);
}

ControllerConfig quad() {
  return loadControllerConfig(controller_cases::configPath("stride_quad"));
}

// Forward distance over the samples in [t0, t1].
double progress(const drive::Run& r, double t0, double t1) {
  double x0 = std::numeric_limits<double>::quiet_NaN(), x1 = x0;
  for (const drive::Sample& s : r.samples) {
    if (std::isnan(x0) && s.t >= t0) x0 = s.q[0];
    if (s.t <= t1) x1 = s.q[0];
  }
  return x1 - x0;
}

double maxTilt(const drive::Run& r) {
  double tilt = 0.0;
  for (const drive::Sample& s : r.samples) tilt = std::max(tilt, tiltDeg(s.q));
  return tilt;
}

// Every third state from 3 s to 5 s carries a NaN: refused (counted), the robot trots on, on the
// policies of the good states in between.
TEST(Faults, NaNStatesAreRefusedAndTheRobotTrotsOn) {
  drive::Options o = recoveryDrive(5.0);
  int spoiled = 0;
  o.state_fault = [&spoiled, n = 0](robot_state_t& m, double t) mutable {
    if (t >= 3.0 && t < 5.0 && n++ % 3 == 0) {
      m.v[4] = std::numeric_limits<double>::quiet_NaN();
      ++spoiled;
    }
    return true;
  };
  const drive::Run r = drive::run(quad(), o);
  EXPECT_FALSE(r.fell());
  EXPECT_GT(spoiled, 100);
  EXPECT_EQ(r.rejected, spoiled) << "each NaN state refused, no other";
  EXPECT_LT(maxTilt(r), 15.0);
  EXPECT_GT(progress(r, 3.0, 5.0), 0.8) << "walks on at ~0.5 m/s through it";
  EXPECT_EQ(r.sim.stand_downs, 0) << "the good states' policies cover the bad ones";
  expectRecovered(r, 5.0);
}

// Every fourth state from 3 s to 5 s is stamped 50 ms in the past (an estimator's clock jumping
// back): refused as out of order, the robot trots on.
TEST(Faults, StampsGoingBackAreRefusedAndTheRobotTrotsOn) {
  drive::Options o = recoveryDrive(5.0);
  int old = 0;
  o.state_fault = [&old, n = 0](robot_state_t& m, double t) mutable {
    if (t >= 3.0 && t < 5.0 && n++ % 4 == 0) {
      m.utime -= 50000;
      ++old;
    }
    return true;
  };
  const drive::Run r = drive::run(quad(), o);
  EXPECT_FALSE(r.fell());
  EXPECT_GT(old, 80);
  EXPECT_EQ(r.rejected, old) << "each old stamp refused, no other";
  EXPECT_LT(maxTilt(r), 15.0);
  EXPECT_GT(progress(r, 3.0, 5.0), 0.8);
  EXPECT_EQ(r.sim.stand_downs, 0);
  expectRecovered(r, 5.0);
}

// No state at all from 3 s to 4 s (the estimator or the network stalled): the controller has
// nothing to answer, the policy runs out, the robot stands down; when states come back the
// controller, alive all along, plans from the robot as it is and trots on.
TEST(Faults, AOneSecondGapInTheStatesIsSurvived) {
  drive::Options o = recoveryDrive(4.0);
  o.state_fault = [](robot_state_t&, double t) { return !(t >= 3.0 && t < 4.0); };
  const drive::Run r = drive::run(quad(), o);
  EXPECT_FALSE(r.fell());
  EXPECT_EQ(r.sim.stand_downs, 1);
  EXPECT_GT(r.sim.stand_down_steps, 800);
  EXPECT_GT(r.sim.states_dropped, 190);  // 200 periods of 5 ms
  EXPECT_LT(maxTilt(r), 15.0);
  std::printf("after the gap: tilt max %.1f deg, %.3f m in the last 2 s\n", maxTilt(r),
              progress(r, 6.0, 8.0));
  EXPECT_GT(progress(r, 6.0, 8.0), 0.8) << "trots on after the gap";
  expectRecovered(r, 4.0);
}

// 1000 policies a second of another robot's sizes (5 each 5 ms period, 23 kB each) arrive on the
// policy channel with the answers: every one refused on its raw bytes before any decoding, and
// the robot's run is bit for bit the run without the flood.
TEST(Faults, AFloodOfForeignPoliciesChangesNothingOnTheRobot) {
  drive::Options o = trotForward(5.0);
  const drive::Run calm = drive::run(quad(), o);
  o.flood_per_period = 5;
  const drive::Run flooded = drive::run(quad(), o);
  ASSERT_EQ(flooded.samples.size(), calm.samples.size());
  for (std::size_t i = 0; i < calm.samples.size(); ++i)
    ASSERT_EQ(flooded.samples[i].q, calm.samples[i].q) << "t " << calm.samples[i].t;
  EXPECT_FALSE(flooded.fell());
  const std::int64_t periods = static_cast<std::int64_t>(calm.samples.size());
  EXPECT_EQ(flooded.sim.policies_wrong_model, 5 * periods);
  EXPECT_EQ(flooded.sim.policies_rejected, 5 * periods);
  EXPECT_EQ(flooded.sim.policies, calm.sim.policies) << "no answer lost in the flood";
  expectRecovered(flooded, 0.0);  // the flood lasts the whole run
}

// The mock robot restarted (stride-sim killed at 3 s, back 1 s later with the robot standing at
// the origin, its clock going on): the controller, alive all along, takes the new robot as it
// comes and trots it forward.
TEST(Faults, TheMockRobotRestartedIsTakenOverByTheController) {
  drive::Options o = recoveryDrive(4.0);
  o.sim_lost_at = 3.0;
  const drive::Run r = drive::run(quad(), o);
  EXPECT_EQ(r.sim_starts, 2);
  EXPECT_FALSE(r.sim_before_restart.fell);
  EXPECT_FALSE(r.fell());
  EXPECT_LT(maxTilt(r), 15.0);
  EXPECT_GT(progress(r, 6.0, 8.0), 0.8) << "the new robot trots forward";
  expectRecovered(r, 4.0);
}

}  // namespace
}  // namespace stride
