#pragma once
// Live mode: the Stride channels of an LCM bus, through a Feed, to the server's clients. Runs on a
// thread of its own: it is one more subscriber on the bus, never waits for a browser (the server's
// queues do the dropping), and builds frames at most `rate` times a second from the newest
// messages (newest wins: a frame is never made of a message a newer one superseded); terrain maps
// at most kTerrainFrameRate a second.

#include <atomic>
#include <chrono>
#include <lcm/lcm-cpp.hpp>

#include "viz/server/feed.hpp"
#include "viz/server/http_server.hpp"

namespace stride::viz {

class LiveSource {
 public:
  // Subscribes `lcm` to every channel of `feed`.
  LiveSource(lcm::LCM& lcm, Feed& feed, HttpServer& server, double rate_hz);
  ~LiveSource();
  LiveSource(const LiveSource&) = delete;
  LiveSource& operator=(const LiveSource&) = delete;

  // Handles messages and sends frames until `stop` is set (checked at least every 50 ms).
  // Returns false when LCM failed (the reason on stderr).
  bool run(const std::atomic<bool>& stop);

 private:
  void onMessage(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  void emit(std::chrono::steady_clock::time_point now);

  lcm::LCM& lcm_;
  Feed& feed_;
  HttpServer& server_;
  double period_;
  int model_version_ = 0;
  std::chrono::steady_clock::time_point next_terrain_{};
  std::vector<lcm::Subscription*> subscriptions_;
};

}  // namespace stride::viz
