#include "terrain/elevation_map.hpp"

#include <cmath>
#include <limits>

namespace stride::terrain {

void ElevationMap::resize(int r, int c) {
  rows = r;
  cols = c;
  height.assign(static_cast<std::size_t>(r) * c, std::numeric_limits<float>::quiet_NaN());
}

double ElevationMap::heightAt(double x, double y) const {
  const double fc = std::round((x - origin_x) / resolution);
  const double fr = std::round((y - origin_y) / resolution);
  if (!(fc >= 0.0 && fc < cols && fr >= 0.0 && fr < rows))
    return std::numeric_limits<double>::quiet_NaN();
  return at(static_cast<int>(fr), static_cast<int>(fc));
}

void sampleTerrain(const Terrain& terrain, double cx, double cy, ElevationMap& map) {
  const double res = map.resolution;
  map.origin_x = std::round(cx / res - 0.5 * (map.cols - 1)) * res;
  map.origin_y = std::round(cy / res - 0.5 * (map.rows - 1)) * res;
  for (int r = 0; r < map.rows; ++r)
    for (int c = 0; c < map.cols; ++c)
      map.at(r, c) =
          static_cast<float>(terrain.height(map.origin_x + c * res, map.origin_y + r * res));
}

}  // namespace stride::terrain
