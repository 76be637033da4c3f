#include "sim/terrain_map.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace stride::sim {

namespace {
constexpr int kMaxCellsPerSide = 512;
}

TerrainMapper::TerrainMapper(const terrain::Terrain& terrain, const TerrainMapOptions& options,
                             double dt)
    : terrain_(terrain), options_(options), dt_(dt), rng_(options.seed) {
  auto fail = [](const std::string& what) { throw std::invalid_argument("terrain map: " + what); };
  if (!(options.rate_hz >= 0.0) || !std::isfinite(options.rate_hz)) fail("rate must be >= 0");
  if (!(options.resolution > 0.0) || !std::isfinite(options.resolution))
    fail("resolution must be > 0");
  if (!(options.size > 0.0) || !std::isfinite(options.size)) fail("size must be > 0");
  if (!(options.noise >= 0.0) || !std::isfinite(options.noise)) fail("noise must be >= 0");
  if (!(options.holes >= 0.0 && options.holes <= 1.0)) fail("holes must be in [0, 1]");
  if (!(options.latency >= 0.0) || !(options.latency <= 10.0)) fail("latency must be in [0, 10] s");
  if (!(dt > 0.0)) fail("dt must be > 0");
  const double cells = std::round(options.size / options.resolution);
  if (!(cells >= 1.0 && cells <= kMaxCellsPerSide))
    fail("size / resolution must give 1 to " + std::to_string(kMaxCellsPerSide) + " cells a side");
  const int n = static_cast<int>(cells);
  map_.resolution = options.resolution;
  map_.resize(n, n);
  msg_.rows = msg_.cols = n;
  msg_.resolution = options.resolution;
  msg_.height.assign(n, std::vector<float>(n, 0.0f));
  buffer_.resize(msg_.getEncodedSize());
  const int history = static_cast<int>(std::ceil(options.latency / dt - 1e-9)) + 1;
  history_x_.assign(history, 0.0);
  history_y_.assign(history, 0.0);
}

void TerrainMapper::reset() {
  head_ = 0;
  filled_ = 0;
  next_ = 0.0;
}

bool TerrainMapper::step(double t, std::int64_t utime_base, double x, double y, Publisher& out) {
  if (options_.rate_hz <= 0.0) return false;
  const int size = static_cast<int>(history_x_.size());
  head_ = (head_ + 1) % size;
  history_x_[head_] = x;
  history_y_[head_] = y;
  if (filled_ < size) ++filled_;
  if (t + 1e-9 < next_) return false;
  next_ += 1.0 / options_.rate_hz;
  if (next_ <= t) next_ = t + 1.0 / options_.rate_hz;  // after a reset or a long step
  // The moment the map shows: `latency` ago, to the physics step (none yet: nothing to send).
  const int back = size - 1;
  if (filled_ < size) return false;
  const int then = (head_ - back + size) % size;
  const double shown = t - back * dt_;
  terrain::sampleTerrain(terrain_, history_x_[then], history_y_[then], map_);
  for (int r = 0; r < map_.rows; ++r)
    for (int c = 0; c < map_.cols; ++c) {
      float h = map_.at(r, c);
      if (options_.noise > 0.0) h += static_cast<float>(options_.noise * gauss_(rng_));
      if (options_.holes > 0.0 && unit_(rng_) < options_.holes)
        h = std::numeric_limits<float>::quiet_NaN();
      map_.at(r, c) = h;
      msg_.height[r][c] = h;
    }
  msg_.utime = utime_base + static_cast<std::int64_t>(std::llround(shown * 1e6));
  msg_.origin_x = map_.origin_x;
  msg_.origin_y = map_.origin_y;
  const int n = msg_.encode(buffer_.data(), 0, static_cast<int>(buffer_.size()));
  if (n <= 0) return false;
  out.publish(options_.channel, buffer_.data(), n);
  ++published_;
  return true;
}

}  // namespace stride::sim
