#pragma once
// Log mode: an lcm-logger log read whole at start into the one JSON document the page plays
// client-side (GET /api/log): {"info": {...}, "model": {...}, "frames": [...sorted by t...]}.
// States are decimated to at most `state_rate` per second of log time, plans and statuses to
// `plan_rate` and `status_rate`, terrain maps to `terrain_rate`: the page interpolates nothing,
// and 100 states a second are smoother than a browser draws.

#include <nlohmann/json.hpp>
#include <string>

#include "viz/server/feed.hpp"

namespace stride::viz {

// A rate of 0 keeps every frame of its kind.
struct LogOptions {
  double state_rate = 100.0;  // per second of log time
  double plan_rate = 20.0;
  double status_rate = 20.0;
  double terrain_rate = kTerrainFrameRate;  // ~50 kB each: a minute of 10 Hz maps would be 30 MB
};

struct LogDocument {
  Json document;    // {"info", "model", "frames"}
  long events = 0;  // events read from the log
  long frames = 0;
  double duration = 0.0;  // [s] from the first frame to the last
};

// Reads the log through `feed` (the model found first, wherever it is in the log, so that the
// states before it are not lost). Throws std::runtime_error when the log cannot be read or no
// robot is known by its end (neither --robot nor a robot_model_t whose robot could be loaded).
LogDocument readLog(const std::string& path, Feed& feed, const LogOptions& options, Json info);

}  // namespace stride::viz
