// The closed loop in lock-step, in one process (memq): the mock robot plays the in-house robots,
// the controller keeps them up. Physics is asserted, not exact numbers: base height and tilt within
// bounds, feet really lifting, progress forward, recovery after a push.
#include <gtest/gtest.h>
#include <stdlib.h>

#include "controller_cases.hpp"
#include "messages/signing.hpp"
#include "tools/drive/closed_loop.hpp"

namespace stride {
namespace test_closed_loop {

using drive::tiltDeg;

drive::Run run(const ControllerConfig& config, const sim::SimNodeOptions& sim, double duration,
               const std::vector<ScriptedCommand>& script = {}) {
  drive::Options o;
  o.sim = sim;
  o.duration = duration;
  o.script = script;
  return drive::run(config, o);
}

// Stands 5 s, trots in place, then forward at 0.3 m/s from 7.5 s.
TEST(ClosedLoop, QuadrupedStandsThenTrots) {
  ControllerConfig config = loadControllerConfig(controller_cases::configPath("stride_quad"));
  std::vector<ScriptedCommand> script(3);  // script[0]: stand from 0 s
  script[1].at = 5.0;
  script[1].gait = "trot";
  script[2] = script[1];
  script[2].at = 7.5;
  script[2].vx = 0.3;
  const drive::Run r = run(config, sim::SimNodeOptions{}, 10.0, script);
  ASSERT_FALSE(r.sim.fell);
  ASSERT_NEAR(r.samples.back().t, 10.0 - 0.005, 1e-9);
  const double z0 = r.samples.front().q[2];
  double drift_standing = 0.0, max_tilt = 0.0, z_min = 1e9, z_max = -1e9;
  int fewer_feet = 0;
  for (const drive::Sample& s : r.samples) {
    if (s.t < 4.0)
      drift_standing = std::max(drift_standing, (s.q.head<3>() - r.samples[0].q.head<3>()).norm());
    max_tilt = std::max(max_tilt, tiltDeg(s.q));
    z_min = std::min(z_min, s.q[2]);
    z_max = std::max(z_max, s.q[2]);
    if (s.t > 5.2) fewer_feet += s.feet_down <= 2;
    EXPECT_EQ(s.policy_status, 0) << "t " << s.t;
  }
  EXPECT_LT(drift_standing, 0.002);  // standing is standing, before the trot
  EXPECT_LT(max_tilt, 10.0);
  EXPECT_GT(z_min, z0 - 0.05);
  EXPECT_LT(z_max, z0 + 0.03);
  EXPECT_GT(fewer_feet, 200) << "the trot lifts two feet at a time";
  // 0.3 m/s from 7.5 s (reached at the acceleration limit within 0.6 s): ~0.6 m by 10 s.
  EXPECT_GT(r.q_end[0] - r.samples.front().q[0], 0.45) << "walks forward after 7.5 s";
  EXPECT_EQ(r.sim.policies_rejected, 0);
  EXPECT_EQ(r.sim.hold_steps, 0);
  EXPECT_EQ(r.mpc.fallbacks, 0);
  EXPECT_EQ(r.rejected, 0);
}

// A shove on the standing robot's base (no command: it stands): it must absorb it and settle back.
TEST(ClosedLoop, QuadrupedRecoversFromAPush) {
  ControllerConfig config = loadControllerConfig(controller_cases::configPath("stride_quad"));
  sim::SimNodeOptions o;
  sim::Push push;
  push.start = 1.0;
  push.duration = 0.1;
  push.force = Eigen::Vector3d(0.0, 15.0, 0.0);  // 1.5 N s on 2.5 kg: 0.6 m/s sideways
  o.pushes.pushes.push_back(push);
  const drive::Run r = run(config, o, 3.0);
  ASSERT_FALSE(r.sim.fell);
  double moved = 0.0;
  for (const drive::Sample& s : r.samples)
    moved = std::max(moved, std::abs(s.q[1] - r.samples[0].q[1]));
  EXPECT_GT(moved, 0.005) << "the push must move the robot";
  const drive::Sample& end = r.samples.back();
  EXPECT_LT(tiltDeg(end.q), 2.0);
  EXPECT_NEAR(end.q[2], r.samples[0].q[2], 0.01);
  EXPECT_LT(end.v.head<6>().norm(), 0.05) << "settled";
}

// Estimates as a real robot's: joint noise, a period of delay, 10% dropped. The robot still trots.
TEST(ClosedLoop, QuadrupedTrotsWithNoiseDelayAndDrops) {
  ControllerConfig config = loadControllerConfig(controller_cases::configPath("stride_quad"));
  std::vector<ScriptedCommand> script(2);
  script[1].at = 0.5;
  script[1].gait = "trot";
  script[1].vx = 0.2;
  sim::SimNodeOptions o;
  o.sensing.encoder_noise = 0.002;  // rad
  o.sensing.joint_velocity_noise = o.sensing.base_velocity_noise = o.sensing.gyro_noise = 0.02;
  o.delay = 1;  // one controller period late
  o.drop = 0.1;
  o.seed = 7;
  const drive::Run r = run(config, o, 4.0, script);
  ASSERT_FALSE(r.sim.fell);
  EXPECT_GT(r.sim.states_dropped, 40);
  double max_tilt = 0.0;
  for (const drive::Sample& s : r.samples) max_tilt = std::max(max_tilt, tiltDeg(s.q));
  EXPECT_LT(max_tilt, 10.0);
  EXPECT_EQ(r.sim.policies_rejected, 0);
}

// Issue 33: with signing on (the robot, its controller and the commands share a key), a rival
// without the key changes nothing even where the source rule would have let it take the robot
// (a source timeout of 0: the newest policy wins): its policies are refused unread. Signing
// itself changes nothing on the robot (bit for bit the unsigned run). A second controller WITH
// the key is the source rule's case again: refused while the first speaks, followed if the rule
// lets it (the rule's risks: sim/README.md, "Rival").
TEST(ClosedLoop, WithSigningARivalWithoutTheKeyCannotTakeTheRobot) {
  char dir[] = "/tmp/stride-key-XXXXXX";
  ASSERT_NE(mkdtemp(dir), nullptr);
  const std::string key = std::string(dir) + "/key";
  msg::writeNewKeyFile(key);
  const ControllerConfig config = loadControllerConfig(controller_cases::configPath("stride_quad"));
  ControllerConfig keyed = config;
  keyed.key_file = key;
  ControllerConfig trotting = config;  // no key
  trotting.gait.plan_file = std::string(STRIDE_CONFIG_DIR) + "/plans/quad_trot_then_stand.yaml";
  drive::Options o;
  // Five drives, three of them with two controllers: 1.5 s each (about 300 ticks) shows every
  // count below and keeps the test under a minute and a half with the sanitizers (issue 43).
  o.duration = 1.5;
  const drive::Run plain = drive::run(config, o);
  const drive::Run alone = drive::run(keyed, o);
  ASSERT_EQ(alone.samples.size(), plain.samples.size());
  for (std::size_t i = 0; i < plain.samples.size(); ++i)
    ASSERT_EQ(alone.samples[i].q, plain.samples[i].q) << "signed, t " << plain.samples[i].t;
  o.rival = &trotting;
  o.sim.source_timeout = 0.0;  // the weakest rule: the newest policy wins
  const drive::Run rivalled = drive::run(keyed, o);
  ASSERT_EQ(rivalled.samples.size(), alone.samples.size());
  for (std::size_t i = 0; i < alone.samples.size(); ++i)
    ASSERT_EQ(rivalled.samples[i].q, alone.samples[i].q) << "t " << alone.samples[i].t;
  EXPECT_GT(rivalled.sim.policies_unauthenticated, 200);  // ~ one per tick, refused unread
  EXPECT_EQ(rivalled.sim.policies_rival, 0);
  EXPECT_EQ(rivalled.sim.source_switches, 0);
  EXPECT_EQ(rivalled.rival_policies, 0) << "nor is it a rival to the robot's controller";

  ControllerConfig trotting_keyed = trotting;  // a second controller with the key
  trotting_keyed.key_file = key;
  o.rival = &trotting_keyed;
  o.sim.source_timeout = sim::SimNodeOptions().source_timeout;
  const drive::Run second = drive::run(keyed, o);
  for (std::size_t i = 0; i < alone.samples.size(); ++i)
    ASSERT_EQ(second.samples[i].q, alone.samples[i].q) << "t " << alone.samples[i].t;
  EXPECT_GT(second.sim.policies_rival, 200);  // refused by the source rule
  EXPECT_EQ(second.sim.policies_unauthenticated, 0);
  o.sim.source_timeout = 0.0;
  const drive::Run taken = drive::run(keyed, o);
  int lifted = 0;
  for (const drive::Sample& s : taken.samples) lifted += s.t > 0.2 && s.feet_down < 4;
  EXPECT_GT(lifted, 20) << "with the key and no rule, the second controller moves the feet";
}

}  // namespace test_closed_loop
}  // namespace stride

namespace stride {
namespace test_closed_loop {

// The humanoid stands, then walks forward at 0.2 m/s on its soles (lock-step, memq).
TEST(ClosedLoop, HumanoidStandsAndSteps) {
  ControllerConfig config = loadControllerConfig(controller_cases::configPath("stride_humanoid"));
  std::vector<ScriptedCommand> script(2);
  script[1].at = 1.0;
  script[1].gait = "walk";
  script[1].vx = 0.2;
  const drive::Run r = run(config, sim::SimNodeOptions{}, 5.0, script);
  ASSERT_FALSE(r.sim.fell);
  const double z0 = r.samples.front().q[2];
  double max_tilt = 0.0, z_min = 1e9;
  int single_support = 0;
  for (const drive::Sample& s : r.samples) {
    max_tilt = std::max(max_tilt, tiltDeg(s.q));
    z_min = std::min(z_min, s.q[2]);
    single_support += s.feet_down == 1;
  }
  EXPECT_LT(max_tilt, 10.0);
  EXPECT_GT(z_min, z0 - 0.05);
  EXPECT_GT(single_support, 50) << "steps lift one foot at a time (samples at 50 Hz)";
  // 0.2 m/s from 1 s, reached at 0.5 m/s² within 0.4 s: ~0.7 m by 5 s.
  EXPECT_GT(r.q_end[0] - r.samples.front().q[0], 0.5) << "walks forward";
  EXPECT_EQ(r.sim.policies_rejected, 0);
  EXPECT_EQ(r.mpc.fallbacks, 0);
}

// One controller per robot (issue 19): a rival controller on the same policy channel, planning a
// trot while the robot's own keeps it standing, changes nothing on the robot: the run is bit for
// bit the run without it, and both sides notice. Following the newest policy instead (a source
// timeout of 0) lets the rival take the robot over: its feet lift.
TEST(ClosedLoop, ARivalControllerChangesNothingOnTheRobot) {
  const ControllerConfig config = loadControllerConfig(controller_cases::configPath("stride_quad"));
  ControllerConfig trotting = config;
  trotting.gait.plan_file = std::string(STRIDE_CONFIG_DIR) + "/plans/quad_trot_then_stand.yaml";
  drive::Options o;
  o.duration = 2.5;
  const drive::Run alone = drive::run(config, o);
  o.rival = &trotting;
  const drive::Run rivalled = drive::run(config, o);
  ASSERT_EQ(rivalled.samples.size(), alone.samples.size());
  for (std::size_t i = 0; i < alone.samples.size(); ++i)
    ASSERT_EQ(rivalled.samples[i].q, alone.samples[i].q) << "t " << alone.samples[i].t;
  EXPECT_FALSE(rivalled.fell());
  EXPECT_GT(rivalled.sim.policies_rival, 200);  // ~ one per tick, refused
  EXPECT_EQ(rivalled.sim.policies_rejected, rivalled.sim.policies_rival);
  EXPECT_EQ(rivalled.sim.source_switches, 0);
  EXPECT_GT(rivalled.rival_policies, 200);  // the robot's controller saw the rival's policies
  int lifted = 0;  // after the first instants (the feet settle onto the ground)
  for (const drive::Sample& s : alone.samples) lifted += s.t > 0.2 && s.feet_down < 4;
  EXPECT_EQ(lifted, 0) << "the robot's controller keeps it standing";

  o.sim.source_timeout = 0.0;  // the newest policy wins: the rival's trot reaches the robot
  const drive::Run taken = drive::run(config, o);
  lifted = 0;
  for (const drive::Sample& s : taken.samples) lifted += s.t > 0.2 && s.feet_down < 4;
  EXPECT_GT(lifted, 20) << "without the rule the rival's plan moves the feet";
}

}  // namespace test_closed_loop
}  // namespace stride
