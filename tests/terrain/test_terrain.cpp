// The terrain's queries (terrain/terrain.hpp, terrain/elevation_map.hpp) against hand-computed
// cases: heights and normals of boxes (yawed too), ramps, flights of stairs (ascending, descending
// from a platform, starting on what lies under them), rough patches and their overlaps; bounds;
// the constraints contacts() gives a point above a top, in front of a riser, just inside one, near
// a box's corner and at a ramp's foot; and the elevation grid sampled from a terrain.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <sstream>
#include <string>

#include "terrain/elevation_map.hpp"
#include "terrain/terrain.hpp"

namespace stride::terrain {
namespace test_terrain {

constexpr double kPi = 3.14159265358979323846;
constexpr double kTol = 1e-12;

double deg(double d) {
  return d * kPi / 180.0;
}

Terrain withBox(Eigen::Vector2d center, Eigen::Vector2d size, double height, double yaw = 0.0,
                double ground = 0.0) {
  TerrainSpec s;
  s.ground = ground;
  s.boxes.push_back({center, size, height, yaw});
  return Terrain(s);
}

// A flight of stairs along yaw from `start`: 3 steps of 0.1 m rise and 0.3 m run, 1 m wide, a
// 0.5 m landing.
StairsSpec flight(Eigen::Vector2d start = {0.0, 0.0}, double yaw = 0.0, double rise = 0.1) {
  StairsSpec f;
  f.start = start;
  f.yaw = yaw;
  f.steps = 3;
  f.rise = rise;
  f.run = 0.3;
  f.width = 1.0;
  f.landing = 0.5;
  return f;
}

// A right-handed orthonormal frame [t1 t2 n].
void expectFrame(const Contact& c) {
  EXPECT_NEAR(c.t1.norm(), 1.0, kTol);
  EXPECT_NEAR(c.t2.norm(), 1.0, kTol);
  EXPECT_NEAR(c.normal.norm(), 1.0, kTol);
  EXPECT_NEAR(c.t1.dot(c.normal), 0.0, kTol);
  EXPECT_NEAR(c.t2.dot(c.normal), 0.0, kTol);
  EXPECT_NEAR(c.t1.cross(c.t2).dot(c.normal), 1.0, kTol);
}

std::string str(const Eigen::Vector3d& v) {
  std::ostringstream s;
  s << "(" << v.x() << ", " << v.y() << ", " << v.z() << ")";
  return s.str();
}

// ---------------------------------------------------------------------------------------------
TEST(Terrain, FlatGround) {
  const Terrain t(0.25);
  EXPECT_TRUE(t.isFlat());
  EXPECT_EQ(t.height(3.0, -7.0), 0.25);
  const Surface s = t.surface(-1.0, 2.0);
  EXPECT_EQ(s.height, 0.25);
  EXPECT_EQ(s.normal, Eigen::Vector3d::UnitZ());
  Contact c[4];
  ASSERT_EQ(t.contacts({1.0, 2.0, 0.3}, 0.1, c, 4), 1);
  EXPECT_EQ(c[0].kind, Contact::Kind::Support);
  EXPECT_TRUE(c[0].world_axes);
  EXPECT_NEAR(c[0].distance, 0.05, kTol);
  EXPECT_EQ(c[0].t1, Eigen::Vector3d::UnitX());
  EXPECT_EQ(c[0].t2, Eigen::Vector3d::UnitY());
  EXPECT_THROW(Terrain(std::nan("")), std::invalid_argument);
}

TEST(Terrain, BoxTop) {
  // Centre (1, 0), 0.4 x 0.6, 0.1 high on a ground at 0.05.
  const Terrain t = withBox({1.0, 0.0}, {0.4, 0.6}, 0.1, 0.0, 0.05);
  EXPECT_FALSE(t.isFlat());
  EXPECT_NEAR(t.height(1.1, 0.2), 0.15, kTol);
  EXPECT_NEAR(t.height(0.81, -0.29), 0.15, kTol);
  EXPECT_NEAR(t.height(1.21, 0.0), 0.05, kTol);  // past the +x side
  EXPECT_NEAR(t.height(1.0, 0.31), 0.05, kTol);  // past the +y side
  const Surface s = t.surface(1.1, 0.2);
  EXPECT_NEAR(s.height, 0.15, kTol);
  EXPECT_EQ(s.normal, Eigen::Vector3d::UnitZ());
}

TEST(Terrain, YawedBoxTop) {
  // 1 m x 0.2 m, 0.2 high, its length along 30°.
  const Terrain t = withBox({0.0, 0.0}, {1.0, 0.2}, 0.2, deg(30));
  const Eigen::Vector2d u(std::cos(deg(30)), std::sin(deg(30))), w(-u.y(), u.x());
  for (double a : {-0.45, 0.0, 0.3, 0.45})
    for (double b : {-0.09, 0.0, 0.09}) {
      const Eigen::Vector2d p = a * u + b * w;
      EXPECT_NEAR(t.height(p.x(), p.y()), 0.2, kTol) << a << ", " << b;
    }
  // (0.45, 0) is 0.39 along the box but 0.225 to its side: outside, where an unrotated box
  // would have it.
  EXPECT_NEAR(t.height(0.45, 0.0), 0.0, kTol);
  const Eigen::Vector2d past = 0.51 * u, beside = 0.11 * w;
  EXPECT_NEAR(t.height(past.x(), past.y()), 0.0, kTol);
  EXPECT_NEAR(t.height(beside.x(), beside.y()), 0.0, kTol);
  EXPECT_EQ(t.surface(0.1, 0.05).normal, Eigen::Vector3d::UnitZ());
}

// A 20° ramp rises along its direction; its normal is (-sin 20°, 0, cos 20°) turned by it.
TEST(Terrain, Ramp) {
  const double slope = std::tan(deg(20));
  for (double dir : {0.0, deg(60), deg(-135)}) {
    const Eigen::Vector2d u(std::cos(dir), std::sin(dir)), w(-u.y(), u.x());
    const Eigen::Vector2d from(1.0, -2.0), to = from + 2.0 * u;
    TerrainSpec s;
    s.ground = 0.1;
    s.ramps.push_back({from, to, 0.8, 2.0 * slope});
    const Terrain t(s);
    const Eigen::Vector3d n(-std::sin(deg(20)) * u.x(), -std::sin(deg(20)) * u.y(),
                            std::cos(deg(20)));
    for (double a : {0.01, 0.5, 1.0, 1.99})
      for (double b : {-0.39, 0.0, 0.2}) {
        const Eigen::Vector2d p = from + a * u + b * w;
        const Surface surf = t.surface(p.x(), p.y());
        EXPECT_NEAR(surf.height, 0.1 + a * slope, 1e-12) << "dir " << dir << " at " << a;
        EXPECT_NEAR((surf.normal - n).norm(), 0.0, 1e-12) << "dir " << dir;
      }
    // Before its foot and past its high end: the ground.
    const Eigen::Vector2d before = from - 0.01 * u, after = to + 0.01 * u,
                          side = from + u + 0.41 * w;
    EXPECT_NEAR(t.height(before.x(), before.y()), 0.1, kTol);
    EXPECT_NEAR(t.height(after.x(), after.y()), 0.1, kTol);
    EXPECT_NEAR(t.height(side.x(), side.y()), 0.1, kTol);
    EXPECT_EQ(t.surface(after.x(), after.y()).normal, Eigen::Vector3d::UnitZ());
  }
}

TEST(Terrain, StairsAscending) {
  TerrainSpec s;
  s.stairs.push_back(flight());
  const Terrain t(s);
  EXPECT_NEAR(t.height(-0.001, 0.0), 0.0, kTol);  // just before the first riser
  EXPECT_NEAR(t.height(0.0, 0.0), 0.1, kTol);     // on the riser's line: the higher side
  EXPECT_NEAR(t.height(0.001, 0.0), 0.1, kTol);   // just after it
  EXPECT_NEAR(t.height(0.299, 0.3), 0.1, kTol);   // the nosing of step 1
  EXPECT_NEAR(t.height(0.301, 0.3), 0.2, kTol);   // past riser 2
  EXPECT_NEAR(t.height(0.599, -0.3), 0.2, kTol);
  EXPECT_NEAR(t.height(0.601, -0.3), 0.3, kTol);  // the last step
  EXPECT_NEAR(t.height(0.95, 0.0), 0.3, kTol);    // the landing, at the last step's height
  EXPECT_NEAR(t.height(1.39, 0.49), 0.3, kTol);   // the landing's far corner
  EXPECT_NEAR(t.height(1.41, 0.0), 0.0, kTol);    // past the landing
  EXPECT_NEAR(t.height(0.5, 0.51), 0.0, kTol);    // beside the flight
  EXPECT_EQ(t.surface(0.45, 0.0).normal, Eigen::Vector3d::UnitZ());
}

TEST(Terrain, StairsYawed) {
  // Up along +y from (2, 0).
  TerrainSpec s;
  s.stairs.push_back(flight({2.0, 0.0}, kPi / 2));
  const Terrain t(s);
  EXPECT_NEAR(t.height(2.0, -0.001), 0.0, kTol);
  EXPECT_NEAR(t.height(2.0, 0.15), 0.1, kTol);
  EXPECT_NEAR(t.height(2.45, 0.45), 0.2, kTol);
  EXPECT_NEAR(t.height(1.55, 1.2), 0.3, kTol);
  EXPECT_NEAR(t.height(2.51, 0.15), 0.0, kTol);  // beside it: its width is along x
  EXPECT_NEAR(t.height(2.0, 1.41), 0.0, kTol);
}

// A flight going down from a platform (a box 0.4 m high whose +x side is the flight's start)
// starts at the platform's height, not the ground's.
TEST(Terrain, StairsDescendingFromAPlatform) {
  TerrainSpec s;
  s.boxes.push_back({{-0.5, 0.0}, {1.0, 1.0}, 0.4, 0.0});
  StairsSpec down = flight({0.0, 0.0}, 0.0, -0.1);
  down.landing = 0.0;
  s.stairs.push_back(down);
  const Terrain t(s);
  EXPECT_NEAR(t.height(-0.2, 0.0), 0.4, kTol);  // the platform
  EXPECT_NEAR(t.height(0.001, 0.0), 0.3, kTol);
  EXPECT_NEAR(t.height(0.299, 0.0), 0.3, kTol);
  EXPECT_NEAR(t.height(0.301, 0.0), 0.2, kTol);
  EXPECT_NEAR(t.height(0.601, 0.0), 0.1, kTol);
  EXPECT_NEAR(t.height(0.899, 0.0), 0.1, kTol);
  EXPECT_NEAR(t.height(0.901, 0.0), 0.0, kTol);  // the ground after the last step
}

// A flight starts at the height of whatever lies under its start: here a 0.2 m box, so its steps
// are at 0.3, 0.4, 0.5, also where they leave the box.
TEST(Terrain, StairsStartOnTheSurfaceUnderThem) {
  TerrainSpec s;
  s.boxes.push_back({{0.0, 0.0}, {2.0, 2.0}, 0.2, 0.0});
  s.stairs.push_back(flight());
  const Terrain t(s);
  EXPECT_NEAR(t.height(-0.1, 0.0), 0.2, kTol);
  EXPECT_NEAR(t.height(0.1, 0.0), 0.3, kTol);
  EXPECT_NEAR(t.height(0.4, 0.0), 0.4, kTol);
  EXPECT_NEAR(t.height(1.2, 0.0), 0.5, kTol);  // the landing, past the box's side at x = 1
  EXPECT_NEAR(t.height(0.4, 0.7), 0.2, kTol);  // beside the flight, on the box
}

TEST(Terrain, StairsStartOnARoughCell) {
  TerrainSpec s;
  s.ground = 0.0;
  s.rough.push_back({{-1.0, -1.0}, {1.0, 1.0}, 0.1, 0.04, 11});
  s.stairs.push_back(flight({0.05, 0.05}));
  const Terrain t(s);
  // The cell holding the point just before the start, [0, 0.1) x [0, 0.1).
  TerrainSpec rough_only = s;
  rough_only.stairs.clear();
  const double base = Terrain(rough_only).height(0.02, 0.05);
  EXPECT_NE(base, 0.0);
  EXPECT_NEAR(t.height(0.2, 0.05), base + 0.1, kTol);
  EXPECT_NEAR(t.height(0.95, 0.05), base + 0.3, kTol);
}

TEST(Terrain, RoughPatch) {
  // 1 m x 0.5 m of 0.1 m cells, ±5 cm around a ground at 0.2.
  TerrainSpec s;
  s.ground = 0.2;
  s.rough.push_back({{0.0, 0.0}, {1.0, 0.5}, 0.1, 0.05, 7});
  const Terrain a(s), b(s);
  s.rough[0].seed = 8;
  const Terrain other(s);
  std::set<double> heights;
  int differ = 0, below = 0;
  for (int i = 0; i < 10; ++i)
    for (int j = 0; j < 5; ++j) {
      const double x = 0.1 * i + 0.05, y = 0.1 * j + 0.05;
      const double h = a.height(x, y);
      EXPECT_EQ(h, b.height(x, y)) << "the same seed, cell " << i << ", " << j;
      EXPECT_GE(h, 0.15);
      EXPECT_LE(h, 0.25);
      // One height over the cell.
      EXPECT_EQ(a.height(x - 0.045, y - 0.045), h);
      EXPECT_EQ(a.height(x + 0.045, y + 0.045), h);
      EXPECT_EQ(a.surface(x, y).normal, Eigen::Vector3d::UnitZ());
      heights.insert(h);
      differ += other.height(x, y) != h;
      below += h < 0.2;
    }
  EXPECT_GT(heights.size(), 40u);  // cells are not all alike
  EXPECT_GT(differ, 40);           // another seed, another patch
  EXPECT_GT(below, 5);
  EXPECT_LT(below, 45);
  EXPECT_EQ(a.height(1.01, 0.25), 0.2);  // outside: the ground
  EXPECT_EQ(a.height(0.5, -0.01), 0.2);
}

// A cell below the ground is a hole: a point in it, below the ground's level, has a wall on the
// patch's border whose normal points into the hole.
TEST(Terrain, RoughHoleHasWalls) {
  TerrainSpec s;
  s.rough.push_back({{0.0, 0.0}, {1.0, 0.1}, 0.1, 0.05, 3});
  const Terrain t(s);
  // A hole cell on the patch's -y border: one row of cells.
  int hole = -1;
  for (int i = 0; i < 10 && hole < 0; ++i)
    if (t.height(0.1 * i + 0.05, 0.05) < -0.01) hole = i;
  ASSERT_GE(hole, 0) << "no cell 1 cm below the ground with seed 3";
  const double x = 0.1 * hole + 0.05, depth = t.height(x, 0.05);
  const Eigen::Vector3d p(x, 0.003, 0.5 * depth);  // 3 mm from the -y border, halfway down
  Contact c[4];
  const int n = t.contacts(p, 0.01, c, 4);
  EXPECT_EQ(c[0].kind, Contact::Kind::Support);
  EXPECT_NEAR(c[0].distance, -0.5 * depth, kTol);
  int walls = 0;
  for (int k = 1; k < n; ++k) {
    ASSERT_EQ(c[k].kind, Contact::Kind::Wall);
    if ((c[k].normal - Eigen::Vector3d::UnitY()).norm() < 1e-9) {
      ++walls;
      EXPECT_NEAR(c[k].distance, 0.003, 1e-9);
      expectFrame(c[k]);
    }
  }
  EXPECT_EQ(walls, 1) << "the patch's border, seen from inside the hole";
  // Outside the patch, 3 mm from it on the ground: the hole's face is below, no wall.
  EXPECT_EQ(t.contacts({x, -0.003, 0.001}, 0.01, c, 4), 1);
  EXPECT_NEAR(c[0].distance, 0.001, kTol);
}

// On a vertical face's line the height is the higher side's (terrain.hpp, height()): the risers
// of an ascending and a descending flight, and the lines between a rough patch's cells.
TEST(Terrain, OnAFaceLineTheHigherSide) {
  TerrainSpec up;
  up.stairs.push_back(flight());
  const Terrain t(up);
  for (double x : {0.0, 0.3, 0.6})
    EXPECT_EQ(t.height(x, 0.0), std::max(t.height(x - 1e-9, 0.0), t.height(x + 1e-9, 0.0)))
        << "ascending, x " << x;
  TerrainSpec down;
  down.boxes.push_back({{-0.5, 0.0}, {1.0, 1.0}, 0.4, 0.0});
  down.stairs.push_back(flight({0.0, 0.0}, 0.0, -0.1));
  const Terrain d(down);
  for (double x : {0.3, 0.6})
    EXPECT_NEAR(d.height(x, 0.0), std::max(d.height(x - 1e-9, 0.0), d.height(x + 1e-9, 0.0)), kTol)
        << "descending, x " << x;
  TerrainSpec rough;
  rough.rough.push_back({{-1.0, -1.0}, {1.0, 1.0}, 0.05, 0.02, 5});
  const Terrain r(rough);
  int lower = 0, lines = 0;
  for (int j = 1; j < 40; ++j)
    for (int i = 0; i < 40; ++i) {
      const double x = -1.0 + 0.05 * i + 0.025, y = -1.0 + 0.05 * j;
      ++lines;
      lower += r.height(x, y) < std::max(r.height(x, y - 1e-9), r.height(x, y + 1e-9));
      // The same across the lines along y.
      ++lines;
      lower += r.height(y, x) < std::max(r.height(y - 1e-9, x), r.height(y + 1e-9, x));
    }
  EXPECT_EQ(lower, 0) << "of " << lines << " points on a rough patch's cell lines";
}

TEST(Terrain, HighestWins) {
  // A ramp from x = 0 to 2 rising 0.4 (0.2 at x = 1), and a box 0.2 high across x in [0.8, 1.2]:
  // the box below x = 1, the ramp above.
  TerrainSpec s;
  s.ramps.push_back({{0.0, 0.0}, {2.0, 0.0}, 1.0, 0.4});
  s.boxes.push_back({{1.0, 0.0}, {0.4, 0.2}, 0.2, 0.0});
  const Terrain t(s);
  EXPECT_NEAR(t.height(0.9, 0.0), 0.2, kTol);
  EXPECT_EQ(t.surface(0.9, 0.0).normal, Eigen::Vector3d::UnitZ());
  EXPECT_NEAR(t.height(1.1, 0.0), 0.22, kTol);
  // The ramp's normal, leaning back against its slope of 0.2.
  EXPECT_NEAR((t.surface(1.1, 0.0).normal - Eigen::Vector3d(-0.2, 0, 1).normalized()).norm(), 0.0,
              1e-12);
  EXPECT_NEAR(t.height(0.9, 0.3), 0.18, kTol);  // beside the box: the ramp

  // Two boxes overlapping in x in [0.5, 1]: the higher one there.
  TerrainSpec two;
  two.boxes.push_back({{0.5, 0.0}, {1.0, 1.0}, 0.1, 0.0});
  two.boxes.push_back({{1.0, 0.0}, {1.0, 1.0}, 0.2, 0.0});
  const Terrain u(two);
  EXPECT_NEAR(u.height(0.25, 0.0), 0.1, kTol);
  EXPECT_NEAR(u.height(0.75, 0.0), 0.2, kTol);
  EXPECT_NEAR(u.height(1.25, 0.0), 0.2, kTol);
  // In either order.
  std::swap(two.boxes[0], two.boxes[1]);
  EXPECT_NEAR(Terrain(two).height(0.75, 0.0), 0.2, kTol);
}

TEST(Terrain, Bounds) {
  Eigen::Vector2d lo, hi;
  Terrain(0.3).bounds(lo, hi);
  EXPECT_EQ(lo, Eigen::Vector2d::Zero());
  EXPECT_EQ(hi, Eigen::Vector2d::Zero());
  // A 2 x 2 box yawed 45° at (1, 2) reaches √2 from its centre along x and y; a flight from the
  // origin along x, 3 x 0.3 + 0.5 long, 1 wide.
  TerrainSpec s;
  s.boxes.push_back({{1.0, 2.0}, {2.0, 2.0}, 0.1, deg(45)});
  s.stairs.push_back(flight());
  Terrain(s).bounds(lo, hi);
  const double r = std::sqrt(2.0);
  EXPECT_NEAR(lo.x(), 1.0 - r, 1e-12);
  EXPECT_NEAR(lo.y(), -0.5, 1e-12);
  EXPECT_NEAR(hi.x(), 1.0 + r, 1e-12);
  EXPECT_NEAR(hi.y(), 2.0 + r, 1e-12);
}

// ---------------------------------------------------------------------------------------------
// contacts()

TEST(TerrainContacts, AboveABoxTop) {
  const Terrain t = withBox({0.0, 0.0}, {1.0, 1.0}, 0.2);
  Contact c[4];
  const Eigen::Vector3d p(0.1, -0.2, 0.25);
  ASSERT_EQ(t.contacts(p, 0.01, c, 4), 1);
  EXPECT_EQ(c[0].kind, Contact::Kind::Support);
  EXPECT_NEAR(c[0].distance, 0.05, kTol);
  EXPECT_NEAR((c[0].point - Eigen::Vector3d(0.1, -0.2, 0.2)).norm(), 0.0, kTol);
  EXPECT_EQ(c[0].normal, Eigen::Vector3d::UnitZ());
  EXPECT_TRUE(c[0].world_axes);
  // Sunk 1 mm into it: negative.
  ASSERT_EQ(t.contacts({0.1, -0.2, 0.199}, 0.01, c, 4), 1);
  EXPECT_NEAR(c[0].distance, -0.001, kTol);
}

TEST(TerrainContacts, AboveARamp) {
  const double th = deg(20);
  TerrainSpec s;
  s.ramps.push_back({{0.0, 0.0}, {1.0, 0.0}, 1.0, std::tan(th)});
  const Terrain t(s);
  Contact c[4];
  ASSERT_EQ(t.contacts({0.5, 0.0, 0.5 * std::tan(th) + 0.1}, 0.01, c, 4), 1);
  // The distance to the ramp's plane, not the vertical gap.
  EXPECT_NEAR(c[0].distance, 0.1 * std::cos(th), 1e-12);
  EXPECT_NEAR(c[0].point.z(), std::tan(th) * c[0].point.x(), 1e-12);  // on the plane
  EXPECT_FALSE(c[0].world_axes);
  expectFrame(c[0]);
  EXPECT_NEAR((c[0].normal - Eigen::Vector3d(-std::sin(th), 0, std::cos(th))).norm(), 0, 1e-12);
}

// In front of a riser, below its top: a wall whose normal points away from the riser, at the
// horizontal gap; above the step's top, none.
TEST(TerrainContacts, InFrontOfARiser) {
  for (double yaw : {0.0, kPi / 2, deg(-30)}) {
    TerrainSpec s;
    s.stairs.push_back(flight({0.5, 0.5}, yaw));
    const Terrain t(s);
    const Eigen::Vector2d u(std::cos(yaw), std::sin(yaw));
    const Eigen::Vector2d xy = Eigen::Vector2d(0.5, 0.5) - 0.004 * u;
    Contact c[4];
    const int n = t.contacts({xy.x(), xy.y(), 0.05}, 0.01, c, 4);
    ASSERT_EQ(n, 2) << "yaw " << yaw;
    EXPECT_EQ(c[0].kind, Contact::Kind::Support);
    EXPECT_NEAR(c[0].distance, 0.05, kTol);
    EXPECT_EQ(c[1].kind, Contact::Kind::Wall);
    EXPECT_NEAR(c[1].distance, 0.004, 1e-9);
    EXPECT_NEAR((c[1].normal - Eigen::Vector3d(-u.x(), -u.y(), 0.0)).norm(), 0.0, 1e-9)
        << "yaw " << yaw << ": " << str(c[1].normal);
    EXPECT_NEAR((c[1].point - Eigen::Vector3d(0.5, 0.5, 0.05)).norm(), 0.0, 1e-9);
    EXPECT_FALSE(c[1].world_axes);
    expectFrame(c[1]);
    // Above the step's top: the support only.
    EXPECT_EQ(t.contacts({xy.x(), xy.y(), 0.11}, 0.01, c, 4), 1);
    // Out of reach: the support only.
    EXPECT_EQ(t.contacts({xy.x(), xy.y(), 0.05}, 0.003, c, 4), 1);
  }
}

// Between risers: in front of riser 2 (on step 1) at 0.15, below step 2's top at 0.2.
TEST(TerrainContacts, InFrontOfTheSecondRiser) {
  TerrainSpec s;
  s.stairs.push_back(flight());
  const Terrain t(s);
  Contact c[4];
  ASSERT_EQ(t.contacts({0.295, 0.0, 0.15}, 0.01, c, 4), 2);
  EXPECT_NEAR(c[0].distance, 0.05, kTol);
  EXPECT_NEAR(c[1].distance, 0.005, 1e-9);
  EXPECT_NEAR((c[1].normal - Eigen::Vector3d(-1, 0, 0)).norm(), 0.0, 1e-9);
  // Above step 2's top: no face.
  EXPECT_EQ(t.contacts({0.295, 0.0, 0.21}, 0.01, c, 4), 1);
}

// A foot crossed 1 mm into a riser sideways, well below the step's top, is pushed back out of
// the riser (a wall at -1 mm) and stands on the low side (the ground at 0, 5 mm below it), not
// 9.5 cm deep under the step's top.
TEST(TerrainContacts, JustInsideARiser) {
  for (double yaw : {0.0, deg(135)}) {
    TerrainSpec s;
    s.stairs.push_back(flight({0.0, 0.0}, yaw));
    const Terrain t(s);
    const Eigen::Vector2d u(std::cos(yaw), std::sin(yaw)), xy = 0.001 * u;
    Contact c[4];
    const int n = t.contacts({xy.x(), xy.y(), 0.005}, 0.01, c, 4);
    ASSERT_EQ(n, 2) << "yaw " << yaw;
    EXPECT_EQ(c[0].kind, Contact::Kind::Support);
    EXPECT_NEAR(c[0].distance, 0.005, 1e-9) << "yaw " << yaw;
    EXPECT_EQ(c[0].normal, Eigen::Vector3d::UnitZ());
    EXPECT_EQ(c[1].kind, Contact::Kind::Wall);
    EXPECT_NEAR(c[1].distance, -0.001, 1e-9);
    EXPECT_NEAR((c[1].normal - Eigen::Vector3d(-u.x(), -u.y(), 0.0)).norm(), 0.0, 1e-9);
    expectFrame(c[1]);
  }
}

// Deeper inside a riser than the reach (3 mm in, 1 mm of reach), 9.5 cm below the step's top:
// still the shortest way out, sideways; the reach bounds the faces a point is about to touch,
// not the ones it is already in.
TEST(TerrainContacts, InsideARiserDeeperThanTheReach) {
  TerrainSpec s;
  s.stairs.push_back(flight());
  const Terrain t(s);
  Contact c[4];
  const int n = t.contacts({0.003, 0.0, 0.005}, 0.001, c, 4);
  EXPECT_NEAR(c[0].distance, 0.005, 1e-9)
      << "the support should be the ground's, got " << c[0].distance << " (the step's top)";
  bool wall = false;
  for (int k = 1; k < n; ++k)
    wall |= c[k].kind == Contact::Kind::Wall &&
            (c[k].normal - Eigen::Vector3d(-1, 0, 0)).norm() < 1e-9 &&
            std::abs(c[k].distance + 0.003) < 1e-9;
  EXPECT_TRUE(wall) << "no way out through the riser: " << n << " constraints";
}

// The same, the foot resting 0.1 mm into the ground (the contact solver's slop) as it crosses:
// still pushed back out of the riser, not up onto the step.
TEST(TerrainContacts, JustInsideARiserSunkIntoTheGround) {
  TerrainSpec s;
  s.stairs.push_back(flight());
  const Terrain t(s);
  Contact c[4];
  const int n = t.contacts({0.0005, 0.0, -1e-4}, 0.01, c, 4);
  EXPECT_NEAR(c[0].distance, -1e-4, 1e-9)
      << "the support should be the ground's, got " << c[0].distance << " (the step's top)";
  bool wall = false;
  for (int k = 1; k < n; ++k)
    wall |= c[k].kind == Contact::Kind::Wall &&
            (c[k].normal - Eigen::Vector3d(-1, 0, 0)).norm() < 1e-9 &&
            std::abs(c[k].distance + 0.0005) < 1e-9;
  EXPECT_TRUE(wall) << "no way out through the riser: " << n << " constraints";
}

// Near a box's corner, outside it: the wall's normal points from the corner to the point and its
// distance is the distance to the corner's edge.
TEST(TerrainContacts, NearABoxCorner) {
  const Terrain t = withBox({0.0, 0.0}, {0.2, 0.2}, 0.1);
  Contact c[4];
  const int n = t.contacts({0.103, 0.104, 0.05}, 0.01, c, 4);
  ASSERT_GE(n, 2);
  EXPECT_EQ(c[0].kind, Contact::Kind::Support);
  EXPECT_NEAR(c[0].distance, 0.05, kTol);
  for (int k = 1; k < n; ++k) {
    EXPECT_EQ(c[k].kind, Contact::Kind::Wall);
    EXPECT_NEAR(c[k].distance, 0.005, 1e-9);
    EXPECT_NEAR((c[k].normal - Eigen::Vector3d(0.6, 0.8, 0.0)).norm(), 0.0, 1e-9)
        << str(c[k].normal);
    EXPECT_NEAR((c[k].point - Eigen::Vector3d(0.1, 0.1, 0.05)).norm(), 0.0, 1e-9);
  }
  // One corner, one constraint: the two sides meeting there are the same wall to the point.
  EXPECT_EQ(n, 2) << "the corner's wall is given " << n - 1 << " times";
  // Beside the +x side (not past the corner): its plane.
  ASSERT_EQ(t.contacts({0.103, 0.05, 0.05}, 0.01, c, 4), 2);
  EXPECT_NEAR(c[1].distance, 0.003, 1e-9);
  EXPECT_NEAR((c[1].normal - Eigen::Vector3d(1, 0, 0)).norm(), 0.0, 1e-9);
}

// A ramp's foot meets the ground at a kink: no wall. Its high end and its sides are faces.
TEST(TerrainContacts, RampFootIsNoWall) {
  TerrainSpec s;
  s.ramps.push_back({{0.0, 0.0}, {1.0, 0.0}, 1.0, 0.3});
  const Terrain t(s);
  Contact c[4];
  EXPECT_EQ(t.contacts({-0.003, 0.0, 0.0005}, 0.01, c, 4), 1);
  EXPECT_EQ(t.contacts({0.003, 0.0, 0.0015}, 0.01, c, 4), 1);
  // Past the high end, below its top: a wall facing +x.
  ASSERT_EQ(t.contacts({1.003, 0.0, 0.1}, 0.01, c, 4), 2);
  EXPECT_NEAR(c[1].distance, 0.003, 1e-9);
  EXPECT_NEAR((c[1].normal - Eigen::Vector3d(1, 0, 0)).norm(), 0.0, 1e-9);
  // Beside it where it is 0.15 high, at 5 cm: a wall facing +y.
  ASSERT_EQ(t.contacts({0.5, 0.503, 0.05}, 0.01, c, 4), 2);
  EXPECT_NEAR(c[1].distance, 0.003, 1e-9);
  EXPECT_NEAR((c[1].normal - Eigen::Vector3d(0, 1, 0)).norm(), 0.0, 1e-9);
}

// At most `max`, the nearest kept; a max of 1 is the support alone.
// A point that is not a place (NaN, from a robot whose state went bad) gets the support alone, and
// no index is computed from it (clang's UBSan flags a NaN cast to int).
TEST(TerrainContacts, NotAPlaceGetsTheSupportAlone) {
  TerrainSpec s;
  s.stairs.push_back({{0.0, 0.0}, 0.0, 3, 0.1, 0.3, 1.0, 0.5});
  s.rough.push_back({{-2.0, -1.0}, {-1.0, 1.0}, 0.1, 0.02, 1});
  const Terrain t(s);
  Contact out[4];
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(t.contacts({nan, 0.0, 0.05}, 0.01, out, 4), 1);
  EXPECT_EQ(t.contacts({0.5, nan, 0.05}, 0.01, out, 4), 1);
  EXPECT_EQ(t.contacts({0.5, 0.0, nan}, 0.01, out, 4), 1);
  EXPECT_EQ(out[0].kind, Contact::Kind::Support);
}

TEST(TerrainContacts, AtMostMax) {
  // The inner corner of two boxes' sides: a point in front of both.
  TerrainSpec s;
  s.boxes.push_back({{0.0, 0.5}, {1.0, 1.0}, 0.2, 0.0});   // y in [0, 1]
  s.boxes.push_back({{0.5, -0.5}, {1.0, 1.0}, 0.2, 0.0});  // x in [0, 1]
  const Terrain t(s);
  Contact c[4];
  const Eigen::Vector3d p(-0.002, -0.004, 0.05);
  ASSERT_EQ(t.contacts(p, 0.01, c, 4), 3);
  std::set<std::pair<int, int>> normals;
  for (int k = 1; k < 3; ++k)
    normals.insert({static_cast<int>(std::lround(c[k].normal.x())),
                    static_cast<int>(std::lround(c[k].normal.y()))});
  EXPECT_TRUE(normals.count({-1, 0}));  // the box along x, its -x side 2 mm away
  EXPECT_TRUE(normals.count({0, -1}));  // the box along y, its -y side 4 mm away
  ASSERT_EQ(t.contacts(p, 0.01, c, 2), 2);
  EXPECT_NEAR(c[1].distance, 0.002, 1e-9);  // the nearer
  ASSERT_EQ(t.contacts(p, 0.01, c, 1), 1);
  EXPECT_EQ(c[0].kind, Contact::Kind::Support);
  EXPECT_EQ(t.contacts(p, 0.01, c, 0), 0);
}

// ---------------------------------------------------------------------------------------------
// ElevationMap

TEST(ElevationMap, SampledOverABox) {
  // A box 0.3 x 0.3 at (0.5, 0.2), 0.1 high on a ground at 0.05; cells of 2 cm (no cell centre on
  // the box's sides at x = 0.35, 0.65, y = 0.05, 0.35).
  const Terrain t = withBox({0.5, 0.2}, {0.3, 0.3}, 0.1, 0.0, 0.05);
  ElevationMap map;
  map.resolution = 0.02;
  map.resize(21, 31);
  EXPECT_TRUE(std::isnan(map.heightAt(0.0, 0.0)));  // unknown before sampling
  sampleTerrain(t, 0.513, 0.207, map);
  // The origin on the grid, the map centred on the cell nearest (0.513, 0.207).
  EXPECT_NEAR(map.origin_x / 0.02, std::round(map.origin_x / 0.02), 1e-9);
  EXPECT_NEAR(map.origin_y / 0.02, std::round(map.origin_y / 0.02), 1e-9);
  EXPECT_NEAR(map.origin_x, 0.22, 1e-12);
  EXPECT_NEAR(map.origin_y, 0.0, 1e-12);
  int in_box = 0;
  for (int r = 0; r < map.rows; ++r)
    for (int c = 0; c < map.cols; ++c) {
      const double x = map.origin_x + c * 0.02, y = map.origin_y + r * 0.02;
      const bool inside = std::abs(x - 0.5) < 0.15 && std::abs(y - 0.2) < 0.15;
      in_box += inside;
      EXPECT_EQ(map.at(r, c), static_cast<float>(inside ? 0.15 : 0.05)) << r << ", " << c;
    }
  EXPECT_EQ(in_box, 15 * 15);
  EXPECT_FLOAT_EQ(map.heightAt(0.5, 0.2), 0.15f);
  EXPECT_FLOAT_EQ(map.heightAt(0.229, 0.009), 0.05f);  // cell (0, 0), rounded to the nearest
  EXPECT_TRUE(std::isnan(map.heightAt(0.209, 0.0)));   // half a cell before the first column
  EXPECT_TRUE(std::isnan(map.heightAt(0.5, 0.411)));   // past the last row
  EXPECT_FLOAT_EQ(map.heightAt(0.82, 0.4), 0.05f);     // the last cell
  // A little further, the same grid: the origin moves by whole cells.
  sampleTerrain(t, 0.553, 0.207, map);
  EXPECT_NEAR(map.origin_x, 0.26, 1e-12);
  EXPECT_FLOAT_EQ(map.heightAt(0.5, 0.2), 0.15f);
}

}  // namespace test_terrain
}  // namespace stride::terrain
