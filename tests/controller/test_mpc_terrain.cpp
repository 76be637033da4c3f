// The controller on an elevation map (issue 31; controller/README.md, "Terrain"): a fresh map is
// planned on (the footholds come from the map's selection), a stale one (older than
// terrain.max_map_age on the robot's clock) falls back to blind planning and is counted, a map
// too large or older than the one in use is refused, and the status says which.

#include <gtest/gtest.h>

#include <cmath>

#include "controller/mpc.hpp"
#include "controller_cases.hpp"
#include "messages/validate.hpp"

namespace stride {
namespace test_mpc_terrain {

using controller_cases::configPath;
using controller_cases::standingState;

// A flat map 2 m x 2 m of 2 cm cells around the origin, measured at utime, with a step of `rise`
// from x = step_x on.
terrain_t map(std::int64_t utime, double step_x = 1e9, double rise = 0.0) {
  terrain_t m;
  msg::shape(m, 100, 100);
  m.utime = utime;
  m.origin_x = m.origin_y = -0.99;
  m.resolution = 0.02;
  for (int r = 0; r < m.rows; ++r)
    for (int c = 0; c < m.cols; ++c)
      m.height[r][c] = m.origin_x + c * m.resolution >= step_x ? static_cast<float>(rise) : 0.0f;
  return m;
}

TEST(TerrainMap, AFreshMapIsPlannedOnAStaleOneFallsBackToBlind) {
  ControllerConfig config = loadControllerConfig(configPath("stride_quad"));
  config.terrain.max_map_age = 0.2;
  Mpc mpc(config);
  BodyCommand walk;
  walk.vx = 0.3;
  mpc.setCommand(walk, 1);  // trot
  robot_state_t s = standingState(mpc.robot(), 1000000);
  ASSERT_TRUE(mpc.tick(&s, 0.0, Mpc::Clock::time_point::max()));
  EXPECT_FALSE(mpc.plannedOnMap());
  EXPECT_EQ(mpc.status().terrain_mode, 0);  // no map yet: blind
  EXPECT_EQ(mpc.status().map_age, -1.0);

  ASSERT_TRUE(mpc.setTerrain(map(s.utime)));
  EXPECT_EQ(mpc.counters().maps, 1);
  auto planned_on_map = [&](const GaitGenerator& g) {
    int mapped = 0;
    for (int c = 0; c < 4; ++c)
      for (int i = 0; i < g.stances(c); ++i) {
        const StanceSource src = g.stance(c, i).source;
        mapped += src == StanceSource::Nominal || src == StanceSource::Moved;
      }
    return mapped;
  };
  for (int i = 1; i <= 30; ++i) {  // 0.15 s: the map is 0.15 s old at the last
    s.utime += 5000;
    ASSERT_TRUE(mpc.tick(&s, 0.0, Mpc::Clock::time_point::max()));
    EXPECT_TRUE(mpc.plannedOnMap()) << i;
  }
  EXPECT_EQ(mpc.status().terrain_mode, 1);
  EXPECT_NEAR(mpc.status().map_age, 0.15, 1e-9);
  EXPECT_GT(planned_on_map(*mpc.reference()), 0);
  EXPECT_EQ(mpc.counters().map_ticks, 30);
  EXPECT_EQ(mpc.counters().stale_map_ticks, 0);

  for (int i = 1; i <= 20; ++i) {  // 0.25 s old at the last: stale from 0.2 s on
    s.utime += 5000;
    ASSERT_TRUE(mpc.tick(&s, 0.0, Mpc::Clock::time_point::max()));
  }
  EXPECT_FALSE(mpc.plannedOnMap());
  EXPECT_EQ(mpc.status().terrain_mode, 2);
  EXPECT_EQ(mpc.counters().stale_map_ticks, 10);
  EXPECT_EQ(mpc.status().stale_map_ticks, 10);
  EXPECT_EQ(planned_on_map(*mpc.reference()), 0);  // every foothold blind or measured
  EXPECT_EQ(mpc.policy().status, kPolicySolved);

  // A new map: planned on again. An older one than that, or one too large, is refused.
  ASSERT_TRUE(mpc.setTerrain(map(s.utime)));
  EXPECT_FALSE(mpc.setTerrain(map(s.utime - 100000)));
  EXPECT_EQ(mpc.counters().maps_refused, 1);
  s.utime += 5000;
  ASSERT_TRUE(mpc.tick(&s, 0.0, Mpc::Clock::time_point::max()));
  EXPECT_TRUE(mpc.plannedOnMap());
  config.terrain.max_cells = 100 * 99;
  Mpc small(config);
  EXPECT_FALSE(small.setTerrain(map(s.utime)));
  EXPECT_EQ(small.counters().maps_refused, 1);
}

TEST(TerrainMap, FootholdsLandOnTheMapsStepAwayFromItsEdge) {
  // stride_quad trotting forward at 0.3 m/s towards a 5 cm step just ahead of its front feet:
  // every planned touch-down is on the map, 3 cm or more from the step's edge, at the height of
  // the surface it is on; the swing that lands on the step rises above it.
  ControllerConfig config = loadControllerConfig(configPath("stride_quad"));
  Mpc mpc(config);
  BodyCommand walk;
  walk.vx = 0.3;
  mpc.setCommand(walk, 1);
  robot_state_t s = standingState(mpc.robot(), 1000000);
  const double step_x = 0.25;
  ASSERT_TRUE(mpc.setTerrain(map(s.utime, step_x, 0.05)));
  ASSERT_TRUE(mpc.tick(&s, 0.0, Mpc::Clock::time_point::max()));
  for (int i = 0; i < 60; ++i) {
    s.utime += 5000;
    ASSERT_TRUE(mpc.tick(&s, 0.0, Mpc::Clock::time_point::max()));
  }
  ASSERT_TRUE(mpc.plannedOnMap());
  const GaitGenerator& g = *mpc.reference();
  const terrain::Steppability& st = mpc.terrain();
  int on_step = 0;
  for (int c = 0; c < 4; ++c) {
    const double foot_z = g.stanceOffset(c).z();
    for (int i = 0; i < g.stances(c); ++i) {
      const GaitGenerator::Stance& x = g.stance(c, i);
      if (x.source == StanceSource::Measured) continue;
      ASSERT_TRUE(x.source == StanceSource::Nominal || x.source == StanceSource::Moved)
          << c << " " << i << ": source " << static_cast<int>(x.source);
      EXPECT_GE(st.edgeDistanceAt(x.p.x(), x.p.y()), st.options().min_edge_distance - 1e-9)
          << c << " " << i;
      EXPECT_GE(std::abs(x.p.x() - step_x + 0.01), 0.03 - 1e-9) << c << " " << i;
      const double surface = x.p.x() > step_x - 0.01 ? 0.05 : 0.0;
      EXPECT_NEAR(x.p.z() - foot_z, surface, 1e-6) << c << " " << i;
      if (surface > 0.0) {
        ++on_step;
        EXPECT_GE(x.swing_height, config.generator.swing_clearance) << c << " " << i;
      }
    }
  }
  EXPECT_GT(on_step, 0);
}

}  // namespace test_mpc_terrain
}  // namespace stride
