// The controller lost and restarted (issue 19): the controller dies while the robot walks, the
// robot stands down on its own (sim/README.md, "Controller loss"), and a new controller started a
// second later takes it over from where it stands and walks it on. Lock-step in one process: the
// kill is the controller node destroyed between two periods, the restart a fresh node (its own
// source id, start-up solve from the measured state). Deterministic; the real-time version is
// tools/faults.sh.
#include <gtest/gtest.h>

#include <cstdio>

#include "controller_cases.hpp"
#include "tools/drive/closed_loop.hpp"
#include "tools/log/segments.hpp"

namespace stride {
namespace test_controller_loss {

using drive::tiltDeg;

struct Outcome {
  bool fell = false;
  double max_tilt = 0.0, z_min = 1e9, progress_after = 0.0;
  drive::Run run;
  logs::Recovery recovery;
};

// Walks `gait` at vx from `walk_at`, kills the controller at `kill`, restarts it 1 s later and
// runs `after` more seconds. progress_after: forward distance over the last `after` / 2 seconds.
// From 2 s after the restart on, the robot also turns at yaw_rate: a command segment after the
// fault that it must track (issue 33: recovery, logs::recovery).
Outcome killAndRestart(const ControllerConfig& config, const char* gait, double vx, double yaw_rate,
                       double walk_at, double kill, double after) {
  drive::Options o;
  o.duration = kill + 1.0 + after;
  o.controller_lost_at = kill;
  o.controller_back_after = 1.0;
  o.script.resize(3);  // stand from 0 s, then the gait, then turning too
  o.script[1].at = walk_at;
  o.script[1].gait = gait;
  o.script[1].vx = vx;
  o.script[2] = o.script[1];
  o.script[2].at = kill + 1.0 + 2.0;
  o.script[2].yaw_rate = yaw_rate;
  Outcome out;
  out.run = drive::run(config, o);
  out.recovery = logs::recovery(out.run.segments(), out.run.baseSamples(), kill + 1.0);
  out.fell = out.run.fell();
  const double t_half = o.duration - 0.5 * after;
  double x_half = 0.0;
  for (const drive::Sample& s : out.run.samples) {
    out.max_tilt = std::max(out.max_tilt, tiltDeg(s.q));
    out.z_min = std::min(out.z_min, s.q[2]);
    if (s.t <= t_half) x_half = s.q[0];
  }
  out.progress_after = out.run.q_end[0] - x_half;
  return out;
}

// Kills spread over one gait cycle (every phase of the feet), a restart 1 s after each: the
// robot stands down without falling or tilting past max_tilt_deg, the new controller is followed,
// and walks it forward again at three quarters of the command or better (min_progress over the last
// after / 2 seconds: it went on at the commanded speed in 40 kills of the quadruped's trot and 10
// of the humanoid's walk, sim/README.md "Controller loss").
void kills(int n, const char* robot, const char* gait, double vx, double yaw_rate, double walk_at,
           double cycle, double after, double min_progress, double max_tilt_deg) {
  const ControllerConfig config = loadControllerConfig(controller_cases::configPath(robot));
  const double first_kill = walk_at + 1.5;  // walking at vx by then
  int falls = 0;
  for (int i = 0; i < n; ++i) {
    const double kill = first_kill + cycle * i / n + 0.0013 * i;  // off the period's grid too
    const Outcome o = killAndRestart(config, gait, vx, yaw_rate, walk_at, kill, after);
    const sim::SimNodeStats& s = o.run.sim;
    std::printf(
        "%s killed at %.4f s: %s, tilt max %.1f deg, base min %.3f m, %.3f m forward in the last "
        "%.1f s; %lld steps standing down, %lld past a policy's end; %s, command tracked %.2f s "
        "after the restart\n",
        robot, kill, o.fell ? "FELL" : "up", o.max_tilt, o.z_min, o.progress_after, 0.5 * after,
        static_cast<long long>(s.stand_down_steps), static_cast<long long>(s.exhausted_steps),
        o.recovery.recovered ? "recovered" : "NOT recovered", o.recovery.time_to_tracking);
    falls += o.fell;
    EXPECT_FALSE(o.fell) << "killed at " << kill;
    EXPECT_LT(o.max_tilt, max_tilt_deg) << "killed at " << kill;
    EXPECT_EQ(o.run.controller_starts, 2);
    EXPECT_EQ(s.stand_downs, 1) << "killed at " << kill;         // lost once, and only then
    EXPECT_GT(s.stand_down_steps, 800) << "killed at " << kill;  // most of the silent second
    EXPECT_EQ(s.source_switches, 1) << "the new controller is followed";
    EXPECT_EQ(s.policies_rival, 0);
    EXPECT_GT(o.progress_after, min_progress) << "walks on after the restart, killed at " << kill;
    // Control came back: the turn that starts 2 s after the restart tracked, and the command in
    // force within 2 s of the restart.
    EXPECT_EQ(o.recovery.segments_after, 1) << "killed at " << kill;
    EXPECT_TRUE(o.recovery.recovered) << "killed at " << kill;
    EXPECT_GE(o.recovery.time_to_tracking, 0.0) << "killed at " << kill;
    EXPECT_LE(o.recovery.time_to_tracking, 2.0) << "killed at " << kill;
  }
  EXPECT_EQ(falls, 0);
}

// The controller killed and never back (5 s): the stand-down alone holds the robot up for good,
// level within max_tilt_deg, at every phase of the gait. (In real time a restarted controller
// can take 2-3 s to take over; a humanoid whose stand-down leaned back slowly fell then.)
void standDownsForGood(int n, const char* robot, const char* gait, double vx, double walk_at,
                       double cycle, double max_tilt_deg) {
  const ControllerConfig config = loadControllerConfig(controller_cases::configPath(robot));
  const double first_kill = walk_at + 1.5;
  for (int i = 0; i < n; ++i) {
    const double kill = first_kill + cycle * i / n + 0.0013 * i;
    drive::Options o;
    o.duration = kill + 5.0;
    o.controller_lost_at = kill;
    o.controller_back_after = 100.0;  // never, in this run
    o.script.resize(2);
    o.script[1].at = walk_at;
    o.script[1].gait = gait;
    o.script[1].vx = vx;
    const drive::Run r = drive::run(config, o);
    double max_tilt = 0.0, tilt_last = 0.0;
    for (const drive::Sample& s : r.samples) {
      max_tilt = std::max(max_tilt, tiltDeg(s.q));
      if (s.t > o.duration - 1.0) tilt_last = std::max(tilt_last, tiltDeg(s.q));
    }
    std::printf(
        "%s killed at %.4f s, no controller for 5 s: %s, tilt max %.1f deg, %.1f in the "
        "last second\n",
        robot, kill, r.fell() ? "FELL" : "up", max_tilt, tilt_last);
    EXPECT_FALSE(r.fell()) << "killed at " << kill;
    EXPECT_LT(max_tilt, max_tilt_deg) << "killed at " << kill;
    EXPECT_LT(tilt_last, 3.0) << "level at the end, killed at " << kill;
    EXPECT_EQ(r.controller_starts, 1);
    EXPECT_EQ(r.sim.stand_downs, 1);
    EXPECT_GT(r.sim.stand_down_steps, 4800);
  }
}

TEST(ControllerLoss, QuadrupedStandsDownForGoodAtTenKills) {
  standDownsForGood(10, "stride_quad", "trot", 0.5, 1.0, 0.4, 10.0);
}

TEST(ControllerLoss, HumanoidStandsDownForGoodAtTenKills) {
  standDownsForGood(10, "stride_humanoid", "walk", 0.2, 1.0, 1.0, 10.0);
}

// The ten-kill tests repeat the one-kill path at every phase of the feet: under the sanitizers
// they take 10 and 15 minutes, so tools/test.sh --sanitize runs this one kill instead (label
// sanitize_slow, tests/CMakeLists.txt; tests/README.md, "Sanitizers").
TEST(ControllerLoss, QuadrupedTrottingSurvivesAKillAndRestart) {
  kills(1, "stride_quad", "trot", 0.5, 0.3, 1.0, 0.4, 4.5, 0.8, 10.0);
}

TEST(ControllerLoss, QuadrupedTrottingSurvivesTenKillsAndRestarts) {
  // stride_quad's trot: a 0.4 s cycle; 0.5 m/s forward.
  kills(10, "stride_quad", "trot", 0.5, 0.3, 1.0, 0.4, 4.5, 0.8, 10.0);
}

TEST(ControllerLoss, HumanoidWalkingSurvivesTenKillsAndRestarts) {
  // stride_humanoid's walk: see its controller YAML for the cycle; 0.2 m/s forward.
  kills(10, "stride_humanoid", "walk", 0.2, 0.2, 1.0, 1.0, 4.5, 0.3, 10.0);
}

}  // namespace test_controller_loss
}  // namespace stride
