#pragma once
// The mock robot's stand-in for a perception stack: an elevation map of the terrain around the
// robot (stride.terrain_t on STRIDE_TERRAIN), measured from the simulated terrain at a fixed rate,
// with optional noise, unknown cells (holes) and latency (sim/README.md, "Terrain map").
//
// Real time: everything is sized at construction; step() allocates nothing and never throws.

#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "messages/publisher.hpp"
#include "stride/terrain_t.hpp"
#include "terrain/elevation_map.hpp"

namespace stride::sim {

struct TerrainMapOptions {
  double rate_hz = 10.0;     // maps per second of robot time; 0: none
  double size = 2.0;         // side of the square map, centred on the base [m]
  double resolution = 0.02;  // cell side [m]
  double noise = 0.0;        // standard deviation of each cell's height [m]
  double holes = 0.0;        // probability that a cell is unknown (NaN)
  double latency = 0.0;      // a map arrives this long after the moment it shows [s]
  std::uint64_t seed = 1;
  std::string channel = "STRIDE_TERRAIN";
};

class TerrainMapper {
 public:
  // `dt`: the physics step (the latency's resolution). Throws std::invalid_argument for bad
  // options (a resolution <= 0, more than 512 cells a side, a negative rate, noise or latency, a
  // hole probability outside [0, 1]).
  TerrainMapper(const terrain::Terrain& terrain, const TerrainMapOptions& options, double dt);

  // Called after every physics step with the robot's time t [s], its clock's base [µs] and the
  // base's place: publishes a map when one is due. Returns true when it did.
  bool step(double t, std::int64_t utime_base, double base_x, double base_y, Publisher& out);
  // Forgets the base's history (the robot was put elsewhere).
  void reset();

  std::int64_t published() const { return published_; }
  const terrain::ElevationMap& lastMap() const { return map_; }
  int cellsPerSide() const { return map_.rows; }

  // The encoded size of a map (fixed at construction): what a publisher preallocates for.
  int messageSize() const { return static_cast<int>(buffer_.size()); }

 private:
  const terrain::Terrain& terrain_;
  TerrainMapOptions options_;
  double dt_;
  terrain::ElevationMap map_;
  terrain_t msg_;
  std::vector<unsigned char> buffer_;
  // The base's place over the last `latency` (one entry per step, a ring).
  std::vector<double> history_x_, history_y_;
  int head_ = 0, filled_ = 0;
  double next_ = 0.0;  // time of the next map
  std::mt19937_64 rng_;
  std::normal_distribution<double> gauss_{0.0, 1.0};
  std::uniform_real_distribution<double> unit_{0.0, 1.0};
  std::int64_t published_ = 0;
};

}  // namespace stride::sim
