// The checks of an elevation map (messages/validate.hpp, terrain_t): on the raw bytes before
// lcm-gen's decoder sizes anything from them (type, counts, the exact size), then on the decoded
// map (finite origin and heights but for unknown cells, resolution, stamp, consistent arrays).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "messages/validate.hpp"
#include "stride/command_t.hpp"
#include "stride/terrain_t.hpp"

namespace stride::msg {
namespace test_terrain_checks {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr int kMaxCells = 512 * 512;
// Byte offsets of the encoded counts (after the type hash, utime and three doubles).
constexpr std::size_t kRowsAt = 8 + 8 + 3 * 8, kColsAt = kRowsAt + 4;

// A 2 cm map of rows x cols, a 5 cm box step where x > 0.1 m and unknown cells at (1, 1..3).
terrain_t boxStep(int rows, int cols) {
  terrain_t m;
  shape(m, rows, cols);
  m.utime = 1000000;
  m.resolution = 0.02;
  m.origin_x = -0.5 * m.resolution * (cols - 1);
  m.origin_y = -0.5 * m.resolution * (rows - 1);
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) m.height[r][c] = m.origin_x + c * m.resolution > 0.1 ? 0.05f : 0;
  for (int c = 1; c < 4 && c < cols; ++c) m.height[1][c] = kNaN;
  return m;
}

template <typename Message>
std::vector<unsigned char> encode(const Message& m) {
  std::vector<unsigned char> buf(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(buf.data(), 0, static_cast<int>(buf.size()));
  return buf;
}

void poke32(std::vector<unsigned char>& buf, std::size_t at, std::int32_t value) {
  std::uint32_t u;
  std::memcpy(&u, &value, 4);
  for (int i = 0; i < 4; ++i) buf[at + i] = static_cast<unsigned char>(u >> (24 - 8 * i));
}

Reject wire(const std::vector<unsigned char>& b, int max_cells = kMaxCells) {
  return checkTerrainWire(b.data(), static_cast<int>(b.size()), max_cells);
}

TEST(ValidateTerrain, AMapWithUnknownCellsIsAccepted) {
  const terrain_t m = boxStep(100, 100);
  const std::vector<unsigned char> bytes = encode(m);
  EXPECT_EQ(static_cast<long>(bytes.size()), terrainWireSize(100, 100));
  EXPECT_EQ(wire(bytes), Reject::None);
  terrain_t in;
  ASSERT_EQ(in.decode(bytes.data(), 0, static_cast<int>(bytes.size())),
            static_cast<int>(bytes.size()));
  EXPECT_EQ(checkTerrain(in), Reject::None);
  EXPECT_TRUE(std::isnan(in.height[1][2]));
  EXPECT_EQ(in.height[50][99], 0.05f);
  // One cell, and a map of exactly the largest size allowed.
  EXPECT_EQ(wire(encode(boxStep(1, 1))), Reject::None);
  EXPECT_EQ(wire(encode(boxStep(10, 30)), 300), Reject::None);
}

TEST(ValidateTerrain, ASizeThatIsNotTheCountsOnesIsRefused) {
  const std::vector<unsigned char> good = encode(boxStep(20, 30));
  std::vector<unsigned char> b(good.begin(), good.end() - 4);  // a cell short
  EXPECT_EQ(wire(b), Reject::WrongSize);
  b = good;
  b.push_back(0);
  EXPECT_EQ(wire(b), Reject::WrongSize);
  b = good;
  poke32(b, kRowsAt, 21);  // more rows than the bytes hold
  EXPECT_EQ(wire(b), Reject::WrongSize);
  b = good;
  poke32(b, kColsAt, 29);
  EXPECT_EQ(wire(b), Reject::WrongSize);
  // Too short to hold the counts; nothing at all.
  b.assign(good.begin(), good.begin() + kColsAt + 2);
  EXPECT_EQ(wire(b), Reject::Undecodable);
  EXPECT_EQ(checkTerrainWire(nullptr, 0, kMaxCells), Reject::Undecodable);
}

TEST(ValidateTerrain, CountsBelowOneOrTooManyCellsAreRefused) {
  std::vector<unsigned char> b = encode(boxStep(20, 30));
  for (const std::int32_t n : {0, -1, std::numeric_limits<std::int32_t>::min()}) {
    std::vector<unsigned char> rows = b, cols = b;
    poke32(rows, kRowsAt, n);
    poke32(cols, kColsAt, n);
    EXPECT_EQ(wire(rows), Reject::WrongSize) << n;
    EXPECT_EQ(wire(cols), Reject::WrongSize) << n;
  }
  // rows * cols over the bound: 600 cells against 599; 2^31 - 1 rows of 2^31 - 1 columns, whose
  // product overflows int (and whose size does not fit the buffer's int either); 65536 x 65536,
  // which wraps to 0 in 32 bits.
  EXPECT_EQ(wire(b, 599), Reject::WrongSize);
  poke32(b, kRowsAt, std::numeric_limits<std::int32_t>::max());
  poke32(b, kColsAt, std::numeric_limits<std::int32_t>::max());
  EXPECT_EQ(wire(b, std::numeric_limits<int>::max()), Reject::WrongSize);
  poke32(b, kRowsAt, 65536);
  poke32(b, kColsAt, 65536);
  EXPECT_EQ(wire(b, std::numeric_limits<int>::max()), Reject::WrongSize);
  EXPECT_EQ(wire(encode(boxStep(513, 512))), Reject::WrongSize);
}

TEST(ValidateTerrain, AnotherTypesBytesAreRefused) {
  std::vector<unsigned char> b = encode(boxStep(5, 5));
  b[3] ^= 0x10;  // the type fingerprint
  EXPECT_EQ(wire(b), Reject::Undecodable);
  command_t cmd{};
  cmd.gait = "trot";
  EXPECT_EQ(wire(encode(cmd)), Reject::Undecodable);
}

TEST(ValidateTerrain, ResolutionZeroNegativeOrNotFiniteIsRefused) {
  for (const double res : {0.0, -0.02, std::numeric_limits<double>::quiet_NaN(),
                           std::numeric_limits<double>::infinity()}) {
    terrain_t m = boxStep(4, 4);
    m.resolution = res;
    EXPECT_EQ(checkTerrain(m), Reject::BadField) << res;
  }
}

TEST(ValidateTerrain, InfiniteHeightsAndOriginsAreRefused) {
  for (const float h : {kInf, -kInf}) {
    terrain_t m = boxStep(4, 4);
    m.height[3][2] = h;
    EXPECT_EQ(checkTerrain(m), Reject::NonFinite) << h;
  }
  terrain_t m = boxStep(4, 4);
  m.origin_x = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(checkTerrain(m), Reject::NonFinite);
  m = boxStep(4, 4);
  m.origin_y = -std::numeric_limits<double>::infinity();
  EXPECT_EQ(checkTerrain(m), Reject::NonFinite);
  // Every cell unknown is a map (of nothing yet).
  m = boxStep(4, 4);
  for (auto& row : m.height) row.assign(row.size(), kNaN);
  EXPECT_EQ(checkTerrain(m), Reject::None);
}

TEST(ValidateTerrain, ANegativeStampIsRefused) {
  terrain_t m = boxStep(4, 4);
  m.utime = -1;
  EXPECT_EQ(checkTerrain(m), Reject::BadField);
  m.utime = 0;  // the robot's first map, at its clock's start
  EXPECT_EQ(checkTerrain(m), Reject::None);
}

TEST(ValidateTerrain, ArraysThatAreNotTheCountsSizesAreRefused) {
  terrain_t m = boxStep(4, 5);
  m.height[2].pop_back();
  EXPECT_EQ(checkTerrain(m), Reject::WrongSize);
  m = boxStep(4, 5);
  m.height.pop_back();
  EXPECT_EQ(checkTerrain(m), Reject::WrongSize);
  m = boxStep(4, 5);
  m.rows = 0;
  m.height.clear();
  EXPECT_EQ(checkTerrain(m), Reject::WrongSize);
}

TEST(ValidateTerrain, ShapeSizesEveryRowAndMarksEveryCellUnknown) {
  terrain_t m;
  shape(m, 3, 7);
  EXPECT_EQ(m.rows, 3);
  EXPECT_EQ(m.cols, 7);
  ASSERT_EQ(m.height.size(), 3u);
  for (const auto& row : m.height) {
    ASSERT_EQ(row.size(), 7u);
    for (float h : row) EXPECT_TRUE(std::isnan(h));
  }
  m.resolution = 0.1;
  EXPECT_EQ(static_cast<long>(encode(m).size()), terrainWireSize(3, 7));
}

}  // namespace test_terrain_checks
}  // namespace stride::msg
