#include "terrain/steppability.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace stride::terrain {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
// Distances and slopes are compared with a little slack: a cell centre exactly min_edge_distance
// from an edge (1.5 cells at 2 cm for 3 cm) must not flip on rounding.
constexpr double kDistanceSlack = 1e-6, kSlopeSlack = 1e-9;
}  // namespace

Steppability::Steppability(const SteppabilityOptions& options, int max_cells) : options_(options) {
  const auto nonneg = [](double v) { return v >= 0.0 && std::isfinite(v); };
  if (!nonneg(options.max_slope) || !nonneg(options.edge_height) ||
      !nonneg(options.min_edge_distance) || !nonneg(options.edge_search_radius))
    throw std::invalid_argument("steppability: thresholds must be finite and >= 0");
  if (options.edge_search_radius < options.min_edge_distance)
    throw std::invalid_argument(
        "steppability: edge_search_radius must be >= min_edge_distance (an edge beyond the search "
        "would go unseen)");
  reserve(max_cells);
}

void Steppability::reserve(int max_cells) {
  if (max_cells <= capacity_) return;
  const auto n = static_cast<std::size_t>(max_cells);
  // The side and integral grids are (rows + 1) x (cols + 1) at most: rows * cols + rows + cols + 1
  // <= 2 n + 2 for any shape of n cells.
  const std::size_t aux = 2 * n + 2;
  map_.height.reserve(n);
  gx_.resize(n);
  gy_.resize(n);
  slope_.resize(n);
  edge_distance_.resize(n);
  steppable_.resize(n);
  jx_.resize(aux);
  jy_.resize(aux);
  touch_sum_.resize(aux);
  capacity_ = max_cells;
}

bool Steppability::known(int r, int c) const {
  return r >= 0 && r < map_.rows && c >= 0 && c < map_.cols && !std::isnan(map_.at(r, c));
}

bool Steppability::isEdge(int r0, int c0, int r1, int c1) const {
  const bool k0 = known(r0, c0), k1 = known(r1, c1);
  if (k0 && k1) return std::abs(map_.at(r0, c0) - map_.at(r1, c1)) > options_.edge_height;
  return (k0 || k1) && options_.unknown_is_edge;
}

double Steppability::nearestEdge(double u, double v) const {
  const int rows = map_.rows, cols = map_.cols;
  const double reach = options_.edge_search_radius / map_.resolution;  // in cells
  const auto lo = [](double x) { return static_cast<int>(std::ceil(x)); };
  const auto hi = [](double x) { return static_cast<int>(std::floor(x)); };
  // The sides that may lie within `reach`. Between columns c' - 1 and c': the segment u = c' - 0.5,
  // v in [r' - 0.5, r' + 0.5]; between rows r' - 1 and r': v = r' - 0.5, u in [c' - 0.5, c' + 0.5].
  const int xr0 = std::max(0, lo(v - reach - 0.5)), xr1 = std::min(rows - 1, hi(v + reach + 0.5));
  const int xc0 = std::max(0, lo(u + 0.5 - reach)), xc1 = std::min(cols, hi(u + 0.5 + reach));
  const int yr0 = std::max(0, lo(v + 0.5 - reach)), yr1 = std::min(rows, hi(v + 0.5 + reach));
  const int yc0 = std::max(0, lo(u - reach - 0.5)), yc1 = std::min(cols - 1, hi(u + reach + 0.5));
  // When no cell beside those sides touches an edge there is nothing to look at (most cells of a
  // flat or ramped map): the integral image says so at once.
  const int r0 = std::max(0, std::min(xr0, yr0 - 1)), r1 = std::min(rows, std::max(xr1, yr1) + 1);
  const int c0 = std::max(0, std::min(xc0 - 1, yc0)), c1 = std::min(cols, std::max(xc1, yc1) + 1);
  if (r0 >= r1 || c0 >= c1) return kInf;
  const auto sum = [&](int r, int c) {
    return touch_sum_[static_cast<std::size_t>(r) * (cols + 1) + c];
  };
  if (sum(r1, c1) - sum(r0, c1) - sum(r1, c0) + sum(r0, c0) == 0) return kInf;

  double best2 = kInf;
  for (int rr = xr0; rr <= xr1; ++rr) {
    const double dv = std::max(0.0, std::abs(v - rr) - 0.5);
    for (int cc = xc0; cc <= xc1; ++cc) {
      if (!jx_[static_cast<std::size_t>(rr) * (cols + 1) + cc]) continue;
      const double du = u - (cc - 0.5);
      best2 = std::min(best2, du * du + dv * dv);
    }
  }
  for (int rr = yr0; rr <= yr1; ++rr) {
    const double dv = v - (rr - 0.5);
    for (int cc = yc0; cc <= yc1; ++cc) {
      if (!jy_[static_cast<std::size_t>(rr) * cols + cc]) continue;
      const double du = std::max(0.0, std::abs(u - cc) - 0.5);
      best2 = std::min(best2, du * du + dv * dv);
    }
  }
  return std::sqrt(best2);
}

void Steppability::fitPlane(int r, int c) {
  const std::size_t i = index(r, c);
  const float h0 = map_.at(r, c);
  // Normal equations of dz = a + gx du + gy dv over the neighbours in cell units (integers: the
  // determinant is a whole number, 0 exactly when the points are collinear).
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  int used = 0;
  for (int dr = -1; dr <= 1; ++dr)
    for (int dc = -1; dc <= 1; ++dc) {
      if (!known(r + dr, c + dc)) continue;
      const double dz = map_.at(r + dr, c + dc) - h0;
      if (std::abs(dz) > options_.edge_height) continue;  // another surface, beyond a face
      const Eigen::Vector3d phi(1.0, dc, dr);
      A.noalias() += phi * phi.transpose();
      b.noalias() += phi * dz;
      ++used;
    }
  Eigen::Vector3d x;
  if (used == 9) {
    x << 0.0, b[1] / 6.0, b[2] / 6.0;  // the whole neighbourhood: A = diag(9, 6, 6)
  } else if (A.determinant() > 0.5) {
    x = A.inverse() * b;
  } else {
    gx_[i] = gy_[i] = 0.0f;
    slope_[i] = kNaN;
    return;
  }
  const double gx = x[1] / map_.resolution, gy = x[2] / map_.resolution;
  gx_[i] = static_cast<float>(gx);
  gy_[i] = static_cast<float>(gy);
  slope_[i] = static_cast<float>(std::atan(std::hypot(gx, gy)));
}

bool Steppability::update(const ElevationMap& map) {
  valid_ = false;
  steppable_count_ = 0;
  const long long n = static_cast<long long>(map.rows) * map.cols;
  if (map.rows <= 0 || map.cols <= 0 || n > capacity_ ||
      map.height.size() != static_cast<std::size_t>(n) || !(map.resolution > 0.0) ||
      !std::isfinite(map.resolution) || !std::isfinite(map.origin_x) ||
      !std::isfinite(map.origin_y)) {
    map_.rows = map_.cols = 0;
    map_.height.clear();
    return false;
  }
  // A copy within the reserved capacity: no allocation.
  map_.origin_x = map.origin_x;
  map_.origin_y = map.origin_y;
  map_.resolution = map.resolution;
  map_.rows = map.rows;
  map_.cols = map.cols;
  map_.height.resize(static_cast<std::size_t>(n));
  std::copy(map.height.begin(), map.height.end(), map_.height.begin());
  const int rows = map_.rows, cols = map_.cols;

  for (int r = 0; r < rows; ++r)
    for (int c = 0; c <= cols; ++c)
      jx_[static_cast<std::size_t>(r) * (cols + 1) + c] = isEdge(r, c - 1, r, c);
  for (int r = 0; r <= rows; ++r)
    for (int c = 0; c < cols; ++c)
      jy_[static_cast<std::size_t>(r) * cols + c] = isEdge(r - 1, c, r, c);
  const auto touch_at = [&](int r, int c) -> int& {
    return touch_sum_[static_cast<std::size_t>(r) * (cols + 1) + c];
  };
  for (int c = 0; c <= cols; ++c) touch_at(0, c) = 0;
  for (int r = 0; r < rows; ++r) {
    touch_at(r + 1, 0) = 0;
    int row_sum = 0;
    for (int c = 0; c < cols; ++c) {
      row_sum += jx_[static_cast<std::size_t>(r) * (cols + 1) + c] ||
                 jx_[static_cast<std::size_t>(r) * (cols + 1) + c + 1] ||
                 jy_[static_cast<std::size_t>(r) * cols + c] ||
                 jy_[static_cast<std::size_t>(r + 1) * cols + c];
      touch_at(r + 1, c + 1) = touch_at(r, c + 1) + row_sum;
    }
  }

  const double radius = options_.edge_search_radius;
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) {
      const std::size_t i = index(r, c);
      steppable_[i] = 0;
      if (std::isnan(map_.at(r, c))) {
        gx_[i] = gy_[i] = 0.0f;
        slope_[i] = kNaN;
        edge_distance_[i] = 0.0f;
        continue;
      }
      fitPlane(r, c);
      double d = nearestEdge(c, r) * map_.resolution;
      if (d > radius) d = kInf;
      edge_distance_[i] = static_cast<float>(d);
      const bool ok = slope_[i] <= options_.max_slope + kSlopeSlack &&
                      d >= options_.min_edge_distance - kDistanceSlack;
      steppable_[i] = ok;
      steppable_count_ += ok;
    }
  valid_ = true;
  return true;
}

Eigen::Vector2d Steppability::gradient(int r, int c) const {
  const std::size_t i = index(r, c);
  return {gx_[i], gy_[i]};
}

Eigen::Vector3d Steppability::normal(int r, int c) const {
  const Eigen::Vector2d g = gradient(r, c);
  return Eigen::Vector3d(-g.x(), -g.y(), 1.0).normalized();
}

bool Steppability::cellOf(double x, double y, int& r, int& c) const {
  if (!valid_) return false;
  // As ElevationMap::heightAt rounds.
  const double fc = std::round((x - map_.origin_x) / map_.resolution);
  const double fr = std::round((y - map_.origin_y) / map_.resolution);
  if (!(fc >= 0.0 && fc < map_.cols && fr >= 0.0 && fr < map_.rows)) return false;
  r = static_cast<int>(fr);
  c = static_cast<int>(fc);
  return true;
}

Eigen::Vector2d Steppability::cellCenter(int r, int c) const {
  return {map_.origin_x + c * map_.resolution, map_.origin_y + r * map_.resolution};
}

double Steppability::edgeDistanceAt(double x, double y) const {
  int r = 0, c = 0;
  if (!cellOf(x, y, r, c) || std::isnan(map_.at(r, c))) return 0.0;
  const double radius = options_.edge_search_radius;
  const double u = (x - map_.origin_x) / map_.resolution, v = (y - map_.origin_y) / map_.resolution;
  const double d = nearestEdge(u, v) * map_.resolution;
  return d > radius ? kInf : d;
}

}  // namespace stride::terrain
