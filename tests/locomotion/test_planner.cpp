// The planner the controller drives every tick (locomotion/planner.hpp): gait switches wait for
// every foot to be down, a jump is made (push, flight, landing, the gait again) or refused with
// its reason, a map too old is not planned on, maps come in stamp order, and a knot
// that lifts a foot the warm start had down is re-seeded with the torques that hold its posture.
// stride_quad (config/robots), the gaits' default timing: trot = all feet 0.1 s, FL-HR swing
// 0.2 s, all feet 0.1 s, FR-HL swing 0.2 s.
#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "locomotion/planner.hpp"
#include "solver/ddp/solver.hpp"

namespace stride {
namespace test_planner {

constexpr unsigned kAllFeet = 0xF;

struct Quad {
  Robot robot = loadRobot(std::string(STRIDE_CONFIG_DIR) + "/robots/stride_quad/stride_quad.yaml");
  PlannerOptions options;
  std::unique_ptr<Planner> planner;
  Eigen::VectorXd x;  // the default posture at rest
  explicit Quad(double max_map_age = 0.5, bool jumps = false) {
    options.locomotion.knots = 40;  // 0.4 s of 10 ms
    if (jumps) {                    // config/controller/stride_quad.yaml's limits
      options.jump.max_distance = 0.3;
      options.jump.max_rise = 0.12;
      options.jump.max_turn = 1.6;
      options.jump.max_speed = 2.0;
      options.jump.min_flight = 0.15;
      options.jump.max_flight = 0.35;
    }
    options.terrain.max_map_age = max_map_age;
    options.terrain.max_cells = 100;
    planner = std::make_unique<Planner>(robot, options, "test");
    x = Eigen::VectorXd::Zero(robot.model.nq + robot.model.nv);
    x.head(robot.model.nq) = robot.default_q;
  }
  int gait(const std::string& name) const {
    const auto& g = planner->gaits();
    return static_cast<int>(std::find(g.begin(), g.end(), name) - g.begin());
  }
};

terrain::ElevationMap flatMap(int rows, int cols) {
  terrain::ElevationMap map;
  map.origin_x = map.origin_y = -0.5;
  map.resolution = 0.1;
  map.rows = rows;
  map.cols = cols;
  map.height.assign(static_cast<std::size_t>(rows) * cols, 0.0f);
  return map;
}

TEST(Planner, AGaitSwitchWaitsForEveryFootDown) {
  Quad q;
  Planner& p = *q.planner;
  EXPECT_TRUE(p.needsBuild());
  p.build(1000000);
  EXPECT_FALSE(p.needsBuild());
  EXPECT_DOUBLE_EQ(p.planTime(1500000), 0.5);  // the first build's stamp is plan time 0
  EXPECT_EQ(p.gaitAt(0.0), "stand");
  // From a stand the trot starts at once.
  p.setCommand(BodyCommand{}, q.gait("trot"));
  p.beginTick(0.0, 1000000, std::nullopt);
  EXPECT_EQ(p.gaitAt(0.0), "trot");
  EXPECT_EQ(p.mask(0.05), kAllFeet);
  EXPECT_NE(p.mask(0.15), kAllFeet);  // FL and HR up from 0.1 to 0.3
  // A stand asked at 0.15, a swing under way: the trot goes on to the next all-feet phase (0.3).
  p.setCommand(BodyCommand{}, q.gait("stand"));
  p.beginTick(0.15, 1150000, std::nullopt);
  EXPECT_EQ(p.gaitAt(0.29), "trot");
  EXPECT_NE(p.mask(0.29), kAllFeet);
  EXPECT_EQ(p.gaitAt(0.31), "stand");
  for (double t = 0.3 + 1e-6; t < 2.0; t += 0.01) ASSERT_EQ(p.mask(t), kAllFeet) << t;
  // A gait index out of range is ignored: the gait asked for stays.
  p.setCommand(BodyCommand{}, 99);
  p.beginTick(0.4, 1400000, std::nullopt);
  EXPECT_EQ(p.gaitAt(0.5), "stand");
}

TEST(Planner, AMapTooOldIsNotPlannedOn) {
  Quad q(0.5);
  Planner& p = *q.planner;
  p.build(0);
  EXPECT_EQ(p.beginTick(0.0, 0, std::nullopt), MapChoice::None);
  EXPECT_FALSE(p.onMap());
  ASSERT_TRUE(p.setMap(flatMap(10, 10), 100000));  // measured at 0.1 s
  EXPECT_EQ(p.beginTick(0.2, 200000, std::nullopt), MapChoice::Fresh);
  EXPECT_TRUE(p.onMap());
  EXPECT_EQ(p.generator().map(), &p.map());
  EXPECT_EQ(p.beginTick(0.6, 600000, std::nullopt), MapChoice::Fresh);  // 0.5 s old: still fresh
  EXPECT_EQ(p.beginTick(0.61, 610000, std::nullopt), MapChoice::Stale);
  EXPECT_FALSE(p.onMap());
  EXPECT_EQ(p.generator().map(), nullptr);  // blind
  // From the future by more than the age: not planned on either.
  EXPECT_EQ(p.beginTick(-0.5, -500000, std::nullopt), MapChoice::Stale);
  // A fresh map again.
  ASSERT_TRUE(p.setMap(flatMap(10, 10), 700000));
  EXPECT_EQ(p.beginTick(0.71, 710000, std::nullopt), MapChoice::Fresh);
}

TEST(Planner, MapsComeInStampOrder) {
  Quad q;
  Planner& p = *q.planner;
  ASSERT_TRUE(p.setMap(flatMap(10, 10), 5000000));
  EXPECT_FALSE(p.setMap(flatMap(10, 10), 4500000));  // older than the one in use
  EXPECT_EQ(p.mapUtime(), 5000000);
  EXPECT_TRUE(p.setMap(flatMap(10, 10), 3000000));  // over a second older: a restarted clock
  EXPECT_EQ(p.mapUtime(), 3000000);
  EXPECT_FALSE(p.setMap(flatMap(11, 10), 3100000));  // larger than terrain.max_cells
  EXPECT_TRUE(p.map().valid());
  // A clock offset moves the map's stamp with it.
  p.shiftClock(-1000000);
  EXPECT_EQ(p.mapUtime(), 2000000);
}

TEST(Planner, AKnotThatLiftsAFootStartsFromHoldingTorques) {
  Quad q;
  Planner& p = *q.planner;
  p.build(0);
  LocomotionProblem& loco = p.problem();
  Solver solver(loco.problem(), SolverKind::Fddp);
  // Standing: every knot has every foot down.
  p.beginTick(0.0, 0, std::nullopt);
  ASSERT_TRUE(p.replan(0.0, q.x, 0.0, solver));
  const int T = loco.problem().horizon();
  for (int k = 0; k < T; ++k) ASSERT_EQ(loco.contactMask(k), kAllFeet) << k;
  // A warm start whose torques are nobody's holding torques.
  std::vector<Eigen::VectorXd> xs(T + 1, q.x),
      us(T, Eigen::VectorXd::Constant(loco.holdingControl(kAllFeet).size(), 0.125));
  ASSERT_TRUE(solver.setWarmStart(xs, us));
  // The trot comes in: its knots with a foot up start from the torques holding their contacts,
  // the knots with every foot down keep the warm start's.
  p.setCommand(BodyCommand{}, q.gait("trot"));
  p.beginTick(0.0, 0, std::nullopt);
  ASSERT_TRUE(p.replan(0.0, q.x, 0.0, solver));
  int lifted = 0, kept = 0;
  for (int k = 0; k < T; ++k) {
    const unsigned mask = loco.contactMask(k);
    if (mask != kAllFeet) {
      EXPECT_TRUE(solver.us()[k].isApprox(loco.holdingControl(mask))) << "knot " << k;
      ++lifted;
    } else {
      EXPECT_TRUE(solver.us()[k].isApprox(us[k])) << "knot " << k;
      ++kept;
    }
  }
  EXPECT_GT(lifted, 10);
  EXPECT_GT(kept, 10);
  ASSERT_FALSE(loco.holdingControl(0b1001).isApprox(us[0]));
  // Re-planned again on the same knots, nothing is lifted that was down: the torques stay.
  for (int k = 0; k < T; ++k) solver.setControl(k, us[k]);
  ASSERT_TRUE(p.replan(0.0, q.x, 0.0, solver));
  for (int k = 0; k < T; ++k) EXPECT_TRUE(solver.us()[k].isApprox(us[k])) << "knot " << k;
}

TEST(Planner, TouchDownsAfterTheStateByContactThenTime) {
  Quad q;
  Planner& p = *q.planner;
  p.build(0);
  Solver solver(p.problem().problem(), SolverKind::Fddp);
  p.setCommand(BodyCommand{}, q.gait("trot"));
  p.beginTick(0.0, 0, std::nullopt);
  ASSERT_TRUE(p.replan(0.0, q.x, 0.0, solver));
  // Trot from 0: FL and HR land at 0.3, FR and HL at 0.6 (after the 0.4 s horizon's end).
  std::vector<std::pair<int, double>> seen;
  p.touchDowns(0.0, 0.4, 4, 8, [&](int c, const GaitGenerator::Stance& s) {
    seen.emplace_back(c, s.touch_down);
    return true;
  });
  ASSERT_EQ(seen.size(), 2u);
  EXPECT_EQ(seen[0].first, 0);
  EXPECT_EQ(seen[1].first, 3);
  EXPECT_NEAR(seen[0].second, 0.3, 1e-9);
  // The visitor says when it is full.
  int n = 0;
  p.touchDowns(0.0, 2.0, 4, 8, [&](int, const GaitGenerator::Stance&) { return ++n < 3; });
  EXPECT_EQ(n, 3);
}

// A jump (issue 45): asked at 1.0 s while trotting, it starts at the trot's next all-feet phase
// with a 0.3 s push, flies 0.25 s (30 cm forward: jump.hpp), lands for 0.4 s, and the trot comes
// back; its states in order, the velocity command held meanwhile; a second one asked in the air
// is refused, as are jumps beyond the limits, with their reasons.
TEST(Planner, AJumpIsMadeOnceThenTheGaitComesBack) {
  Quad q(0.5, true);
  Planner& p = *q.planner;
  JumpTarget forward{0.3, 0.0, 0.0, 0.0};
  EXPECT_FALSE(p.requestJump(1, forward, 0.0));  // before the first state: nothing to plan on
  EXPECT_EQ(p.jumpStatus().state, JumpState::Refused);
  EXPECT_STREQ(p.jumpStatus().refusal, "the controller has no state yet");
  p.build(0);
  BodyCommand walk;
  walk.vx = 0.3;
  p.setCommand(walk, q.gait("trot"));
  p.beginTick(0.0, 0, std::nullopt);
  ASSERT_EQ(p.gaitAt(0.0), "trot");
  // At 1.0 s the trot (0.6 s cycle) is in its FL-HR swing (0.1-0.3 of the cycle, from 0.6 s): its
  // next all-feet phase starts at 1.2 s.
  ASSERT_TRUE(p.requestJump(2, forward, 1.0));
  EXPECT_EQ(p.jumpStatus().id, 2);
  EXPECT_EQ(p.jumpStatus().state, JumpState::Accepted);
  EXPECT_STREQ(p.jumpStatus().refusal, "");
  const double push = 1.2, lift_off = push + 0.3, touch_down = lift_off + 0.25;
  const double end = touch_down + 0.4;
  p.beginTick(1.0, 1000000, std::nullopt);
  EXPECT_EQ(p.gaitAt(1.1), "trot");
  EXPECT_EQ(p.gaitAt(push + 0.01), "jump");
  EXPECT_EQ(p.mask(push + 0.01), kAllFeet);
  EXPECT_EQ(p.mask(lift_off + 0.01), 0u);  // in the air
  EXPECT_EQ(p.mask(touch_down - 0.01), 0u);
  EXPECT_EQ(p.mask(touch_down + 0.01), kAllFeet);
  EXPECT_EQ(p.mask(end - 0.01), kAllFeet);
  EXPECT_TRUE(p.generator().jumping());
  EXPECT_EQ(p.generator().command().vx, 0.0);  // the velocity waits for the jump
  // In the air: a second jump is refused, the first goes on.
  p.beginTick(lift_off + 0.1, 1600000, std::nullopt);
  EXPECT_EQ(p.jumpStatus().state, JumpState::InAir);
  EXPECT_FALSE(p.requestJump(3, forward, lift_off + 0.1));
  EXPECT_STREQ(p.jumpStatus().refusal, "another jump is under way");
  EXPECT_EQ(p.jumpStatus().refused, 2);
  EXPECT_EQ(p.mask(touch_down + 0.01), kAllFeet);  // (the first's landing stays planned)
  p.beginTick(touch_down + 0.01, 1760000, std::nullopt);
  EXPECT_EQ(p.jumpStatus().id, 3);  // the status tells the last one asked for
  EXPECT_EQ(p.jumpStatus().state, JumpState::Refused);
  EXPECT_EQ(p.jumpStatus().made, 1);  // and counts the first's landing
  // Its end: the trot again, and the velocity.
  p.beginTick(end, static_cast<std::int64_t>(end * 1e6), std::nullopt);
  EXPECT_FALSE(p.generator().jumping());
  EXPECT_EQ(p.generator().command().vx, 0.3);
  EXPECT_EQ(p.gaitAt(end + 0.01), "trot");
  EXPECT_NE(p.mask(end + 0.15), kAllFeet);  // stepping
  // Beyond the limits: refused, nothing changes.
  EXPECT_FALSE(p.requestJump(4, {0.5, 0.0, 0.0, 0.0}, end + 0.1));
  EXPECT_STREQ(p.jumpStatus().refusal,
               "a jump of 0.50 m is beyond the robot's reach (jump.max_distance 0.30 m)");
  EXPECT_EQ(p.jumpStatus().id, 4);
  EXPECT_EQ(p.jumpStatus().made, 1);
  EXPECT_EQ(p.jumpStatus().refused, 3);
  EXPECT_EQ(p.gaitAt(end + 0.5), "trot");
}

// Landing as it happens (issue 45): stride_quad pronks (the default timing: 0.1 s on every foot,
// 0.15 s in the air). A foot loaded in the second half of a flight lands it then, and the pronk
// goes on from that touch-down; a flight the clock ends while no foot is loaded goes on by 20 ms
// at a time until a foot is, at most 0.15 s.
TEST(Planner, AFlightLandsOnTheMeasuredContacts) {
  Quad q;
  Planner& p = *q.planner;
  p.build(0);
  p.setCommand(BodyCommand{}, q.gait("pronk"));
  p.beginTick(0.0, 0, kAllFeet);
  ASSERT_EQ(p.mask(0.05), kAllFeet);
  ASSERT_EQ(p.mask(0.15), 0u);  // in the air from 0.1 to 0.25
  // Early: loaded at 0.2, the flight's second half (0.175 on).
  p.beginTick(0.16, 160000, kAllFeet);  // its first half: a push's load, not a landing
  EXPECT_EQ(p.mask(0.2), 0u);
  p.beginTick(0.2, 200000, kAllFeet);
  EXPECT_EQ(p.earlyLandings(), 1);
  EXPECT_EQ(p.mask(0.2 + 1e-6), kAllFeet);
  EXPECT_EQ(p.mask(0.29), kAllFeet);  // 0.1 s down from the touch-down
  EXPECT_EQ(p.mask(0.31), 0u);        // the next flight, 0.05 s earlier than the clock had it
  EXPECT_NEAR(p.generator().timeline().lastChange(0, 0.25), 0.2, 1e-9);
  EXPECT_NEAR(p.generator().timeline().lastChange(0, 0.35), 0.3, 1e-9);
  // Late: the next flight ends at 0.45 by the clock; no foot loaded then, nor 20 ms later.
  p.beginTick(0.35, 350000, 0u);
  p.beginTick(0.45, 450000, 0u);
  EXPECT_EQ(p.lateLandings(), 1);
  EXPECT_EQ(p.mask(0.45 + 1e-6), 0u);  // still in the air
  EXPECT_EQ(p.mask(0.47 + 1e-6), kAllFeet);
  p.beginTick(0.47, 470000, 0u);
  EXPECT_EQ(p.mask(0.47 + 1e-6), 0u);
  p.beginTick(0.49, 490000, kAllFeet);  // down
  EXPECT_EQ(p.mask(0.49 + 1e-6), kAllFeet);
  EXPECT_EQ(p.mask(0.58), kAllFeet);
  EXPECT_EQ(p.mask(0.6), 0u);      // the pronk goes on from that touch-down
  EXPECT_EQ(p.lateLandings(), 1);  // one flight
  // A flight that never meets the ground by the measure is held 0.15 s at most.
  const double lift_off = 0.59, clock_touch_down = lift_off + 0.15;
  double t = clock_touch_down;
  for (int k = 0; k < 20; ++k, t += 0.01) p.beginTick(t, static_cast<std::int64_t>(t * 1e6), 0u);
  EXPECT_EQ(p.lateLandings(), 2);
  double landed = clock_touch_down;
  while (p.mask(landed) == 0u) landed += 0.001;
  EXPECT_GE(landed, clock_touch_down + 0.1);
  EXPECT_LE(landed, clock_touch_down + 0.15 + 1e-3);
  EXPECT_EQ(p.earlyLandings(), 1);
}

}  // namespace test_planner
}  // namespace stride
