#include "viz/server/live.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <set>

namespace stride::viz {

namespace {
// How often the feed's counters and warnings reach /api/info and the info frames.
constexpr double kSourceInfoPeriod = 0.5;
// Messages LCM keeps per channel for this thread: a burst while a frame is built waits here;
// beyond it the oldest are dropped, as a viewer can afford.
constexpr int kQueueCapacity = 100;
}  // namespace

LiveSource::LiveSource(lcm::LCM& lcm, Feed& feed, HttpServer& server, double rate_hz)
    : lcm_(lcm), feed_(feed), server_(server), period_(1.0 / std::max(rate_hz, 0.1)) {
  std::set<std::string> unique;  // a name given for two channels is subscribed once
  for (const std::string& channel : feed_.channels().all())
    if (unique.insert(channel).second) {
      lcm::Subscription* s = lcm_.subscribe(channel, &LiveSource::onMessage, this);
      if (s != nullptr) {
        s->setQueueCapacity(kQueueCapacity);
        subscriptions_.push_back(s);
      }
    }
}

LiveSource::~LiveSource() {
  for (lcm::Subscription* s : subscriptions_) lcm_.unsubscribe(s);
}

void LiveSource::onMessage(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
  feed_.take(channel, rbuf->data, static_cast<int>(rbuf->data_size));
}

void LiveSource::emit(std::chrono::steady_clock::time_point now) {
  if (feed_.modelVersion() != model_version_) {
    model_version_ = feed_.modelVersion();
    server_.setRobotFiles(feed_.robotFiles());
    const Json model = feed_.modelFrame();
    if (!model.is_null()) server_.setModel(model);
  }
  for (const FrameKind kind : {FrameKind::State, FrameKind::Plan, FrameKind::Status}) {
    const Json frame = feed_.frame(kind);
    if (!frame.is_null()) server_.broadcast(kind, frameText(frame));
  }
  // The newest map, when the last one went out long enough ago (the maps in between are not
  // framed: the newest supersedes them). Kept by the server for the browsers that come later.
  if (now >= next_terrain_ && feed_.pendingUtime(FrameKind::Terrain) >= 0) {
    const Json terrain = feed_.frame(FrameKind::Terrain);
    if (!terrain.is_null()) server_.setTerrain(terrain);
    next_terrain_ = now + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                              std::chrono::duration<double>(1.0 / kTerrainFrameRate));
  }
}

bool LiveSource::run(const std::atomic<bool>& stop) {
  using Clock = std::chrono::steady_clock;
  const auto period =
      std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(period_));
  const auto info_period =
      std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(kSourceInfoPeriod));
  auto next_emit = Clock::now(), next_info = Clock::now();
  while (!stop) {
    const auto now = Clock::now();
    if (now >= next_emit) {
      emit(now);
      next_emit += period;
      if (next_emit < now) next_emit = now + period;  // behind: skip, never catch up in a burst
    }
    if (now >= next_info) {
      server_.setSourceInfo({{"messages", feed_.counters()}, {"warnings", feed_.warnings()}});
      next_info = now + info_period;
    }
    const auto wait = std::chrono::duration_cast<std::chrono::milliseconds>(
        std::min(next_emit, next_info) - Clock::now());
    const int ms = static_cast<int>(std::clamp<long>(wait.count(), 1, 50));
    if (lcm_.handleTimeout(ms) < 0) {
      std::fprintf(stderr, "stride-viz: LCM failed to receive\n");
      return false;
    }
  }
  return true;
}

}  // namespace stride::viz
