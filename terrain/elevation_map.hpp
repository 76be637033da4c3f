#pragma once
// An elevation grid: what a perception stack gives a controller (the wire's stride.terrain_t), and
// what the mock robot measures from its terrain. Cell (r, c) is the square of side `resolution`
// centred on (origin_x + c * resolution, origin_y + r * resolution); rows run along world y,
// columns along x. NaN heights are unknown cells.

#include <cstdint>
#include <vector>

#include "terrain/terrain.hpp"

namespace stride::terrain {

struct ElevationMap {
  double origin_x = 0.0, origin_y = 0.0, resolution = 0.02;
  int rows = 0, cols = 0;
  std::vector<float> height;  // rows * cols, row-major

  void resize(int rows, int cols);
  float& at(int r, int c) { return height[static_cast<std::size_t>(r) * cols + c]; }
  float at(int r, int c) const { return height[static_cast<std::size_t>(r) * cols + c]; }
  // The height of the cell holding (x, y): NaN outside the map or in an unknown cell.
  double heightAt(double x, double y) const;
};

// Fills every cell of `map` (its size and resolution as they are) with the terrain's height at
// the cell's centre, the map centred on (cx, cy) with its origin on the resolution's grid (so that
// a moving robot's maps do not shimmer). Allocates nothing.
void sampleTerrain(const Terrain& terrain, double cx, double cy, ElevationMap& map);

}  // namespace stride::terrain
