#include "terrain/foothold.hpp"

#include <algorithm>
#include <cmath>

namespace stride::terrain {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
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
  out.position << nominal.x(), nominal.y(), kNaN;
  int r0 = 0, c0 = 0;
  if (!map.valid() || !nominal.allFinite() || !map.cellOf(nominal.x(), nominal.y(), r0, c0))
    return out;  // Unknown
  const auto in_reach = [&](const Eigen::Vector2d& p) {
    return (p - reach.hip).norm() <= reach.max_hip_distance;  // NaN or a NaN hip: not in reach
  };
  const bool nominal_known = !std::isnan(map.height(r0, c0));

  if (map.steppable(r0, c0) && in_reach(nominal) &&
      map.edgeDistanceAt(nominal.x(), nominal.y()) >= map.options().min_edge_distance - 1e-6) {
    // The point, not its cell's centre: no quantisation of footholds where nothing is in the way.
    const Eigen::Vector2d offset = nominal - map.cellCenter(r0, c0);
    out.status = FootholdStatus::Nominal;
    out.position.z() = map.height(r0, c0) + map.gradient(r0, c0).dot(offset);
    out.normal = map.normal(r0, c0);
    out.row = r0;
    out.col = c0;
    return out;
  }

  const double max_shift = reach.max_shift >= 0.0 ? reach.max_shift : -1.0;  // NaN: none
  const double max_shift2 = max_shift * max_shift + kTie;
  int best_r = -1, best_c = -1;
  double best2 = kInf;
  bool any_known = false;
  if (max_shift >= 0.0) {
    const double cells = std::ceil(max_shift / map.resolution());
    const int k = static_cast<int>(std::min<double>(cells, std::max(map.rows(), map.cols())));
    for (int r = std::max(0, r0 - k); r <= std::min(map.rows() - 1, r0 + k); ++r)
      for (int c = std::max(0, c0 - k); c <= std::min(map.cols() - 1, c0 + k); ++c) {
        const Eigen::Vector2d p = map.cellCenter(r, c);
        const double d2 = (p - nominal).squaredNorm();
        if (d2 > max_shift2 || !in_reach(p) || std::isnan(map.height(r, c))) continue;
        any_known = true;
        if (map.steppable(r, c) && d2 < best2 - kTie) {
          best2 = d2;
          best_r = r;
          best_c = c;
        }
      }
  }
  if (best_r >= 0) {
    out.status = FootholdStatus::Moved;
    out.position << map.cellCenter(best_r, best_c), map.height(best_r, best_c);
    out.normal = map.normal(best_r, best_c);
    out.shift = std::sqrt(best2);
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

double maxHeightAlong(const ElevationMap& map, const Eigen::Vector2d& from,
                      const Eigen::Vector2d& to) {
  if (map.rows <= 0 || map.cols <= 0 || !(map.resolution > 0.0) || !from.allFinite() ||
      !to.allFinite() || map.height.size() != static_cast<std::size_t>(map.rows) * map.cols)
    return kNaN;
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
    return kNaN;
  const auto cell = [](double x, int n) {
    return std::clamp(static_cast<int>(std::floor(x)), 0, n - 1);
  };
  const double ua = u0 + t0 * du, va = v0 + t0 * dv;
  int c = cell(ua, map.cols), r = cell(va, map.rows);
  const int c_end = cell(u0 + t1 * du, map.cols), r_end = cell(v0 + t1 * dv, map.rows);
  // The grid walk (each step crosses the nearer of the next column or row line).
  const int step_c = du > 0.0 ? 1 : -1, step_r = dv > 0.0 ? 1 : -1;
  const double delta_u = du != 0.0 ? 1.0 / std::abs(du) : kInf;
  const double delta_v = dv != 0.0 ? 1.0 / std::abs(dv) : kInf;
  // Parameter (of the clipped part, from t0) at which the next column / row line is crossed.
  double next_u = du != 0.0 ? (step_c > 0 ? c + 1 - ua : ua - c) * delta_u : kInf;
  double next_v = dv != 0.0 ? (step_r > 0 ? r + 1 - va : va - r) * delta_v : kInf;
  const int steps = std::abs(c_end - c) + std::abs(r_end - r);
  double best = -kInf;
  for (int i = 0;; ++i) {
    const float h = map.at(r, c);
    if (!std::isnan(h)) best = std::max(best, static_cast<double>(h));
    if (i == steps) break;
    // Never past the end cell on either axis, whatever the rounding of the crossings.
    if ((next_u < next_v && c != c_end) || r == r_end) {
      c += step_c;
      next_u += delta_u;
    } else {
      r += step_r;
      next_v += delta_v;
    }
  }
  return best == -kInf ? kNaN : best;
}

double swingApexHeight(const ElevationMap& map, const Eigen::Vector3d& lift_off,
                       const Eigen::Vector3d& touch_down, double clearance) {
  double top = std::max(lift_off.z(), touch_down.z());
  const double between = maxHeightAlong(map, lift_off.head<2>(), touch_down.head<2>());
  if (!std::isnan(between)) top = std::max(top, between);
  return top + clearance;
}

}  // namespace stride::terrain
