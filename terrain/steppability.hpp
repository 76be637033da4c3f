#pragma once
// Where a foot may stand on an elevation map (issue 31): per cell, the local slope and the distance
// to the nearest height edge, and whether both are within the thresholds. The controller reads it
// to pick footholds (foothold.hpp); it knows nothing of robots.
//
// Definitions (terrain/README.md, "Planning on a map"):
// - An **edge** is the side shared by two neighbouring cells (4-neighbours) whose heights differ by
//   more than `edge_height`, or, with `unknown_is_edge`, by a known cell and an unknown one (NaN,
//   or outside the map: what the map does not show may be a hole). It is a vertical face on the
//   line between the two cells, one resolution long.
// - A cell's **edge distance** is the distance in metres from its centre to the nearest point of
//   an edge, searched within `edge_search_radius` (+inf when there is none that near).
// - A cell's **slope** is that of the least-squares plane z = h + gx dx + gy dy through its own
//   height and those of its known 3x3 neighbours on the same side of every edge (a neighbour more
//   than `edge_height` away from it is another surface: the edge distance accounts for it). NaN
//   when the points do not span a plane.
// - A cell is **steppable** when known, its slope <= `max_slope` and its edge distance >=
//   `min_edge_distance`.
//
// Steppability keeps a copy of the map it was computed from, so that it stays consistent while the
// next map arrives. update() allocates nothing and never throws once the capacity is reserved.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "terrain/elevation_map.hpp"

namespace stride::terrain {

struct SteppabilityOptions {
  double max_slope = 0.5235987755982988;  // [rad] 30 degrees
  double edge_height = 0.02;              // [m] a larger difference between neighbours is a face
  // [m] no foothold nearer an edge. Issue 31 asks for 2 cm; a map of 2 cm cells places an edge
  // only to within 1 cm (half a cell), and a foot lands up to about 1 cm off its foothold.
  double min_edge_distance = 0.04;
  // [m] how far to look for edges; >= min_edge_distance. Bounds the work per cell. Footholds
  // prefer cells clearer of edges up to this distance (selectFoothold).
  double edge_search_radius = 0.08;
  bool unknown_is_edge = true;  // a side towards an unknown cell (or the map's border) is an edge
};

class Steppability {
 public:
  // Throws std::invalid_argument for options that are not valid (negative or non-finite values, a
  // search radius below the minimum edge distance). Reserves room for maps of up to `max_cells`.
  explicit Steppability(const SteppabilityOptions& options = {}, int max_cells = 0);

  // Makes room for maps of up to `max_cells` cells (allocates: not in a tick).
  void reserve(int max_cells);
  int capacity() const { return capacity_; }

  // Recomputes every cell for `map`. Allocates nothing and never throws. Returns false, leaving
  // nothing steppable (valid() false), for a map larger than the capacity or not well formed (a
  // resolution that is not > 0 and finite, non-finite origin, heights not rows * cols).
  bool update(const ElevationMap& map);
  bool valid() const { return valid_; }

  const SteppabilityOptions& options() const { return options_; }
  // The map of the last update (its heights copied).
  const ElevationMap& map() const { return map_; }
  int rows() const { return map_.rows; }
  int cols() const { return map_.cols; }
  double resolution() const { return map_.resolution; }
  // Cells that are steppable in the last update.
  int steppableCount() const { return steppable_count_; }

  bool steppable(int r, int c) const { return steppable_[index(r, c)] != 0; }
  // The plane's inclination [rad]: NaN for an unknown cell or one whose points span no plane.
  double slope(int r, int c) const { return slope_[index(r, c)]; }
  // [m] from the cell's centre to the nearest edge; +inf when none within the search radius, 0 for
  // an unknown cell.
  double edgeDistance(int r, int c) const { return edge_distance_[index(r, c)]; }
  double height(int r, int c) const { return map_.at(r, c); }
  // The fitted plane's gradient (dz/dx, dz/dy) and upward unit normal; zero gradient (up) where
  // the slope is NaN.
  Eigen::Vector2d gradient(int r, int c) const;
  Eigen::Vector3d normal(int r, int c) const;

  // The cell holding (x, y); false outside the map.
  bool cellOf(double x, double y, int& r, int& c) const;
  Eigen::Vector2d cellCenter(int r, int c) const;
  // [m] from the point (x, y) itself (not its cell's centre) to the nearest edge within the search
  // radius (+inf when none; 0 outside the map or on an unknown cell). Bounded work, no allocation.
  double edgeDistanceAt(double x, double y) const;

 private:
  std::size_t index(int r, int c) const { return static_cast<std::size_t>(r) * map_.cols + c; }
  bool known(int r, int c) const;
  // Whether the side between two cells is an edge (either may be outside the map).
  bool isEdge(int r0, int c0, int r1, int c1) const;
  // Distance in cells from the point (u along columns, v along rows, in cell units from cell
  // (0, 0)'s centre) to the nearest edge, looked for within the search radius; +inf when none (a
  // result beyond the radius is possible: the callers cut it).
  double nearestEdge(double u, double v) const;
  void fitPlane(int r, int c);

  SteppabilityOptions options_;
  int capacity_ = 0;
  bool valid_ = false;
  int steppable_count_ = 0;
  ElevationMap map_;
  std::vector<float> gx_, gy_, slope_, edge_distance_;
  std::vector<std::uint8_t> steppable_;
  // Jump sides: jx_ between (r, c - 1) and (r, c) for c in [0, cols] (rows x (cols + 1)), jy_
  // between (r - 1, c) and (r, c) for r in [0, rows] ((rows + 1) x cols); index 0 and the last are
  // the map's border.
  std::vector<std::uint8_t> jx_, jy_;
  // Integral image ((rows + 1) x (cols + 1)) of the cells touching an edge, so that a cell with no
  // edge near it skips the search (most of a flat or ramped map).
  std::vector<int> touch_sum_;
};

}  // namespace stride::terrain
