// The controller core: configuration, plan files, ticks, fallbacks.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>

#include "controller/mpc.hpp"
#include "controller/mpc_node.hpp"
#include "controller_cases.hpp"
#include "sanitizers.hpp"

namespace stride {
namespace test_mpc {

using controller_cases::configPath;
using controller_cases::standingState;

TEST(ControllerConfig, ShippedConfigsLoad) {
  for (const char* robot :
       {"stride_quad", "stride_humanoid", "solo12", "anymal_c", "talos_reduced"}) {
    const ControllerConfig c = loadControllerConfig(configPath(robot));
    EXPECT_TRUE(std::filesystem::exists(c.robot_yaml)) << c.robot_yaml;
    EXPECT_GT(c.rate_hz, 0.0);
    EXPECT_EQ(c.solver, SolverKind::BoxFddp);
    EXPECT_TRUE(c.locomotion.torque_limits);
  }
}

std::string configError(const std::string& yaml) {
  const std::string path = ::testing::TempDir() + "/stride_bad_config.yaml";
  std::ofstream(path) << yaml;
  try {
    loadControllerConfig(path);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(ControllerConfig, ErrorsNameTheFileAndTheKey) {
  const std::string robot =
      "robot: " + std::string(STRIDE_CONFIG_DIR) + "/robots/stride_quad/stride_quad.yaml\n";
  EXPECT_NE(configError("rate_hz: 100\n").find("robot"), std::string::npos);
  EXPECT_NE(configError(robot + "rate_hz: -5\n").find("rate_hz"), std::string::npos);
  EXPECT_NE(configError(robot + "rate_hz: fast\n").find("rate_hz"), std::string::npos);
  EXPECT_NE(configError(robot + "horizon: {knots: 100, dtt: 0.01}\n").find("horizon.dtt"),
            std::string::npos);
  EXPECT_NE(configError(robot + "solver: {kind: newton}\n").find("solver.kind"), std::string::npos);
  EXPECT_NE(configError(robot + "gait: {gallop: {support: 0.1}}\n").find("gait.gallop"),
            std::string::npos);
  EXPECT_NE(configError(robot + "gait: {trot: {support: -0.1}}\n").find("gait.trot.support"),
            std::string::npos);
  EXPECT_NE(configError(robot + "command: {max_velocity: [1, 2]}\n").find("command.max_velocity"),
            std::string::npos);
  EXPECT_NE(configError(robot + "command: {timeout_ms: 0}\n").find("command.timeout_ms"),
            std::string::npos);
  EXPECT_NE(configError(robot + "safety: {fallback: pray}\n").find("safety.fallback"),
            std::string::npos);
  EXPECT_NE(configError(robot + "horizon: [1, 2\n").find("malformed"), std::string::npos);
  // Renamed when "jump" became a motion (issue 45): the old key says the new one.
  EXPECT_NE(configError(robot + "terrain: {jump_height: 0.03}\n").find("terrain.edge_height"),
            std::string::npos);
  EXPECT_EQ(configError(robot + "terrain: {edge_height: 0.03}\n"), "");
  EXPECT_EQ(configError(robot), "") << "a file with only the robot is valid (defaults)";
  EXPECT_NE(configError(robot + "rate_hz: -5\n").find("stride_bad_config.yaml"), std::string::npos);
  try {
    loadControllerConfig("/nonexistent/stride.yaml");
    FAIL() << "a missing file must throw";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/stride.yaml"), std::string::npos);
  }
}

// horizon.integrator: euler (the default) or rk4 for every contact knot of the horizon; anything
// else is refused naming the file, the key and the choices.
TEST(ControllerConfig, IntegratorKey) {
  const std::string robot =
      "robot: " + std::string(STRIDE_CONFIG_DIR) + "/robots/stride_quad/stride_quad.yaml\n";
  const std::string path = ::testing::TempDir() + "/stride_integrator_config.yaml";
  auto load = [&](const std::string& yaml) {
    std::ofstream(path) << robot << yaml;
    return loadControllerConfig(path);
  };
  EXPECT_EQ(load("").locomotion.integrator, Integrator::Euler);
  EXPECT_EQ(load("horizon: {knots: 50, dt: 0.01, integrator: euler}\n").locomotion.integrator,
            Integrator::Euler);
  const ControllerConfig rk4 = load("horizon: {knots: 50, dt: 0.01, integrator: rk4}\n");
  EXPECT_EQ(rk4.locomotion.integrator, Integrator::Rk4);
  EXPECT_NE(describeHorizon(rk4.locomotion).find("rk4"), std::string::npos);
  EXPECT_EQ(describeHorizon(load("").locomotion).find("rk4"), std::string::npos);
  // With a grid too.
  EXPECT_EQ(load("horizon: {grid: [{knots: 10, dt: 0.01}, {knots: 20, dt: 0.03}], "
                 "integrator: rk4}\n")
                .locomotion.integrator,
            Integrator::Rk4);
  for (const char* bad : {"rk5", "RK4", "[euler]"}) {
    const std::string e = configError(robot + "horizon: {integrator: " + bad + "}\n");
    EXPECT_NE(e.find("horizon.integrator"), std::string::npos) << e;
    EXPECT_NE(e.find("stride_bad_config.yaml"), std::string::npos) << e;
  }
  const std::string e = configError(robot + "horizon: {integrator: rk5}\n");
  EXPECT_NE(e.find("'rk5' is not one of euler, rk4"), std::string::npos) << e;
}

// The gaits' cyclic patterns: every one starts with all feet down (where the timeline switches),
// trot and pace lift pairs, walk one foot at a time; a biped walks, and cannot trot.
// Policies that need more than one UDP datagram are warned about at start, with the knots that fit
// (talos_reduced's 4 knots are 81 kB); not on a transport without datagrams.
TEST(MpcNode, PolicyLargerThanADatagramIsWarnedAbout) {
  const std::string udpm = "udpm://239.255.76.67:7667?ttl=0";
  EXPECT_EQ(policyDatagramWarning(30000, 8, udpm), "");
  EXPECT_EQ(policyDatagramWarning(81000, 8, "memq://"), "");
  const std::string w = policyDatagramWarning(81000, 8, udpm);
  EXPECT_NE(w.find("a policy is 81000 bytes (8 knots), more than one UDP datagram (65507)"),
            std::string::npos)
      << w;
  EXPECT_NE(w.find("policy_knots: 6 fits in one"), std::string::npos) << w;
}

// A plan file in the controller's YAML (the plan files themselves, locomotion/gait.hpp's
// loadContactPlan: tests/locomotion/test_gait.cpp) replaces the gaits; one that names feet the
// robot lacks is refused when the controller is made.
TEST(Mpc, TakesThePlanFileOfItsConfiguration) {
  ControllerConfig config = loadControllerConfig(configPath("stride_quad"));
  config.gait.plan_file = std::string(STRIDE_CONFIG_DIR) + "/plans/quad_trot_then_stand.yaml";
  Mpc mpc(config);
  robot_state_t s = standingState(mpc.robot(), 0);
  ASSERT_TRUE(mpc.tick(&s, 0.0, Mpc::Clock::time_point::max()));
  EXPECT_EQ(mpc.status().gait, "plan");
  const ContactTimeline& timeline = mpc.reference()->timeline();
  EXPECT_EQ(timeline.pattern(timeline.patternAt(0.0)).phases(), 14);
  // Its own file: test_gait's runs beside it under ctest -j.
  const std::string bad = ::testing::TempDir() + "/stride_plan_with_other_feet.yaml";
  std::ofstream(bad) << "phases:\n  - {duration: 1, contacts: [L_sole]}\n";
  config.gait.plan_file = bad;
  EXPECT_THROW(Mpc{config}, ConfigError);
}

// A plan replaces the gaits (a gait asked for is ignored) while the command still sets the
// velocity: the base reference moves at it, and the footholds with it.
TEST(Mpc, PlanKeepsTheCommandVelocity) {
  ControllerConfig config = loadControllerConfig(configPath("stride_quad"));
  config.gait.plan_file = std::string(STRIDE_CONFIG_DIR) + "/plans/quad_trot_then_stand.yaml";
  Mpc mpc(config);
  BodyCommand walk;
  walk.vx = 0.3;
  mpc.setCommand(walk, 3);  // and "pace", which the plan overrides
  robot_state_t s = standingState(mpc.robot(), 1000000);
  ASSERT_TRUE(mpc.tick(&s, 0.0, Mpc::Clock::time_point::max()));
  const GaitGenerator& ref = *mpc.reference();
  EXPECT_EQ(mpc.status().gait, "plan");
  EXPECT_EQ(ref.timeline().patternAt(1.0), ref.timeline().lastPattern());
  EXPECT_NEAR(ref.basePosition(1.0).x() - ref.basePosition(0.0).x(), 0.3, 1e-9);
  EXPECT_NEAR(mpc.status().command[0], 0.3, 1e-12);
  // FL lifts at 1.1 s in the plan and lands at 1.3 s, ahead of where it stood.
  int fl = 0;
  for (int i = 0; i < ref.stances(fl); ++i)
    if (ref.stance(fl, i).touch_down > 1.0) {
      EXPECT_GT(ref.stance(fl, i).p.x(), ref.stance(fl, 0).p.x() + 0.1);
      break;
    }
}

// The footholds the gait generator chose go out with the horizon (issue 31): for a trot, each
// foot's touch-downs after the state and no later than the last knot, by contact then time, with
// the generator's positions and sources, their times after the state; none while standing; no
// more than the capacity the message was shaped with.
TEST(Mpc, HorizonCarriesTheChosenFootholds) {
  ControllerConfig config = loadControllerConfig(configPath("stride_quad"));
  Mpc mpc(config);
  const int nc = static_cast<int>(mpc.robot().contacts.size());
  const int nq = mpc.robot().model.nq;
  ASSERT_EQ(mpc.horizonFootholds(), msg::kHorizonFootholdsPerContact * nc);
  horizon_t h;
  msg::shape(h, mpc.horizonKnots(), nq, nc, mpc.horizonFootholds());
  robot_state_t s = standingState(mpc.robot(), 1000000);
  ASSERT_TRUE(mpc.tick(&s, 0.0, Mpc::Clock::time_point::max()));
  ASSERT_TRUE(mpc.writeHorizon(h));
  EXPECT_EQ(h.nfootholds, 0);  // standing: no touch-down planned

  BodyCommand walk;
  walk.vx = 0.3;
  mpc.setCommand(walk, 1);  // trot
  // The footholds the generator planned for the solve, found here from its stances.
  struct Expected {
    int contact;
    double dt;
    Eigen::Vector3d p;
    int source;
  };
  auto expected = [&]() {
    std::vector<Expected> e;
    const GaitGenerator& gen = *mpc.reference();
    const double t = mpc.status().plan_time;
    const double t_end = mpc.problem()->knotTimes()[h.knots - 1];
    for (int c = 0; c < nc; ++c) {
      int n = 0;
      for (int i = 0; i < gen.stances(c); ++i) {
        const GaitGenerator::Stance& st = gen.stance(c, i);
        if (st.touch_down > t && st.touch_down <= t_end && n < msg::kHorizonFootholdsPerContact) {
          e.push_back({c, st.touch_down - t, st.p, static_cast<int>(st.source)});
          ++n;
        }
      }
    }
    return e;
  };
  int checked = 0;
  for (int i = 0; i < 40; ++i) {
    s.utime += 5000;
    ASSERT_TRUE(mpc.tick(&s, 0.0, Mpc::Clock::time_point::max()));
    if (!mpc.writeHorizon(h)) continue;  // a rejected step: nothing written
    const std::vector<Expected> e = expected();
    ASSERT_EQ(h.nfootholds, static_cast<int>(e.size())) << "tick " << i;
    std::vector<int> per_contact(nc, 0);
    for (int k = 0; k < h.nfootholds; ++k) {
      EXPECT_EQ(h.foothold_contact[k], e[k].contact) << k;
      EXPECT_DOUBLE_EQ(h.foothold_time[k], e[k].dt) << k;
      EXPECT_GT(h.foothold_time[k], 0.0) << k;
      EXPECT_LE(h.foothold_time[k], h.t[h.knots - 1] + config.locomotion.dt) << k;
      for (int j = 0; j < 3; ++j) EXPECT_EQ(h.foothold[k][j], e[k].p[j]) << k << " " << j;
      EXPECT_EQ(h.foothold_source[k], e[k].source) << k;
      if (k > 0 && h.foothold_contact[k] == h.foothold_contact[k - 1]) {
        EXPECT_GT(h.foothold_time[k], h.foothold_time[k - 1]) << k;
      }
      if (k > 0) {
        EXPECT_GE(h.foothold_contact[k], h.foothold_contact[k - 1]) << k;
      }
      ++per_contact[h.foothold_contact[k]];
    }
    // A trot of 0.6 s cycles over a 1 s horizon: every foot lands at least once.
    for (int c = 0; c < nc; ++c) {
      EXPECT_GE(per_contact[c], 1) << "contact " << c << " tick " << i;
      EXPECT_LE(per_contact[c], msg::kHorizonFootholdsPerContact) << c;
    }
    ++checked;
  }
  EXPECT_GE(checked, 20);
  // Walking forward: the first foot's next foothold lies ahead of where it stands.
  ASSERT_GT(h.nfootholds, 0);
  EXPECT_GT(h.foothold[0][0], mpc.reference()->stance(0, 0).p.x());

  // A message shaped for fewer footholds gets the first ones, and says how many (after a tick
  // whose last step was accepted: a rejected one writes nothing, as above).
  horizon_t small;
  msg::shape(small, mpc.horizonKnots(), nq, nc, 3);
  for (int i = 0; i < 20 && !mpc.writeHorizon(h); ++i) {
    s.utime += 5000;
    ASSERT_TRUE(mpc.tick(&s, 0.0, Mpc::Clock::time_point::max()));
  }
  ASSERT_TRUE(mpc.writeHorizon(small));
  ASSERT_EQ(small.nfootholds, 3);
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(small.foothold_contact[k], h.foothold_contact[k]);
    EXPECT_EQ(small.foothold_time[k], h.foothold_time[k]);
    EXPECT_EQ(small.foothold[k], h.foothold[k]);
  }
}

// The controller around a robot that stands still: the first tick solves to convergence and
// publishes; the next ones shift and re-solve within their budget.
TEST(Mpc, StandingTicks) {
  ControllerConfig config = loadControllerConfig(configPath("stride_quad"));
  Mpc mpc(config);
  robot_state_t s = standingState(mpc.robot(), 1000000);
  EXPECT_FALSE(mpc.tick(nullptr, 0.0, Mpc::Clock::time_point::max()));
  EXPECT_EQ(mpc.status().policy_status, kPolicyNone);
  ASSERT_TRUE(mpc.tick(&s, 0.0, Mpc::Clock::time_point::max()));
  EXPECT_TRUE(mpc.startupTick());
  const policy_t& p = mpc.policy();
  EXPECT_EQ(p.status, kPolicySolved);
  EXPECT_EQ(p.utime, s.utime);
  EXPECT_EQ(msg::checkPolicy(p, true), msg::Reject::None);
  // Standing: the feed-forward carries the weight (hind and front knees both loaded).
  for (int k = 0; k < p.knots; ++k) EXPECT_GT(std::abs(p.u_ff[k][2]), 0.05);
  for (int i = 1; i <= 20; ++i) {
    s.utime += 5000;
    ASSERT_TRUE(mpc.tick(&s, 0.0, Mpc::Clock::time_point::max()));
    EXPECT_FALSE(mpc.startupTick());
    EXPECT_EQ(mpc.policy().status, kPolicySolved);
    EXPECT_EQ(mpc.status().iterations, 1);
  }
  EXPECT_NEAR(mpc.status().plan_time, 0.1, 1e-12);
  EXPECT_EQ(mpc.counters().fallbacks, 0);
}

// horizon.integrator: rk4 end to end: the controller's horizon integrates by RK4, and its ticks
// solve and publish as with Euler.
TEST(Mpc, StandingTicksWithRk4Knots) {
  ControllerConfig config = loadControllerConfig(configPath("stride_quad"));
  config.locomotion.integrator = Integrator::Rk4;
  Mpc mpc(config);
  robot_state_t s = standingState(mpc.robot(), 1000000);
  ASSERT_TRUE(mpc.tick(&s, 0.0, Mpc::Clock::time_point::max()));
  EXPECT_EQ(mpc.policy().status, kPolicySolved);
  EXPECT_EQ(msg::checkPolicy(mpc.policy(), true), msg::Reject::None);
  for (int i = 1; i <= 5; ++i) {
    s.utime += 5000;
    ASSERT_TRUE(mpc.tick(&s, 0.0, Mpc::Clock::time_point::max()));
    EXPECT_EQ(mpc.policy().status, kPolicySolved);
  }
  EXPECT_EQ(mpc.counters().fallbacks, 0);
}

// The tick answers with the iteration prepared after the last one when the state comes near the
// expected time, and linearizes again after the state when it does not (counted).
// One period of the real-time loop: the preparation for the next state, then the tick on that
// state, dt_us later.
bool preparedTick(Mpc& mpc, robot_state_t& s, std::int64_t dt_us,
                  Mpc::Clock::time_point deadline = Mpc::Clock::time_point::max()) {
  mpc.prepare(Mpc::Clock::time_point::max());
  s.utime += dt_us;
  return mpc.tick(&s, 0.0, deadline);
}

TEST(Mpc, PreparedTicksAndTheirFallback) {
  ControllerConfig config = loadControllerConfig(configPath("stride_quad"));
  Mpc mpc(config);
  const auto never = Mpc::Clock::time_point::max();
  robot_state_t s = standingState(mpc.robot(), 0);
  ASSERT_TRUE(mpc.tick(&s, 0.0, never));  // start-up: nothing prepared yet, not counted
  EXPECT_EQ(mpc.status().prepared, 0);
  for (int i = 0; i < 4; ++i) {  // on time: every tick prepared (200 Hz, knots of 10 ms)
    ASSERT_TRUE(preparedTick(mpc, s, 5000));
    EXPECT_EQ(mpc.status().prepared, 1) << i;
    EXPECT_GT(mpc.status().prepare_ms, 0.0);
    EXPECT_EQ(mpc.policy().status, kPolicySolved);
  }
  EXPECT_EQ(mpc.counters().unprepared_solves, 0);
  // One period late (a skipped tick): less than a knot from the prepared knot 0, still used.
  ASSERT_TRUE(preparedTick(mpc, s, 10000));
  EXPECT_EQ(mpc.status().prepared, 1);
  // Three knots late: the preparation is dropped and the tick shifts and solves after the state.
  ASSERT_TRUE(preparedTick(mpc, s, 30000));
  EXPECT_EQ(mpc.status().prepared, 0);
  EXPECT_EQ(mpc.counters().unprepared_solves, 1);
  EXPECT_EQ(mpc.status().unprepared_solves, 1);
  EXPECT_EQ(mpc.policy().status, kPolicySolved);
  // No preparation at all (the loop had no time for it): the same.
  s.utime += 5000;
  ASSERT_TRUE(mpc.tick(&s, 0.0, never));
  EXPECT_EQ(mpc.status().prepared, 0);
  EXPECT_EQ(mpc.counters().unprepared_solves, 2);
  // A preparation after a fallback tick does nothing (there is no solved iterate to go on from).
  s.utime += 5000;
  ASSERT_TRUE(mpc.tick(&s, 1.0, never));  // stale
  EXPECT_EQ(mpc.policy().status, kPolicyPrevious);
  ASSERT_TRUE(preparedTick(mpc, s, 5000));
  EXPECT_EQ(mpc.status().prepared, 0);
  EXPECT_EQ(mpc.counters().unprepared_solves, 3);
}

// Issue 33: a controller stopped for longer than its horizon (SIGSTOP, a host stall, a debugger)
// found a warm start its next state had left behind. The preparation gave up on it, every tick
// then shed for want of a preparation, and the controller answered with fallbacks for good. In
// real time (answers due soon after each tick, preparations until half a period after the next) the
// ticks must drive again (solved policies) within 2 s of the robot's time after the pause.
TEST(Mpc, AControllerStoppedLongerThanItsHorizonDrivesAgain) {
  ControllerConfig config = loadControllerConfig(configPath("stride_quad"));
  Mpc mpc(config);
  BodyCommand forward;
  forward.vx = 0.3;
  const auto& gaits = mpc.gaits();
  mpc.setCommand(forward,
                 static_cast<int>(std::find(gaits.begin(), gaits.end(), "trot") - gaits.begin()));
  robot_state_t s = standingState(mpc.robot(), 1000000);
  // The wall-clock budgets, longer under the sanitizers (the work is slower there, not the robot).
  constexpr int kSlow = test_support::kSanitizerSlowdown;
  const auto period = std::chrono::microseconds(5000 * kSlow);
  const auto tickRealTime = [&](std::int64_t dt_us) {
    s.utime += dt_us;
    const auto start = Mpc::Clock::now();
    // An answer due 1.5 ms after the tick's start: a prepared tick's rollout fits, a whole
    // iteration does not (as on a loaded host, where the pause was seen).
    const bool sent = mpc.tick(&s, 0.0, start + std::chrono::microseconds(1500 * kSlow));
    mpc.prepare(start + period + period / 2);
    return sent;
  };
  // Driving before the pause: most of the last 50 ticks solved (one tick of a loaded host may
  // re-send the previous policy: its answer was due 1.5 ms after it started).
  int solved_before = 0;
  for (int i = 0; i < 200; ++i)
    solved_before += tickRealTime(5000) && i >= 150 && mpc.policy().status == kPolicySolved;
  ASSERT_GE(solved_before, 40) << "of the 50 ticks before the pause";
  const std::int64_t fallbacks = mpc.counters().fallbacks;
  // 1.5 s without a tick, then the ticks go on.
  int solved_after = -1;
  for (int i = 0; i < 400 && solved_after < 0; ++i) {
    tickRealTime(i == 0 ? 1500000 : 5000);
    if (mpc.policy().status == kPolicySolved) solved_after = i;
  }
  ASSERT_GE(solved_after, 0) << "never solved again: " << mpc.counters().fallbacks - fallbacks
                             << " fallbacks";
  EXPECT_LE(solved_after, 5) << "ticks after the pause";
  int solved = 0;
  for (int i = 0; i < 100; ++i)
    solved += tickRealTime(5000) && mpc.policy().status == kPolicySolved;
  EXPECT_GE(solved, 90) << "and it keeps solving";
}

// A deadline is on the answer: a tick whose policy goes out after it is one miss, whether its
// solve stopped there or finished late; a tick on time is none.
TEST(Mpc, DeadlineMissesCountAnswersAfterTheDeadline) {
  ControllerConfig config = loadControllerConfig(configPath("stride_quad"));
  Mpc mpc(config);
  robot_state_t s = standingState(mpc.robot(), 0);
  const auto past = [] { return Mpc::Clock::now() - std::chrono::milliseconds(1); };
  // The start-up solve runs to convergence before the first policy, without a deadline (in real
  // time made again on newer states while it takes longer than a period, whatever the host's
  // speed: ALongStartUpSolveIsMadeAgain...; here it answers, as in lock-step).
  ASSERT_TRUE(mpc.tick(&s, 0.0, Mpc::Clock::time_point::max()));
  EXPECT_EQ(mpc.counters().deadline_misses, 0);
  ASSERT_TRUE(preparedTick(mpc, s, 5000));
  EXPECT_EQ(mpc.counters().deadline_misses, 0);
  // The deadline passed before the tick started (its state came in too late to answer on time).
  ASSERT_TRUE(preparedTick(mpc, s, 5000, past()));
  EXPECT_EQ(mpc.counters().deadline_misses, 1);
  EXPECT_EQ(mpc.status().deadline_misses, 1);
  // On time again: no new miss, and a late start the loop reports shows in the status.
  mpc.countLateTick();
  ASSERT_TRUE(preparedTick(mpc, s, 5000));
  EXPECT_EQ(mpc.counters().deadline_misses, 1);
  EXPECT_EQ(mpc.status().late_ticks, 1);
  // A tick the loop skipped is a miss.
  mpc.countSkippedTick();
  EXPECT_EQ(mpc.counters().deadline_misses, 2);
}

// In real time the start-up solve (to convergence, 0.1-0.8 s for the humanoid) answers for a state
// that old: its policy is not sent, and the next tick solves again, as a start-up, from that
// solution on the newer state, until one takes less than a period (at most kMaxStartupResolves
// times). In lock-step (no deadline) the first solve answers.
TEST(Mpc, ALongStartUpSolveIsMadeAgainOnTheNewestState) {
  const auto soon = [] { return Mpc::Clock::now() + std::chrono::milliseconds(5); };
  // Ticks in real time (deadlines 5 ms ahead, stride_quad's period), the robot's clock 50 ms
  // further at each; returns how many ticks it took to send a policy.
  const auto startUp = [&](Mpc& mpc, robot_state_t& s) {
    int ticks = 0;
    for (;;) {
      ++ticks;
      const bool sent = mpc.tick(&s, 0.0, soon());
      EXPECT_TRUE(mpc.startupTick()) << "no deadline, not a latency, not a miss";
      EXPECT_EQ(mpc.counters().startup_resolves, sent ? ticks - 1 : ticks);
      if (sent) return ticks;
      EXPECT_EQ(mpc.status().policy_status, kPolicyNone);
      if (ticks > Mpc::kMaxStartupResolves) return ticks;
      s.utime += 50000;
    }
  };
  {  // Every solve slowed down 100 times: each start-up solve takes longer than a period, and the
     // last one longer than half a policy (issue 33: it would reach the robot past its end): none
     // is sent, and the tick after them, a regular one bounded by its deadline, answers.
    ControllerConfig config = loadControllerConfig(configPath("stride_quad"));
    config.emulated_slowdown = 100.0;
    Mpc mpc(config);
    EXPECT_EQ(mpc.mode(), MpcMode::NotStarted);
    robot_state_t s = standingState(mpc.robot(), 1000000);
    for (int i = 0; i <= Mpc::kMaxStartupResolves; ++i) {
      EXPECT_FALSE(mpc.tick(&s, 0.0, soon())) << i;
      EXPECT_TRUE(mpc.startupTick()) << i;
      // The controller's mode (controller/README.md): made again while re-solves are left; past
      // them the answer is dropped and the next tick is a regular one.
      EXPECT_EQ(mpc.mode(),
                i < Mpc::kMaxStartupResolves ? MpcMode::ResolvingStartUp : MpcMode::Solving)
          << i;
      s.utime += 50000;
    }
    EXPECT_EQ(mpc.counters().startup_resolves, Mpc::kMaxStartupResolves + 1);
    ASSERT_TRUE(mpc.tick(&s, 0.0, soon()));
    EXPECT_FALSE(mpc.startupTick());
    EXPECT_EQ(mpc.mode(), MpcMode::Solving);
    EXPECT_EQ(mpc.policy().utime, s.utime);  // for the newest state
    EXPECT_EQ(mpc.counters().fallbacks, 0);
  }
  {  // At this host's speed: sent for the newest state, and the ticks go on as after any start.
    ControllerConfig config = loadControllerConfig(configPath("stride_quad"));
    Mpc mpc(config);
    robot_state_t s = standingState(mpc.robot(), 1000000);
    const int ticks = startUp(mpc, s);
    EXPECT_LE(ticks, Mpc::kMaxStartupResolves + 1);
    std::printf("stride_quad's start-up here: a policy at tick %d\n", ticks);
    if (mpc.policy().utime != s.utime) {
      // A host too slow for any start-up solve within half a policy (the sanitizers' 3-10x): the
      // last one is withheld too, and the next tick, a regular one, answers.
      EXPECT_TRUE(test_support::kAddressSanitizer)
          << "at this host's speed a start-up solve answers";
      EXPECT_EQ(ticks, Mpc::kMaxStartupResolves + 1);
      s.utime += 5000;
      ASSERT_TRUE(mpc.tick(&s, 0.0, Mpc::Clock::time_point::max()));
      EXPECT_FALSE(mpc.startupTick());
      EXPECT_EQ(mpc.policy().utime, s.utime);
    } else {
      EXPECT_EQ(mpc.policy().status, kPolicySolved);
      s.utime += 5000;
      ASSERT_TRUE(mpc.tick(&s, 0.0, Mpc::Clock::time_point::max()));
      EXPECT_FALSE(mpc.startupTick());
    }
  }
  {  // Lock-step (no deadline): the first solve answers.
    ControllerConfig config = loadControllerConfig(configPath("stride_quad"));
    Mpc mpc(config);
    robot_state_t s = standingState(mpc.robot(), 1000000);
    ASSERT_TRUE(mpc.tick(&s, 0.0, Mpc::Clock::time_point::max()));
    EXPECT_EQ(mpc.counters().startup_resolves, 0);
  }
}

// Runs of missed periods: all of them count in max_misses_in_a_row, and those without a host
// stall in max_own_misses_in_a_row (what the overload test bounds).
TEST(Mpc, MissRunsWithAHostStallAreTheHosts) {
  ControllerConfig config = loadControllerConfig(configPath("stride_quad"));
  Mpc mpc(config);
  const auto periods = [&](std::vector<std::pair<bool, bool>> missed_stalled) {
    for (const auto& [missed, stalled] : missed_stalled) mpc.countPeriod(missed, stalled);
  };
  periods({{true, false}, {false, false}, {true, false}, {false, true}});
  EXPECT_EQ(mpc.counters().max_misses_in_a_row, 1);
  EXPECT_EQ(mpc.counters().max_own_misses_in_a_row, 1);
  EXPECT_EQ(mpc.counters().host_stalls, 1);
  // A stall (here in the second period) makes the whole run the host's.
  periods({{true, false}, {true, true}, {true, false}, {false, false}});
  EXPECT_EQ(mpc.counters().max_misses_in_a_row, 3);
  EXPECT_EQ(mpc.counters().max_own_misses_in_a_row, 1);
  EXPECT_EQ(mpc.counters().host_stalls, 2);
  // Without one, two in a row are the controller's.
  periods({{true, false}, {true, false}, {false, false}});
  EXPECT_EQ(mpc.counters().max_own_misses_in_a_row, 2);
}

TEST(Mpc, FallbacksOnStaleStates) {
  ControllerConfig config = loadControllerConfig(configPath("stride_quad"));
  config.max_previous_ticks = 3;
  Mpc mpc(config);
  robot_state_t s = standingState(mpc.robot(), 0);
  ASSERT_TRUE(mpc.tick(&s, 0.0, Mpc::Clock::time_point::max()));
  const std::vector<double> u1 = mpc.policy().u_ff[1];
  // Stale (older than max_state_age): the previous policy, advanced to the state's time.
  s.utime += 10000;
  ASSERT_TRUE(mpc.tick(&s, 1.0, Mpc::Clock::time_point::max()));
  EXPECT_EQ(mpc.policy().status, kPolicyPrevious);
  EXPECT_EQ(mpc.policy().utime, 10000);        // answers this state
  EXPECT_EQ(mpc.policy().knot0_utime, 10000);  // its knot 0: the old knot 1 (10 ms later)
  EXPECT_EQ(mpc.policy().u_ff[0], u1);
  for (int i = 0; i < 2; ++i) ASSERT_TRUE(mpc.tick(&s, 1.0, Mpc::Clock::time_point::max()));
  EXPECT_EQ(mpc.policy().status, kPolicyPrevious);
  // Then the hold policy: PD on the joints to the default posture.
  ASSERT_TRUE(mpc.tick(&s, 1.0, Mpc::Clock::time_point::max()));
  const policy_t& hold = mpc.policy();
  EXPECT_EQ(hold.status, kPolicyHold);
  EXPECT_EQ(msg::checkPolicy(hold, true), msg::Reject::None);
  const int ndx = hold.ndx;
  EXPECT_DOUBLE_EQ(hold.K[0][0 * ndx + 6], config.hold_kp);
  EXPECT_DOUBLE_EQ(hold.K[0][0 * ndx + hold.nv + 6], config.hold_kd);
  EXPECT_EQ(mpc.counters().stale_states, 4);
  EXPECT_EQ(mpc.counters().fallbacks, 4);
  EXPECT_EQ(mpc.status().fallbacks, 4);
  // A fresh state again: solved.
  s.utime += 5000;
  ASSERT_TRUE(mpc.tick(&s, 0.0, Mpc::Clock::time_point::max()));
  EXPECT_EQ(mpc.policy().status, kPolicySolved);
}

}  // namespace test_mpc
}  // namespace stride
