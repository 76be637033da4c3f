// stride-log-summary on logs written here (lcm::LogFile, no network): the command segments in the
// table and the JSON, the rejected commands, and the exit status for a robot that tracks, one that
// falls short (1 with --check-tracking), and one that falls (4, with the flag or without).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "messages/signing.hpp"
#include "stride/command_t.hpp"
#include "stride/mpc_status_t.hpp"
#include "stride/robot_state_t.hpp"
#include "stride/terrain_t.hpp"

namespace test_log_summary {

enum class Robot { Tracks, SlowInSegment1, FallsInSegment2 };

// Signs what write() writes, when set (messages/README.md, "Signing").
stride::msg::Signer* g_signer = nullptr;

// Raw bytes into the log: a malformed message as a broken or hostile publisher would send it.
void writeBytes(lcm::LogFile& log, const std::string& channel, std::vector<unsigned char> bytes,
                std::int64_t utime) {
  lcm::LogEvent e{};
  e.timestamp = utime;
  e.channel = channel;
  e.datalen = static_cast<int32_t>(bytes.size());
  e.data = bytes.data();
  log.writeEvent(&e);
}

template <typename Message>
void write(lcm::LogFile& log, const std::string& channel, const Message& m, std::int64_t utime) {
  std::vector<unsigned char> bytes(m.getEncodedSize() + stride::msg::kSignatureSize);
  const int n = m.encode(bytes.data(), 0, m.getEncodedSize());
  bytes.resize(
      g_signer ? g_signer->sign(channel.c_str(), bytes.data(), n, static_cast<int>(bytes.size()))
               : n);
  writeBytes(log, channel, std::move(bytes), utime);
}

// 9 s at 100 Hz: stand 3 s, walk forward at 0.5 m/s 3 s, walk and turn at 1 rad/s 3 s, with the
// commands repeated at 20 Hz and stamped with the state they answer. One command is NaN.
std::string writeSession(const std::string& name, Robot robot) {
  const std::string path = testing::TempDir() + "/" + name + ".lcmlog";
  lcm::LogFile log(path, "w");
  EXPECT_TRUE(log.good());
  const std::int64_t u0 = 7000000;
  double x = 0, y = 0, yaw = 0;
  for (int i = 0; i <= 900; ++i) {
    const double t = i / 100.0;
    const std::int64_t utime = u0 + 10000L * i;
    const int segment = t < 3.0 ? 0 : t < 6.0 ? 1 : 2;
    double vx = segment == 0 ? 0.0 : 0.5, w = segment == 2 ? 1.0 : 0.0;
    if (robot == Robot::SlowInSegment1 && segment == 1) vx = 0.3;
    stride::robot_state_t s;
    s.utime = utime;
    s.model_hash = 0;  // a bare base (the summary holds every state to the first one's model)
    s.session = 1;
    s.nq = 7;
    s.nv = 6;
    const bool down = robot == Robot::FallsInSegment2 && t >= 7.0;
    s.q = std::vector<double>{x, y, down ? 0.1 : 0.3, 0, 0, std::sin(yaw / 2), std::cos(yaw / 2)};
    s.v = std::vector<double>{vx, 0, 0, 0, 0, w};
    s.ncontacts = 0;
    write(log, "STRIDE_STATE", s, utime);
    if (i % 5 == 0 && i < 900) {
      stride::command_t c{};
      c.utime = utime;
      c.vx = segment == 0 ? 0.0 : 0.5;
      c.vy = 0.0;
      c.yaw_rate = segment == 2 ? 1.0 : 0.0;
      c.gait = segment == 0 ? "stand" : "trot";
      c.body_height = 0.0;
      if (i == 400) c.vx = std::numeric_limits<double>::quiet_NaN();
      write(log, "STRIDE_COMMAND", c, utime);
    }
    x += (std::cos(yaw) * vx) * 0.01;
    y += (std::sin(yaw) * vx) * 0.01;
    yaw += w * 0.01;
  }
  return path;
}

struct Summary {
  int status;
  std::string output;
  nlohmann::json json;  // null when the file is missing or is not JSON
};

Summary summarize(const std::string& log, const std::string& flags) {
  const std::string out = log + ".txt", json = log + ".json";
  const std::string cmd = std::string(STRIDE_LOG_SUMMARY_BIN) + " " + log + " --summary " + json +
                          " " + flags + " > " + out + " 2>&1";
  const int raw = std::system(cmd.c_str());
  const auto slurp = [](const std::string& p) {
    std::ifstream f(p);
    std::stringstream ss;
    ss << f.rdbuf();
    return ss.str();
  };
  return {WIFEXITED(raw) ? WEXITSTATUS(raw) : -1, slurp(out),
          nlohmann::json::parse(slurp(json), nullptr, false)};
}

TEST(LogSummary, SegmentsOfARobotThatTracks) {
  const Summary r = summarize(writeSession("tracks", Robot::Tracks), "--check-tracking");
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("tracking: every segment tracked its command (3 of 3"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("commands: 1 rejected"), std::string::npos) << r.output;
  const nlohmann::json& segments = r.json["segments"];
  ASSERT_EQ(segments.size(), 3u) << r.json.dump(2);
  EXPECT_EQ(segments[0]["t0"], 0.0);
  EXPECT_EQ(segments[0]["t1"], 3.0);
  EXPECT_EQ(segments[0]["command"], nlohmann::json({0.0, 0.0, 0.0}));
  EXPECT_EQ(segments[0]["gait"], "stand");
  // The turn: constant in the heading frame, although the world velocity went round.
  const nlohmann::json& turn = segments[2];
  EXPECT_EQ(turn["t0"], 6.0);
  EXPECT_EQ(turn["t1"], 9.0);
  EXPECT_EQ(turn["command"], nlohmann::json({0.5, 0.0, 1.0}));
  EXPECT_EQ(turn["gait"], "trot");
  EXPECT_EQ(turn["body_height"], 0.0);
  EXPECT_NEAR(turn["achieved"][0].get<double>(), 0.5, 1e-9) << turn.dump();
  EXPECT_EQ(r.json["command_rejects"], 1);
  EXPECT_EQ(r.json["fell"], false);
  EXPECT_EQ(r.json["tracked"], true);
}

TEST(LogSummary, NoDataIsNullNotZero) {
  // States and commands but no controller status: no tick, so no latency to speak of.
  const Summary r = summarize(writeSession("no_status", Robot::Tracks), "");
  EXPECT_EQ(r.status, 0) << r.output;
  for (const char* timing : {"tick_latency", "solve_time", "prepare_time"}) {
    const nlohmann::json& t = r.json[timing];
    EXPECT_EQ(t["count"], 0) << timing;
    for (const char* key : {"p50_ms", "p99_ms", "max_ms"})
      EXPECT_TRUE(t[key].is_null()) << timing << "." << key << ": " << t.dump();
  }
  EXPECT_EQ(r.json["ticks"], 0);
  for (const char* counter : {"deadline_misses", "late_ticks", "fallbacks", "rejected_messages"})
    EXPECT_TRUE(r.json[counter].is_null()) << counter;
  EXPECT_TRUE(r.json["distance_m"].is_number());  // the states are there
}

TEST(LogSummary, CheckTrackingFailsOnAMissedCommand) {
  const std::string log = writeSession("slow", Robot::SlowInSegment1);
  const Summary checked = summarize(log, "--check-tracking");
  EXPECT_EQ(checked.status, 1) << checked.output;
  EXPECT_NE(checked.output.find("tracking: segment 1 (3.00 .. 6.00 s, trot) missed vx: commanded "
                                "+0.500, achieved +0.300, tolerance 0.075"),
            std::string::npos)
      << checked.output;
  EXPECT_EQ(checked.json["tracked"], false);
  // Without the flag the status stays 0, and the verdict is still printed.
  const Summary plain = summarize(log, "");
  EXPECT_EQ(plain.status, 0) << plain.output;
  EXPECT_NE(plain.output.find("tracking: NOT every segment tracked its command (1 misses)"),
            std::string::npos)
      << plain.output;
  // A looser tolerance lets it pass.
  EXPECT_EQ(summarize(log, "--check-tracking --tolerance 0.5").status, 0);
}

TEST(LogSummary, AFallIsItsOwnExitStatusWithOrWithoutCheckTracking) {
  const std::string log = writeSession("falls", Robot::FallsInSegment2);
  EXPECT_EQ(summarize(log, "").status, 4);
  const Summary r = summarize(log, "--check-tracking");
  EXPECT_EQ(r.status, 4) << r.output;
  EXPECT_NE(r.output.find("tracking: segment 2 (6.00 .. 9.00 s, trot): the robot fell"),
            std::string::npos)
      << r.output;
  const nlohmann::json& fallen = r.json["segments"][2];
  EXPECT_EQ(fallen["samples"], 201) << fallen.dump();
  EXPECT_EQ(fallen["commands"], 60);
  EXPECT_EQ(fallen["fell"], true);
}

// A free-flying base at rest 0.3 m up, of no robot in particular (model hash 0).
stride::robot_state_t standing(std::int64_t utime) {
  stride::robot_state_t s;
  s.utime = utime;
  s.model_hash = 0;
  s.session = 1;
  s.nq = 7;
  s.nv = 6;
  s.q = std::vector<double>{0, 0, 0.3, 0, 0, 0, 1};
  s.v = std::vector<double>(6, 0.0);
  s.ncontacts = 0;
  return s;
}

// 2 s of a 100 Hz estimator and controller, with states 50-59 and status ticks 100-104 missing
// from the log (as lcm-logger drops them under load).
std::string writeLossySession() {
  const std::string path = testing::TempDir() + "/lossy.lcmlog";
  lcm::LogFile log(path, "w");
  EXPECT_TRUE(log.good());
  for (int i = 0; i < 200; ++i) {
    const std::int64_t utime = 7000000 + 10000L * i;
    if (i < 50 || i >= 60) write(log, "STRIDE_STATE", standing(utime), utime);
    if (i < 100 || i >= 105) {
      stride::mpc_status_t st{};
      st.utime = utime;
      st.tick = i + 1;
      st.policy_status = 0;
      st.gait = "stand";
      write(log, "STRIDE_STATUS", st, utime);
    }
  }
  return path;
}

TEST(LogSummary, LostMessagesAreCountedAndCanFailTheRun) {
  const std::string log = writeLossySession();
  const Summary plain = summarize(log, "");
  EXPECT_EQ(plain.status, 0) << plain.output;
  EXPECT_NE(plain.output.find("lost: 5 status messages (gaps in the tick counter), 10 state "
                              "estimates (stamp gaps; period 10.000 ms)\n"),
            std::string::npos)
      << plain.output;
  EXPECT_EQ(plain.json["lost"], nlohmann::json({{"statuses", 5}, {"states", 10}})) << plain.json;
  // Every status but the start-up solve's is a tick with a latency (0 ms here, and 0 is data);
  // none was prepared, and no state estimate is missing from the robot's side.
  EXPECT_EQ(plain.json["tick_latency"],
            nlohmann::json({{"p50_ms", 0.0}, {"p99_ms", 0.0}, {"max_ms", 0.0}, {"count", 194}}));
  EXPECT_TRUE(plain.json["prepare_time"]["p50_ms"].is_null());
  EXPECT_EQ(plain.json["base_height_min_m"], 0.3);
  const Summary strict = summarize(log, "--max-lost 14");
  EXPECT_EQ(strict.status, 5) << strict.output;
  EXPECT_NE(strict.output.find("MORE THAN --max-lost"), std::string::npos) << strict.output;
  EXPECT_EQ(summarize(log, "--max-lost 15").status, 0);
}

// The mock robot's own summary (stride-sim --summary) says why it did not follow its controller
// (sim::whyText): said on a line of its own and kept in the JSON; null when it had nothing to say.
TEST(LogSummary, TheMockRobotsWhyIsSaid) {
  const std::string log = writeSession("why", Robot::Tracks);
  const std::string sim = testing::TempDir() + "/why_sim.json";
  const std::string why =
      "997 of 997 policies arrived at or after their end (up to 0.000 s after; a policy covers "
      "0.060 s)";
  std::ofstream(sim) << nlohmann::json{{"fell", false}, {"why", why}}.dump();
  Summary r = summarize(log, "--sim-summary " + sim);
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("robot: " + why + "\n"), std::string::npos) << r.output;
  EXPECT_EQ(r.json["why"], why);
  std::ofstream(sim) << nlohmann::json{{"fell", false}, {"why", nullptr}}.dump();
  r = summarize(log, "--sim-summary " + sim);
  EXPECT_EQ(r.output.find("robot: "), std::string::npos) << r.output;
  EXPECT_TRUE(r.json["why"].is_null());
}

// Issue 33, the logger's race: lcm-logger stopped 0.3 s before the robot's last state, and the
// robot fell in those 0.3 s (its own summary says so, with the stamp of its last state). The
// summary says the log's loss, calls the robot fallen (never "did not fall" first) and exits 4.
TEST(LogSummary, AFallAfterTheLoggerStoppedIsAFall) {
  const std::string log = writeSession("tail", Robot::Tracks);  // last state at 16 000 000 us
  const std::string sim = testing::TempDir() + "/tail_sim.json";
  std::ofstream(sim) << nlohmann::json{{"fell", true}, {"last_state_utime", 16300000}}.dump();
  const Summary r = summarize(log, "--sim-summary " + sim);
  EXPECT_EQ(r.status, 4) << r.output;
  EXPECT_NE(r.output.find("log: the logger stopped 0.300 s before the robot's last state"),
            std::string::npos)
      << r.output;
  EXPECT_EQ(r.output.find("did not fall"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(", FELL\n"), std::string::npos) << r.output;
  EXPECT_EQ(r.json["fell"], true);
  EXPECT_NEAR(r.json["log_tail_lost_s"].get<double>(), 0.3, 1e-9);
  // The logger had it all: no loss said.
  std::ofstream(sim) << nlohmann::json{{"fell", false}, {"last_state_utime", 16000000}}.dump();
  const Summary whole = summarize(log, "--sim-summary " + sim);
  EXPECT_EQ(whole.status, 0) << whole.output;
  EXPECT_EQ(whole.output.find("log: the logger stopped"), std::string::npos) << whole.output;
  EXPECT_EQ(whole.json["log_tail_lost_s"], 0.0);
}

// Issue 33: --fault-end says whether control came back after a fault: every segment starting 2 s
// after it tracked (exit 6 if not), and when the command was first tracked.
TEST(LogSummary, RecoveryAfterAFault) {
  const Summary ok = summarize(writeSession("recovers", Robot::Tracks), "--fault-end 1.0");
  EXPECT_EQ(ok.status, 0) << ok.output;
  EXPECT_NE(ok.output.find("recovery: the fault ended at 1.00 s; 2 of 2 segments starting 2 s "
                           "after it tracked: control came back"),
            std::string::npos)
      << ok.output;
  EXPECT_EQ(ok.json["recovery"]["segments_after"], 2);
  EXPECT_EQ(ok.json["recovery"]["recovered"], true);
  EXPECT_EQ(ok.json["recovery"]["time_to_tracking_s"], 0.0);  // standing, as commanded
  const Summary slow =
      summarize(writeSession("slow_after", Robot::SlowInSegment1), "--fault-end 1.0");
  EXPECT_EQ(slow.status, 6) << slow.output;
  EXPECT_NE(slow.output.find("1 of 2 segments starting 2 s after it tracked: control did NOT come "
                             "back"),
            std::string::npos)
      << slow.output;
  EXPECT_EQ(slow.json["recovery"]["recovered"], false);
  // Past every segment's start: not judged, and not a failure of recovery either (the fault
  // ended too late in the run to tell).
  const Summary late = summarize(writeSession("late", Robot::Tracks), "--fault-end 8.0");
  EXPECT_EQ(late.status, 0) << late.output;
  EXPECT_NE(late.output.find("no checked segment starts 2 s after it: not judged"),
            std::string::npos)
      << late.output;
  EXPECT_EQ(late.json["recovery"]["recovered"], false);
}

// Signed messages in a log (a session with signing on) read as the plain ones: the summary reads,
// it does not verify.
TEST(LogSummary, ASignedSessionReadsAsThePlainOne) {
  const stride::msg::Key key = stride::msg::makeKey({1, 2, 3});
  stride::msg::Signer signer(key, 5);
  g_signer = &signer;
  const std::string log = writeSession("signed", Robot::Tracks);
  g_signer = nullptr;
  const Summary plain = summarize(writeSession("unsigned", Robot::Tracks), "");
  const Summary r = summarize(log, "");
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(r.json["segments"], plain.json["segments"]);
  EXPECT_EQ(r.json["command_rejects"], plain.json["command_rejects"]);
  EXPECT_EQ(r.json["distance_m"], plain.json["distance_m"]);
}

template <typename Message>
std::vector<unsigned char> encoded(const Message& m) {
  std::vector<unsigned char> b(m.getEncodedSize());
  m.encode(b.data(), 0, static_cast<int>(b.size()));
  return b;
}

// A log with malformed messages (issue 43): the summary reads them through the live receivers'
// checks (messages/validate.hpp), so each is refused and counted by reason, never decoded on
// trust, and the session reads as the clean one. The first event is a truncated state: the
// summary learns the model from the first state that passes.
TEST(LogSummary, MalformedMessagesInALogAreRefusedAndCounted) {
  const std::string path = testing::TempDir() + "/malformed.lcmlog";
  {
    lcm::LogFile log(path, "w");
    ASSERT_TRUE(log.good());
    const std::int64_t u0 = 7000000;
    std::vector<unsigned char> cut = encoded(standing(u0 - 10000));
    cut.resize(cut.size() - 5);  // truncated
    writeBytes(log, "STRIDE_STATE", cut, u0 - 10000);
    for (int i = 0; i < 200; ++i) {
      const std::int64_t utime = u0 + 10000L * i;
      write(log, "STRIDE_STATE", standing(utime), utime);
      if (i == 50) {
        std::vector<unsigned char> lie = encoded(standing(utime + 1));
        // ncontacts (after the hash, utime, model_hash, session, nq, nv, q[7], v[6]) says 2^30
        // flags
        const std::size_t at = 8 + 8 + 8 + 8 + 4 + 4 + 8 * 13;
        lie[at] = 0x40;
        writeBytes(log, "STRIDE_STATE", lie, utime + 1);
        stride::robot_state_t nan = standing(utime + 2);
        nan.q[2] = std::numeric_limits<double>::quiet_NaN();
        write(log, "STRIDE_STATE", nan, utime + 2);
        stride::robot_state_t tilted = standing(utime + 3);
        tilted.q[6] = 0.5;  // |quaternion| = 0.5: not a pose
        write(log, "STRIDE_STATE", tilted, utime + 3);
        stride::terrain_t map;
        map.utime = utime;
        map.origin_x = map.origin_y = 0.0;
        map.resolution = 0.1;
        map.rows = map.cols = 2;
        map.height = {{0.0f, 0.0f}, {0.0f, 0.0f}};
        std::vector<unsigned char> short_map = encoded(map);
        short_map.resize(short_map.size() - 3);
        writeBytes(log, "STRIDE_TERRAIN", short_map, utime);
      }
    }
  }
  const Summary r = summarize(path, "");
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("log: 4 malformed states refused"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("log: 1 malformed elevation maps refused"), std::string::npos)
      << r.output;
  EXPECT_EQ(r.json["refused_states"], 4) << r.json.dump(2);
  EXPECT_EQ(r.json["refused_terrain_maps"], 1);
  EXPECT_EQ(r.json["terrain_maps"], 0);
  // None of them entered the session: upright, at its height, the 200 good states' 1.99 s.
  EXPECT_EQ(r.json["fell"], false);
  EXPECT_EQ(r.json["base_height_min_m"], 0.3);
  EXPECT_EQ(r.json["max_tilt_deg"], 0.0);
  EXPECT_NEAR(r.json["duration_s"].get<double>(), 1.99, 1e-9);
}

// A signed state, stamped `stamp` by its sender, logged at `logged` (the logger's clock).
void writeSignedAt(lcm::LogFile& log, const stride::msg::Signer& signer,
                   const stride::robot_state_t& s, std::int64_t stamp, std::int64_t logged) {
  std::vector<unsigned char> bytes(s.getEncodedSize() + stride::msg::kSignatureSize);
  const int n = s.encode(bytes.data(), 0, s.getEncodedSize());
  bytes.resize(
      signer.signAt("STRIDE_STATE", bytes.data(), n, static_cast<int>(bytes.size()), stamp));
  writeBytes(log, "STRIDE_STATE", std::move(bytes), logged);
}

// Issue 44: a recording of an earlier signed session replayed on the bus during a live one, as
// lcm-logger (stamping each event with its wall clock on receipt) logs it. The receivers refused
// the recording as stale; the summary refuses it the same way (the trailer's stamp against the
// logger's clock, the receivers' window), so the session is the live robot's alone: standing at
// the origin, not walking to where the recording's robot stood. A sender 0.3 s ahead is within
// the window and read.
TEST(LogSummary, ARecordingReplayedOnTheBusIsRefusedAsTheReceiversRefuseIt) {
  const std::string path = testing::TempDir() + "/replayed.lcmlog";
  const stride::msg::Key key = stride::msg::makeKey({4, 5, 6});
  const stride::msg::Signer live(key, 7), recorded(key, 8);
  const std::int64_t wall0 = 1'800'000'000'000'000;  // µs on the wall clock (2027)
  {
    lcm::LogFile log(path, "w");
    ASSERT_TRUE(log.good());
    for (int i = 0; i < 200; ++i) {
      const std::int64_t utime = 7000000 + 10000L * i, logged = wall0 + 10000L * i;
      writeSignedAt(log, live, standing(utime), logged + (i % 2 == 0 ? 0 : 300000), logged);
      stride::robot_state_t old = standing(utime);
      old.session = 2;
      old.q[0] = 5.0 + 0.01 * i;  // the recording's robot, elsewhere and walking
      writeSignedAt(log, recorded, old, logged - 30'000'000, logged + 1);
    }
  }
  const Summary r = summarize(path, "");
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(r.json["stale_signed"], 200) << r.json.dump(2);
  EXPECT_EQ(r.json["distance_m"], 0.0);
  EXPECT_EQ(r.json["final_base"][0], 0.0);
  EXPECT_NE(r.output.find("log: 200 signed messages stamped more than 0.5 s from the logger's "
                          "clock refused"),
            std::string::npos)
      << r.output;
}

}  // namespace test_log_summary
