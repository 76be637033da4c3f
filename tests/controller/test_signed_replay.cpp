// Issue 44: nobody drives the robot with yesterday's messages. Each attack of the issue, in
// lock-step in one process (tools/drive/closed_loop.hpp: the attacker is Options::on_bus), with a
// key: a recording of a signed session replayed at restarted receivers (the robot alone, a new
// controller), once stale and once within the freshness window (another run: refused by session);
// junk signed with the key, a live sender's id and a timestamp from the future; a sender restarted
// mid-run. The forged-frame flood is real time: tools/faults.sh --forged-flood (ctest
// forged_flood_real_time).
#include <gtest/gtest.h>
#include <stdlib.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "controller_cases.hpp"
#include "drive_cases.hpp"
#include "messages/signing.hpp"
#include "tools/drive/closed_loop.hpp"

namespace stride {
namespace test_signed_replay {

std::string newKeyFile() {
  char dir[] = "/tmp/stride-replay-XXXXXX";
  if (mkdtemp(dir) == nullptr) throw std::runtime_error("mkdtemp");
  const std::string path = std::string(dir) + "/key";
  msg::writeNewKeyFile(path);
  return path;
}

// Stand, trot from 0.5 s, forward at 0.5 m/s from 1 s.
drive::Options trotForward(double duration) {
  return drive_cases::trotForward(duration, 0.5, 1.0);
}

double walked(const drive::Run& r) {
  const Eigen::VectorXd& a = r.samples.front().q;
  const Eigen::VectorXd& b = r.q_end;
  return std::hypot(b[0] - a[0], b[1] - a[1]);
}

// An LCM log's events, each at its time on the recording robot's clock (run time, s).
struct Event {
  double t;
  std::string channel;
  std::vector<std::uint8_t> data;
};
std::vector<Event> readLog(const std::string& path) {
  lcm::LogFile log(path, "r");
  if (!log.good()) throw std::runtime_error("cannot read " + path);
  std::vector<Event> events;
  const std::int64_t base = sim::SimNodeOptions().utime_base;
  while (const lcm::LogEvent* e = log.readNextEvent()) {
    const auto* d = static_cast<const std::uint8_t*>(e->data);
    events.push_back({static_cast<double>(e->timestamp - base) * 1e-6, e->channel,
                      std::vector<std::uint8_t>(d, d + e->datalen)});
  }
  return events;
}

// The attacker: publishes the recording's messages on `channels` at their times (lcm-logplayer's
// pacing, on the new run's clock), along with the live ones.
// `sent` counts them by channel.
using Sent = std::map<std::string, long>;
std::function<void(lcm::LCM&, double)> replay(const std::vector<Event>& events,
                                              std::set<std::string> channels, Sent* sent) {
  auto next = std::make_shared<std::size_t>(0);
  return [&events, channels, next, sent](lcm::LCM& bus, double t) {
    for (; *next < events.size() && events[*next].t <= t + 1e-9; ++*next) {
      const Event& e = events[*next];
      if (channels.count(e.channel) == 0) continue;
      bus.publish(e.channel, e.data.data(), static_cast<unsigned>(e.data.size()));
      ++(*sent)[e.channel];
    }
  };
}

long total(const Sent& sent) {
  long n = 0;
  for (const auto& [channel, count] : sent) n += count;
  return n;
}

class SignedReplay : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    config_ =
        new ControllerConfig(loadControllerConfig(controller_cases::configPath("stride_quad")));
    config_->key_file = newKeyFile();
  }
  static void TearDownTestSuite() {
    delete config_;
    delete events_;
  }
  // The recording, made by the first test that replays it (ctest runs each test in its own
  // process: the others make none): a keyed session trotting forward 2 s (states, commands,
  // policies signed).
  static const std::vector<Event>& recording() {
    if (events_ == nullptr) {
      char dir[] = "/tmp/stride-replay-log-XXXXXX";
      if (mkdtemp(dir) == nullptr) throw std::runtime_error("mkdtemp");
      drive::Options o = trotForward(2.0);
      o.log = std::string(dir) + "/session.lcmlog";
      recorded_walk_ = walked(drive::run(*config_, o));
      std::printf("the recorded session walked %.3f m\n", recorded_walk_);
      events_ = new std::vector<Event>(readLog(o.log));
    }
    return *events_;
  }
  static ControllerConfig* config_;
  static std::vector<Event>* events_;
  static double recorded_walk_;
};
ControllerConfig* SignedReplay::config_ = nullptr;
std::vector<Event>* SignedReplay::events_ = nullptr;
double SignedReplay::recorded_walk_ = 0.0;

// The recording replayed once it is older than the freshness window (any recording of an earlier
// session): at a robot with no controller (it walked 2.82 m on the replay) every policy
// is refused as stale and the robot does not move; at a new controller beside a standing robot,
// every command and state of the recording is refused as stale, the robot does not walk.
TEST_F(SignedReplay, ARecordingIsStaleAtEveryRestartedReceiver) {
  const std::vector<Event>& events = recording();
  ASSERT_GT(recorded_walk_, 0.2);
  std::this_thread::sleep_for(
      std::chrono::microseconds(msg::kFreshnessWindowMicros + 100000));  // the recording ages

  Sent sent;
  const std::string& policy = config_->policy_channel;
  drive::Options alone;
  alone.duration = 2.0;
  alone.controller = false;
  alone.on_bus = replay(events, {policy}, &sent);
  const drive::Run robot = drive::run(*config_, alone);
  std::printf("robot alone: %ld policies replayed, %lld taken, %lld refused (%s), walked %.4f m\n",
              sent[policy], static_cast<long long>(robot.sim.policies),
              static_cast<long long>(robot.sim.policies_unauthenticated),
              robot.sim_auth_text.c_str(), walked(robot));
  EXPECT_GT(sent[policy], 200);
  EXPECT_EQ(robot.sim.policies, 0);
  EXPECT_EQ(robot.sim_stale, sent[policy]) << "every one refused as stale";
  EXPECT_LT(walked(robot), 0.01);

  Sent to_controller;
  drive::Options beside;  // a new controller, its robot standing: no command of its own
  beside.duration = 2.0;
  beside.on_bus =
      replay(events, {config_->state_channel, config_->command_channel, policy}, &to_controller);
  const drive::Run controller = drive::run(*config_, beside);
  std::printf(
      "new controller: %ld messages replayed (%ld commands); %lld commands accepted; %lld "
      "refused as stale, %lld policies refused by the robot; walked %.4f m\n",
      total(to_controller), to_controller[config_->command_channel],
      static_cast<long long>(controller.command_counters.accepted),
      static_cast<long long>(controller.mpc_stale),
      static_cast<long long>(controller.sim.policies_unauthenticated), walked(controller));
  EXPECT_GT(to_controller[config_->command_channel], 100);
  EXPECT_EQ(controller.command_counters.accepted, 0);
  EXPECT_EQ(controller.mpc_stale, total(to_controller)) << "every one refused as stale";
  EXPECT_EQ(controller.sim_stale, to_controller[policy]);
  EXPECT_LT(walked(controller), 0.05);
  EXPECT_FALSE(controller.fell());
}

// The recording replayed within the freshness window (here 60 s wide: another lock-step run
// whose clock also started at 0, or a replay a moment after the recording): every policy is
// refused as made for another run of the robot, every state as another run's, and the robot with
// its own controller does exactly what it does without the replay.
TEST_F(SignedReplay, AnotherRunsMessagesWithinTheWindowAreRefusedBySession) {
  const std::vector<Event>& events = recording();
  ControllerConfig wide = *config_;
  wide.signature_window = 60.0;
  Sent replayed;
  drive::Options alone;
  alone.duration = 2.0;
  alone.controller = false;
  alone.sim.signature_window = 60.0;
  alone.on_bus = replay(events, {config_->policy_channel}, &replayed);
  const drive::Run robot = drive::run(wide, alone);
  const long sent = replayed[config_->policy_channel];
  std::printf(
      "robot alone: %ld policies replayed, %lld taken, %lld of another run; walked %.4f m\n", sent,
      static_cast<long long>(robot.sim.policies),
      static_cast<long long>(robot.sim.policies_other_session), walked(robot));
  EXPECT_GT(sent, 200);
  EXPECT_EQ(robot.sim.policies, 0);
  EXPECT_EQ(robot.sim.policies_other_session + robot.sim.policies_unauthenticated, sent);
  // Those a fast lock-step run delivers over the new senders' budget are refused before hashing.
  EXPECT_GT(robot.sim.policies_other_session, 100);
  EXPECT_LT(walked(robot), 0.01);

  drive::Options own = trotForward(2.0);
  own.sim.signature_window = 60.0;
  const drive::Run clean = drive::run(wide, own);
  Sent both;
  own.on_bus = replay(events, {config_->state_channel, config_->policy_channel}, &both);
  const drive::Run attacked = drive::run(wide, own);
  std::printf(
      "with its controller: %ld replayed; %lld states of another run refused, %lld "
      "policies of another run; walked %.3f m (%.3f m without the replay)\n",
      total(both), static_cast<long long>(attacked.mpc_other_session),
      static_cast<long long>(attacked.sim.policies_other_session), walked(attacked), walked(clean));
  ASSERT_EQ(attacked.samples.size(), clean.samples.size());
  for (std::size_t i = 0; i < clean.samples.size(); ++i)
    ASSERT_EQ(attacked.samples[i].q, clean.samples[i].q) << "t " << clean.samples[i].t;
  EXPECT_GT(attacked.mpc_other_session, 100);
  EXPECT_GT(attacked.sim.policies_other_session, 100);
  EXPECT_EQ(attacked.sim.policies_rival, 0);
  EXPECT_EQ(attacked.sim.source_switches, 0);
}

// One signed junk message with a live sender's id (learnt from the bus) and a timestamp from the
// future (INT64_MAX, an hour ahead) or inside the window (0.3 s ahead, content refused): on the
// old code the first locked the live controller out for the run. Nothing changes on the robot:
// the run is the clean one, bit for bit, a controller restarted mid-run included.
TEST_F(SignedReplay, AJunkMessageFromTheFutureLocksNobodyOut) {
  drive::Options o = trotForward(3.0);
  o.controller_lost_at = 1.8;
  o.controller_back_after = 0.2;
  const drive::Run clean = drive::run(*config_, o);
  const msg::Key key = msg::loadKeyFile(config_->key_file);
  struct Attacker {
    lcm::Subscription* sub = nullptr;
    std::uint32_t live = 0;  // the live controller's sender id (the newest policy's trailer)
    msg::WireClaim claim;    // and its model
    int sent = 0, fired = 0;
    void onPolicy(const lcm::ReceiveBuffer* rbuf, const std::string&) {
      const auto* b = static_cast<const std::uint8_t*>(rbuf->data);
      const int n = static_cast<int>(rbuf->data_size);
      msg::SignatureClaim signature;
      if (!msg::readSignatureClaim(b, n, signature) || !msg::readPolicyClaim(b, n, claim)) return;
      live = signature.sender;
    }
  };
  auto attacker = std::make_shared<Attacker>();
  const std::string channel = config_->policy_channel;
  o.on_bus = [attacker, key, channel](lcm::LCM& bus, double t) {
    if (attacker->sub == nullptr)
      attacker->sub = bus.subscribe(channel, &Attacker::onPolicy, attacker.get());
    if (attacker->live == 0 || attacker->fired >= 2 ||
        t + 1e-9 < (attacker->fired == 0 ? 1.0 : 2.5))
      return;
    ++attacker->fired;
    // A policy of this robot's model, for no run, with NaN gains: junk only a key holder can sign.
    policy_t junk;
    msg::shape(junk, 8, attacker->claim.nq, attacker->claim.nv, 12);
    junk.model_hash = attacker->claim.hash;
    junk.utime = junk.knot0_utime = junk.tick = junk.source_id = junk.session = 0;
    junk.t0 = 0.0;
    junk.dt = 0.01;
    junk.phase = 0;
    junk.status = 0;
    junk.K[0][0] = std::numeric_limits<double>::quiet_NaN();
    std::vector<std::uint8_t> b(junk.getEncodedSize() + msg::kSignatureSize);
    const int n = junk.encode(b.data(), 0, junk.getEncodedSize());
    const msg::Signer forger(key, attacker->live);
    timespec wall{};
    clock_gettime(CLOCK_REALTIME, &wall);
    const std::int64_t now = static_cast<std::int64_t>(wall.tv_sec) * 1000000 + wall.tv_nsec / 1000;
    for (const std::int64_t at : {std::numeric_limits<std::int64_t>::max(),
                                  std::int64_t{now + 3600LL * 1000000}, now + 300000}) {
      const int size = forger.signAt(channel.c_str(), b.data(), n, static_cast<int>(b.size()), at);
      bus.publish(channel, b.data(), static_cast<unsigned>(size));
      ++attacker->sent;
    }
  };
  const drive::Run attacked = drive::run(*config_, o);
  std::printf(
      "%d junk policies with the live controller's id: %lld refused unread (%s), %lld of "
      "another run; walked %.3f m (%.3f m clean)\n",
      attacker->sent, static_cast<long long>(attacked.sim.policies_unauthenticated),
      attacked.sim_auth_text.c_str(), static_cast<long long>(attacked.sim.policies_other_session),
      walked(attacked), walked(clean));
  EXPECT_EQ(attacker->sent, 6);
  ASSERT_EQ(attacked.samples.size(), clean.samples.size());
  for (std::size_t i = 0; i < clean.samples.size(); ++i)
    ASSERT_EQ(attacked.samples[i].q, clean.samples[i].q) << "t " << clean.samples[i].t;
  EXPECT_EQ(attacked.sim.policies_unauthenticated, 4);  // the two far ahead, twice
  EXPECT_EQ(attacked.sim.policies_other_session, 2);    // the one inside the window: its content
  EXPECT_EQ(attacked.sim.stand_downs, clean.sim.stand_downs);
  EXPECT_EQ(attacked.controller_starts, 2);
  EXPECT_GT(walked(attacked), 0.3);
  std::printf("the controller refused %s\n", attacked.mpc_auth_text.c_str());
}

// A legitimate sender restarted mid-run (a new controller, a new robot) is taken at once: no
// refusal of its signatures, and with a key the run is the one without, bit for bit.
TEST_F(SignedReplay, ARestartedSenderIsTakenAtOnce) {
  ControllerConfig plain = *config_;
  plain.key_file.clear();
  for (int which : {0, 1}) {
    drive::Options o = trotForward(3.0);
    if (which == 0) {
      o.controller_lost_at = 1.5;
      o.controller_back_after = 0.1;
    } else {
      o.sim_lost_at = 1.5;
      o.sim_back_after = 0.3;
    }
    const drive::Run keyed = drive::run(*config_, o);
    const drive::Run unkeyed = drive::run(plain, o);
    std::printf(
        "%s restarted: %lld policies refused by the robot, %lld messages by the "
        "controller; walked %.3f m\n",
        which == 0 ? "the controller" : "the robot",
        static_cast<long long>(keyed.sim.policies_unauthenticated),
        static_cast<long long>(keyed.mpc_unauthenticated), walked(keyed));
    EXPECT_EQ(keyed.sim.policies_unauthenticated, 0);
    EXPECT_EQ(keyed.mpc_unauthenticated, 0);
    ASSERT_EQ(keyed.samples.size(), unkeyed.samples.size());
    for (std::size_t i = 0; i < keyed.samples.size(); ++i)
      ASSERT_EQ(keyed.samples[i].q, unkeyed.samples[i].q) << which << " t " << keyed.samples[i].t;
    EXPECT_FALSE(keyed.fell());
  }
}

}  // namespace test_signed_replay
}  // namespace stride
