// The gaits as contact patterns (locomotion/gait.hpp): each gait's phases for a quadruped and a
// biped (with flights too); a jump's flight and its refusals (locomotion/jump.hpp); the gaits
// refused for the contacts or the timing; a contact plan file and its errors. What the controller
// makes of a plan file: tests/controller/test_mpc.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <string>
#include <vector>

#include "config/robot_config.hpp"
#include "locomotion/gait.hpp"
#include "locomotion/jump.hpp"

namespace stride {
namespace test_gait {

TEST(Gait, Patterns) {
  const Robot quad =
      loadRobot(std::string(STRIDE_CONFIG_DIR) + "/robots/stride_quad/stride_quad.yaml");
  EXPECT_EQ(gaitNames(4), (std::vector<std::string>{"stand", "trot", "walk", "pace", "pronk",
                                                    "bound", "flying_trot"}));
  EXPECT_EQ(gaitNames(2), (std::vector<std::string>{"stand", "walk", "hop"}));
  EXPECT_EQ(gaitNames(3), (std::vector<std::string>{"stand"}));
  const GaitTiming timing{0.1, 0.2, 0.15};
  auto lifted = [&](const ContactPlan& plan, double t) {
    std::string up;
    for (const auto& c : quad.contacts)
      if (!plan.isClosed(c.frame, t)) up += c.frame.substr(0, 2) + " ";
    return up;
  };
  const ContactPlan trot = makeGaitPattern("trot", timing, quad.contacts);
  EXPECT_TRUE(trot.cyclic);
  EXPECT_DOUBLE_EQ(trot.duration(), 0.6);
  EXPECT_EQ(lifted(trot, 0.05), "");
  EXPECT_EQ(lifted(trot, 0.15), "FL HR ");
  EXPECT_EQ(lifted(trot, 0.45), "FR HL ");
  EXPECT_EQ(lifted(trot, 0.6 + 0.15), "FL HR ");  // repeats
  const ContactPlan pace = makeGaitPattern("pace", timing, quad.contacts);
  EXPECT_EQ(lifted(pace, 0.15), "FL HL ");
  EXPECT_EQ(lifted(pace, 0.45), "FR HR ");
  const ContactPlan walk = makeGaitPattern("walk", timing, quad.contacts);
  EXPECT_DOUBLE_EQ(walk.duration(), 1.2);
  EXPECT_EQ(lifted(walk, 0.15), "HL ");
  EXPECT_EQ(lifted(walk, 0.45), "FL ");
  EXPECT_EQ(lifted(walk, 0.75), "HR ");
  EXPECT_EQ(lifted(walk, 1.05), "FR ");
  const ContactPlan stand = makeGaitPattern("stand", timing, quad.contacts);
  EXPECT_EQ(lifted(stand, 12.3), "");
  // With flights (issue 45): stances of `support`, flights of `flight`.
  const ContactPlan pronk = makeGaitPattern("pronk", timing, quad.contacts);
  EXPECT_DOUBLE_EQ(pronk.duration(), 0.25);
  EXPECT_EQ(lifted(pronk, 0.05), "");
  EXPECT_EQ(lifted(pronk, 0.2), "FL FR HL HR ");
  const ContactPlan bound = makeGaitPattern("bound", timing, quad.contacts);
  EXPECT_DOUBLE_EQ(bound.duration(), 0.5);
  EXPECT_EQ(lifted(bound, 0.05), "HL HR ");  // the front pair down
  EXPECT_EQ(lifted(bound, 0.2), "FL FR HL HR ");
  EXPECT_EQ(lifted(bound, 0.3), "FL FR ");
  EXPECT_EQ(lifted(bound, 0.45), "FL FR HL HR ");
  const ContactPlan flying = makeGaitPattern("flying_trot", timing, quad.contacts);
  EXPECT_EQ(lifted(flying, 0.05), "FR HL ");  // the FL-HR pair down
  EXPECT_EQ(lifted(flying, 0.2), "FL FR HL HR ");
  EXPECT_EQ(lifted(flying, 0.3), "FL HR ");
  EXPECT_THROW(makeGaitPattern("pronk", GaitTiming{0.1, 0.2, 0.0}, quad.contacts), ConfigError);

  const Robot biped =
      loadRobot(std::string(STRIDE_CONFIG_DIR) + "/robots/stride_humanoid/stride_humanoid.yaml");
  const ContactPlan steps = makeGaitPattern("walk", timing, biped.contacts);
  EXPECT_TRUE(steps.isClosed("R_sole", 0.15));
  EXPECT_FALSE(steps.isClosed("L_sole", 0.15));
  EXPECT_FALSE(steps.isClosed("R_sole", 0.45));
  const ContactPlan hop = makeGaitPattern("hop", timing, biped.contacts);
  EXPECT_TRUE(hop.isClosed("L_sole", 0.05) && hop.isClosed("R_sole", 0.05));
  EXPECT_FALSE(hop.isClosed("L_sole", 0.2) || hop.isClosed("R_sole", 0.2));
  EXPECT_THROW(makeGaitPattern("trot", timing, biped.contacts), ConfigError);
  EXPECT_THROW(makeGaitPattern("bound", timing, biped.contacts), ConfigError);
  EXPECT_THROW(makeGaitPattern("hop", timing, quad.contacts), ConfigError);
  EXPECT_THROW(makeGaitPattern("gallop", timing, quad.contacts), ConfigError);
  EXPECT_THROW(makeGaitPattern("trot", GaitTiming{0.0, 0.2}, quad.contacts), ConfigError);
}

TEST(Gait, PlanFile) {
  const std::string path = std::string(STRIDE_CONFIG_DIR) + "/plans/quad_trot_then_stand.yaml";
  const ContactPlan plan = loadContactPlan(path);
  EXPECT_EQ(plan.phases.size(), 14u);
  EXPECT_FALSE(plan.isClosed("FL_foot", 1.15));
  EXPECT_TRUE(plan.isClosed("FL_foot", 10.0));
  const std::string bad = ::testing::TempDir() + "/stride_bad_plan.yaml";
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
}

// A jump's flight (issue 45): the flight time that needs the least take-off speed, on the flight
// step's grid, and a take-off velocity whose ballistic arc lands on the target.
JumpLimits solo12Jumps() {  // config/controller/solo12.yaml's
  JumpLimits j;
  j.max_distance = 0.3;
  j.max_rise = 0.12;
  j.max_turn = 1.6;
  j.max_speed = 2.0;
  j.min_flight = 0.15;
  j.max_flight = 0.35;
  return j;
}

TEST(Jump, TheTakeOffVelocityLandsOnTheTarget) {
  const double g = 9.81;
  char why[192];
  JumpPlan plan;
  for (const JumpTarget& target :
       {JumpTarget{0.3, 0.0, 0.0, 0.0}, JumpTarget{0.2, -0.1, 0.1, 1.5},
        JumpTarget{0.0, 0.0, 0.0, 1.57}, JumpTarget{0.1, 0.0, -0.1, 0.0}}) {
    ASSERT_TRUE(planJump(target, solo12Jumps(), plan, why, sizeof why)) << why;
    EXPECT_STREQ(why, "");
    const double T = plan.flight;
    // The ballistic point: where the take-off velocity carries the base after T.
    EXPECT_NEAR(plan.vx * T, target.dx, 1e-12);
    EXPECT_NEAR(plan.vy * T, target.dy, 1e-12);
    EXPECT_NEAR(plan.vz * T - 0.5 * g * T * T, target.dz, 1e-12);
    EXPECT_NEAR(plan.speed, std::sqrt(plan.vx * plan.vx + plan.vy * plan.vy + plan.vz * plan.vz),
                1e-12);
    // On the grid, within the limits, and nearest the least-speed time T⁴ = 4 (d² + dz²) / g².
    EXPECT_GE(T, 0.15 - 1e-12);
    EXPECT_LE(T, 0.35 + 1e-12);
    EXPECT_NEAR(std::remainder(T - 0.15, 0.01), 0.0, 1e-9);
    const double d2 = target.dx * target.dx + target.dy * target.dy + target.dz * target.dz;
    const double best = std::clamp(std::sqrt(2.0 * std::sqrt(d2) / g), 0.15, 0.35);
    EXPECT_LE(std::abs(T - best), 0.005 + 1e-9);
  }
  // 30 cm forward: 0.25 s in the air, 1.2 m/s forward and 1.23 m/s up.
  ASSERT_TRUE(planJump({0.3, 0.0, 0.0, 0.0}, solo12Jumps(), plan, why, sizeof why));
  EXPECT_NEAR(plan.flight, 0.25, 1e-12);
  EXPECT_NEAR(plan.vx, 1.2, 1e-12);
  EXPECT_NEAR(plan.vz, 0.5 * g * 0.25, 1e-12);
}

TEST(Jump, ARefusalSaysWhichLimitAndItsValue) {
  char why[192];
  JumpPlan plan;
  auto refused = [&](const JumpTarget& target, const JumpLimits& limits) {
    EXPECT_FALSE(planJump(target, limits, plan, why, sizeof why));
    return std::string(why);
  };
  EXPECT_EQ(refused({0.1, 0.0, 0.0, 0.0}, JumpLimits{}),
            "this robot does not jump (no jump: section in its controller YAML)");
  EXPECT_EQ(refused({0.4, 0.0, 0.0, 0.0}, solo12Jumps()),
            "a jump of 0.40 m is beyond the robot's reach (jump.max_distance 0.30 m)");
  EXPECT_EQ(refused({0.1, 0.0, 0.2, 0.0}, solo12Jumps()),
            "a landing 0.20 m higher is beyond the robot's rise (jump.max_rise 0.12 m)");
  EXPECT_EQ(refused({0.0, 0.0, 0.0, -2.0}, solo12Jumps()),
            "a turn of -2.00 rad in the air is beyond the robot's (jump.max_turn 1.60 rad)");
  JumpLimits weak = solo12Jumps();
  weak.max_speed = 1.0;
  EXPECT_EQ(refused({0.3, 0.0, 0.0, 0.0}, weak),
            "the jump needs a take-off speed of 1.72 m/s, more than the robot's legs give "
            "(jump.max_speed 1.00 m/s)");
  EXPECT_EQ(refused({std::nan(""), 0.0, 0.0, 0.0}, solo12Jumps()),
            "the jump's target is not finite");
  // A buffer too short is cut, still terminated.
  char shortbuf[8];
  EXPECT_FALSE(planJump({0.4, 0.0, 0.0, 0.0}, solo12Jumps(), plan, shortbuf, sizeof shortbuf));
  EXPECT_EQ(std::string(shortbuf), "a jump ");
}

}  // namespace test_gait
}  // namespace stride
