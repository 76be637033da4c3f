// The gaits as contact patterns (locomotion/gait.hpp): each gait's phases for a quadruped and a
// biped (with flights too), the gaits refused for the contacts or the timing; a contact plan file
// and its errors. What the controller makes of a plan file: tests/controller/test_mpc.cpp.
#include <gtest/gtest.h>

#include <fstream>
#include <string>
#include <vector>

#include "config/robot_config.hpp"
#include "locomotion/gait.hpp"

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

}  // namespace test_gait
}  // namespace stride
