// The controller core: configuration, gait plans, ticks, fallbacks.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>

#include "controller/gait.hpp"
#include "controller/mpc.hpp"
#include "controller_cases.hpp"

namespace stride {
namespace {

using controller_cases::configPath;
using controller_cases::standingState;

TEST(ControllerConfig, ShippedConfigsLoad) {
  for (const char* robot : {"stride_quad", "stride_humanoid"}) {
    const ControllerConfig c = loadControllerConfig(configPath(robot));
    EXPECT_TRUE(std::filesystem::exists(c.robot_yaml)) << c.robot_yaml;
    EXPECT_GT(c.rate_hz, 0.0);
    EXPECT_EQ(c.solver, SolverKind::BoxFddp);
    EXPECT_TRUE(c.locomotion.torque_limits);
  }
}

std::string configError(const std::string& yaml) {
  const std::string path = testing::TempDir() + "/stride_bad_config.yaml";
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
  EXPECT_NE(configError(robot + "gait: {type: gallop}\n").find("gait.type"), std::string::npos);
  EXPECT_NE(configError(robot + "safety: {fallback: pray}\n").find("safety.fallback"),
            std::string::npos);
  EXPECT_NE(configError(robot + "horizon: [1, 2\n").find("malformed"), std::string::npos);
  EXPECT_EQ(configError(robot), "") << "a file with only the robot is valid (defaults)";
  EXPECT_NE(configError(robot + "rate_hz: -5\n").find("stride_bad_config.yaml"), std::string::npos);
  try {
    loadControllerConfig("/nonexistent/stride.yaml");
    FAIL() << "a missing file must throw";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/stride.yaml"), std::string::npos);
  }
}

TEST(Gait, TrotAndWalkPlans) {
  const Robot quad =
      loadRobot(std::string(STRIDE_CONFIG_DIR) + "/robots/stride_quad/stride_quad.yaml");
  GaitConfig g;
  g.type = "trot";
  g.stand = 1.0;
  g.support = 0.1;
  g.swing = 0.2;
  g.duration = 3.0;
  const ContactPlan trot = makeGaitPlan(g, quad.contacts);
  EXPECT_FALSE(trot.cyclic);
  EXPECT_TRUE(trot.isClosed("FL_foot", 0.5));
  EXPECT_FALSE(trot.isClosed("FL_foot", 1.15));
  EXPECT_FALSE(trot.isClosed("HR_foot", 1.15));
  EXPECT_TRUE(trot.isClosed("FR_foot", 1.15));
  EXPECT_FALSE(trot.isClosed("FR_foot", 1.45));
  EXPECT_TRUE(trot.isClosed("FR_foot", 100.0));  // stands after the plan
  g.type = "walk";
  const ContactPlan walk = makeGaitPlan(g, quad.contacts);
  int open_at_once = 0;
  for (double t = 0.0; t < 3.0; t += 0.01) {
    int open = 0;
    for (const auto& c : quad.contacts) open += !walk.isClosed(c.frame, t);
    open_at_once = std::max(open_at_once, open);
  }
  EXPECT_EQ(open_at_once, 1);

  const Robot biped =
      loadRobot(std::string(STRIDE_CONFIG_DIR) + "/robots/stride_humanoid/stride_humanoid.yaml");
  EXPECT_NO_THROW(makeGaitPlan(g, biped.contacts));
  g.type = "trot";
  EXPECT_THROW(makeGaitPlan(g, biped.contacts), ConfigError);
}

TEST(Gait, StepsInPlaceUntilStepAfter) {
  const Robot quad =
      loadRobot(std::string(STRIDE_CONFIG_DIR) + "/robots/stride_quad/stride_quad.yaml");
  ContactSet contacts;
  for (const auto& c : quad.contacts)
    contacts.add(quad.model, c.frame, 3, ReferenceFrame::LocalWorldAligned);
  GaitConfig g;
  g.stand = 0.5;
  g.duration = 5.0;
  LocomotionOptions o;
  o.knots = 10;
  o.step = Eigen::Vector3d(0.05, 0.0, 0.0);
  o.step_after = 1.7;
  Eigen::VectorXd x = Eigen::VectorXd::Zero(quad.model.nq + quad.model.nv);
  x.head(quad.model.nq) = quad.default_q;
  LocomotionProblem loco(quad.model, contacts, makeGaitPlan(g, quad.contacts), x, o);
  const Eigen::Vector3d start = loco.footReference(0, 0.0);
  // Touch-downs of FL up to 1.7 s (at 0.8 and 1.4 s) leave it in place; later ones move it.
  EXPECT_NEAR((loco.footReference(0, 1.65) - start).norm(), 0.0, 1e-12);
  EXPECT_NEAR(loco.footReference(0, 2.05).x() - start.x(), 0.05, 1e-12);  // landed at 2.0 s
  EXPECT_NEAR(loco.footReference(0, 2.65).x() - start.x(), 0.10, 1e-12);
  // Mid-swing before step_after: up, not forward.
  EXPECT_NEAR(loco.footReference(0, 1.3).x(), start.x(), 1e-12);
  EXPECT_GT(loco.footReference(0, 1.3).z(), start.z() + 0.01);
}

// A footstep list: each touch-down after step_after takes the next displacement, in plan order;
// the swing arc goes from one foothold to the next; after the list, the feet stay.
TEST(Gait, FootstepList) {
  const Robot biped =
      loadRobot(std::string(STRIDE_CONFIG_DIR) + "/robots/stride_humanoid/stride_humanoid.yaml");
  ContactSet contacts;
  for (const auto& c : biped.contacts)
    contacts.add(biped.model, c.frame, 6, ReferenceFrame::LocalWorldAligned);
  GaitConfig g;
  g.type = "walk";
  g.stand = 1.0;
  g.support = 0.2;
  g.swing = 0.6;
  g.duration = 10.0;
  LocomotionOptions o;
  o.knots = 10;
  o.dt = 0.02;
  o.step_after = 1.0;
  o.footsteps = {Eigen::Vector3d(0.1, 0.0, 0.0), Eigen::Vector3d(0.2, 0.05, 0.0),
                 Eigen::Vector3d(0.1, -0.05, 0.0)};
  Eigen::VectorXd x = Eigen::VectorXd::Zero(biped.model.nq + biped.model.nv);
  x.head(biped.model.nq) = biped.default_q;
  LocomotionProblem loco(biped.model, contacts, makeGaitPlan(g, biped.contacts), x, o);
  const Eigen::Vector3d L0 = loco.footReference(0, 0.0), R0 = loco.footReference(1, 0.0);
  // Left swings 1.2-1.8 s, right 2.0-2.6 s, left 2.8-3.4 s, right 3.6-4.2 s (in place).
  EXPECT_TRUE((loco.footReference(0, 1.9) - L0).isApprox(Eigen::Vector3d(0.1, 0, 0), 1e-12));
  EXPECT_TRUE((loco.footReference(1, 2.7) - R0).isApprox(Eigen::Vector3d(0.2, 0.05, 0), 1e-12));
  EXPECT_TRUE((loco.footReference(0, 3.5) - L0).isApprox(Eigen::Vector3d(0.2, -0.05, 0), 1e-12));
  EXPECT_TRUE((loco.footReference(1, 5.0) - R0).isApprox(Eigen::Vector3d(0.2, 0.05, 0), 1e-12));
  // Mid-swing: half way on the ramp, at the arc's top.
  const Eigen::Vector3d mid = loco.footReference(1, 2.3) - R0;
  EXPECT_NEAR(mid.x(), 0.1, 1e-12);
  EXPECT_NEAR(mid.y(), 0.025, 1e-12);
  EXPECT_NEAR(mid.z(), o.swing_height, 1e-12);
}

TEST(Gait, PlanFile) {
  const std::string path = std::string(STRIDE_CONFIG_DIR) + "/plans/quad_trot_then_stand.yaml";
  const ContactPlan plan = loadContactPlan(path);
  EXPECT_EQ(plan.phases.size(), 14u);
  EXPECT_FALSE(plan.isClosed("FL_foot", 1.15));
  EXPECT_TRUE(plan.isClosed("FL_foot", 10.0));
  const std::string bad = testing::TempDir() + "/stride_bad_plan.yaml";
  std::ofstream(bad) << "phases:\n  - {duration: -1, contacts: [FL_foot]}\n";
  EXPECT_THROW(loadContactPlan(bad), ConfigError);
  std::ofstream(bad) << "phases:\n  - {contacts: [FL_foot]}\n";
  try {
    loadContactPlan(bad);
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("phase 0"), std::string::npos) << e.what();
  }
  EXPECT_THROW(loadContactPlan("/nonexistent/plan.yaml"), ConfigError);
  // The controller takes it from its YAML, and refuses one that names feet the robot lacks.
  ControllerConfig config = loadControllerConfig(configPath("stride_quad"));
  config.gait.plan_file = path;
  Mpc mpc(config);
  robot_state_t s = standingState(mpc.robot(), 0);
  ASSERT_TRUE(mpc.tick(&s, 0.0, Mpc::Clock::time_point::max()));
  EXPECT_EQ(mpc.problem()->schedule().phases(), 14);
  std::ofstream(bad) << "phases:\n  - {duration: 1, contacts: [L_sole]}\n";
  config.gait.plan_file = bad;
  EXPECT_THROW(Mpc{config}, ConfigError);
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

// A deadline is on the answer: a tick whose policy goes out after it is one miss, whether its
// solve stopped there or finished late; a tick on time is none.
TEST(Mpc, DeadlineMissesCountAnswersAfterTheDeadline) {
  ControllerConfig config = loadControllerConfig(configPath("stride_quad"));
  Mpc mpc(config);
  robot_state_t s = standingState(mpc.robot(), 0);
  const auto past = [] { return Mpc::Clock::now() - std::chrono::milliseconds(1); };
  // The start-up solve runs to convergence before the first policy, without a deadline.
  ASSERT_TRUE(mpc.tick(&s, 0.0, past()));
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

}  // namespace
}  // namespace stride
