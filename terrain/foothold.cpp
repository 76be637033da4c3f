#include "terrain/foothold.hpp"

#include <algorithm>
#include <cmath>

namespace stride::terrain {

namespace {
constexpr double kNoHeight = std::numeric_limits<double>::quiet_NaN();  // nothing under a point
constexpr double kInfinity = std::numeric_limits<double>::infinity();
// Squared distances closer than this are a tie, settled by the scan order (reproducible footholds).
constexpr double kTie = 1e-12;
}  // namespace

const char* toString(FootholdStatus status) {
  switch (status) {
    case FootholdStatus::Nominal:
      return "nominal";
    case FootholdStatus::Moved:
      return "moved";
    case FootholdStatus::Unreachable:
      return "unreachable";
    case FootholdStatus::Unknown:
      return "unknown";
  }
  return "?";
}

Foothold selectFoothold(const Steppability& map, const Eigen::Vector2d& nominal,
                        const FootholdReach& reach) {
  Foothold out;
  out.position << nominal.x(), nominal.y(), kNoHeight;
  int r0 = 0, c0 = 0;
  if (!map.valid() || !nominal.allFinite() || !map.cellOf(nominal.x(), nominal.y(), r0, c0))
    return out;  // Unknown
  const auto in_reach = [&](const Eigen::Vector2d& p) {
    return (p - reach.hip).norm() <= reach.max_hip_distance;  // NaN or a NaN hip: not in reach
  };
  const bool nominal_known = !std::isnan(map.height(r0, c0));
  // Nearer an edge than the search radius costs as much as a shift of the same length: a foothold
  // just past min_edge_distance is taken only when nothing clearer is near. A foot lands a
  // centimetre or so off its foothold and the map places an edge only to within half a cell: one
  // planned at the minimum then lands on the edge.
  const double radius = map.options().edge_search_radius;
  const auto edge_cost = [radius](double edge_distance) {
    const double inside = std::max(0.0, radius - std::min(edge_distance, radius));
    return inside * inside;
  };
  // The point's own edge distance only where its cell may be stepped on (a bounded search).
  const bool nominal_stands = map.steppable(r0, c0) && in_reach(nominal);
  const double nominal_edge = nominal_stands ? map.edgeDistanceAt(nominal.x(), nominal.y()) : 0.0;
  const bool nominal_safe =
      nominal_stands && nominal_edge >= map.options().min_edge_distance - 1e-6;
  const double nominal_cost = nominal_safe ? edge_cost(nominal_edge) : kInfinity;
  const auto take_nominal = [&]() {
    // The point, not its cell's centre: no quantisation of footholds where nothing is in the way.
    const Eigen::Vector2d offset = nominal - map.cellCenter(r0, c0);
    out.status = FootholdStatus::Nominal;
    out.edge_distance = nominal_edge;
    out.position.z() = map.height(r0, c0) + map.gradient(r0, c0).dot(offset);
    out.normal = map.normal(r0, c0);
    out.row = r0;
    out.col = c0;
    return out;
  };
  if (nominal_safe && nominal_cost == 0.0) return take_nominal();

  const double max_shift = reach.max_shift >= 0.0 ? reach.max_shift : -1.0;  // NaN: none
  const double max_shift2 = max_shift * max_shift + kTie;
  int best_r = -1, best_c = -1;
  double best2 = kInfinity, best_cost = nominal_cost;
  bool any_known = false;
  const auto consider = [&](int r, int c, double limit2) {
    const Eigen::Vector2d p = map.cellCenter(r, c);
    const double d2 = (p - nominal).squaredNorm();
    if (d2 > limit2 || !in_reach(p) || std::isnan(map.height(r, c))) return;
    any_known = true;
    // Backwards counts twice: (2 b)^2 = b^2 + 3 b^2 for the part b against the travel.
    const double back = std::min(0.0, (p - nominal).dot(reach.forward));
    const double cost = d2 + 3.0 * back * back + edge_cost(map.edgeDistance(r, c));
    if (map.steppable(r, c) && cost < best_cost - kTie) {
      best_cost = cost;
      best2 = d2;
      best_r = r;
      best_c = c;
    }
  };
  if (max_shift >= 0.0) {
    // The last choice first, with its longer reach: a tie keeps it.
    int kept_r = -1, kept_c = -1;
    const double kept_shift = std::max(max_shift, reach.kept_max_shift);  // NaN: max_shift
    if (reach.kept.allFinite() && map.cellOf(reach.kept.x(), reach.kept.y(), kept_r, kept_c))
      consider(kept_r, kept_c, kept_shift * kept_shift + kTie);
    const double cells = std::ceil(max_shift / map.resolution());
    const int k = static_cast<int>(std::min<double>(cells, std::max(map.rows(), map.cols())));
    for (int r = std::max(0, r0 - k); r <= std::min(map.rows() - 1, r0 + k); ++r)
      for (int c = std::max(0, c0 - k); c <= std::min(map.cols() - 1, c0 + k); ++c)
        if (r != kept_r || c != kept_c) consider(r, c, max_shift2);
  }
  if (best_r < 0 && nominal_safe) return take_nominal();  // near an edge, nothing clearer near
  if (best_r >= 0) {
    out.status = FootholdStatus::Moved;
    out.position << map.cellCenter(best_r, best_c), map.height(best_r, best_c);
    out.normal = map.normal(best_r, best_c);
    out.shift = std::sqrt(best2);
    out.edge_distance = map.edgeDistance(best_r, best_c);
    out.row = best_r;
    out.col = best_c;
    return out;
  }
  if (!any_known && !nominal_known) return out;  // Unknown: nothing within reach is known
  out.status = FootholdStatus::Unreachable;
  out.row = r0;
  out.col = c0;
  if (nominal_known) {
    out.position.z() = map.height(r0, c0);
    out.normal = map.normal(r0, c0);
  }
  return out;
}

namespace {
// Visits every cell of `map` that the horizontal segment from `from` to `to` passes through, in
// order (a walk along the grid, so that a corner it clips is not missed), as visit(r, c, f0, f1):
// the cell and the fractions of the segment at which it enters and leaves it. The parts outside
// the map are skipped. False (nothing visited) for a map or segment that is not well formed, or
// one that misses the map. At most |cells along x| + |cells along y| + 1 visits.
template <class Visit>
bool walkSegment(const ElevationMap& map, const Eigen::Vector2d& from, const Eigen::Vector2d& to,
                 Visit&& visit) {
  if (map.rows <= 0 || map.cols <= 0 || !(map.resolution > 0.0) || !from.allFinite() ||
      !to.allFinite() || map.height.size() != static_cast<std::size_t>(map.rows) * map.cols)
    return false;
  // Grid coordinates in which cell (r, c) is the square [c, c + 1) x [r, r + 1).
  const double u0 = (from.x() - map.origin_x) / map.resolution + 0.5;
  const double v0 = (from.y() - map.origin_y) / map.resolution + 0.5;
  const double du = (to.x() - from.x()) / map.resolution, dv = (to.y() - from.y()) / map.resolution;
  // Clipped to the map first (Liang-Barsky), so that the walk is bounded by the map's size whatever
  // the segment's length.
  double t0 = 0.0, t1 = 1.0;
  const auto clip = [&](double p, double q) {  // keeps the part where p t <= q
    if (p == 0.0) return q >= 0.0;
    const double t = q / p;
    if (p < 0.0)
      t0 = std::max(t0, t);
    else
      t1 = std::min(t1, t);
    return t0 <= t1;
  };
  if (!clip(-du, u0) || !clip(du, map.cols - u0) || !clip(-dv, v0) || !clip(dv, map.rows - v0))
    return false;
  const auto cell = [](double x, int n) {
    return std::clamp(static_cast<int>(std::floor(x)), 0, n - 1);
  };
  const double ua = u0 + t0 * du, va = v0 + t0 * dv;
  int c = cell(ua, map.cols), r = cell(va, map.rows);
  const int c_end = cell(u0 + t1 * du, map.cols), r_end = cell(v0 + t1 * dv, map.rows);
  // The grid walk (each step crosses the nearer of the next column or row line).
  const int step_c = du > 0.0 ? 1 : -1, step_r = dv > 0.0 ? 1 : -1;
  const double delta_u = du != 0.0 ? 1.0 / std::abs(du) : kInfinity;
  const double delta_v = dv != 0.0 ? 1.0 / std::abs(dv) : kInfinity;
  // Parameter (of the clipped part, from t0) at which the next column / row line is crossed.
  double next_u = du != 0.0 ? (step_c > 0 ? c + 1 - ua : ua - c) * delta_u : kInfinity;
  double next_v = dv != 0.0 ? (step_r > 0 ? r + 1 - va : va - r) * delta_v : kInfinity;
  const int steps = std::abs(c_end - c) + std::abs(r_end - r);
  double enter = t0;
  for (int i = 0;; ++i) {
    const double leave = i == steps ? t1 : std::clamp(t0 + std::min(next_u, next_v), enter, t1);
    visit(r, c, enter, leave);
    if (i == steps) break;
    enter = leave;
    // Never past the end cell on either axis, whatever the rounding of the crossings.
    if ((next_u < next_v && c != c_end) || r == r_end) {
      c += step_c;
      next_u += delta_u;
    } else {
      r += step_r;
      next_v += delta_v;
    }
  }
  return true;
}
}  // namespace

double maxHeightAlong(const ElevationMap& map, const Eigen::Vector2d& from,
                      const Eigen::Vector2d& to) {
  double best = -kInfinity;
  walkSegment(map, from, to, [&](int r, int c, double, double) {
    const float h = map.at(r, c);
    if (!std::isnan(h)) best = std::max(best, static_cast<double>(h));
  });
  return best == -kInfinity ? kNoHeight : best;
}

double swingLift(const ElevationMap& map, const Eigen::Vector3d& lift_off,
                 const Eigen::Vector3d& touch_down, double foot_height, double clearance) {
  // The arc at the fraction f of the way: z(f) = line(f) + h 2 sqrt(f (1 - f)) (sin(pi s) with
  // f = (1 - cos(pi s)) / 2). Clearing a cell of height H over [f0, f1] by clearance c (faded the
  // same way towards both ends, where the foot must meet the ground) needs
  //   h >= c + (H + foot_height - line(f)) / (2 sqrt(f (1 - f))),
  // evaluated at the cell's ends and middle; the ends' own few per cent are left out (the cells the
  // foot stands on: a map's noise there would ask for an arbitrarily high arc).
  constexpr double kEnd = 0.05;
  const double dz = touch_down.z() - lift_off.z();
  double need = 0.0;
  walkSegment(map, lift_off.head<2>(), touch_down.head<2>(),
              [&](int r, int c, double f0, double f1) {
                const float h = map.at(r, c);
                if (std::isnan(h)) return;
                for (const double f_raw : {f0, 0.5 * (f0 + f1), f1}) {
                  const double f = std::clamp(f_raw, kEnd, 1.0 - kEnd);
                  const double above = h + foot_height - (lift_off.z() + f * dz);
                  if (above > 0.0) need = std::max(need, above / (2.0 * std::sqrt(f * (1.0 - f))));
                }
              });
  return clearance + need;
}

}  // namespace stride::terrain
