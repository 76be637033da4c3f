// stride-viz: a browser view of a running Stride controller or of a recorded session
// (viz/README.md). Subscribes to the Stride channels on an LCM bus, or reads an lcm-logger log,
// and serves the page and its frames over HTTP and WebSocket, on the loopback interface by default.
//   stride-viz --url udpm://239.255.76.67:7667?ttl=0      live (default: $LCM_DEFAULT_URL)
//   stride-viz --log session.lcmlog                        a recorded session, played in the page
// Prints one line with the URL once it serves; SIGINT or SIGTERM stop it with a summary.
// Exit status: 0 stopped; 1 an error (robot, log, address, LCM failing while running); 2 a usage
// error or an LCM URL that cannot be opened.

#include <CLI/CLI.hpp>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "config/command_line.hpp"
#include "viz/server/feed.hpp"
#include "viz/server/http_server.hpp"
#include "viz/server/live.hpp"
#include "viz/server/log_document.hpp"

#ifndef STRIDE_CONFIG_DIR
#error "STRIDE_CONFIG_DIR (the source tree's config/) must be defined"
#endif
#ifndef STRIDE_VIZ_WEB_DIR
#error "STRIDE_VIZ_WEB_DIR (the web bundle in the build tree) must be defined"
#endif
#ifndef STRIDE_VIZ_BIN_TO_DATA
#error \
    "STRIDE_VIZ_BIN_TO_DATA (the installed data folder, relative to the programs') must be defined"
#endif

namespace {

namespace fs = std::filesystem;
using stride::viz::Json;

// The installed share/stride/<what> next to this program's bin/, "" when not installed.
std::string installed(const std::string& what) {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (ec) return "";
  const fs::path dir =
      (exe.parent_path() / STRIDE_VIZ_BIN_TO_DATA / "stride" / what).lexically_normal();
  return fs::is_directory(dir, ec) ? dir.string() : "";
}

std::string defaultWebDir() {
  const std::string web = installed("viz/web");
  return web.empty() ? STRIDE_VIZ_WEB_DIR : web;
}

void printSummary(const stride::viz::HttpServer& server, const stride::viz::Feed& feed) {
  const stride::viz::ServerCounters c = server.counters();
  std::printf(
      "stride-viz: stopped: %llu clients served, %llu frames sent, %llu frames dropped (slow "
      "browsers); %llu requests, %llu bad\n",
      static_cast<unsigned long long>(c.clients_served),
      static_cast<unsigned long long>(c.frames_sent),
      static_cast<unsigned long long>(c.frames_dropped),
      static_cast<unsigned long long>(c.requests), static_cast<unsigned long long>(c.bad_requests));
  for (const std::string& channel : feed.channels().all())
    if (feed.rejected(channel) > 0)
      std::fprintf(stderr, "stride-viz: '%s': %ld accepted, %ld rejected %s\n", channel.c_str(),
                   feed.accepted(channel), feed.rejected(channel),
                   feed.counters()["channels"][channel]["rejected"].dump().c_str());
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "stride-viz: the robot, its plan and the controller's status in a browser, live from an LCM "
      "bus or from a log"};
  stride::commandLineConventions(app, "stride-viz");
  const char* env_url = std::getenv("LCM_DEFAULT_URL");
  std::string url = env_url != nullptr ? env_url : "", log_path;
  stride::viz::Channels channels;
  stride::viz::RobotSource robot;
  stride::viz::ServerOptions server_options;
  server_options.web_dir = defaultWebDir();
  double rate = 30.0;
  app.add_option("--url", url, "live: the LCM URL to subscribe on")
      ->default_str(env_url != nullptr ? url : "$LCM_DEFAULT_URL, unset");
  app.add_option("--log", log_path, "play this lcm-logger log instead of a live bus")
      ->check(CLI::ExistingFile)
      ->excludes("--url");
  app.add_option("--robot", robot.yaml,
                 "the robot's YAML (config/robots/<name>/<name>.yaml); default: the one the "
                 "controller's robot_model_t names, in the config folders")
      ->check(CLI::ExistingFile);
  app.add_option("--robots-dir", robot.robots_dirs,
                 "where package:// URIs are looked for before ROS_PACKAGE_PATH (repeatable)");
  app.add_option("--bind", server_options.bind, "the address to serve on (IPv4 or IPv6)");
  app.add_option("--port", server_options.port, "the port to serve on; 0 picks a free one");
  app.add_option("--web-dir", server_options.web_dir, "the page's files (index.html, assets/)");
  app.add_option("--rate", rate, "live: frames of each kind per second, at most")
      ->check(CLI::Range(0.1, 1000.0));
  bool all_frames = false;
  app.add_flag("--all-frames", all_frames,
               "log: every state, plan and status of the log becomes a frame (default: at most "
               "100 states, 20 plans and 20 statuses per second of log time; terrain maps stay "
               "at 2 per second)")
      ->needs("--log");
  app.add_option("--queue-frames", server_options.queue.max_frames,
                 "frames queued for one browser, at most (then the oldest are dropped)")
      ->check(CLI::Range(1, 100000));
  app.add_option("--queue-bytes", server_options.queue.max_bytes,
                 "bytes queued for one browser, at most (then the oldest frames are dropped)")
      ->check(CLI::Range(1024, 1 << 30));
  app.add_option("--max-clients", server_options.max_clients, "browsers at once, at most")
      ->check(CLI::Range(1, 1000));
  double duration = 0.0;
  app.add_option("--duration", duration, "stop after this many seconds (0: on SIGINT/SIGTERM)")
      ->check(CLI::Range(0.0, 1e9));
  app.add_option("--state-channel", channels.state);
  app.add_option("--policy-channel", channels.policy);
  app.add_option("--status-channel", channels.status);
  app.add_option("--model-channel", channels.model);
  app.add_option("--command-channel", channels.command);
  app.add_option("--horizon-channel", channels.horizon);
  app.add_option("--terrain-channel", channels.terrain,
                 "the elevation maps (terrain_t) drawn under the robot");
  app.footer(
      "Prints 'stride-viz: http://ADDR:PORT/ (live URL | log FILE)' once it serves. Exit status: 0 "
      "stopped (SIGINT, SIGTERM, --duration); 1 an error: the robot, the log, the address, LCM "
      "failing; 2 a usage error or an LCM URL that cannot be opened.");
  if (const int status = stride::parseCommandLine(app, argc, argv); status >= 0) return status;
  if (log_path.empty() && url.empty()) {
    std::fprintf(stderr,
                 "stride-viz: no LCM URL: give --url URL (or set LCM_DEFAULT_URL), or --log FILE\n"
                 "%s",
                 CLI::Formatter().make_usage(&app, app.get_name()).c_str());
    return 2;
  }
  robot.config_dirs = {STRIDE_CONFIG_DIR, installed("config")};
  server_options.handle_signals = true;
  server_options.duration = duration;
  const bool live = log_path.empty();
  if (!live) server_options.info_period = 0.0;  // nothing changes in a log: one info frame

  std::unique_ptr<lcm::LCM> lcm;
  if (live) {
    lcm = std::make_unique<lcm::LCM>(url);
    if (!lcm->good()) {
      std::fprintf(stderr, "stride-viz: cannot open the LCM URL '%s'\n", url.c_str());
      return 2;
    }
  }
  try {
    stride::viz::Feed feed(channels, robot);
    Json info =
        live ? Json{{"mode", "live"}, {"url", url}} : Json{{"mode", "log"}, {"log", log_path}};
    stride::viz::HttpServer server(server_options, info);
    if (!live) {
      // Decimation keeps a long session's document small; a short log whose every knot matters
      // (the paper's snapshots: a plan per state) asks for all of them.
      stride::viz::LogOptions log_options;
      // Maps stay at kTerrainFrameRate: each is ~50 kB, and a snapshot needs the one under the
      // robot, not every one.
      if (all_frames) log_options = {0.0, 0.0, 0.0, stride::viz::kTerrainFrameRate};
      stride::viz::LogDocument log = stride::viz::readLog(log_path, feed, log_options, info);
      server.setLogDocument(std::make_shared<const std::string>(
          log.document.dump(-1, ' ', false, Json::error_handler_t::replace)));
      server.setRobotFiles(feed.robotFiles());  // the model travels in the document
      server.setSourceInfo({{"messages", feed.counters()},
                            {"warnings", feed.warnings()},
                            {"frames", log.frames},
                            {"duration", log.duration}});
      std::fprintf(stderr, "stride-viz: %s: %ld events, %ld frames over %.2f s\n", log_path.c_str(),
                   log.events, log.frames, log.duration);
    }
    std::printf("stride-viz: %s (%s %s)\n", server.url().c_str(), live ? "live" : "log",
                live ? url.c_str() : log_path.c_str());
    std::fflush(stdout);
    if (!live) {
      server.run();
      printSummary(server, feed);
      return 0;
    }
    stride::viz::LiveSource source(*lcm, feed, server, rate);
    std::atomic<bool> stop{false}, lcm_ok{true};
    std::thread lcm_thread([&] {
      try {
        lcm_ok = source.run(stop);
      } catch (const std::exception& e) {
        std::fprintf(stderr, "stride-viz: %s\n", e.what());
        lcm_ok = false;
      }
      if (!lcm_ok) server.stop();
    });
    server.run();
    stop = true;
    lcm_thread.join();
    printSummary(server, feed);
    return lcm_ok ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "stride-viz: %s\n", e.what());
    return 1;
  }
}
