// Planning on an elevation map (issue 31): steppability, foothold selection, swing clearance and
// the ground plane from the stance feet, against hand-made maps and points whose answers are known;
// and that the per-call functions touch no heap (malloc counted: allocation_counter.hpp).

#include <gtest/gtest.h>

#include "allocation_counter.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "terrain/elevation_map.hpp"
#include "terrain/foothold.hpp"
#include "terrain/ground_plane.hpp"
#include "terrain/steppability.hpp"

namespace stride::terrain {
namespace test_terrain_planning {

using stride::test_support::allocations;

constexpr double kPi = 3.14159265358979323846;
constexpr double kRes = 0.02;
const double kNaN = std::numeric_limits<double>::quiet_NaN();

double deg(double d) {
  return d * kPi / 180.0;
}

// rows x cols at 2 cm from the origin (0, 0), every cell at `h`.
ElevationMap flatMap(int rows, int cols, float h = 0.0f) {
  ElevationMap map;
  map.resolution = kRes;
  map.resize(rows, cols);
  for (float& z : map.height) z = h;
  return map;
}

// 30 x 50 cells, ground at 0, a box `height` high on columns >= 25: its side is the line
// x = 24.5 cells = 0.49 m.
ElevationMap boxMap(float height = 0.05f) {
  ElevationMap map = flatMap(30, 50);
  for (int r = 0; r < map.rows; ++r)
    for (int c = 25; c < map.cols; ++c) map.at(r, c) = height;
  return map;
}

// The thresholds these cases were drawn for (the shipped default min_edge_distance is 4 cm:
// terrain/steppability.hpp): edges within 3 cm, searched within 6 cm.
SteppabilityOptions threeCentimetres() {
  SteppabilityOptions o;
  o.min_edge_distance = 0.03;
  o.edge_search_radius = 0.06;
  return o;
}

Steppability computed(const ElevationMap& map, SteppabilityOptions options = threeCentimetres()) {
  Steppability s(options, map.rows * map.cols);
  EXPECT_TRUE(s.update(map));
  return s;
}

TEST(Steppability, FlatMapSteppableAwayFromItsUnknownBorder) {
  // Two rings of unknown cells around a known flat floor (rows and columns 2 .. rows - 3): the side
  // between them is 0.5 cell (1 cm) from the first known ring, 1.5 cells (3 cm) from the second.
  ElevationMap map = flatMap(20, 30, 0.1f);
  for (int r = 0; r < map.rows; ++r)
    for (int c = 0; c < map.cols; ++c)
      if (r < 2 || r >= map.rows - 2 || c < 2 || c >= map.cols - 2) map.at(r, c) = NAN;
  const Steppability s = computed(map);  // min_edge_distance 3 cm
  ASSERT_TRUE(s.valid());
  int count = 0;
  for (int r = 0; r < map.rows; ++r)
    for (int c = 0; c < map.cols; ++c) {
      const bool inner = r >= 3 && r <= map.rows - 4 && c >= 3 && c <= map.cols - 4;
      EXPECT_EQ(s.steppable(r, c), inner) << r << ", " << c;
      count += inner;
      if (!std::isnan(map.at(r, c))) {
        EXPECT_NEAR(s.slope(r, c), 0.0, 1e-9);
        EXPECT_NEAR(s.normal(r, c).z(), 1.0, 1e-12);
      } else {
        EXPECT_TRUE(std::isnan(s.slope(r, c)));
        EXPECT_EQ(s.edgeDistance(r, c), 0.0);
      }
    }
  EXPECT_EQ(s.steppableCount(), count);
  EXPECT_NEAR(s.edgeDistance(10, 2), 0.01, 1e-6);
  EXPECT_NEAR(s.edgeDistance(10, 3), 0.03, 1e-6);
  EXPECT_NEAR(s.edgeDistance(10, 4), 0.05, 1e-6);
  EXPECT_NEAR(s.edgeDistance(3, 3), 0.03, 1e-6);
  // Beyond the search radius (6 cm): no edge near.
  EXPECT_TRUE(std::isinf(s.edgeDistance(10, 15)));

  // Unknown cells as no edge: every known cell is steppable, the map's own border included.
  SteppabilityOptions lenient = threeCentimetres();
  lenient.unknown_is_edge = false;
  EXPECT_EQ(computed(map, lenient).steppableCount(), 16 * 26);
}

TEST(Steppability, BoxStepUnsteppableWithinMinEdgeDistanceOnBothSides) {
  const ElevationMap map = boxMap(0.05f);
  SteppabilityOptions options = threeCentimetres();
  options.min_edge_distance = 0.04;
  const Steppability s = computed(map, options);
  // Cell centres are 1 and 3 cm from the side on either side (columns 24, 23 below, 25, 26 on the
  // box), then 5 cm (22, 27). The map's border is an edge too (what lies beyond is unknown).
  EXPECT_NEAR(s.edgeDistance(15, 24), 0.01, 1e-6);
  EXPECT_NEAR(s.edgeDistance(15, 23), 0.03, 1e-6);
  EXPECT_NEAR(s.edgeDistance(15, 25), 0.01, 1e-6);
  EXPECT_NEAR(s.edgeDistance(15, 26), 0.03, 1e-6);
  EXPECT_NEAR(s.edgeDistance(15, 22), 0.05, 1e-6);
  for (int r = 2; r < map.rows - 2; ++r)
    for (int c = 2; c < map.cols - 2; ++c)
      EXPECT_EQ(s.steppable(r, c), c < 23 || c > 26) << r << ", " << c;
  for (int c = 0; c < map.cols; ++c) EXPECT_FALSE(s.steppable(1, c)) << c;  // 3 cm from the border

  // The default 3 cm: the cells 3 cm away are steppable, those 1 cm away are not.
  const Steppability s3 = computed(map);
  EXPECT_FALSE(s3.steppable(15, 24));
  EXPECT_FALSE(s3.steppable(15, 25));
  EXPECT_TRUE(s3.steppable(15, 23));
  EXPECT_TRUE(s3.steppable(15, 26));
  // The point, not its cell: 2.5 cm from the side inside a cell whose centre is 3 cm away.
  EXPECT_NEAR(s3.edgeDistanceAt(0.465, 0.3), 0.025, 1e-9);

  // A 1.5 cm step is below the jump height: no edge, and its slope is within 30 degrees.
  const Steppability low = computed(boxMap(0.015f));
  EXPECT_TRUE(std::isinf(low.edgeDistance(15, 24)));
  EXPECT_TRUE(low.steppable(15, 24));
  EXPECT_TRUE(low.steppable(15, 25));
}

TEST(Steppability, RampSlopeAndNormal) {
  // 20 degrees rising along the direction 30 degrees from x.
  const double slope = deg(20), dir = deg(30);
  ElevationMap map = flatMap(30, 30);
  for (int r = 0; r < map.rows; ++r)
    for (int c = 0; c < map.cols; ++c)
      map.at(r, c) = static_cast<float>(std::tan(slope) *
                                        (c * kRes * std::cos(dir) + r * kRes * std::sin(dir)));
  const Eigen::Vector3d n(-std::sin(slope) * std::cos(dir), -std::sin(slope) * std::sin(dir),
                          std::cos(slope));
  SteppabilityOptions options = threeCentimetres();
  options.max_slope = deg(30);
  const Steppability s = computed(map, options);
  // All but the border ring (1 cm from the map's edge).
  for (int r = 1; r < map.rows - 1; ++r)
    for (int c = 1; c < map.cols - 1; ++c) {
      ASSERT_TRUE(s.steppable(r, c)) << r << ", " << c;
      EXPECT_NEAR(s.slope(r, c), slope, 1e-5);
      EXPECT_NEAR((s.normal(r, c) - n).norm(), 0.0, 1e-5);
    }
  EXPECT_EQ(s.steppableCount(), 28 * 28);

  options.max_slope = deg(15);
  const Steppability steep = computed(map, options);
  EXPECT_EQ(steep.steppableCount(), 0);
  EXPECT_NEAR(steep.slope(15, 15), slope, 1e-5);
}

TEST(Steppability, RefusesMapsItCannotHold) {
  Steppability s(threeCentimetres(), 100);
  ElevationMap big = flatMap(11, 10);
  EXPECT_FALSE(s.update(big));
  EXPECT_FALSE(s.valid());
  EXPECT_EQ(s.steppableCount(), 0);
  ElevationMap bad = flatMap(10, 10);
  bad.resolution = 0.0;
  EXPECT_FALSE(s.update(bad));
  ElevationMap ok = flatMap(10, 10);
  EXPECT_TRUE(s.update(ok));
  EXPECT_EQ(s.steppableCount(), 8 * 8);  // the border ring is 1 cm from the map's edge
  EXPECT_EQ(selectFoothold(Steppability({}, 10), {0.1, 0.1}, {}).status, FootholdStatus::Unknown);
  SteppabilityOptions blind;
  blind.min_edge_distance = 0.05;
  blind.edge_search_radius = 0.04;  // an edge 4 to 5 cm away would go unseen
  EXPECT_THROW(Steppability{blind}, std::invalid_argument);
  SteppabilityOptions negative;
  negative.edge_height = -0.01;
  EXPECT_THROW(Steppability{negative}, std::invalid_argument);
}

TEST(Foothold, NominalWhereItIsSafe) {
  const Steppability s = computed(boxMap());
  FootholdReach reach;
  const Foothold f = selectFoothold(s, {0.203, 0.307}, reach);
  EXPECT_EQ(f.status, FootholdStatus::Nominal);
  EXPECT_EQ(f.position.x(), 0.203);
  EXPECT_EQ(f.position.y(), 0.307);
  EXPECT_EQ(f.position.z(), 0.0);
  EXPECT_EQ(f.shift, 0.0);
  EXPECT_NEAR(f.normal.z(), 1.0, 1e-12);
  const Foothold on_box = selectFoothold(s, {0.7, 0.3}, reach);
  EXPECT_EQ(on_box.status, FootholdStatus::Nominal);
  EXPECT_NEAR(on_box.position.z(), 0.05, 1e-7);
}

TEST(Foothold, OnAnEdgeMovesToTheNearestSafeCell) {
  const Steppability s = computed(boxMap());  // side at x = 0.49, min_edge_distance 3 cm
  FootholdReach reach;
  reach.max_shift = 0.1;
  // 2 mm onto the box: the safe cells are at x = 0.46 (3.2 cm back) and 0.52 (2.8 cm ahead).
  const Foothold f = selectFoothold(s, {0.492, 0.30}, reach);
  EXPECT_EQ(f.status, FootholdStatus::Moved);
  EXPECT_EQ(f.row, 15);
  EXPECT_EQ(f.col, 26);
  EXPECT_NEAR(f.position.x(), 0.52, 1e-12);
  EXPECT_NEAR(f.position.y(), 0.30, 1e-12);
  EXPECT_NEAR(f.position.z(), 0.05, 1e-7);
  EXPECT_NEAR(f.shift, 0.028, 1e-12);
  EXPECT_NEAR(f.normal.z(), 1.0, 1e-12);
  EXPECT_GE(s.edgeDistanceAt(f.position.x(), f.position.y()), 0.03 - 1e-9);

  // 2 mm in front of the side: back to x = 0.46 (2.8 cm) rather than onto the box (3.2 cm).
  const Foothold g = selectFoothold(s, {0.488, 0.30}, reach);
  EXPECT_EQ(g.status, FootholdStatus::Moved);
  EXPECT_EQ(g.col, 23);
  EXPECT_NEAR(g.position.z(), 0.0, 1e-12);

  // In a steppable cell (centre 3 cm from the side) but the point itself 2.5 cm from it: moved to
  // the cell 5 cm from the side (2.5 cm away), not to its own cell's centre 3 cm from it (5 mm
  // away): within the search radius (6 cm) a centimetre nearer the edge costs as a centimetre of
  // shift, 2.5^2 + 1^2 < 0.5^2 + 3^2.
  const Foothold h = selectFoothold(s, {0.465, 0.30}, reach);
  EXPECT_EQ(h.status, FootholdStatus::Moved);
  EXPECT_EQ(h.row, 15);
  EXPECT_EQ(h.col, 22);
  EXPECT_NEAR(h.shift, 0.025, 1e-12);
}

TEST(Foothold, AClearerCellIsWorthItsShift) {
  // The box's side at x = 0.49, edges within 3 cm unsafe, searched within 6 cm.
  const Steppability s = computed(boxMap());
  FootholdReach reach;
  reach.max_shift = 0.1;
  // A safe nominal 5.5 cm from the side: kept (0.5^2 beats any move: the cell 0.44, 5 cm from the
  // side, costs 0.5^2 + 1^2, the first past the radius, 0.42, 1.5^2).
  Foothold f = selectFoothold(s, {0.435, 0.30}, reach);
  EXPECT_EQ(f.status, FootholdStatus::Nominal);
  EXPECT_EQ(f.position.x(), 0.435);
  // 3.2 cm from it: to the cell at 5 cm (1.8^2 + 1^2 < 2.8^2).
  f = selectFoothold(s, {0.458, 0.30}, reach);
  EXPECT_EQ(f.status, FootholdStatus::Moved);
  EXPECT_NEAR(f.position.x(), 0.44, 1e-12);
  EXPECT_GE(s.edgeDistanceAt(f.position.x(), f.position.y()), 0.05 - 1e-9);
  // 6 cm or more from every edge: the nominal point itself, not a cell's centre.
  f = selectFoothold(s, {0.421, 0.30}, reach);
  EXPECT_EQ(f.status, FootholdStatus::Nominal);
  EXPECT_EQ(f.position.x(), 0.421);
  // Nothing clearer within reach: a safe nominal near the edge is kept as it is.
  reach.max_shift = 0.0;
  f = selectFoothold(s, {0.458, 0.30}, reach);
  EXPECT_EQ(f.status, FootholdStatus::Nominal);
  EXPECT_EQ(f.position.x(), 0.458);
}

TEST(Foothold, AMoveAgainstTheTravelCountsTwice) {
  // The box's side at x = 0.49: the nearest safe cells are 0.46 before it and 0.52 on the box
  // (3 cm each way). From 0.485, 2.5 cm back or 3.5 cm on: without a direction the shorter step
  // back; walking +x the longer one over the edge (2 x 2.5 > 3.5); walking -x, back.
  const Steppability map = computed(boxMap());
  FootholdReach reach;
  EXPECT_NEAR(selectFoothold(map, {0.485, 0.3}, reach).position.x(), 0.46, 1e-12);
  reach.forward = Eigen::Vector2d::UnitX();
  Foothold f = selectFoothold(map, {0.485, 0.3}, reach);
  EXPECT_EQ(f.status, FootholdStatus::Moved);
  EXPECT_NEAR(f.position.x(), 0.52, 1e-12);
  EXPECT_NEAR(f.position.z(), 0.05, 1e-7);
  EXPECT_NEAR(f.shift, 0.035, 1e-12);  // the distance itself, not the weighted one
  reach.forward = -Eigen::Vector2d::UnitX();
  EXPECT_NEAR(selectFoothold(map, {0.485, 0.3}, reach).position.x(), 0.46, 1e-12);
  // Still the nearest when the step back is less than half the one on: from 0.475, 1.5 cm back
  // against 4.5 cm on.
  reach.forward = Eigen::Vector2d::UnitX();
  EXPECT_NEAR(selectFoothold(map, {0.475, 0.3}, reach).position.x(), 0.46, 1e-12);
}

TEST(Foothold, TheLastChoiceStaysInReachLonger) {
  // The box's side at x = 0.49: safe cells at 0.46 before it and 0.52 on it. From 0.488 walking
  // +x, the cell on the box is 3.2 cm on, beyond a reach of 3 cm: back to 0.46 (2.8 cm).
  const Steppability map = computed(boxMap());
  FootholdReach reach;
  reach.max_shift = 0.03;
  reach.forward = Eigen::Vector2d::UnitX();
  EXPECT_NEAR(selectFoothold(map, {0.488, 0.3}, reach).position.x(), 0.46, 1e-12);
  // Chosen on the box at the last plan (the body has since lagged 1 cm): kept, within 4.5 cm.
  reach.kept = {0.52, 0.3};
  reach.kept_max_shift = 0.045;
  Foothold f = selectFoothold(map, {0.488, 0.3}, reach);
  EXPECT_EQ(f.status, FootholdStatus::Moved);
  EXPECT_NEAR(f.position.x(), 0.52, 1e-12);
  EXPECT_NEAR(f.position.z(), 0.05, 1e-7);
  EXPECT_NEAR(f.shift, 0.032, 1e-12);
  // Any point of the kept cell names it.
  reach.kept = {0.527, 0.305};
  EXPECT_NEAR(selectFoothold(map, {0.488, 0.3}, reach).position.x(), 0.52, 1e-12);
  // Beyond the longer reach too: the nearest safe cell again.
  reach.kept_max_shift = 0.031;
  EXPECT_NEAR(selectFoothold(map, {0.488, 0.3}, reach).position.x(), 0.46, 1e-12);
  reach.kept_max_shift = 0.045;
  // A kept place that is not safe (on the edge) is not kept.
  reach.kept = {0.49, 0.3};
  EXPECT_NEAR(selectFoothold(map, {0.488, 0.3}, reach).position.x(), 0.46, 1e-12);
  // Only a longer reach, not a discount: a cheaper cell within the reach still wins (from 0.505 on
  // the box, 0.52 at 1.5 cm beats the kept 0.46 at 4.5 cm).
  reach.kept = {0.46, 0.3};
  EXPECT_NEAR(selectFoothold(map, {0.505, 0.3}, reach).position.x(), 0.52, 1e-12);
}

TEST(Foothold, SafeCellsBeyondReachAreReportedNotTaken) {
  const Steppability s = computed(boxMap());
  const Eigen::Vector2d nominal(0.492, 0.30);
  FootholdReach reach;
  reach.max_shift = 0.02;  // the nearest safe cell is 2.8 cm away
  const Foothold f = selectFoothold(s, nominal, reach);
  EXPECT_EQ(f.status, FootholdStatus::Unreachable);
  EXPECT_EQ(f.position.x(), nominal.x());
  EXPECT_EQ(f.position.y(), nominal.y());
  EXPECT_NEAR(f.position.z(), 0.05, 1e-7);  // the nominal's cell, on the box
  EXPECT_EQ(f.shift, 0.0);

  // The hip's reach rules out the box side: back to the ground's side, 3.2 cm.
  reach.max_shift = 0.1;
  reach.hip = {0.3, 0.3};
  reach.max_hip_distance = 0.19;  // x = 0.52 is 0.22 from the hip, x = 0.46 is 0.16
  const Foothold g = selectFoothold(s, nominal, reach);
  EXPECT_EQ(g.status, FootholdStatus::Moved);
  EXPECT_EQ(g.col, 23);
  EXPECT_NEAR(g.shift, 0.032, 1e-12);

  // Outside the map, or in an unknown patch wider than the reach: Unknown, the nominal, no height.
  const Foothold out = selectFoothold(s, {-0.5, 0.3}, FootholdReach{});
  EXPECT_EQ(out.status, FootholdStatus::Unknown);
  EXPECT_EQ(out.position.x(), -0.5);
  EXPECT_TRUE(std::isnan(out.position.z()));
  ElevationMap holed = boxMap();
  for (int r = 5; r < 25; ++r)
    for (int c = 5; c < 20; ++c) holed.at(r, c) = NAN;
  FootholdReach near;
  near.max_shift = 0.05;
  EXPECT_EQ(selectFoothold(computed(holed), {0.24, 0.30}, near).status, FootholdStatus::Unknown);
  // Closer to its rim: known cells within reach, all too near the hole.
  EXPECT_EQ(selectFoothold(computed(holed), {0.36, 0.30}, near).status,
            FootholdStatus::Unreachable);
}

TEST(SwingClearance, HighestTerrainBetweenLiftOffAndTouchDown) {
  // A box 8 cm high on columns 20 .. 29 (x from 0.39 to 0.59), rows 10 .. 19 (y 0.19 to 0.39).
  ElevationMap map = flatMap(30, 50);
  for (int r = 10; r < 20; ++r)
    for (int c = 20; c < 30; ++c) map.at(r, c) = 0.08f;
  EXPECT_NEAR(maxHeightAlong(map, {0.1, 0.3}, {0.8, 0.3}), 0.08, 1e-7);
  EXPECT_NEAR(maxHeightAlong(map, {0.8, 0.3}, {0.1, 0.3}), 0.08, 1e-7);
  EXPECT_NEAR(maxHeightAlong(map, {0.45, 0.05}, {0.45, 0.55}), 0.08, 1e-7);
  EXPECT_NEAR(maxHeightAlong(map, {0.1, 0.5}, {0.8, 0.5}), 0.0, 1e-12);  // beside it
  // From outside the map and back out: the part over the map counts.
  EXPECT_NEAR(maxHeightAlong(map, {-1.0, 0.25}, {3.0, 0.35}), 0.08, 1e-7);
  EXPECT_TRUE(std::isnan(maxHeightAlong(map, {-1.0, -1.0}, {-0.5, 2.0})));

  // One cell 20 cm high ([0.19, 0.21] squared): a diagonal that clips its corner (x + y = 0.415,
  // inside it for x in [0.205, 0.21]) sees it, one just past the corner (x + y = 0.425) does not.
  ElevationMap pillar = flatMap(20, 20);
  pillar.at(10, 10) = 0.2f;
  EXPECT_NEAR(maxHeightAlong(pillar, {0.115, 0.30}, {0.315, 0.10}), 0.2, 1e-7);
  EXPECT_NEAR(maxHeightAlong(pillar, {0.125, 0.30}, {0.325, 0.10}), 0.0, 1e-12);
  // Unknown cells are skipped, not taken as a height; a line of them only gives NaN.
  pillar.at(5, 3) = NAN;
  EXPECT_NEAR(maxHeightAlong(pillar, {0.0, 0.1}, {0.3, 0.1}), 0.0, 1e-12);
  for (int c = 0; c < 20; ++c) pillar.at(4, c) = NAN;
  EXPECT_TRUE(std::isnan(maxHeightAlong(pillar, {0.0, 0.08}, {0.3, 0.08})));
}

// The controller's arc at the fraction f of the way (GaitGenerator::foot, in f).
double arcHeight(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double h, double f) {
  return a.z() + f * (b.z() - a.z()) + h * 2.0 * std::sqrt(f * (1.0 - f));
}

TEST(SwingClearance, TheArcClearsTheTerrainBetweenItsFootholds) {
  // The box 8 cm high of x in [0.39, 0.59] between footholds at x = 0.1 and 0.8 (the foot frame
  // 2 cm above the sole): the apex clears every cell of the box by the clearance faded as the
  // arc's bump (2 sqrt(f (1 - f))), and no lower apex does.
  ElevationMap map = flatMap(30, 50);
  for (int r = 10; r < 20; ++r)
    for (int c = 20; c < 30; ++c) map.at(r, c) = 0.08f;
  const double foot = 0.02, clearance = 0.05;
  const Eigen::Vector3d a(0.1, 0.3, foot), b(0.8, 0.3, foot);
  const double h = swingLift(map, a, b, foot, clearance);
  auto worst = [&](double apex) {  // the smallest margin over the box, per unit of fade
    double m = 1e9;
    for (double x = 0.39; x <= 0.59 + 1e-9; x += 0.001) {
      const double f = (x - a.x()) / (b.x() - a.x());
      const double fade = 2.0 * std::sqrt(f * (1.0 - f));
      m = std::min(m, (arcHeight(a, b, apex, f) - (0.08 + foot)) / fade);
    }
    return m;
  };
  EXPECT_GE(worst(h), clearance - 1e-6);  // the map holds floats
  EXPECT_LT(worst(h - 0.01), clearance);  // tight: the box's near edge sets it
  EXPECT_GT(h, 0.08 + clearance);         // higher than the box itself over the line
  // Beside the box (y = 0.5): the clearance over flat ground, whatever the footholds' heights.
  EXPECT_NEAR(swingLift(map, {0.1, 0.5, foot}, {0.8, 0.5, foot}, foot, clearance), clearance,
              1e-12);
  // Up a step: landing on the box (its top 0.08) from the ground; the box's cells before the
  // touch-down are above the line, so the arc rises above the straight climb by more than the
  // clearance, yet stays finite (the ends' cells are left out).
  const Eigen::Vector3d on_box(0.5, 0.3, 0.08 + foot);
  const double up = swingLift(map, a, on_box, foot, clearance);
  EXPECT_GT(up, clearance);
  EXPECT_LT(up, 0.3);
  for (double x = 0.40; x <= 0.49; x += 0.01) {
    const double f = (x - a.x()) / (on_box.x() - a.x());
    if (f < 0.95) {
      EXPECT_GE(arcHeight(a, on_box, up, f), 0.08 + foot) << x;
    }
  }
  // Unknown cells are no obstacle; outside the map neither.
  ElevationMap unknown = map;
  for (int r = 10; r < 20; ++r)
    for (int c = 20; c < 30; ++c) unknown.at(r, c) = NAN;
  EXPECT_NEAR(swingLift(unknown, a, b, foot, clearance), clearance, 1e-12);
  EXPECT_NEAR(swingLift(map, {-2.0, -2.0, foot}, {-1.0, -2.0, foot}, foot, clearance), clearance,
              1e-12);
}

// z = 0.1 + tan(10 deg) x - 0.05 y.
const GroundPlane kSlope{0.1, std::tan(0.17453292519943295), -0.05};
Eigen::Vector3d onSlope(double x, double y) {
  return {x, y, kSlope.height(x, y)};
}

TEST(GroundPlane, FourFeetOnASlope) {
  const Eigen::Vector3d feet[4] = {onSlope(0.3, 0.2), onSlope(0.3, -0.2), onSlope(-0.3, 0.2),
                                   onSlope(-0.3, -0.2)};
  GroundPlane p;
  EXPECT_EQ(fitGroundPlane(feet, 4, GroundPlane{}, p), 4);
  EXPECT_NEAR(p.a, kSlope.a, 1e-12);
  EXPECT_NEAR(p.b, kSlope.b, 1e-12);
  EXPECT_NEAR(p.c, kSlope.c, 1e-12);
  EXPECT_NEAR(p.height(1.0, -2.0), kSlope.height(1.0, -2.0), 1e-12);
  const Eigen::Vector3d n = Eigen::Vector3d(-kSlope.b, -kSlope.c, 1.0).normalized();
  EXPECT_NEAR((p.normal() - n).norm(), 0.0, 1e-12);
  // Least squares: feet off the plane by +-1 cm in a pattern with no slope of its own.
  Eigen::Vector3d noisy[4] = {feet[0], feet[1], feet[2], feet[3]};
  noisy[0].z() += 0.01;
  noisy[3].z() += 0.01;
  noisy[1].z() -= 0.01;
  noisy[2].z() -= 0.01;
  fitGroundPlane(noisy, 4, GroundPlane{}, p);
  EXPECT_NEAR(p.b, kSlope.b, 1e-12);
  EXPECT_NEAR(p.height(0.0, 0.0), kSlope.a, 1e-12);
}

TEST(GroundPlane, TwoFeetGiveTheSlopeAlongThemOneFootTheHeight) {
  const Eigen::Vector3d pair[2] = {onSlope(0.3, 0.2), onSlope(-0.3, -0.2)};
  const Eigen::Vector2d d = Eigen::Vector2d(0.6, 0.4).normalized(), across(-d.y(), d.x());
  GroundPlane p;
  EXPECT_EQ(fitGroundPlane(pair, 2, GroundPlane{}, p), 2);
  EXPECT_NEAR(p.gradient().dot(d), kSlope.gradient().dot(d), 1e-12);
  EXPECT_NEAR(p.gradient().dot(across), 0.0, 1e-12);  // no roll from a flat prior
  EXPECT_NEAR(p.height(0.0, 0.0), kSlope.height(0.0, 0.0), 1e-12);
  // With the true plane as the prior, the pair confirms it.
  fitGroundPlane(pair, 2, kSlope, p);
  EXPECT_NEAR((p.gradient() - kSlope.gradient()).norm(), 0.0, 1e-12);
  // Three feet on one line: the same as the pair.
  const Eigen::Vector3d line[3] = {pair[0], pair[1], onSlope(0.0, 0.0)};
  fitGroundPlane(line, 3, GroundPlane{}, p);
  EXPECT_NEAR(p.gradient().dot(across), 0.0, 1e-9);
  EXPECT_NEAR(p.gradient().dot(d), kSlope.gradient().dot(d), 1e-9);

  const Eigen::Vector3d one[1] = {{0.2, 0.1, 0.07}};
  fitGroundPlane(one, 1, GroundPlane{}, p);
  EXPECT_EQ(p.gradient(), Eigen::Vector2d::Zero());
  EXPECT_NEAR(p.height(5.0, 5.0), 0.07, 1e-12);
  fitGroundPlane(one, 1, kSlope, p);
  EXPECT_EQ(p.gradient(), kSlope.gradient());
  EXPECT_NEAR(p.height(0.2, 0.1), 0.07, 1e-12);
  EXPECT_EQ(fitGroundPlane(one, 0, kSlope, p), 0);
  EXPECT_EQ(p.a, kSlope.a);
}

TEST(TerrainPlanningNoAllocation, CounterSeesAllocations) {
  EXPECT_GE(allocations([] {
              Eigen::internal::set_is_malloc_allowed(true);
              std::vector<int> v(10);
              int* volatile data = v.data();  // volatile: clang may drop an unused allocation
              (void)data;
            }),
            1);
}

TEST(TerrainPlanningNoAllocation, PerCallFunctions) {
  // A 2 m map at 2 cm (stride-sim's default) with a box, a ramp and an unknown patch.
  ElevationMap map = flatMap(100, 100);
  for (int r = 0; r < 100; ++r)
    for (int c = 0; c < 100; ++c) {
      if (c >= 40 && c < 60 && r >= 30 && r < 70) map.at(r, c) = 0.08f;
      if (c >= 70) map.at(r, c) = static_cast<float>(0.3 * (c - 70) * kRes);
      if (r < 10 && c < 10) map.at(r, c) = NAN;
    }
  ElevationMap too_big = flatMap(101, 100);
  Steppability s({}, 100 * 100);
  const Eigen::Vector3d feet[4] = {onSlope(0.3, 0.2), onSlope(0.3, -0.2), onSlope(-0.3, 0.2),
                                   onSlope(-0.3, -0.2)};
  FootholdReach reach;
  reach.hip = {0.8, 1.0};
  reach.max_hip_distance = 0.4;
  double sink = 0.0;
  int moved = 0, updated = 0;
  bool refused = false;
  GroundPlane p;
  const long n = allocations([&] {
    for (int i = 0; i < 3; ++i) {
      updated += s.update(map);
      for (double x = 0.0; x < 2.0; x += 0.037) {
        const Foothold f = selectFoothold(s, {x, 0.6 + 0.3 * x}, reach);
        moved += f.status == FootholdStatus::Moved;
        sink += f.position.x() + std::min(s.edgeDistanceAt(x, 1.0), 1.0);  // +inf: none near
        sink += maxHeightAlong(map, {x, 0.2}, {1.9 - 0.9 * x, 1.8});
        sink += swingLift(map, {x, 0.5, 0.0}, {x + 0.2, 0.6, 0.08}, 0.02, 0.05);
      }
      fitGroundPlane(feet, 4, kSlope, p);
      fitGroundPlane(feet, 2, p, p);
    }
    refused = !s.update(too_big);
  });
  EXPECT_EQ(n, 0);
  EXPECT_EQ(updated, 3);
  EXPECT_TRUE(refused);
  EXPECT_GT(moved, 0) << "the search was exercised";
  EXPECT_TRUE(std::isfinite(sink));
}

}  // namespace test_terrain_planning
}  // namespace stride::terrain
