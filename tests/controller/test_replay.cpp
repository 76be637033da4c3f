// stride-mpc --replay: a logged session through the controller, on the log's own stamps, as fast as
// possible. Two replays of the same log must give bit-identical policies.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <lcm/lcm-cpp.hpp>
#include <limits>

#include "config/model_hash.hpp"
#include "config/robot_config.hpp"
#include "controller_cases.hpp"

namespace stride {
namespace test_replay {

// A 1 kHz session of the quadruped swaying on its feet, with the faults a real log has: a
// repeated stamp and a NaN estimate (both must be rejected, not crash the replay). other_robot:
// the states cut to a floating body alone (nq 7, nv 6), as another robot's log would have them;
// other_hash (when not 0): the states stamped with another model's hash (same sizes).
std::string writeSession(const std::string& path, int states, bool other_robot = false,
                         std::int64_t other_hash = 0) {
  const Robot robot =
      loadRobot(std::string(STRIDE_CONFIG_DIR) + "/robots/stride_quad/stride_quad.yaml");
  lcm::LogFile log(path, "w");
  EXPECT_TRUE(log.good());
  for (int i = 0; i < states; ++i) {
    robot_state_t s = controller_cases::standingState(robot, 5000000 + 1000L * i);
    const double t = 1e-3 * i;
    s.q[2] += 0.005 * std::sin(2 * M_PI * t);
    s.v[2] = 0.005 * 2 * M_PI * std::cos(2 * M_PI * t);
    s.q[7 + 1] += 0.05 * std::sin(4 * M_PI * t);
    if (i == 300) s.q[9] = std::numeric_limits<double>::quiet_NaN();
    if (i == 301) s.utime -= 2000;  // the stamp of state 299, the newest accepted
    if (other_hash != 0) s.model_hash = other_hash;
    if (other_robot) {
      s.nq = 7;
      s.nv = 6;
      s.q.resize(7);
      s.v.resize(6);
    }
    std::vector<unsigned char> bytes(s.getEncodedSize());
    s.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
    lcm::LogEvent e{};
    e.eventnum = i;
    e.timestamp = s.utime;
    e.channel = "STRIDE_STATE";
    e.datalen = static_cast<int32_t>(bytes.size());
    e.data = bytes.data();
    log.writeEvent(&e);
  }
  return path;
}

struct Output {
  std::vector<std::vector<unsigned char>> policies;
  std::vector<policy_t> decoded;
  int statuses = 0;
  mpc_status_t last_status{};
};

Output readOutput(const std::string& path) {
  lcm::LogFile log(path, "r");
  EXPECT_TRUE(log.good()) << path;
  Output out;
  for (const lcm::LogEvent* e = log.readNextEvent(); e != nullptr; e = log.readNextEvent()) {
    const auto* b = static_cast<const unsigned char*>(e->data);
    if (e->channel == "STRIDE_POLICY") {
      out.policies.emplace_back(b, b + e->datalen);
      policy_t p;
      EXPECT_GE(p.decode(e->data, 0, e->datalen), 0);
      out.decoded.push_back(p);
    } else if (e->channel == "STRIDE_STATUS") {
      EXPECT_GE(out.last_status.decode(e->data, 0, e->datalen), 0);
      ++out.statuses;
    }
  }
  return out;
}

TEST(Replay, TwoReplaysGiveBitIdenticalPolicies) {
  const std::string dir = testing::TempDir();
  const std::string session = writeSession(dir + "/stride_session.lcmlog", 1000);
  const std::string config = controller_cases::configPath("stride_quad");
  std::vector<Output> runs;
  for (int run = 0; run < 2; ++run) {
    const std::string out = dir + "/stride_replay_" + std::to_string(run) + ".lcmlog";
    std::remove(out.c_str());
    const std::string cmd = std::string(STRIDE_MPC_BIN) + " --config " + config + " --replay " +
                            session + " --output " + out + " > " + out + ".txt 2>&1";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
    runs.push_back(readOutput(out));
  }
  // 1 s of states at 1 kHz, ticks every 5 ms of log time: 200 ticks.
  EXPECT_EQ(runs[0].policies.size(), 200u);
  EXPECT_EQ(runs[0].statuses, 200);
  EXPECT_EQ(runs[0].last_status.rejected_messages, 2);  // the NaN and the repeated stamp
  EXPECT_EQ(runs[0].last_status.fallbacks, 0);
  EXPECT_EQ(runs[0].last_status.deadline_misses, 0);
  ASSERT_EQ(runs[0].policies.size(), runs[1].policies.size());
  for (size_t i = 0; i < runs[0].policies.size(); ++i)
    ASSERT_EQ(runs[0].policies[i], runs[1].policies[i]) << "policy " << i << " differs";
  // The policies answer the log's stamps, one tick period apart, except where the tick fell on
  // the rejected states (300 and 301): it moves to the next valid state, 5 302 000 µs.
  for (size_t i = 1; i < runs[0].decoded.size(); ++i) {
    const std::int64_t u = runs[0].decoded[i].utime, prev = runs[0].decoded[i - 1].utime;
    if (u == 5302000)
      EXPECT_EQ(u - prev, 7000);
    else if (prev == 5302000)
      EXPECT_EQ(u - prev, 3000);
    else
      EXPECT_EQ(u - prev, 5000) << i;
    EXPECT_EQ(runs[0].decoded[i].status, 0) << i;
  }
}

std::string readText(const std::string& path) {
  std::ifstream f(path);
  return std::string((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
}

std::string hashOf(const Robot& robot) {
  char hex[17];
  msg::formatHash(modelHash(robot), hex);
  return hex;
}

// A log of another robot: every state is rejected, the cause is said once with what the model
// expected and what came, and the replay exits 1 instead of reporting an empty run as a success.
// Another robot's sizes (a floating body alone: nq 7, nv 6) ...
TEST(Replay, ALogOfAnotherRobotIsAnError) {
  const std::string path = writeSession(testing::TempDir() + "/other_robot.lcmlog", 50, true);
  const std::string err = path + ".err";
  const std::string cmd = std::string(STRIDE_MPC_BIN) + " --config " +
                          controller_cases::configPath("stride_quad") + " --replay " + path +
                          " > /dev/null 2> " + err;
  const int rc = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(rc));
  EXPECT_EQ(WEXITSTATUS(rc), 1);
  const std::string text = readText(err);
  const std::string hash =
      hashOf(loadRobot(STRIDE_CONFIG_DIR "/robots/stride_quad/stride_quad.yaml"));
  EXPECT_NE(text.find("stride-mpc: refused a state on 'STRIDE_STATE': expected nq 19, nv 18 "
                      "(stride_quad, hash " +
                      hash + "), got nq 7, nv 6 (hash " + hash + ")\n"),
            std::string::npos)
      << text;
  EXPECT_EQ(text.find("refused a state", text.find("refused a state") + 1), std::string::npos)
      << "one line per cause, not per state:\n"
      << text;
  EXPECT_NE(text.find("the replay accepted none of the 50 states on 'STRIDE_STATE': 50 another "
                      "robot's model (hash or sizes); the model expects nq 19, nv 18 "
                      "(stride_quad, hash " +
                      hash + ")"),
            std::string::npos)
      << text;
}

// ... and another robot of the same sizes: solo12's log replayed into stride_quad's controller
// (nq 19, nv 18 both) is refused by the model hash, not silently accepted.
TEST(Replay, ALogOfAnotherRobotOfTheSameSizesIsAnError) {
  const Robot solo =
      loadRobot(STRIDE_CONFIG_DIR "/robots/solo12/solo12.yaml", {STRIDE_ROBOT_PACKAGES});
  const std::string path =
      writeSession(testing::TempDir() + "/solo12.lcmlog", 50, false, modelHash(solo));
  const std::string err = path + ".err";
  const int rc = std::system((std::string(STRIDE_MPC_BIN) + " --config " +
                              controller_cases::configPath("stride_quad") + " --replay " + path +
                              " > /dev/null 2> " + err)
                                 .c_str());
  ASSERT_TRUE(WIFEXITED(rc));
  EXPECT_EQ(WEXITSTATUS(rc), 1);
  const std::string text = readText(err);
  const std::string ours =
      hashOf(loadRobot(STRIDE_CONFIG_DIR "/robots/stride_quad/stride_quad.yaml"));
  EXPECT_NE(text.find("expected hash " + ours + " (stride_quad, nq 19, nv 18), got hash " +
                      hashOf(solo) + ": the same sizes, another robot or joint order"),
            std::string::npos)
      << text;
}

TEST(Replay, MissingLogIsAClearError) {
  const std::string cmd = std::string(STRIDE_MPC_BIN) + " --config " +
                          controller_cases::configPath("stride_quad") +
                          " --replay /nonexistent/session.lcmlog > /dev/null 2>&1";
  const int rc = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(rc));
  EXPECT_EQ(WEXITSTATUS(rc), 1);
}

}  // namespace test_replay
}  // namespace stride
