#include "viz/server/log_document.hpp"

#include <algorithm>
#include <cmath>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>

namespace stride::viz {

namespace {

// Keeps at most `rate` frames of one kind per second of their own stamps.
class Decimator {
 public:
  explicit Decimator(double rate)
      : period_(rate > 0.0 ? static_cast<std::int64_t>(std::llround(1e6 / rate)) : 0) {}
  bool due(std::int64_t utime) const {
    // A stamp behind the last one kept is a new session in the log: kept.
    return last_ < 0 || utime < last_ || utime - last_ >= period_;
  }
  void kept(std::int64_t utime) { last_ = utime; }

 private:
  std::int64_t period_;
  std::int64_t last_ = -1;
};

void openLog(const std::string& path, std::unique_ptr<lcm::LogFile>& log) {
  log = std::make_unique<lcm::LogFile>(path, "r");
  if (!log->good()) throw std::runtime_error("cannot read the log '" + path + "'");
}

}  // namespace

LogDocument readLog(const std::string& path, Feed& feed, const LogOptions& options, Json info) {
  std::unique_ptr<lcm::LogFile> log;
  // The controller publishes its model at its first tick, after the robot's first states: the
  // model is looked for first, so that every state can be checked and drawn.
  openLog(path, log);
  for (const lcm::LogEvent* e = log->readNextEvent(); e != nullptr; e = log->readNextEvent())
    if (e->channel == feed.channels().model &&
        feed.take(e->channel, e->data, e->datalen) == Feed::Took::Model)
      break;
  if (!feed.robot())
    throw std::runtime_error(
        "the log '" + path + "' names no robot stride-viz could load (no robot_model_t on '" +
        feed.channels().model + "', or its robot was not found): give --robot");

  LogDocument out;
  Json frames = Json::array();
  struct Stream {
    FrameKind kind;
    Decimator decimator;
  } streams[] = {{FrameKind::State, Decimator(options.state_rate)},
                 {FrameKind::Plan, Decimator(options.plan_rate)},
                 {FrameKind::Status, Decimator(options.status_rate)},
                 {FrameKind::Terrain, Decimator(options.terrain_rate)}};
  openLog(path, log);
  for (const lcm::LogEvent* e = log->readNextEvent(); e != nullptr; e = log->readNextEvent()) {
    ++out.events;
    if (feed.take(e->channel, e->data, e->datalen) == Feed::Took::None) continue;
    for (Stream& s : streams) {
      const std::int64_t utime = feed.pendingUtime(s.kind);
      // A status stamped 0 answered no state yet: it has no place on the robot's timeline. A map
      // stamped 0 is one measured at the start of a clock that starts at 0.
      const std::int64_t first = s.kind == FrameKind::Terrain ? 0 : 1;
      if (utime < first || !s.decimator.due(utime)) continue;
      Json frame = feed.frame(s.kind);
      if (frame.is_null()) continue;
      s.decimator.kept(utime);
      frames.push_back(std::move(frame));
    }
  }
  std::stable_sort(frames.begin(), frames.end(), [](const Json& a, const Json& b) {
    return a["t"].get<double>() < b["t"].get<double>();
  });
  out.frames = static_cast<long>(frames.size());
  if (!frames.empty())
    out.duration = frames.back()["t"].get<double>() - frames.front()["t"].get<double>();
  info["events"] = out.events;
  info["duration"] = out.duration;
  info["warnings"] = feed.warnings();
  info["messages"] = feed.counters();
  out.document = {
      {"info", std::move(info)}, {"model", feed.modelFrame()}, {"frames", std::move(frames)}};
  return out;
}

}  // namespace stride::viz
