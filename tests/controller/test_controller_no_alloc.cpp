// The controller's tick allocates nothing after start-up (ARCHITECTURE.md §4): decoding the state
// bytes, validating them, shifting the horizon, the solve, the policy and the status messages
// (and the predicted horizon with its footholds), encoding them and handing them to the
// publisher, through fallbacks too.
#include <gtest/gtest.h>
#include <stdlib.h>

#include <optional>

#include <algorithm>
#include <chrono>
#include <string>
#include <thread>
#include <utility>

#include "allocation_counter.hpp"
#include "controller/mpc_node.hpp"
#include "controller_cases.hpp"
#include "messages/signing.hpp"

namespace stride {
namespace test_controller_no_alloc {

using test_support::allocations;

// The test's wall-clock budgets (a tick's deadline, the state's age) are a release build's: the
// sanitizers (tools/test.sh --sanitize) make a tick several times slower, so they scale with it.
// A tick given kTickBudget must not be shed: 40 ms, ten times a humanoid tick's time here, so that
// a loaded host (a CI run beside other builds) that takes the core away for a few ms does not make
// it late (4 ms did: HumanoidTicks shed 5 ticks instead of 3 in a clean-clone CI run).
constexpr int kSlowdown = test_support::kSanitizerSlowdown;
constexpr auto kTickBudget = std::chrono::milliseconds(40 * kSlowdown);

struct Sink : Publisher {
  long bytes = 0;
  void publish(const std::string&, const void*, int size) override { bytes += size; }
};

TEST(ControllerNoAllocation, CounterSeesAllocations) {
  EXPECT_GE(allocations([] {
              std::vector<double> v(100);
              double* volatile data = v.data();  // volatile: clang may drop an unused allocation
              (void)data;
            }),
            1);
}

// With `key_file`, the states come signed and the node checks them and signs what it sends
// (messages/README.md, "Signing"): that allocates nothing either.
void tickNoAllocation(const std::string& robot, int ticks, const std::string& key_file = "") {
  ControllerConfig config = loadControllerConfig(controller_cases::configPath(robot));
  config.max_previous_ticks = 2;
  config.max_state_age *= kSlowdown;
  config.key_file = key_file;
  Sink out;
  MpcNode node(config, out, TimeSource::RealTime);  // stale = arrived too long ago
  std::optional<msg::Signer> signer;
  if (!key_file.empty()) signer.emplace(msg::loadKeyFile(key_file), 5);
  robot_state_t s = controller_cases::standingState(node.mpc().robot(), 1000);
  std::vector<unsigned char> bytes(s.getEncodedSize() + msg::kSignatureSize);
  const auto period = static_cast<std::int64_t>(1e6 / config.rate_hz);
  auto feed = [&](std::int64_t utime) {
    s.utime = utime;
    // A little motion, so that every tick has work to do.
    s.v[2] = 0.01 * std::sin(1e-5 * static_cast<double>(utime));
    int n = s.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
    if (signer)
      n = signer->sign(config.state_channel.c_str(), bytes.data(), n,
                       static_cast<int>(bytes.size()));
    lcm::ReceiveBuffer rbuf{bytes.data(), static_cast<uint32_t>(n), 0};
    node.onState(&rbuf, config.state_channel);
  };
  feed(1000);
  node.tick(Mpc::Clock::time_point::max());  // start-up: builds and solves the problem
  ASSERT_EQ(node.mpc().policy().status, kPolicySolved);
  std::int64_t t = 1000;
  for (int i = 0; i < ticks; ++i) {
    t += period;
    // Every other tick without a preparation (a deadline already passed), so that both paths
    // run: the line search on a prepared iteration, and a whole iteration after the state.
    const bool prepare = i % 2 == 0;
    const long n = allocations([&] {
      node.prepare(prepare ? Mpc::Clock::time_point::max() : Mpc::Clock::now());
      feed(t);
      node.tick(Mpc::Clock::time_point::max());
    });
    EXPECT_EQ(n, 0) << robot << " tick " << i;
    EXPECT_EQ(node.mpc().status().prepared, prepare ? 1 : 0) << robot << " tick " << i;
  }
  EXPECT_EQ(node.mpc().counters().fallbacks, 0);
  EXPECT_EQ(node.mpc().counters().unprepared_solves, ticks / 2);
  // A real-time tick (finite deadline) without its preparation: the previous policy re-sent
  // instead of a whole iteration after the state (overload shedding), and the period prepares.
  node.prepare(Mpc::Clock::now());  // cut: nothing prepared
  t += period;
  EXPECT_EQ(allocations([&] {
              feed(t);
              node.tick(Mpc::Clock::now() + kTickBudget);
            }),
            0);
  EXPECT_EQ(node.mpc().policy().status, kPolicyPrevious);
  EXPECT_EQ(node.mpc().counters().shed_ticks, 1);
  EXPECT_EQ(node.mpc().counters().fallbacks, 0);
  // A preparation cut by its deadline (1 us: a chunk of knots at most), its tick re-sending the
  // previous policy, and the next period's preparation resuming it (or starting again when it
  // no longer serves the next state); its tick uses it.
  const auto tickAfter = [&](Mpc::Clock::time_point prepare_by, bool late) {
    return allocations([&] {
      node.prepare(prepare_by);
      t += period;
      feed(t);
      node.tick(late ? Mpc::Clock::now() : Mpc::Clock::now() + kTickBudget);
    });
  };
  EXPECT_EQ(tickAfter(Mpc::Clock::now() + std::chrono::microseconds(1), false), 0);
  EXPECT_EQ(node.mpc().policy().status, kPolicyPrevious);
  EXPECT_EQ(tickAfter(Mpc::Clock::time_point::max(), false), 0);
  EXPECT_EQ(node.mpc().status().prepared, 1);
  EXPECT_NE(node.mpc().policy().status, kPolicyPrevious);
  // A tick too late for even one rollout: the previous policy re-sent, its preparation kept for
  // the next tick, which uses it.
  EXPECT_EQ(tickAfter(Mpc::Clock::time_point::max(), true), 0);
  EXPECT_EQ(node.mpc().policy().status, kPolicyPrevious);
  EXPECT_EQ(tickAfter(Mpc::Clock::time_point::max(), false), 0);
  EXPECT_EQ(node.mpc().status().prepared, 1);
  EXPECT_NE(node.mpc().policy().status, kPolicyPrevious);
  EXPECT_EQ(node.mpc().counters().shed_ticks, 3);
  // Fallbacks: no new state for longer than max_state_age: the previous policy, then hold.
  std::this_thread::sleep_for(std::chrono::duration<double>(config.max_state_age * 1.5));
  std::vector<int> statuses;
  statuses.reserve(4);
  EXPECT_EQ(allocations([&] {
              for (int i = 0; i < 4; ++i) {
                node.tick(Mpc::Clock::time_point::max());
                statuses.push_back(node.mpc().policy().status);
              }
            }),
            0);
  EXPECT_EQ(statuses,
            (std::vector<int>{kPolicyPrevious, kPolicyPrevious, kPolicyHold, kPolicyHold}));
  EXPECT_GT(out.bytes, 0);
  EXPECT_EQ(node.rejected(), 0);
}

// The horizon goes out with the footholds the gait generator chose, and writing them allocates
// nothing (issue 31): a planner's trot (config/plans/quad_trot_then_stand.yaml: stand 1 s, then
// trot), in stamps mode, a horizon every 0.1 s of stamps. Its size tells how many footholds it
// carries (37 bytes each).
struct HorizonSizes : Publisher {
  explicit HorizonSizes(std::string c) : channel(std::move(c)) {}
  std::string channel;
  int horizons = 0, smallest = 1 << 30, largest = 0;
  void publish(const std::string& c, const void*, int size) override {
    if (c != channel) return;
    ++horizons;
    smallest = std::min(smallest, size);
    largest = std::max(largest, size);
  }
};

TEST(ControllerNoAllocation, HorizonsWithFootholds) {
  ControllerConfig config = loadControllerConfig(controller_cases::configPath("stride_quad"));
  config.gait.plan_file = std::string(STRIDE_CONFIG_DIR) + "/plans/quad_trot_then_stand.yaml";
  HorizonSizes out(config.horizon_channel);
  MpcNode node(config, out, TimeSource::Stamps);
  const Robot& robot = node.mpc().robot();
  robot_state_t s = controller_cases::standingState(robot, 0);
  std::vector<unsigned char> bytes(s.getEncodedSize());
  auto tick = [&](std::int64_t utime) {
    s.utime = utime;
    s.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
    lcm::ReceiveBuffer rbuf{bytes.data(), static_cast<uint32_t>(bytes.size()), 0};
    node.onState(&rbuf, config.state_channel);
    node.tick(Mpc::Clock::time_point::max());
    node.prepare(Mpc::Clock::time_point::max());
  };
  tick(0);  // start-up: builds and solves the problem
  const auto period = static_cast<std::int64_t>(1e6 / config.rate_hz);
  for (std::int64_t t = period; t <= 800000; t += period)
    EXPECT_EQ(allocations([&] { tick(t); }), 0) << "at " << t << " us";
  horizon_t none;
  msg::shape(none, node.mpc().horizonKnots(), robot.model.nq,
             static_cast<int>(robot.contacts.size()));
  const int fewest = (out.smallest - none.getEncodedSize()) / 37;
  const int most = (out.largest - none.getEncodedSize()) / 37;
  EXPECT_GE(out.horizons, 7);
  // Standing until 0.3 s, nothing to land; from 0.4 s the touch-downs from 1.3 s on are within
  // the 1 s horizon: two feet at 1.3 s, two at 1.6 s, ... (at most 4 per foot).
  EXPECT_EQ(fewest, 0);
  EXPECT_GE(most, 2);
  EXPECT_LT(most, node.mpc().horizonFootholds());
}

// Ticks on an elevation map allocate nothing either (issue 31): maps arriving at 10 Hz of stamps
// (decoded, checked, their steppability computed: after the first map of a size, whose decoding
// sizes the message's rows), footholds chosen on them, swing arcs over their cells, and the
// fallback to blind planning on a stale map. A planner's trot towards a 5 cm step.
TEST(ControllerNoAllocation, TicksOnAMap) {
  ControllerConfig config = loadControllerConfig(controller_cases::configPath("stride_quad"));
  config.gait.plan_file = std::string(STRIDE_CONFIG_DIR) + "/plans/quad_trot_then_stand.yaml";
  config.terrain.max_map_age = 0.3;
  Sink out;
  MpcNode node(config, out, TimeSource::Stamps);
  robot_state_t s = controller_cases::standingState(node.mpc().robot(), 0);
  std::vector<unsigned char> bytes(s.getEncodedSize());
  terrain_t map;
  msg::shape(map, 100, 100);
  map.origin_x = map.origin_y = -0.99;
  map.resolution = 0.02;
  for (int r = 0; r < map.rows; ++r)
    for (int c = 0; c < map.cols; ++c) map.height[r][c] = c >= 62 ? 0.05f : 0.0f;
  std::vector<unsigned char> map_bytes(map.getEncodedSize());
  auto send_map = [&](std::int64_t utime) {
    map.utime = utime;
    map.encode(map_bytes.data(), 0, static_cast<int>(map_bytes.size()));
    lcm::ReceiveBuffer rbuf{map_bytes.data(), static_cast<uint32_t>(map_bytes.size()), 0};
    node.onTerrain(&rbuf, config.terrain_channel);
  };
  auto tick = [&](std::int64_t utime) {
    s.utime = utime;
    s.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
    lcm::ReceiveBuffer rbuf{bytes.data(), static_cast<uint32_t>(bytes.size()), 0};
    node.onState(&rbuf, config.state_channel);
    node.tick(Mpc::Clock::time_point::max());
    node.prepare(Mpc::Clock::time_point::max());
  };
  send_map(0);
  tick(0);  // start-up
  const auto period = static_cast<std::int64_t>(1e6 / config.rate_hz);
  for (std::int64_t t = period; t <= 1600000; t += period)
    EXPECT_EQ(allocations([&] {
                if (t % 100000 == 0 && t <= 1200000) send_map(t);  // none after 1.2 s: stale
                tick(t);
              }),
              0)
        << "at " << t << " us";
  const MpcCounters& c = node.mpc().counters();
  EXPECT_EQ(c.maps, 13);
  EXPECT_GT(c.map_ticks, 0);
  EXPECT_GT(c.stale_map_ticks, 0);
  EXPECT_EQ(c.fallbacks, 0);
  EXPECT_FALSE(node.mpc().plannedOnMap());
}

TEST(ControllerNoAllocation, QuadrupedTicks) {
  tickNoAllocation("stride_quad", 30);
}
TEST(ControllerNoAllocation, HumanoidTicks) {
  tickNoAllocation("stride_humanoid", 10);
}
TEST(ControllerNoAllocation, QuadrupedTicksSigned) {
  char dir[] = "/tmp/stride-key-XXXXXX";
  ASSERT_NE(mkdtemp(dir), nullptr);
  const std::string key = std::string(dir) + "/key";
  msg::writeNewKeyFile(key);
  tickNoAllocation("stride_quad", 30, key);
}

}  // namespace test_controller_no_alloc
}  // namespace stride
