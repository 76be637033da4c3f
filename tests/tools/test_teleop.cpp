// stride-teleop's logic without a terminal or LCM: the keys (arrow escape sequences included, in
// any chunking) and the script player on the robot's clock.
#include <gtest/gtest.h>

#include <cstdint>
#include <set>

#include "tools/teleop/keyboard_command.hpp"
#include "tools/teleop/script_player.hpp"

namespace stride::teleop {
namespace test_teleop {

using Event = KeyboardCommand::Event;

const std::string kUp = "\x1b[A", kDown = "\x1b[B", kRight = "\x1b[C", kLeft = "\x1b[D";

TEST(KeyboardCommand, LettersAndArrowsStepTheVelocities) {
  KeyboardCommand k(GaitSet::Quadruped, {});
  EXPECT_EQ(k.feed("w"), Event::Changed);
  EXPECT_EQ(k.feed(kUp), Event::Changed);
  EXPECT_EQ(k.feed("W"), Event::Changed);
  EXPECT_NEAR(k.command().vx, 0.3, 1e-12);
  EXPECT_EQ(k.feed("s" + kDown), Event::Changed);
  EXPECT_NEAR(k.command().vx, 0.1, 1e-12);
  EXPECT_EQ(k.feed("a"), Event::Changed);  // left
  EXPECT_NEAR(k.command().vy, 0.05, 1e-12);
  EXPECT_EQ(k.feed("dd"), Event::Changed);
  EXPECT_NEAR(k.command().vy, -0.05, 1e-12);
  EXPECT_EQ(k.feed(kLeft), Event::Changed);  // turn left: counter-clockwise, positive
  EXPECT_NEAR(k.command().yaw_rate, 0.2, 1e-12);
  EXPECT_EQ(k.feed("q"), Event::Changed);
  EXPECT_NEAR(k.command().yaw_rate, 0.4, 1e-12);
  EXPECT_EQ(k.feed(kRight + "e" + "e"), Event::Changed);
  EXPECT_NEAR(k.command().yaw_rate, -0.2, 1e-12);
  EXPECT_EQ(k.feed("r"), Event::Changed);
  EXPECT_NEAR(k.command().body_height, 0.01, 1e-12);
  EXPECT_EQ(k.feed("ff"), Event::Changed);
  EXPECT_NEAR(k.command().body_height, -0.01, 1e-12);
  EXPECT_EQ(k.command().gait, "trot");  // the first velocity key left the stand
}

TEST(KeyboardCommand, ValuesStopAtTheirLimits) {
  KeyboardLimits limits;
  limits.max_vx = 0.35;
  KeyboardCommand k(GaitSet::Quadruped, limits);
  for (int i = 0; i < 20; ++i) k.feed("w");
  EXPECT_DOUBLE_EQ(k.command().vx, 0.35);
  EXPECT_EQ(k.feed("w"), Event::None);  // no change at the limit
  for (int i = 0; i < 20; ++i) k.feed("s" + kLeft + "d" + "f");
  EXPECT_DOUBLE_EQ(k.command().vx, -0.35);
  EXPECT_DOUBLE_EQ(k.command().vy, -0.5);
  EXPECT_DOUBLE_EQ(k.command().yaw_rate, 1.5);
  EXPECT_DOUBLE_EQ(k.command().body_height, -0.1);
}

TEST(KeyboardCommand, StepsBackToZeroShowNoNegativeZero) {
  KeyboardCommand k(GaitSet::Quadruped, {});
  k.feed("www");  // 0.1 + 0.1 + 0.1 is not 0.3 in floating point
  k.feed("sss");
  EXPECT_EQ(k.command().vx, 0.0);
  k.feed("ss");
  k.feed("ww");
  EXPECT_EQ(k.command().vx, 0.0);
  EXPECT_EQ(statusLine(k.command(), 0).substr(0, 14), "trot  vx +0.00");
}

TEST(KeyboardCommand, EscapeSequencesInAnyChunking) {
  KeyboardCommand k(GaitSet::Quadruped, {});
  // An arrow split across three reads.
  EXPECT_EQ(k.feed("\x1b"), Event::None);
  EXPECT_EQ(k.feed("["), Event::None);
  EXPECT_EQ(k.feed("A"), Event::Changed);
  EXPECT_NEAR(k.command().vx, 0.1, 1e-12);
  // Application cursor mode (ESC O A) and a modified arrow (Ctrl+Up: ESC [ 1 ; 5 A).
  k.feed("\x1bOA");
  k.feed("\x1b[1;5A");
  EXPECT_NEAR(k.command().vx, 0.3, 1e-12);
  // Sequences of other keys (Delete: ESC [ 3 ~, F1: ESC O P) do nothing, and the "A" inside them
  // is not the A key.
  EXPECT_EQ(k.feed("\x1b[3~\x1bOP\x1b[1;2P"), Event::None);
  EXPECT_EQ(k.command().vy, 0.0);
  // The Escape key alone, then a letter: the letter counts.
  EXPECT_EQ(k.feed("\x1b"), Event::None);
  EXPECT_EQ(k.feed("a"), Event::Changed);
  EXPECT_NEAR(k.command().vy, 0.05, 1e-12);
  // Two arrows and a letter in one read.
  k.feed(kDown + kDown + "w");
  EXPECT_NEAR(k.command().vx, 0.2, 1e-12);
}

TEST(KeyboardCommand, NumberKeysChooseTheRobotsGaits) {
  KeyboardCommand quad(GaitSet::Quadruped, {});
  EXPECT_EQ(quad.feed("2"), Event::Changed);
  EXPECT_EQ(quad.command().gait, "trot");
  EXPECT_EQ(quad.feed("2"), Event::None);
  quad.feed("3");
  EXPECT_EQ(quad.command().gait, "walk");
  quad.feed("4");
  EXPECT_EQ(quad.command().gait, "pace");
  quad.feed("5");  // the gaits with flights (issue 45)
  EXPECT_EQ(quad.command().gait, "pronk");
  quad.feed("6");
  EXPECT_EQ(quad.command().gait, "bound");
  quad.feed("7");
  EXPECT_EQ(quad.command().gait, "flying_trot");
  EXPECT_EQ(quad.feed("8"), Event::None);
  quad.feed("1");
  EXPECT_EQ(quad.command().gait, "stand");

  KeyboardCommand biped(GaitSet::Biped, {});
  EXPECT_EQ(biped.feed("2"), Event::Changed);
  EXPECT_EQ(biped.command().gait, "walk");
  EXPECT_EQ(biped.feed("3"), Event::Changed);
  EXPECT_EQ(biped.command().gait, "hop");
  EXPECT_EQ(biped.feed("4"), Event::None);
  EXPECT_EQ(biped.command().gait, "hop");
}

TEST(KeyboardCommand, SpaceStopsButKeepsTheHeight) {
  KeyboardCommand k(GaitSet::Quadruped, {});
  k.feed("2wwaqr");
  EXPECT_EQ(k.feed(" "), Event::Changed);
  EXPECT_EQ(k.command().vx, 0.0);
  EXPECT_EQ(k.command().vy, 0.0);
  EXPECT_EQ(k.command().yaw_rate, 0.0);
  EXPECT_EQ(k.command().gait, "stand");
  EXPECT_NEAR(k.command().body_height, 0.01, 1e-12);
  EXPECT_EQ(k.feed(" "), Event::None);
}

TEST(KeyboardCommand, XAndCtrlCQuitWithAStop) {
  for (const std::string quit : {"x", "X", "\x03"}) {
    KeyboardCommand k(GaitSet::Quadruped, {});
    k.feed("2ww");
    // The keys after the quit key in the same read are ignored.
    EXPECT_EQ(k.feed("d" + quit + "wwww"), Event::Quit);
    EXPECT_EQ(k.command().vx, 0.0);
    EXPECT_EQ(k.command().vy, 0.0);
    EXPECT_EQ(k.command().gait, "stand");
  }
  KeyboardCommand k(GaitSet::Quadruped, {});
  EXPECT_EQ(k.feed("zZ?\t\r\n0"), Event::None);  // unknown keys
}

TEST(KeyboardCommand, StatusLine) {
  TeleopCommand c;
  c.gait = "trot";
  c.vx = 0.5;
  EXPECT_EQ(statusLine(c, 123),
            "trot  vx +0.50 m/s  vy +0.00 m/s  yaw +0.00 rad/s  height +0.00 m  [sent 123]");
  c.gait = "stand";
  c.vy = -0.05;
  c.yaw_rate = -1.5;
  c.body_height = 0.1;
  EXPECT_EQ(statusLine(c, 0),
            "stand vx +0.50 m/s  vy -0.05 m/s  yaw -1.50 rad/s  height +0.10 m  [sent 0]");
}

// ---- the script player
// ----------------------------------------------------------------------------

std::vector<ScriptedCommand> demoScript() {
  std::vector<ScriptedCommand> s(4);
  s[0].at = 0.0;
  s[1].at = 2.0;
  s[1].gait = "trot";
  s[1].vx = 0.5;
  s[2].at = 6.0;
  s[2].gait = "trot";
  s[2].vx = 0.5;
  s[2].yaw_rate = 1.0;
  s[3].at = 9.0;
  s[3].body_height = 0.02;
  return s;
}

struct Played {
  std::vector<ScriptPlayer::Step> sent;  // the steps that published
  std::vector<std::int64_t> done;        // stamps of script_done steps
};

// States at 1 kHz of robot time from an arbitrary clock origin.
Played play(ScriptPlayer& p, std::int64_t utime0, int states, std::int64_t dt_us = 1000) {
  Played out;
  for (int i = 0; i < states; ++i) {
    const auto step = p.onState(utime0 + i * dt_us);
    if (step.publish) out.sent.push_back(step);
    if (step.script_done) out.done.push_back(utime0 + i * dt_us);
  }
  return out;
}

TEST(ScriptPlayer, AnswersStatesAtTheRateWithTheEntryInForceAndTheirStamps) {
  ScriptPlayer p(demoScript(), {20.0, 1.0, 0.0});
  const std::int64_t t0 = 5000000;
  const Played out = play(p, t0, 12000);
  const std::vector<ScriptedCommand> script = demoScript();
  ASSERT_EQ(out.sent.size(), 240u);  // 12 s at 20 Hz
  for (std::size_t k = 0; k < out.sent.size(); ++k) {
    const auto& c = out.sent[k].command;
    ASSERT_EQ(c.utime, t0 + static_cast<std::int64_t>(k) * 50000);  // a state's stamp
    const double t = k / 20.0;
    const int entry = t < 2.0 ? 0 : t < 6.0 ? 1 : t < 9.0 ? 2 : 3;
    ASSERT_EQ(out.sent[k].entry, entry) << t;
    const ScriptedCommand& e = script[entry];
    EXPECT_EQ(c.vx, e.vx);
    EXPECT_EQ(c.vy, e.vy);
    EXPECT_EQ(c.yaw_rate, e.yaw_rate);
    EXPECT_EQ(c.gait, e.gait);
    EXPECT_EQ(c.body_height, e.body_height);
    // The first command of each entry is flagged (stride-teleop prints it): exactly on time.
    EXPECT_EQ(out.sent[k].entry_started, k == 0 || k == 40 || k == 120 || k == 180) << k;
  }
  // Done once, at 9 + 1 s, then the last entry goes on.
  ASSERT_EQ(out.done.size(), 1u);
  EXPECT_EQ(out.done[0], t0 + 10000000);
  EXPECT_EQ(out.sent.back().entry, 3);
  EXPECT_FALSE(p.finished());
  EXPECT_EQ(p.states(), 12000);
  EXPECT_EQ(p.published(), 240);
  EXPECT_DOUBLE_EQ(p.time(), 11.999);
}

TEST(ScriptPlayer, OnlyStateStampsCount) {
  // Irregular stamps (a real-time robot's jitter, or a lock-step sim's): at most one command per
  // 50 ms grid interval of robot time, and one in every interval that has a state.
  ScriptPlayer p(demoScript(), {20.0, 1.0, 0.0});
  std::int64_t u = 0;
  std::vector<std::int64_t> sent;
  for (int i = 0; i < 5000; ++i) {
    u += 900 + (i * 7919) % 250;  // 0.9 - 1.15 ms steps
    if (p.onState(u).publish) sent.push_back(u);
  }
  const std::int64_t t0 = 900;  // the first state
  std::set<std::int64_t> intervals;
  for (std::int64_t s : sent) EXPECT_TRUE(intervals.insert((s - t0) / 50000).second) << s;
  EXPECT_EQ(static_cast<std::int64_t>(intervals.size()), (u - t0) / 50000 + 1);
  // Sparser states than the rate: every state is answered.
  ScriptPlayer sparse(demoScript(), {20.0, 1.0, 0.0});
  EXPECT_EQ(play(sparse, 0, 50, 100000).sent.size(), 50u);
}

TEST(ScriptPlayer, IgnoresStampsThatDoNotIncrease) {
  ScriptPlayer p(demoScript(), {20.0, 1.0, 0.0});
  EXPECT_TRUE(p.onState(1000000).publish);
  EXPECT_FALSE(p.onState(1000000).publish);
  EXPECT_FALSE(p.onState(900000).publish);
  EXPECT_EQ(p.outOfOrder(), 2);
  EXPECT_TRUE(p.onState(1050000).publish);
  EXPECT_DOUBLE_EQ(p.time(), 0.05);
}

TEST(ScriptPlayer, StopsAfterTheDurationOfRobotTime) {
  ScriptPlayer p(demoScript(), {20.0, 1.0, 4.5});
  const Played out = play(p, 123456, 6000);
  ASSERT_EQ(out.sent.size(), 90u);  // t = 0, 0.05, ... 4.45
  EXPECT_EQ(out.sent.back().command.utime, 123456 + 4450000);
  EXPECT_TRUE(p.finished());
  EXPECT_EQ(p.states(), 4501);  // the state at 4.5 s finished it
  EXPECT_FALSE(p.onState(999999999).publish);
  // A duration equal to the script's length: the last state still says the script is done.
  ScriptPlayer q(demoScript(), {20.0, 1.0, 10.0});
  const Played to_end = play(q, 0, 11000);
  EXPECT_EQ(to_end.sent.size(), 200u);
  ASSERT_EQ(to_end.done.size(), 1u);
  EXPECT_EQ(to_end.done[0], 10000000);
  EXPECT_TRUE(q.finished());
}

TEST(ScriptPlayer, ShortEntriesAndALateFirstEntry) {
  // Entry 1 lasts 10 ms: between two commands at 20 Hz, never sent. The first entry starts at
  // 0.5 s, but is in force from the first state (commandAt).
  std::vector<ScriptedCommand> s(3);
  s[0].at = 0.5;
  s[0].gait = "trot";
  s[1].at = 1.01;
  s[1].vx = 0.2;
  s[2].at = 1.02;
  s[2].vx = 0.3;
  ScriptPlayer p(s, {20.0, 0.5, 0.0});
  const Played out = play(p, 0, 2000);
  ASSERT_EQ(out.sent.size(), 40u);
  EXPECT_EQ(out.sent[0].entry, 0);
  EXPECT_EQ(out.sent[0].command.gait, "trot");
  EXPECT_EQ(out.sent[20].entry, 0);  // 1.00 s
  EXPECT_EQ(out.sent[21].entry, 2);  // 1.05 s
  EXPECT_TRUE(out.sent[21].entry_started);
  EXPECT_DOUBLE_EQ(out.sent[21].command.vx, 0.3);
  ASSERT_EQ(out.done.size(), 1u);
  EXPECT_EQ(out.done[0], 1520000);
  EXPECT_DOUBLE_EQ(p.end(), 1.52);
}

TEST(ScriptPlayer, RejectsAnEmptyScriptAndABadRate) {
  EXPECT_THROW(ScriptPlayer({}, {}), std::invalid_argument);
  EXPECT_THROW(ScriptPlayer(demoScript(), {0.0, 1.0, 0.0}), std::invalid_argument);
}

}  // namespace test_teleop
}  // namespace stride::teleop
