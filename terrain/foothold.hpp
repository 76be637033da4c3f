#pragma once
// Footholds and swing clearance on an elevation map (issue 31), for the controller to call each
// time it plans a step. Both do bounded work (a disc of cells, a line of cells), allocate nothing
// and never throw.

#include <Eigen/Core>
#include <cstdint>
#include <limits>

#include "terrain/elevation_map.hpp"
#include "terrain/steppability.hpp"

namespace stride::terrain {

enum class FootholdStatus : std::uint8_t {
  Nominal,      // the nominal point itself is safe: kept as it is
  Moved,        // moved to the nearest steppable cell's centre within reach
  Unreachable,  // the map knows cells within reach but none is steppable: the nominal, unchanged
  Unknown,      // outside the map, no valid map, or no known cell within reach: the nominal
};
const char* toString(FootholdStatus status);

// Where the foot may go: within `max_shift` of the nominal foothold and, optionally, within
// `max_hip_distance` of the hip (horizontally; +inf: no such limit).
struct FootholdReach {
  double max_shift = 0.1;  // [m]
  Eigen::Vector2d hip = Eigen::Vector2d::Zero();
  double max_hip_distance = std::numeric_limits<double>::infinity();  // [m]
  // The direction of travel (unit; zero: none). A move against it counts twice its length when
  // the nearest safe cell is chosen: a foot that shortens its step before an unsafe band (a
  // riser's edge) lands where the next nominal foothold falls before it again, and the body stalls
  // behind it; one that lengthens it crosses.
  Eigen::Vector2d forward = Eigen::Vector2d::Zero();
  // The place chosen for this same touch-down the last time (NaN: none). Its cell stays a
  // candidate up to `kept_max_shift` from the nominal (at least max_shift): with one hard limit,
  // a choice between two cells on either side of an unsafe band (short of a riser, or past it)
  // flipped back and forth as the nominal drifted across the point where the far one left reach,
  // and the swinging foot's target jumped by the band's width from one tick to the next.
  Eigen::Vector2d kept = Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN());
  double kept_max_shift = 0.0;  // [m]
};

struct Foothold {
  FootholdStatus status = FootholdStatus::Unknown;
  // x, y: where to step; z: the terrain there (Nominal: the cell's height along its slope;
  // Moved: the cell's height; Unreachable: the nominal's cell height, NaN when it is unknown;
  // Unknown: NaN). A caller falls back to its blind estimate where z is NaN.
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // the fitted plane's, up when unknown
  double shift = 0.0;                                 // [m] horizontal distance from the nominal
  // [m] Nominal, Moved: from the nearest edge, as far as edge_search_radius looks (+inf: none
  // within it); else +inf.
  double edge_distance = std::numeric_limits<double>::infinity();
  int row = -1, col = -1;  // the cell stepped on (the nominal's for Unreachable), -1 when none
};

// The safe foothold on `map` that costs least, a place's cost being its squared distance from
// `nominal` (the part against reach.forward counted twice) plus the square of how much nearer
// than edge_search_radius it is to an edge (within the radius, a metre clearer of an edge is worth
// a metre of shift):
// - Nominal when the nominal's cell is steppable, the point itself is at least min_edge_distance
//   from every edge (Steppability::edgeDistanceAt) and within the hip's reach, and no cell is
//   cheaper;
// - otherwise Moved to the centre of the cheapest steppable cell within the reach, the kept
//   cell's reach being kept_max_shift (ties: the kept cell, then the lowest row, then the lowest
//   column);
// - Unreachable (the nominal returned unchanged, never a far cell) when no steppable cell is within
//   reach but a known one is, Unknown when the nominal is outside the map or nothing within reach
//   is known.
// Scans the kept cell and the (2k + 1)^2 cells around the nominal, k = ceil(max_shift /
// resolution) (clipped to the map).
Foothold selectFoothold(const Steppability& map, const Eigen::Vector2d& nominal,
                        const FootholdReach& reach);

// The highest known height of `map` on the horizontal segment from `from` to `to`: every cell the
// segment passes through (a walk along the grid, so that a corner it clips is not missed), unknown
// cells and the parts outside the map ignored. NaN when it crosses no known cell. Visits at most
// |cells along x| + |cells along y| + 1 cells.
double maxHeightAlong(const ElevationMap& map, const Eigen::Vector2d& from,
                      const Eigen::Vector2d& to);

// The apex h the swing arc p(f) = a + f (b - a) + h 2 sqrt(f (1 - f)) e_z of the controller
// (GaitGenerator: the horizontal fraction f = (1 - cos(pi s)) / 2 and the bump h sin(pi s) of the
// swing phase s) needs so that the foot frame, foot_height above the sole, clears every known cell
// between lift-off a and touch-down b by `clearance` in mid-swing (faded as sin(pi s) towards both
// ends, where the foot meets the ground). A flat path: `clearance`. Bounded as maxHeightAlong.
double swingLift(const ElevationMap& map, const Eigen::Vector3d& lift_off,
                 const Eigen::Vector3d& touch_down, double foot_height, double clearance);

}  // namespace stride::terrain
