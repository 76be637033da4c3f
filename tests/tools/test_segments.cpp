// Command segments (tools/log/segments.hpp) on synthetic sessions: the heading-frame velocity, the
// split into runs of identical commands, the averages after the settling time, falls, and the
// tracking check's tolerances.
#include <gtest/gtest.h>

#include <cmath>

#include "tools/log/segments.hpp"

namespace stride::logs {
namespace test_segments {

// q of a base at (x, y, z) turned by yaw about z, then pitched by pitch about its own y axis.
std::array<double, 7> pose(double x, double y, double z, double yaw, double pitch = 0.0) {
  const double cy = std::cos(yaw / 2), sy = std::sin(yaw / 2);
  const double cp = std::cos(pitch / 2), sp = std::sin(pitch / 2);
  // (0, 0, sy, cy) * (0, sp, 0, cp), quaternions x y z w
  return {x, y, z, -sy * sp, cy * sp, sy * cp, cy * cp};
}

BaseSample sample(double t, const std::array<double, 7>& q, const std::array<double, 6>& v) {
  BaseSample s;
  s.t = t;
  s.q = q;
  s.v = v;
  return s;
}

CommandSample command(double t, double vx, double vy, double yaw_rate, const std::string& gait,
                      double body_height = 0.0) {
  CommandSample c;
  c.t = t;
  c.vx = vx;
  c.vy = vy;
  c.yaw_rate = yaw_rate;
  c.gait = gait;
  c.body_height = body_height;
  return c;
}

// Commands as stride-teleop sends them: the same command repeated at 20 Hz between changes. Times
// are computed, not accumulated, so boundaries fall exactly on whole seconds.
void repeat(std::vector<CommandSample>& out, const CommandSample& c, double until) {
  for (int k = 0; c.t + k / 20.0 < until - 1e-9; ++k) {
    CommandSample next = c;
    next.t = c.t + k / 20.0;
    out.push_back(next);
  }
}

// A base that follows (vx, vy, yaw_rate) in its heading frame exactly, from state to state.
struct KinematicBase {
  double x = 0, y = 0, z = 0.3, yaw = 0;
  void step(double dt, double vx, double vy, double w) {
    x += (std::cos(yaw) * vx - std::sin(yaw) * vy) * dt;
    y += (std::sin(yaw) * vx + std::cos(yaw) * vy) * dt;
    yaw += w * dt;
  }
};

TEST(Segments, HeadingVelocityOfAStraightLine) {
  // Facing +x and facing +y, walking forward: 0.5 m/s forward in the heading frame either way.
  for (double yaw_angle : {0.0, M_PI / 2, -2.5}) {
    const auto h = headingVelocity(sample(0, pose(1, 2, 0.3, yaw_angle), {0.5, 0, 0, 0, 0, 0}));
    EXPECT_NEAR(h[0], 0.5, 1e-12) << yaw_angle;
    EXPECT_NEAR(h[1], 0.0, 1e-12) << yaw_angle;
    EXPECT_NEAR(h[2], 0.0, 1e-12) << yaw_angle;
  }
  // Sideways in the base frame is sideways in the heading frame.
  const auto side = headingVelocity(sample(0, pose(0, 0, 0.3, 1.0), {0, -0.2, 0, 0, 0, 0}));
  EXPECT_NEAR(side[0], 0.0, 1e-12);
  EXPECT_NEAR(side[1], -0.2, 1e-12);
}

TEST(Segments, HeadingFrameIgnoresPitch) {
  // Pitched 0.3 rad nose-down, moving along its own x axis: the world velocity points into the
  // ground, and its horizontal part, forward in the heading frame, is v cos(pitch).
  const double pitch = 0.3, yaw_angle = 0.7;
  const BaseSample s = sample(0, pose(0, 0, 0.3, yaw_angle, pitch), {0.5, 0, 0, 0, 0, 0});
  const auto h = headingVelocity(s);
  EXPECT_NEAR(h[0], 0.5 * std::cos(pitch), 1e-12);
  EXPECT_NEAR(h[1], 0.0, 1e-12);
  EXPECT_NEAR(yaw(s.q), yaw_angle, 1e-12);
  EXPECT_NEAR(tilt(s.q), pitch, 1e-12);
}

TEST(Segments, PureTurnAtOneRadianPerSecondHasAConstantHeadingVelocity) {
  // 0.5 m/s forward while turning at 1 rad/s for 2π s: the world velocity goes once around the
  // circle (its mean is ~0), the heading-frame velocity stays (0.5, 0, 1).
  std::vector<BaseSample> states;
  KinematicBase base;
  const double dt = 0.01;
  double world_vx_sum = 0.0;
  for (int i = 0; i * dt < 1.0 + 2 * M_PI; ++i) {
    const BaseSample s =
        sample(i * dt, pose(base.x, base.y, base.z, base.yaw), {0.5, 0, 0, 0, 0, 1.0});
    states.push_back(s);
    if (s.t >= 1.0) world_vx_sum += 0.5 * std::cos(base.yaw);
    const auto h = headingVelocity(s);
    ASSERT_NEAR(h[0], 0.5, 1e-12);
    ASSERT_NEAR(h[1], 0.0, 1e-12);
    ASSERT_NEAR(h[2], 1.0, 1e-12);
    base.step(dt, 0.5, 0.0, 1.0);
  }
  const auto segments = segmentCommands({command(0.0, 0.5, 0.0, 1.0, "trot")}, states);
  ASSERT_EQ(segments.size(), 1u);
  const Segment& s = segments[0];
  EXPECT_GT(s.samples, 600);
  EXPECT_NEAR(s.achieved[0], 0.5, 1e-12);
  EXPECT_NEAR(s.achieved[1], 0.0, 1e-12);
  EXPECT_NEAR(s.achieved[2], 1.0, 1e-12);
  EXPECT_NEAR(world_vx_sum / s.samples, 0.0, 0.01);  // what a world-frame average would report
  EXPECT_FALSE(s.fell);
  EXPECT_TRUE(checkTracking(segments, {}).empty());
}

// Stand 2 s, walk forward 4 s, walk and turn 3 s: a robot that tracks exactly after a 0.3 s lag.
struct Session {
  std::vector<CommandSample> commands;
  std::vector<BaseSample> states;
};
Session threeSegments(double lag = 0.3, double gain = 1.0) {
  Session s;
  repeat(s.commands, command(0.0, 0, 0, 0, "stand"), 2.0);
  repeat(s.commands, command(2.0, 0.5, 0, 0, "trot"), 6.0);
  repeat(s.commands, command(6.0, 0.5, 0, 0.8, "trot"), 9.0);
  KinematicBase base;
  const double dt = 0.005;
  for (int i = 0; i <= 1800; ++i) {
    const double t = i / 200.0;
    const double tc = t - lag;  // the command the robot follows now
    const double vx = tc >= 2.0 ? 0.5 * gain : 0.0, w = tc >= 6.0 ? 0.8 * gain : 0.0;
    s.states.push_back(sample(t, pose(base.x, base.y, base.z, base.yaw), {vx, 0, 0, 0, 0, w}));
    base.step(dt, vx, 0.0, w);
  }
  return s;
}

TEST(Segments, OneSegmentPerRunOfIdenticalCommands) {
  const Session session = threeSegments();
  const auto segments = segmentCommands(session.commands, session.states);
  ASSERT_EQ(segments.size(), 3u);
  EXPECT_DOUBLE_EQ(segments[0].t0, 0.0);
  EXPECT_DOUBLE_EQ(segments[0].t1, segments[1].t0);
  EXPECT_NEAR(segments[1].t0, 2.0, 1e-9);
  EXPECT_NEAR(segments[2].t0, 6.0, 1e-9);
  EXPECT_DOUBLE_EQ(segments[2].t1, 9.0);  // the last state
  EXPECT_EQ(segments[0].commands, 40);
  EXPECT_EQ(segments[1].commands, 80);
  EXPECT_EQ(segments[0].gait, "stand");
  EXPECT_EQ(segments[2].gait, "trot");
  EXPECT_EQ(segments[2].command, (std::array<double, 3>{0.5, 0, 0.8}));
  // Averaged from t0 + 1 s: the 0.3 s lag is outside the average.
  EXPECT_EQ(segments[1].samples, 600);  // [3, 6) at 200 Hz
  EXPECT_EQ(segments[2].samples, 401);  // [7, 9], the last state included
  for (const Segment& s : segments) {
    for (int j = 0; j < 3; ++j) EXPECT_NEAR(s.achieved[j], s.command[j], 1e-12);
    EXPECT_FALSE(s.fell);
  }
  EXPECT_TRUE(checkTracking(segments, {}).empty());
}

TEST(Segments, AChangeOfGaitOrBodyHeightAloneStartsASegment) {
  const std::vector<CommandSample> commands = {
      command(0.0, 0, 0, 0, "stand"), command(0.05, 0, 0, 0, "stand"),
      command(0.1, 0, 0, 0, "trot"), command(0.15, 0, 0, 0, "trot", 0.02),
      command(0.2, 0, 0, 0, "trot", 0.02)};
  const auto segments = segmentCommands(commands, {});
  ASSERT_EQ(segments.size(), 3u);
  EXPECT_EQ(segments[2].body_height, 0.02);
  EXPECT_EQ(segments[2].commands, 2);
  EXPECT_EQ(segments[2].samples, 0);
  // No states: the last segment ends where it starts, never before.
  EXPECT_DOUBLE_EQ(segments[2].t1, segments[2].t0);
}

TEST(Segments, ASegmentWithAFall) {
  // The robot trots in place, then drops to a third of its height 1 s into the second segment
  // and stays there: that segment and the later one fell, the first did not.
  Session s;
  repeat(s.commands, command(0.0, 0, 0, 0, "trot"), 3.0);
  repeat(s.commands, command(3.0, 0.3, 0, 0, "trot"), 6.0);
  repeat(s.commands, command(6.0, 0, 0, 0, "stand"), 9.0);
  for (int i = 0; i <= 900; ++i) {
    const double t = i / 100.0;
    const double z = t < 4.0 ? 0.3 : 0.1;
    s.states.push_back(sample(t, pose(0, 0, z, 0), {0, 0, 0, 0, 0, 0}));
  }
  const auto segments = segmentCommands(s.commands, s.states);
  ASSERT_EQ(segments.size(), 3u);
  EXPECT_FALSE(segments[0].fell);
  EXPECT_TRUE(segments[1].fell);
  EXPECT_TRUE(segments[2].fell);
  const auto misses = checkTracking(segments, {});
  // Segment 1: fell, and vx 0 instead of 0.3. Segment 2: fell, its zero velocity tracked.
  ASSERT_EQ(misses.size(), 3u);
  EXPECT_EQ(misses[0].segment, 1);
  EXPECT_EQ(misses[0].kind, TrackingMiss::Kind::Fell);
  EXPECT_EQ(misses[1].segment, 1);
  EXPECT_EQ(misses[1].kind, TrackingMiss::Kind::Component);
  EXPECT_EQ(misses[1].component, 0);
  EXPECT_DOUBLE_EQ(misses[1].commanded, 0.3);
  EXPECT_DOUBLE_EQ(misses[1].achieved, 0.0);
  EXPECT_DOUBLE_EQ(misses[1].tolerance, 0.05);
  EXPECT_EQ(misses[2].segment, 2);
  EXPECT_EQ(misses[2].kind, TrackingMiss::Kind::Fell);
}

TEST(Segments, FallByTilt) {
  const FallLimits limits;  // 50 % of the first height, 60 degrees
  EXPECT_FALSE(fallen(sample(0, pose(0, 0, 0.3, 2.0, 1.0), {}), 0.3, limits));  // 57 degrees
  EXPECT_TRUE(fallen(sample(0, pose(0, 0, 0.3, 2.0, 1.1), {}), 0.3, limits));   // 63 degrees
  EXPECT_TRUE(fallen(sample(0, pose(0, 0, 0.149, 0.0), {}), 0.3, limits));
}

TEST(Segments, TrackingTolerances) {
  // The relative tolerance (15 %) above the floors, the floors (0.05 m/s, 0.1 rad/s) below them.
  Segment s;
  s.t0 = 0.0;
  s.t1 = 3.0;
  s.samples = 100;
  s.command = {1.0, 0.1, -1.0};
  s.achieved = {0.86, 0.149, -0.86};  // errors 0.14 < 0.15, 0.049 < 0.05, 0.14 < 0.15
  EXPECT_TRUE(checkTracking({s}, {}).empty());
  s.achieved = {0.84, 0.151, -1.16};
  const auto misses = checkTracking({s}, {});
  ASSERT_EQ(misses.size(), 3u);
  for (int j = 0; j < 3; ++j) EXPECT_EQ(misses[j].component, j);
  EXPECT_NEAR(misses[0].tolerance, 0.15, 1e-12);
  EXPECT_NEAR(misses[1].tolerance, 0.05, 1e-12);
  EXPECT_NEAR(misses[2].tolerance, 0.15, 1e-12);
  EXPECT_STREQ(componentName(2), "yaw_rate");
  // Zero yaw command: the 0.1 rad/s floor.
  s.command = {0, 0, 0};
  s.achieved = {0.0, 0.0, 0.099};
  EXPECT_TRUE(checkTracking({s}, {}).empty());
  s.achieved = {0.0, 0.0, -0.101};
  EXPECT_EQ(checkTracking({s}, {}).size(), 1u);
  // Shorter than 2 s: not checked. Long enough without any state: a miss of its own kind.
  s.t1 = 1.9;
  EXPECT_TRUE(checkTracking({s}, {}).empty());
  s.t1 = 3.0;
  s.samples = 0;
  const auto none = checkTracking({s}, {});
  ASSERT_EQ(none.size(), 1u);
  EXPECT_EQ(none[0].kind, TrackingMiss::Kind::NoSamples);
}

TEST(Segments, ARobotThatFallsShortOfItsCommandMissesIt) {
  // 80 % of the commanded velocities: vx 0.4 for 0.5 (error 0.1 > 0.075), yaw 0.64 for 0.8.
  const Session session = threeSegments(0.3, 0.8);
  const auto segments = segmentCommands(session.commands, session.states);
  const auto misses = checkTracking(segments, {});
  ASSERT_EQ(misses.size(), 3u);
  EXPECT_EQ(misses[0].segment, 1);
  EXPECT_EQ(misses[0].component, 0);
  EXPECT_EQ(misses[1].segment, 2);
  EXPECT_EQ(misses[1].component, 0);
  EXPECT_EQ(misses[2].segment, 2);
  EXPECT_EQ(misses[2].component, 2);
  EXPECT_NEAR(misses[2].achieved, 0.64, 1e-12);
}

// Issue 33's recovery: forward 0.5 m/s for 4 s, turn for 4 s, sidestep for 4 s; a fault from 0.5
// to 1.5 s stops the robot until `back` (or for good). The robot otherwise follows exactly.
Session faultSession(double back) {
  Session s;
  repeat(s.commands, command(0.0, 0.5, 0, 0, "trot"), 4.0);
  repeat(s.commands, command(4.0, 0, 0, 1.0, "trot"), 8.0);
  repeat(s.commands, command(8.0, 0, 0.25, 0, "trot"), 12.0);
  KinematicBase base;
  const double dt = 0.005;
  for (int i = 0; i <= 2400; ++i) {
    const double t = i / 200.0;
    const bool stopped = t >= 0.5 && t < back;
    const double vx = stopped || t >= 4.0 ? 0.0 : 0.5,
                 w = !stopped && t >= 4.0 && t < 8.0 ? 1.0 : 0.0,
                 vy = !stopped && t >= 8.0 ? 0.25 : 0.0;
    s.states.push_back(sample(t, pose(base.x, base.y, base.z, base.yaw), {vx, vy, 0, 0, 0, w}));
    base.step(dt, vx, vy, w);
  }
  return s;
}

TEST(Recovery, ControlBackSoonAfterTheFault) {
  const Session session = faultSession(2.1);
  const auto segments = segmentCommands(session.commands, session.states);
  const Recovery r = recovery(segments, session.states, 1.5);
  EXPECT_EQ(r.segments_after, 2);  // the turn and the sidestep start 2 s or more after 1.5 s
  EXPECT_EQ(r.missed_after, 0);
  EXPECT_TRUE(r.recovered);
  // The first 1 s window that averages within 0.075 m/s of 0.5: 0.5 (t + 1 - 2.1) >= 0.425.
  EXPECT_NEAR(r.time_to_tracking, 1.95 - 1.5, 0.006);
  // The forward segment itself, which holds the fault, misses: surviving is not the criterion.
  EXPECT_FALSE(checkTracking(segments).empty());
}

TEST(Recovery, ARobotThatNeverMovesAgainDidNotRecover) {
  const Session session = faultSession(1e9);
  const Recovery r =
      recovery(segmentCommands(session.commands, session.states), session.states, 1.5);
  EXPECT_EQ(r.segments_after, 2);
  EXPECT_EQ(r.missed_after, 2);
  EXPECT_FALSE(r.recovered);
  EXPECT_LT(r.time_to_tracking, 0.0);
}

TEST(Recovery, NoSegmentAfterTheFaultJudgesNothing) {
  const Session session = faultSession(2.1);
  const Recovery r =
      recovery(segmentCommands(session.commands, session.states), session.states, 9.0);
  EXPECT_EQ(r.segments_after, 0);
  EXPECT_FALSE(r.recovered) << "no segment to show it";
  EXPECT_NEAR(r.time_to_tracking, 0.0, 1e-9) << "the sidestep tracks from the fault's end on";
}

}  // namespace test_segments
}  // namespace stride::logs
