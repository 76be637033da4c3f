#pragma once
// stride-viz's HTTP and WebSocket server (Boost.Beast; viz/README.md, "HTTP"): the page's static
// files, the robot's URDF and the files it names, /api/info, /api/log (log mode), and /ws, which
// streams frames to each browser through its own bounded queue (client_queue.hpp). Beast parses
// every request; a request it cannot parse gets 400 and the connection is closed.
//
// Threads: run() serves on the calling thread (one Asio loop: sessions need no locks among
// themselves). The setters and broadcast() may be called from any other thread (the LCM thread):
// they take a mutex, queue, and wake the loop; they never wait for a client.
//
// Beast stays in http_server.cpp: this header is all its users compile.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <nlohmann/json_fwd.hpp>
#include <string>

#include "viz/server/client_queue.hpp"
#include "viz/server/robot_files.hpp"

namespace stride::viz {

using Json = nlohmann::json;

struct ServerOptions {
  std::string bind = "127.0.0.1";
  unsigned short port = 8765;   // 0: a free port, see HttpServer::port()
  std::string web_dir;          // the page's static root (index.html, assets/)
  QueueLimits queue;            // per WebSocket client
  int max_clients = 32;         // WebSocket clients at once (more get 503)
  int max_connections = 256;    // HTTP connections at once (more are closed at once)
  double info_period = 1.0;     // [s] between info frames to each client; 0: the first only
  bool handle_signals = false;  // SIGINT and SIGTERM stop run()
  double duration = 0.0;        // [s] run() stops after this long; 0: never
};

struct ServerCounters {
  std::uint64_t clients_served = 0;  // WebSocket clients accepted since the start
  std::uint64_t frames_sent = 0;     // written to WebSocket clients
  std::uint64_t frames_dropped = 0;  // dropped by the clients' queues (slow browsers)
  std::uint64_t bytes_dropped = 0;   // their size
  std::uint64_t requests = 0;        // HTTP requests parsed
  std::uint64_t bad_requests = 0;    // answered 400 (unparseable)
  std::size_t clients = 0;           // WebSocket clients now
  std::size_t queued_bytes = 0;      // in the clients' queues now
};

class HttpServer {
 public:
  // Binds and listens at once (throws std::runtime_error naming the address when it cannot).
  // `info`: the fixed fields of the info frames and /api/info ({"mode": "live", "url": ...}).
  HttpServer(ServerOptions options, Json info);
  ~HttpServer();
  HttpServer(const HttpServer&) = delete;
  HttpServer& operator=(const HttpServer&) = delete;

  unsigned short port() const;  // the bound port (the one picked for port 0)
  // "http://127.0.0.1:8765/" ([] around an IPv6 address)
  std::string url() const;

  // Serves until stop(), a signal (handle_signals) or the duration.
  void run();
  void stop();  // any thread

  // From any thread:
  void setRobotFiles(std::shared_ptr<const RobotFiles> files);
  // The model frame: sent to every client now and to each new one first.
  void setModel(const Json& model);
  // The newest terrain frame: sent to every client now and to each new one after the model (a map
  // may come rarely, or no more).
  void setTerrain(const Json& terrain);
  void setLogDocument(std::shared_ptr<const std::string> document);
  // The source's counters and warnings, shown in /api/info ({"messages": ..., "warnings": [...]});
  // the warnings also go into the info frames.
  void setSourceInfo(const Json& source);
  // A frame to every WebSocket client's queue.
  void broadcast(FrameKind kind, FrameText text);

  ServerCounters counters() const;

  class Impl;  // http_server.cpp's, with its sessions

 private:
  std::unique_ptr<Impl> impl_;
};

// The text a frame travels as: JSON, with invalid UTF-8 from the wire (a gait name is any bytes)
// replaced rather than thrown on.
FrameText frameText(const Json& frame);

}  // namespace stride::viz
