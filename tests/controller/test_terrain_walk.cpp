// The controller on terrain, in lock-step (tools/drive/closed_loop.hpp). Blind (issue 31's first
// part): the floor 5 cm below or above where the controller's model puts it (stride-sim --ground),
// which toppled anymal_c and talos_reduced before the gait generator planned on the ground the feet
// feel (GaitGenerator::ground()); each robot walks forward on it and tracks its command.

#include <gtest/gtest.h>

#include "controller_cases.hpp"
#include "terrain/terrain.hpp"
#include "terrain/terrain_file.hpp"
#include "tools/drive/closed_loop.hpp"
#include "tools/log/segments.hpp"

namespace stride {
namespace test_terrain_walk {

// Stand, the stepping gait, forward at vx from 2 s to 7 s, stand.
std::vector<ScriptedCommand> forward(const std::string& gait, double vx) {
  std::vector<ScriptedCommand> s(4);
  s[0].gait = "stand";
  s[1].at = 1.0;
  s[1].gait = gait;
  s[2] = s[1];
  s[2].at = 2.0;
  s[2].vx = vx;
  s[3].at = 7.0;
  s[3].gait = "stand";
  return s;
}

struct Case {
  const char* robot;
  const char* gait;
  double vx, ground;
};

class BlindGroundOffset : public ::testing::TestWithParam<Case> {};

TEST_P(BlindGroundOffset, WalksAndTracks) {
  const Case c = GetParam();
  ControllerConfig config = loadControllerConfig(controller_cases::configPath(c.robot));
  config.robots_dirs = {STRIDE_ROBOT_PACKAGES};
  drive::Options o;
  o.duration = 9.0;
  o.script = forward(c.gait, c.vx);
  o.terrain = std::make_shared<const terrain::Terrain>(c.ground);
  o.sim.map.rate_hz = 0.0;  // blind: no elevation map
  const drive::Run r = drive::run(config, o);
  EXPECT_EQ(r.mpc.maps, 0);
  ASSERT_FALSE(r.fell()) << c.robot << " on a floor at " << c.ground << " m";
  // It stood on that floor: its feet felt it, and the base is as high above it as it stands.
  const double z0 = r.samples.front().q[2];
  EXPECT_NEAR(r.q_end[2] - c.ground, z0 - c.ground, 0.03);
  EXPECT_NEAR(r.base_above_terrain, z0 - c.ground, 0.03);
  const auto segments = r.segments();
  const auto misses = logs::checkTracking(segments);
  EXPECT_TRUE(misses.empty()) << misses.size() << " segments missed their command";
  double forward_speed = 0.0;
  for (const logs::Segment& s : segments)
    if (s.command[0] > 0.0 && s.samples > 0) forward_speed = s.achieved[0];
  EXPECT_GT(forward_speed, 0.85 * c.vx);
  EXPECT_EQ(r.mpc.fallbacks, 0);
}

INSTANTIATE_TEST_SUITE_P(
    Robots, BlindGroundOffset,
    ::testing::Values(Case{"anymal_c", "trot", 0.8, -0.05}, Case{"anymal_c", "trot", 0.8, 0.05},
                      Case{"talos_reduced", "walk", 0.2, -0.05},
                      Case{"talos_reduced", "walk", 0.2, 0.05}),
    [](const ::testing::TestParamInfo<Case>& info) {
      return std::string(info.param.robot) + (info.param.ground < 0 ? "_lower_" : "_higher_") +
             std::to_string(static_cast<int>(std::abs(info.param.ground) * 100)) + "cm";
    });

// Forward at vx from 2 s to `until`, then stand.
std::vector<ScriptedCommand> forwardUntil(double vx, double until, const char* gait = "trot") {
  std::vector<ScriptedCommand> s = forward(gait, vx);
  s[3].at = until;
  return s;
}

// The mean forward speed of the segment commanded at vx.
double forwardSpeed(const drive::Run& r, double vx) {
  for (const logs::Segment& s : r.segments())
    if (s.command[0] == vx && s.samples > 0) return s.achieved[0];
  return 0.0;
}

// With the elevation map (issue 31): anymal_c trots at 0.4 m/s up the shipped 17 cm x 29 cm
// stairs (4 steps from x = 1.5), across the 1 m landing and down the 4 steps on the other side
// (to the ground from x = 4.82): no fall, at least 70 % of the command, at most one trip on a
// riser, no touch-down within 2 cm of an edge, every tick planned on a fresh map.
TEST(TerrainWithMap, AnymalClimbsAndDescendsTheStairs) {
  ControllerConfig config = loadControllerConfig(controller_cases::configPath("anymal_c"));
  config.robots_dirs = {STRIDE_ROBOT_PACKAGES};
  drive::Options o;
  o.duration = 16.0;
  o.script = forwardUntil(0.4, 15.5);
  o.terrain = std::make_shared<const terrain::Terrain>(
      terrain::loadTerrainFile(std::string(STRIDE_CONFIG_DIR) + "/terrain/stairs_anymal_c.yaml"));
  const drive::Run r = drive::run(config, o);
  ASSERT_FALSE(r.fell());
  EXPECT_GT(r.q_end[0], 5.0) << "down the stairs and on the ground beyond";
  EXPECT_NEAR(r.base_above_terrain, r.samples.front().q[2], 0.03);
  EXPECT_GE(forwardSpeed(r, 0.4), 0.7 * 0.4);
  EXPECT_LE(r.trips, 1);
  EXPECT_EQ(r.edge_footholds, 0);
  EXPECT_GT(r.mpc.maps, 100);
  EXPECT_EQ(r.mpc.stale_map_ticks, 0);
  EXPECT_EQ(r.mpc.fallbacks, 0);
}

// With the map, a humanoid: talos_reduced walks at 0.2 m/s up the shipped 10 cm step (a box from
// x = 0.8 to 1.8) and down its far side: each sole's centre 13 cm or more from the edges (none of
// the sole on one), its toe and heel over the riser, no fall, no trip.
TEST(TerrainWithMap, TalosStepsUpAndDown) {
  ControllerConfig config = loadControllerConfig(controller_cases::configPath("talos_reduced"));
  config.robots_dirs = {STRIDE_ROBOT_PACKAGES};
  drive::Options o;
  o.duration = 14.0;
  o.script = forwardUntil(0.2, 13.5, "walk");
  o.terrain = std::make_shared<const terrain::Terrain>(terrain::loadTerrainFile(
      std::string(STRIDE_CONFIG_DIR) + "/terrain/step_talos_reduced.yaml"));
  const drive::Run r = drive::run(config, o);
  ASSERT_FALSE(r.fell());
  EXPECT_GT(r.q_end[0], 2.0) << "up, across and down the step";
  EXPECT_GE(forwardSpeed(r, 0.2), 0.7 * 0.2);
  EXPECT_EQ(r.trips, 0);
  EXPECT_EQ(r.edge_footholds, 0);
  EXPECT_EQ(r.mpc.stale_map_ticks, 0);
}

// Blind (no map): solo12 trots at 0.3 m/s across a rough patch of 10 cm cells up to 2 cm high or
// low from x = 0.5 to 3.0, planning on the ground its feet feel.
TEST(TerrainBlind, Solo12CrossesTheRoughPatch) {
  ControllerConfig config = loadControllerConfig(controller_cases::configPath("solo12"));
  config.robots_dirs = {STRIDE_ROBOT_PACKAGES};
  drive::Options o;
  o.duration = 14.0;
  o.script = forwardUntil(0.3, 13.5);
  o.terrain = std::make_shared<const terrain::Terrain>(terrain::parseTerrain(
      "ground: 0.0\nrough:\n  - {min: [0.5, -1.0], max: [3.0, 1.0], cell: 0.1, amplitude: 0.02, "
      "seed: 5}\n",
      "test"));
  o.sim.map.rate_hz = 0.0;
  const drive::Run r = drive::run(config, o);
  ASSERT_FALSE(r.fell());
  EXPECT_GT(r.q_end[0], 3.0) << "across the patch";
  EXPECT_GE(forwardSpeed(r, 0.3), 0.7 * 0.3);
  EXPECT_EQ(r.mpc.maps, 0);
  EXPECT_EQ(r.mpc.fallbacks, 0);
}

}  // namespace test_terrain_walk
}  // namespace stride
