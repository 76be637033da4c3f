// stride-viz's server, for real: the program serving a session log on a free port (a process, as a
// user runs it), and the live path in process on an LCM memq:// bus (no network at all): bad
// requests answered 400 while it keeps serving, the log document, the URDF, the static files and
// what may not be reached, and a browser that never reads costing bounded memory.
#include <gtest/gtest.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <thread>

#include "http_client.hpp"
#include "sanitizers.hpp"
#include "viz/server/feed.hpp"
#include "viz/server/http_server.hpp"
#include "viz/server/live.hpp"
#include "viz_cases.hpp"

namespace stride::viz {
namespace test_viz_server {

using namespace stride::viz::test;
namespace fs = std::filesystem;

// A temporary folder, removed at the end.
struct TempDir {
  fs::path path;
  TempDir() {
    char name[] = "/tmp/stride-viz-test-XXXXXX";
    path = ::mkdtemp(name);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

// stride-viz --log LOG --port 0 --web-dir WEB, its port read from its first line.
class LogServer : public ::testing::Test {
 protected:
  void start(const std::vector<std::string>& more = {}) {
    const std::string log = sessionLog();
    ASSERT_FALSE(log.empty()) << "no session log";
    std::vector<std::string> args = {STRIDE_VIZ_BIN, "--log",          log, "--port", "0",
                                     "--web-dir",    web.path.string()};
    args.insert(args.end(), more.begin(), more.end());
    child = std::make_unique<Child>(args);
    const std::string line = child->readLine(60);
    std::smatch m;
    ASSERT_TRUE(std::regex_match(
        line, m, std::regex(R"(stride-viz: http://127\.0\.0\.1:(\d+)/ \(log (.+)\))")))
        << "first line: '" << line << "'";
    EXPECT_EQ(m[2].str(), log);
    port = std::stoi(m[1].str());
  }
  Json info() {
    const Reply r = get(port, "/api/info");
    EXPECT_EQ(r.status, 200);
    return Json::parse(r.body);
  }

  TempDir web;
  std::unique_ptr<Child> child;
  int port = 0;
};

TEST_F(LogServer, MalformedRequestsGet400AndTheServerKeepsServing) {
  start();
  const std::string garbage("\x16\x03\x01\x02\x00\x01\x00\x01\xfc\x03\x03\xff\xfe\r\n\r\n", 17);
  const std::string no_version = "GET /api/info\r\n\r\n";
  const std::string oversized =
      "GET /api/info HTTP/1.1\r\nHost: x\r\nX-Big: " + std::string(20000, 'a') + "\r\n\r\n";
  const std::string bad_header = "GET / HTTP/1.1\r\nHost x\r\n\r\n";
  int answered_400 = 0;
  for (const std::string& request : {garbage, no_version, oversized, bad_header}) {
    const Reply r = roundTrip(port, request);
    // 400 and closed, or closed at once (the server may reset before the client reads).
    EXPECT_TRUE(r.status == 400 || r.status == 0) << "got " << r.status << " for a bad request";
    answered_400 += r.status == 400;
    EXPECT_EQ(get(port, "/api/info").status, 200) << "the server stopped serving";
  }
  EXPECT_GE(answered_400, 2);
  EXPECT_GE(info()["server"]["bad_requests"].get<int>(), 4);
  // A method other than GET or HEAD, a WebSocket on another path.
  EXPECT_EQ(
      roundTrip(port, "DELETE /api/info HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n").status,
      405);
  EXPECT_EQ(get(port, "/ws").status, 426);
  EXPECT_EQ(child->stop(SIGTERM), 0);
  EXPECT_NE(child->rest().find("stride-viz: stopped: 0 clients served"), std::string::npos);
}

TEST_F(LogServer, TheLogDocumentHoldsStatesAndPlans) {
  start();
  const Reply r = get(port, "/api/log");
  ASSERT_EQ(r.status, 200);
  EXPECT_NE(r.head.find("Content-Type: application/json"), std::string::npos);
  const Json doc = Json::parse(r.body);
  EXPECT_EQ(doc["info"]["mode"], "log");
  EXPECT_EQ(doc["model"]["type"], "model");
  EXPECT_EQ(doc["model"]["robot"], "stride_quad");
  EXPECT_EQ(doc["model"]["nq"], 19);
  EXPECT_EQ(doc["model"]["urdf"], "/robot.urdf");
  int states = 0, with_forces = 0, plans = 0, planned_forces = 0, statuses = 0;
  double t = -1e300;
  for (const Json& f : doc["frames"]) {
    EXPECT_GE(f["t"].get<double>(), t) << "frames not sorted by t";
    t = f["t"].get<double>();
    if (f["type"] == "state") {
      ++states;
      EXPECT_EQ(f["q"].size(), 19u);
      EXPECT_EQ(f["contact"].size(), 4u);
      EXPECT_TRUE(f["forces"].empty() || f["forces"].size() == 4u);
      with_forces += f["forces"].size() == 4u;
    } else if (f["type"] == "plan") {
      ++plans;
      planned_forces += f["forces"].size() == 4u;  // from the controller's horizon_t
      EXPECT_FALSE(f["base"].empty());
      EXPECT_EQ(f["feet"].size(), f["base"].size());
      EXPECT_EQ(f["feet"][0].size(), 4u);
    } else if (f["type"] == "status") {
      ++statuses;
      EXPECT_TRUE(f.contains("tick_ms") && f.contains("gait") && f.contains("command"));
    }
  }
  // 2 s of log: states decimated to 100 per second, statuses to 20; plans come from the
  // controller's horizon_t, which it publishes at 10 Hz.
  EXPECT_GE(states, 150);
  EXPECT_LE(states, 201);
  EXPECT_GE(with_forces, states - 10);
  EXPECT_GE(plans, 15);
  EXPECT_LE(plans, 41);
  EXPECT_GE(planned_forces, 15);
  EXPECT_GE(statuses, 30);
  EXPECT_LE(statuses, 41);
}

TEST_F(LogServer, TheUrdfAndOnlyTheFilesItNames) {
  start();
  const Reply urdf = get(port, "/robot.urdf");
  ASSERT_EQ(urdf.status, 200);
  EXPECT_NE(urdf.body.find("<robot"), std::string::npos);
  EXPECT_EQ(urdf.body.find("package://"), std::string::npos);
  for (const char* path :
       {"/robot/files/0/x", "/robot/files/0/../../../etc/passwd", "/assets/../../etc/passwd",
        "/assets/%2e%2e/etc/passwd", "/assets/.hidden", "/etc/passwd", "/robot/files/99999999/a",
        "/api/nothing", "//etc/passwd"})
    EXPECT_EQ(get(port, path).status, 404) << path;
}

TEST_F(LogServer, WithoutThePageTheRootSays503) {
  start();
  const Reply r = get(port, "/");
  EXPECT_EQ(r.status, 503);
  EXPECT_NE(r.body.find("the viewer's page was not built"), std::string::npos);
  EXPECT_EQ(get(port, "/api/info").status, 200);
}

TEST_F(LogServer, ServesThePageAndItsAssets) {
  fs::create_directories(web.path / "assets");
  std::ofstream(web.path / "index.html") << "<!doctype html><title>stride-viz</title>";
  std::ofstream(web.path / "assets" / "app.js") << "console.log(1);";
  start();
  Reply r = get(port, "/");
  ASSERT_EQ(r.status, 200);
  EXPECT_NE(r.head.find("Content-Type: text/html"), std::string::npos);
  EXPECT_EQ(r.body, "<!doctype html><title>stride-viz</title>");
  r = get(port, "/assets/app.js");
  ASSERT_EQ(r.status, 200);
  EXPECT_NE(r.head.find("Content-Type: text/javascript"), std::string::npos);
  EXPECT_EQ(r.body, "console.log(1);");
  r = roundTrip(port, "HEAD /assets/app.js HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n");
  EXPECT_EQ(r.status, 200);
  EXPECT_NE(r.head.find("Content-Length: 15"), std::string::npos);
  EXPECT_EQ(r.body, "");
}

// In log mode /ws sends the info frame only: the page plays /api/log itself.
TEST_F(LogServer, AWebSocketGetsTheInfoFrame) {
  start();
  const int ws = openWebSocket(port);
  ASSERT_GE(ws, 0);
  const Json frame = Json::parse(readWebSocketText(ws));
  EXPECT_EQ(frame["type"], "info");
  EXPECT_EQ(frame["mode"], "log");
  EXPECT_EQ(frame["dropped_frames"], 0);
  ::close(ws);
  EXPECT_EQ(child->stop(SIGINT), 0);
  EXPECT_NE(child->rest().find("stride-viz: stopped: 1 clients served"), std::string::npos);
}

// Live, in process: the real server and LCM source on a memq:// bus, fed faster than any controller
// publishes (a 100-knot horizon, a state and a status every millisecond, frames at 1 kHz). One
// browser never reads (a 4 KiB receive window, so the kernel's buffers fill within a second); one
// reads everything.
class Live : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(lcm.good());
    RobotSource source;
    source.yaml = quadYaml();
    feed = std::make_unique<Feed>(Channels{}, source);
    ServerOptions options;
    options.port = 0;
    options.web_dir = "/nonexistent";
    options.queue = kLimits;
    options.info_period = 0.2;
    server = std::make_unique<HttpServer>(options, Json{{"mode", "live"}, {"url", "memq://"}});
    live = std::make_unique<LiveSource>(lcm, *feed, *server, 1000.0);
    // Counted on the source's thread, after the LiveSource's own handler for the same message.
    lcm.subscribe("STRIDE_STATUS", &Live::onStatus, this);
    server_thread = std::thread([this] { server->run(); });
    source_thread = std::thread([this] { live->run(stop); });
  }
  void TearDown() override {
    stop = true;
    server->stop();
    if (server_thread.joinable()) server_thread.join();
    if (source_thread.joinable()) source_thread.join();
  }
  void onStatus(const lcm::ReceiveBuffer*, const std::string&) { ++handled_; }
  // One millisecond's messages. memq:// keeps every message not yet handled, whatever the
  // subscription's queue capacity (UDP drops beyond it), so a publisher faster than the source
  // (a slow host, the sanitizers) would grow LCM's queue, not the server's: the publisher waits
  // (up to 1 s) until the source is at most kAhead status messages behind.
  void publish(std::int64_t utime) {
    const auto give_up = Clock::now() + std::chrono::seconds(1);
    while (published_ - handled_.load() > kAhead && Clock::now() < give_up)
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    ++published_;
    const robot_state_t s = standingState(utime);
    lcm.publish("STRIDE_STATE", &s);
    horizon_.utime = utime;
    lcm.publish("STRIDE_HORIZON", &horizon_);
    mpc_status_t st{};
    st.utime = utime;
    st.tick = utime / 1000;
    st.gait = "stand";
    lcm.publish("STRIDE_STATUS", &st);
  }
  Json info() { return Json::parse(get(server->port(), "/api/info").body); }

  const QueueLimits kLimits{64, 512 * 1024};
  static constexpr long kDroppedKb = 32 * 1024, kRssGrowthKb = 8 * 1024;
  lcm::LCM lcm{"memq://"};
  std::unique_ptr<Feed> feed;
  std::unique_ptr<HttpServer> server;
  std::unique_ptr<LiveSource> live;
  std::atomic<bool> stop{false};
  std::thread server_thread, source_thread;
  horizon_t horizon_ = standingHorizon(0, 100);
  static constexpr long kAhead = 20;
  long published_ = 0;
  std::atomic<long> handled_{0};
};

TEST_F(Live, ABrowserThatNeverReadsCostsBoundedMemory) {
  const robot_model_t model = quadModel();
  lcm.publish("STRIDE_MODEL", &model);
  const int port = server->port();
  const int stalled = openWebSocket(port, 4096);
  ASSERT_GE(stalled, 0);

  std::int64_t utime = 1000000;
  const auto run_for = [&](double seconds) {
    const auto end = Clock::now() + std::chrono::duration<double>(seconds);
    while (Clock::now() < end) {
      publish(utime += 1000);
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  };
  run_for(1.5);  // the socket's buffers fill, the queue reaches its limits
  // VmRSS, or under AddressSanitizer the heap in use (tests/sanitizers.hpp).
  using stride::test_support::heldMemoryKb, stride::test_support::kHeldMemory;
  const long rss0 = heldMemoryKb(vmRssKb());
  const Json info0 = info();
  const auto droppedSince = [&info0](const Json& now, const char* what) {
    return now["server"][what].get<long>() - info0["server"][what].get<long>();
  };
  // Until 32 MB were dropped for it (~5 s here), however slow the machine, within 60 s.
  long max_queued = 0, dropped_kb = 0;
  Json now;
  const auto give_up = Clock::now() + std::chrono::seconds(60);
  while (dropped_kb < kDroppedKb && Clock::now() < give_up) {
    run_for(0.5);
    now = info();
    const long queued = now["server"]["queued_bytes"].get<long>();
    max_queued = std::max(max_queued, queued);
    EXPECT_LE(queued, static_cast<long>(kLimits.max_bytes));
    ASSERT_EQ(now["server"]["viewers"].size(), 1u);
    EXPECT_LE(now["server"]["viewers"][0]["queued_frames"].get<long>(),
              static_cast<long>(kLimits.max_frames));
    dropped_kb = droppedSince(now, "bytes_dropped") / 1024;
  }
  const long rss1 = heldMemoryKb(vmRssKb());
  const long dropped = droppedSince(now, "frames_dropped");
  std::printf(
      "a browser that never reads: %ld frames (%ld kB) dropped, at most %ld bytes queued, "
      "%s %ld -> %ld kB\n",
      dropped, dropped_kb, max_queued, kHeldMemory, rss0, rss1);
  // What a buffering server would have kept; this one dropped it, and its memory stayed.
  EXPECT_GE(dropped_kb, kDroppedKb) << "the server built too few frames in 60 s";
  EXPECT_GT(max_queued, 0);
  EXPECT_LT(rss1 - rss0, kRssGrowthKb) << kHeldMemory << " grew from " << rss0 << " kB to " << rss1
                                       << " kB while " << dropped_kb << " kB were dropped";
  EXPECT_GT(now["server"]["frames_sent"].get<long>(), 0);
  ::close(stalled);
}

TEST_F(Live, FramesFlowToAReadingBrowserAndBadMessagesAreCounted) {
  const int port = server->port();
  const int ws = openWebSocket(port);
  ASSERT_GE(ws, 0);
  const std::vector<unsigned char> garbage(100, 0xab);
  for (const char* channel : {"STRIDE_STATE", "STRIDE_POLICY", "STRIDE_STATUS", "STRIDE_MODEL",
                              "STRIDE_COMMAND", "STRIDE_HORIZON"})
    lcm.publish(channel, garbage.data(), static_cast<unsigned>(garbage.size()));
  const robot_model_t model = quadModel();
  lcm.publish("STRIDE_MODEL", &model);
  std::set<std::string> kinds;
  Json state;
  std::int64_t utime = 1000000;
  const auto end = Clock::now() + std::chrono::seconds(10);
  while (kinds.size() < 5 && Clock::now() < end) {
    publish(utime += 20000);
    const std::string text = readWebSocketText(ws, 1.0);
    if (text.empty()) continue;
    const Json frame = Json::parse(text);
    kinds.insert(frame["type"].get<std::string>());
    if (frame["type"] == "state") state = frame;
  }
  EXPECT_EQ(kinds, (std::set<std::string>{"info", "model", "state", "plan", "status"}));
  ASSERT_FALSE(state.is_null());
  EXPECT_EQ(state["q"].size(), 19u);
  std::this_thread::sleep_for(std::chrono::milliseconds(600));  // the source's counters reach info
  const Json messages = info()["messages"]["channels"];
  for (const char* channel : {"STRIDE_STATE", "STRIDE_POLICY", "STRIDE_STATUS", "STRIDE_MODEL",
                              "STRIDE_COMMAND", "STRIDE_HORIZON"}) {
    long rejected = 0;
    for (const auto& [reason, n] : messages[channel]["rejected"].items()) rejected += n.get<long>();
    EXPECT_EQ(rejected, 1) << channel;
  }
  EXPECT_GT(messages["STRIDE_STATE"]["accepted"].get<long>(), 0);
  ::close(ws);
}

// Maps published at 100 Hz reach a browser at most kTerrainFrameRate a second, each the newest
// one with its numbers; a malformed one is counted; a browser that comes later gets the newest
// map right after the model, without waiting for the next one (a map may come rarely).
TEST_F(Live, MapsReachTheBrowserTwiceASecondAndLaterBrowsersGetTheNewest) {
  const robot_model_t model = quadModel();
  lcm.publish("STRIDE_MODEL", &model);
  const int ws = openWebSocket(server->port());
  ASSERT_GE(ws, 0);
  const std::vector<unsigned char> garbage(100, 0xab);
  lcm.publish("STRIDE_TERRAIN", garbage.data(), static_cast<unsigned>(garbage.size()));
  std::vector<Json> maps;
  std::int64_t utime = 1000000;
  const auto start = Clock::now();
  const auto end = start + std::chrono::milliseconds(2200);
  while (Clock::now() < end) {
    utime += 10000;
    const terrain_t map = boxStepMap(utime, 100, 100, 1e-6 * utime, 0.0);
    lcm.publish("STRIDE_TERRAIN", &map);
    // A frame once one begins to come (read whole: a timeout inside a 50 kB frame would lose the
    // stream's framing), else the next map.
    pollfd readable{ws, POLLIN, 0};
    if (::poll(&readable, 1, 10) <= 0) continue;
    const std::string text = readWebSocketText(ws, 10.0);
    ASSERT_FALSE(text.empty());
    if (Json::parse(text)["type"] == "terrain") maps.push_back(Json::parse(text));
  }
  const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
  std::printf("%zu terrain frames in %.2f s of maps at 100 Hz\n", maps.size(), seconds);
  // One at once, then one every 0.5 s; the last may still be on its way.
  EXPECT_GE(maps.size(), 2u);
  EXPECT_LE(maps.size(), static_cast<std::size_t>(seconds * kTerrainFrameRate) + 1);
  for (std::size_t i = 0; i < maps.size(); ++i) {
    const Json& m = maps[i];
    EXPECT_EQ(m["rows"], 100);
    EXPECT_EQ(m["cols"], 100);
    ASSERT_EQ(m["heights"].size(), 10000u);
    EXPECT_TRUE(m["heights"][10 * 100 + 10].is_null());
    // Centred on x = t: the origin 0.99 m behind.
    EXPECT_NEAR(m["origin_x"].get<double>(), m["t"].get<double>() - 0.99, 1e-6);
    if (i > 0) {
      EXPECT_GE(m["t"].get<double>() - maps[i - 1]["t"].get<double>(), 0.3);
    }
  }
  ASSERT_FALSE(maps.empty());
  // A browser that comes after the last map: info, model, then that map.
  std::this_thread::sleep_for(std::chrono::milliseconds(600));
  const int late = openWebSocket(server->port());
  ASSERT_GE(late, 0);
  Json map;
  for (int i = 0; i < 3 && map.is_null(); ++i) {
    const std::string text = readWebSocketText(late, 2.0);
    ASSERT_FALSE(text.empty());
    const Json frame = Json::parse(text);
    if (frame["type"] == "terrain") map = frame;
  }
  ASSERT_FALSE(map.is_null());
  EXPECT_NEAR(map["t"].get<double>(), 1e-6 * utime, 1e-9) << "the newest map";
  const Json messages = info()["messages"]["channels"]["STRIDE_TERRAIN"];
  EXPECT_EQ(messages["rejected"][msg::describe(msg::Reject::Undecodable)], 1) << messages;
  EXPECT_GT(messages["accepted"].get<long>(), 100);
  ::close(ws);
  ::close(late);
}

}  // namespace test_viz_server
}  // namespace stride::viz
