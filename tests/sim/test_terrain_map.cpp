// The mock robot's elevation maps (sim/terrain_map.hpp): their rate, where they are and what they
// show, what --map-latency, --map-noise and --map-holes change, the options refused, and no
// allocation per step (malloc counted: allocation_counter.hpp).

#include <gtest/gtest.h>

#include "allocation_counter.hpp"

#include <cmath>
#include <vector>

#include "messages/publisher.hpp"
#include "sim/terrain_map.hpp"
#include "stride/terrain_t.hpp"
#include "terrain/terrain.hpp"

namespace stride {
namespace test_terrain_map {

using sim::TerrainMapOptions;
using sim::TerrainMapper;
using terrain::Terrain;
using terrain::TerrainSpec;

// Keeps the last message it was given, decoded.
class LastMap : public Publisher {
 public:
  void publish(const std::string& channel, const void* data, int size) override {
    channel_ = channel;
    if (!keep_) {
      ++count_;
      return;
    }
    ASSERT_GT(last_.decode(data, 0, size), 0);
    ++count_;
  }
  void keep(bool on) { keep_ = on; }
  terrain_t last_;
  std::string channel_;
  int count_ = 0;

 private:
  bool keep_ = true;
};

// A 0.2 m box at x in [0.5, 1.5]: the map shows it where it is.
Terrain boxWorld() {
  TerrainSpec s;
  s.boxes.push_back({{1.0, 0.0}, {1.0, 1.0}, 0.2, 0.0});
  return Terrain(s);
}

TEST(TerrainMap, TenPerSecondCentredOnTheBaseShowingTheTerrain) {
  const Terrain world = boxWorld();
  TerrainMapOptions o;  // 10 Hz, 2 m, 2 cm
  TerrainMapper mapper(world, o, 1e-3);
  LastMap out;
  const std::int64_t base = 1000000;
  int published = 0;
  for (int i = 1; i <= 2000; ++i) published += mapper.step(i * 1e-3, base, 0.7, -0.1, out);
  EXPECT_EQ(published, 21);  // one at the start, then 2 s at 10 Hz
  EXPECT_EQ(out.count_, 21);
  EXPECT_EQ(out.channel_, "STRIDE_TERRAIN");
  const terrain_t& m = out.last_;
  ASSERT_EQ(m.rows, 100);
  ASSERT_EQ(m.cols, 100);
  EXPECT_DOUBLE_EQ(m.resolution, 0.02);
  // Centred on the base (to a cell), its origin on the 2 cm grid.
  const double cx = m.origin_x + 0.5 * (m.cols - 1) * m.resolution;
  const double cy = m.origin_y + 0.5 * (m.rows - 1) * m.resolution;
  EXPECT_NEAR(cx, 0.7, 0.011);
  EXPECT_NEAR(cy, -0.1, 0.011);
  EXPECT_NEAR(std::remainder(m.origin_x, 0.02), 0.0, 1e-9);
  // Every cell is the terrain's height at its centre.
  for (int r = 0; r < m.rows; ++r)
    for (int c = 0; c < m.cols; ++c) {
      const double x = m.origin_x + c * m.resolution, y = m.origin_y + r * m.resolution;
      ASSERT_FLOAT_EQ(m.height[r][c], static_cast<float>(world.height(x, y))) << r << " " << c;
    }
  // Both the box (x in [0.5, 1.5]) and the ground in front of it are in view.
  const int box_column = static_cast<int>(std::lround((1.0 - m.origin_x) / m.resolution));
  EXPECT_FLOAT_EQ(m.height[50][box_column], 0.2f);
  EXPECT_FLOAT_EQ(m.height[50][0], 0.0f);
  EXPECT_EQ(m.utime, base + 2000000);  // measured now: no latency
}

TEST(TerrainMap, LatencyShowsWhereTheRobotWasAndStampsThen) {
  const Terrain world = boxWorld();
  TerrainMapOptions o;
  o.latency = 0.025;  // 25 physics steps
  TerrainMapper mapper(world, o, 1e-3);
  LastMap out;
  // The base moves along x at 1 m/s; at 1 s the map shows the terrain around x = 0.975.
  for (int i = 1; i <= 1000; ++i) mapper.step(i * 1e-3, 0, i * 1e-3, 0.0, out);
  const terrain_t& m = out.last_;
  EXPECT_EQ(m.utime, 1000000 - 25000);
  const double cx = m.origin_x + 0.5 * (m.cols - 1) * m.resolution;
  EXPECT_NEAR(cx, 0.975, 0.011);
  // Without latency the same run's last map is centred at 1.0.
  TerrainMapper now(world, TerrainMapOptions{}, 1e-3);
  LastMap out_now;
  for (int i = 1; i <= 1000; ++i) now.step(i * 1e-3, 0, i * 1e-3, 0.0, out_now);
  EXPECT_NEAR(out_now.last_.origin_x + 0.5 * 99 * 0.02, 1.0, 0.011);
  EXPECT_EQ(out_now.last_.utime, 1000000);
}

TEST(TerrainMap, NoiseAndHolesAsAsked) {
  const Terrain flat(0.0);
  TerrainMapOptions o;
  o.noise = 0.01;
  o.holes = 0.2;
  o.seed = 7;
  TerrainMapper mapper(flat, o, 1e-3);
  LastMap out;
  for (int i = 1; i <= 100; ++i) mapper.step(i * 1e-3, 0, 0.0, 0.0, out);
  const terrain_t& m = out.last_;
  int holes = 0, known = 0;
  double sum = 0.0, sum2 = 0.0;
  for (int r = 0; r < m.rows; ++r)
    for (int c = 0; c < m.cols; ++c) {
      const float h = m.height[r][c];
      if (std::isnan(h)) {
        ++holes;
        continue;
      }
      ++known;
      sum += h;
      sum2 += h * h;
    }
  EXPECT_NEAR(holes / 10000.0, 0.2, 0.02);
  const double mean = sum / known, std = std::sqrt(sum2 / known - mean * mean);
  EXPECT_NEAR(mean, 0.0, 0.001);
  EXPECT_NEAR(std, 0.01, 0.001);
  // The same seed, the same maps.
  TerrainMapper again(flat, o, 1e-3);
  LastMap out_again;
  for (int i = 1; i <= 100; ++i) again.step(i * 1e-3, 0, 0.0, 0.0, out_again);
  for (int r = 0; r < m.rows; ++r)
    for (int c = 0; c < m.cols; ++c) {
      const float a = m.height[r][c], b = out_again.last_.height[r][c];
      ASSERT_TRUE((std::isnan(a) && std::isnan(b)) || a == b) << r << " " << c;
    }
}

TEST(TerrainMap, RateZeroSendsNothingAndBadOptionsAreRefused) {
  const Terrain flat(0.0);
  TerrainMapOptions none;
  none.rate_hz = 0.0;
  TerrainMapper mapper(flat, none, 1e-3);
  LastMap out;
  for (int i = 1; i <= 1000; ++i) EXPECT_FALSE(mapper.step(i * 1e-3, 0, 0.0, 0.0, out));
  EXPECT_EQ(out.count_, 0);
  auto refused = [&](auto change) {
    TerrainMapOptions o;
    change(o);
    EXPECT_THROW(TerrainMapper(flat, o, 1e-3), std::invalid_argument);
  };
  refused([](TerrainMapOptions& o) { o.resolution = 0.0; });
  refused([](TerrainMapOptions& o) { o.resolution = NAN; });
  refused([](TerrainMapOptions& o) { o.size = 20.0; });  // 1000 cells a side
  refused([](TerrainMapOptions& o) { o.rate_hz = -1.0; });
  refused([](TerrainMapOptions& o) { o.noise = -0.1; });
  refused([](TerrainMapOptions& o) { o.holes = 1.5; });
  refused([](TerrainMapOptions& o) { o.latency = -0.01; });
}

TEST(TerrainMap, AStepAllocatesNothing) {
  TerrainSpec s;
  s.stairs.push_back({{0.5, 0.0}, 0.0, 4, 0.1, 0.25, 1.0, 0.5});
  s.rough.push_back({{-1.0, -1.0}, {0.4, 1.0}, 0.1, 0.03, 2});
  const Terrain world(s);
  TerrainMapOptions o;
  o.noise = 0.005;
  o.holes = 0.05;
  o.latency = 0.01;
  TerrainMapper mapper(world, o, 1e-3);
  LastMap out;
  out.keep(false);  // decoding the message would allocate: the sink only counts
  for (int i = 1; i <= 200; ++i) mapper.step(i * 1e-3, 0, 0.001 * i, 0.0, out);
  const long n = test_support::allocations([&] {
    for (int i = 201; i <= 1200; ++i) mapper.step(i * 1e-3, 0, 0.001 * i, 0.0, out);
  });
  EXPECT_EQ(n, 0);
  EXPECT_GE(out.count_, 11);
}

}  // namespace test_terrain_map
}  // namespace stride
