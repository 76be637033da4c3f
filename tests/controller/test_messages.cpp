// LCM messages: a memq round trip of every type, and the node's rejection of malformed input.
#include <gtest/gtest.h>

#include <stdlib.h>
#include <time.h>
#include <chrono>
#include <thread>

#include <algorithm>
#include <cmath>
#include <lcm/lcm-cpp.hpp>
#include <limits>

#include "controller/mpc_node.hpp"
#include "controller_cases.hpp"
#include "messages/signing.hpp"

namespace stride {
namespace test_messages {

using controller_cases::configPath;
using controller_cases::standingState;

// Receives one message of type T on a channel.
template <typename T>
struct Catcher {
  T msg;
  int count = 0;
  void on(const lcm::ReceiveBuffer*, const std::string&, const T* m) {
    msg = *m;
    ++count;
  }
};

template <typename T>
T roundTrip(lcm::LCM& lcm, const std::string& channel, const T& sent) {
  Catcher<T> c;
  lcm::Subscription* sub = lcm.subscribe(channel, &Catcher<T>::on, &c);
  EXPECT_EQ(lcm.publish(channel, &sent), 0);
  EXPECT_GT(lcm.handleTimeout(1000), 0);
  lcm.unsubscribe(sub);
  EXPECT_EQ(c.count, 1);
  return c.msg;
}

TEST(Messages, MemqRoundTripOfEveryType) {
  lcm::LCM lcm("memq://");  // in process: no network at all
  ASSERT_TRUE(lcm.good());

  robot_state_t s;
  msg::shape(s, 19, 18, 4);
  s.utime = 123456789;
  s.model_hash = -7;
  for (int i = 0; i < 19; ++i) s.q[i] = 0.1 * i;
  for (int i = 0; i < 18; ++i) s.v[i] = -0.2 * i;
  s.contact = {1, 0, 1, 1};
  const robot_state_t s2 = roundTrip(lcm, "STATE", s);
  EXPECT_EQ(s2.utime, s.utime);
  EXPECT_EQ(s2.model_hash, s.model_hash);
  EXPECT_EQ(s2.q, s.q);
  EXPECT_EQ(s2.v, s.v);
  EXPECT_EQ(s2.contact, s.contact);

  policy_t p;
  msg::shape(p, 3, 19, 18, 12);
  p.utime = 42;
  p.model_hash = 1234567890123;
  p.tick = 7;
  p.t0 = 1.25;
  p.dt = 0.01;
  p.phase = 3;
  p.status = 1;
  for (int k = 0; k < 3; ++k) {
    for (int i = 0; i < p.nx; ++i) p.x_ref[k][i] = k + 0.01 * i;
    for (int i = 0; i < p.nu; ++i) p.u_ff[k][i] = -k - 0.02 * i;
    for (int i = 0; i < p.nk; ++i) p.K[k][i] = std::sin(k * 1000 + i);
  }
  const policy_t p2 = roundTrip(lcm, "POLICY", p);
  EXPECT_EQ(p2.x_ref, p.x_ref);
  EXPECT_EQ(p2.u_ff, p.u_ff);
  EXPECT_EQ(p2.K, p.K);
  EXPECT_EQ(p2.t0, p.t0);
  EXPECT_EQ(p2.status, p.status);
  EXPECT_EQ(p2.model_hash, p.model_hash);
  EXPECT_EQ(msg::policyWireSize(3, 19, 18, 12), p.getEncodedSize());
  EXPECT_EQ(msg::stateWireSize(19, 18, 4), s.getEncodedSize());

  mpc_status_t st{};
  st.utime = 5;
  st.tick = 6;
  st.solve_ms = 1.5;
  st.iterations = 1;
  st.cost = 12.5;
  st.deadline_misses = 2;
  st.rejected_messages = 9;
  st.policy_status = 2;
  const mpc_status_t st2 = roundTrip(lcm, "STATUS", st);
  EXPECT_EQ(st2.solve_ms, st.solve_ms);
  EXPECT_EQ(st2.cost, st.cost);
  EXPECT_EQ(st2.deadline_misses, st.deadline_misses);
  EXPECT_EQ(st2.rejected_messages, st.rejected_messages);
  EXPECT_EQ(st2.policy_status, st.policy_status);

  contact_plan_t plan;
  plan.utime = 1000;
  plan.cyclic = 1;
  plan.ncontacts = 2;
  plan.contacts = {"L_sole", "R_sole"};
  plan.nphases = 2;
  plan.duration = {0.2, 0.6};
  plan.closed = {{1, 1}, {0, 1}};
  const contact_plan_t plan2 = roundTrip(lcm, "PLAN", plan);
  EXPECT_EQ(plan2.contacts, plan.contacts);
  EXPECT_EQ(plan2.duration, plan.duration);
  EXPECT_EQ(plan2.closed, plan.closed);
  std::vector<unsigned char> bytes(plan.getEncodedSize());
  plan.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  EXPECT_EQ(msg::checkPlanWire(bytes.data(), static_cast<int>(bytes.size()), 16, 100),
            msg::Reject::None);
  EXPECT_EQ(msg::checkPlan(plan2), msg::Reject::None);
}

// Records what the node publishes.
struct Recorder : Publisher {
  int policies = 0, statuses = 0, models = 0, horizons = 0;
  robot_model_t model;
  horizon_t horizon;
  void publish(const std::string& channel, const void* data, int size) override {
    if (channel == "STRIDE_HORIZON") horizons += horizon.decode(data, 0, size) == size;
    if (channel == "STRIDE_POLICY") ++policies;
    if (channel == "STRIDE_STATUS") ++statuses;
    if (channel == "STRIDE_MODEL") models += model.decode(data, 0, size) == size;
  }
};

class NodeInput : public testing::Test {
 protected:
  NodeInput()
      : config_(loadControllerConfig(configPath("stride_quad"))),
        node_(config_, out_, TimeSource::Stamps) {}

  void feed(const void* data, int size) {
    lcm::ReceiveBuffer rbuf{const_cast<void*>(data), static_cast<uint32_t>(size), 0};
    node_.onState(&rbuf, "STRIDE_STATE");
  }
  void feed(const robot_state_t& m) {
    std::vector<unsigned char> b(m.getEncodedSize());
    m.encode(b.data(), 0, static_cast<int>(b.size()));
    feed(b.data(), static_cast<int>(b.size()));
  }
  robot_state_t good(std::int64_t utime) { return standingState(node_.mpc().robot(), utime); }

  ControllerConfig config_;
  Recorder out_;
  MpcNode node_;
};

TEST_F(NodeInput, RejectsAndCountsMalformedStates) {
  using msg::Reject;
  feed(good(1000));
  EXPECT_EQ(node_.acceptedStates(), 1);
  EXPECT_EQ(node_.rejected(), 0);

  robot_state_t m = good(2000);
  m.q[8] = std::numeric_limits<double>::quiet_NaN();
  feed(m);
  EXPECT_EQ(node_.rejected(Reject::NonFinite), 1);
  m = good(2000);
  m.v[3] = std::numeric_limits<double>::infinity();
  feed(m);
  EXPECT_EQ(node_.rejected(Reject::NonFinite), 2);

  m = good(2000);
  m.q[6] = 0.9;  // |quaternion| = 0.9
  feed(m);
  EXPECT_EQ(node_.rejected(Reject::NotUnitQuaternion), 1);

  // Another model: another robot's sizes, or the same sizes with another model hash (another
  // joint order or robot). Each cause is described once, with what was expected and what came.
  robot_state_t other;
  msg::shape(other, 29, 28, 0);
  other.q[6] = 1.0;
  other.utime = 2000;
  other.model_hash = 42;
  feed(other);
  feed(other);
  EXPECT_EQ(node_.rejected(Reject::WrongModel), 2);
  ASSERT_EQ(node_.mismatchCount(), 1);
  EXPECT_EQ(node_.mismatch(0).count, 2);
  char ours[17];
  msg::formatHash(node_.wireModel().hash, ours);
  EXPECT_EQ(std::string(node_.mismatch(0).text.data()),
            "expected nq 19, nv 18 (stride_quad, hash " + std::string(ours) +
                "), got nq 29, nv 28 (hash 000000000000002a)");
  m = good(2000);
  m.model_hash ^= 1;  // same sizes, another layout
  feed(m);
  EXPECT_EQ(node_.rejected(Reject::WrongModel), 3);
  ASSERT_EQ(node_.mismatchCount(), 2);
  EXPECT_NE(std::string(node_.mismatch(1).text.data())
                .find("expected hash " + std::string(ours) + " (stride_quad, nq 19, nv 18), got"),
            std::string::npos);
  // Counts that do not match the bytes.
  m = good(2000);
  std::vector<unsigned char> b(m.getEncodedSize());
  m.encode(b.data(), 0, static_cast<int>(b.size()));
  std::vector<unsigned char> huge = b;
  huge[32] = 0x7f;  // nq = 2^31 - ...: must never reach the decoder
  feed(huge.data(), static_cast<int>(huge.size()));
  EXPECT_EQ(node_.rejected(Reject::WrongModel), 4);
  huge = b;
  huge[b.size() - 4 - 1] = 0x7f;  // the contact count (4 bytes before the 0 flags) = 2^31 - ...
  huge[b.size() - 4] = 0x7f;
  feed(huge.data(), static_cast<int>(huge.size()));
  EXPECT_EQ(node_.rejected(Reject::WrongSize), 1);
  feed(b.data(), static_cast<int>(b.size()) - 3);  // truncated inside the contact count
  EXPECT_EQ(node_.rejected(Reject::Undecodable), 1);
  feed(b.data(), 10);
  EXPECT_EQ(node_.rejected(Reject::Undecodable), 2);
  std::vector<unsigned char> wrong_hash = b;
  wrong_hash[0] ^= 0xff;
  feed(wrong_hash.data(), static_cast<int>(wrong_hash.size()));
  EXPECT_EQ(node_.rejected(Reject::Undecodable), 3);
  std::vector<unsigned char> longer = b;
  longer.push_back(0);  // a byte more than the counts imply
  feed(longer.data(), static_cast<int>(longer.size()));
  EXPECT_EQ(node_.rejected(Reject::WrongSize), 2);

  // Stamps: equal or older than the newest accepted state are out of order.
  feed(good(1000));
  feed(good(500));
  EXPECT_EQ(node_.rejected(Reject::OutOfOrder), 2);
  m = good(3000);
  m.contact = {1, 2};
  m.ncontacts = 2;
  feed(m);
  EXPECT_EQ(node_.rejected(Reject::BadField), 1);

  EXPECT_EQ(node_.acceptedStates(), 1);
  EXPECT_EQ(node_.rejected(), 15);
  feed(good(3000));
  EXPECT_EQ(node_.acceptedStates(), 2);

  // The status message carries the counts and the latest model mismatch.
  node_.tick(Mpc::Clock::time_point::max());
  EXPECT_EQ(node_.mpc().status().rejected_messages, 15);
  EXPECT_EQ(node_.mpc().status().wrong_model, 4);
  EXPECT_EQ(node_.mpc().status().wrong_model_cause, std::string(node_.mismatch(2).text.data()));
  EXPECT_EQ(out_.policies, 1);
  EXPECT_EQ(out_.statuses, 1);
}

// A state's contact flags are bounded by the contact limit (solver/contact/contact_set.hpp), the
// one number the solver, the wire's masks and the receivers share.
TEST_F(NodeInput, ContactFlagsUpToTheContactLimit) {
  static_assert(kMaxContacts <= msg::kContactMaskBits);
  robot_state_t m = good(1000);
  m.ncontacts = kMaxContacts;
  m.contact.assign(kMaxContacts, 1);
  feed(m);
  EXPECT_EQ(node_.acceptedStates(), 1);
  m = good(2000);
  m.ncontacts = kMaxContacts + 1;
  m.contact.assign(kMaxContacts + 1, 1);
  feed(m);
  EXPECT_EQ(node_.rejected(msg::Reject::WrongSize), 1);
  EXPECT_EQ(node_.acceptedStates(), 1);
}

// A standing state of the node's robot stamped `utime`, as LCM hands it over: received at
// recv_utime (wall clock, µs; 0: unknown, taken as now).
void feedState(MpcNode& node, std::int64_t utime, std::int64_t recv_utime = 0) {
  robot_state_t m = standingState(node.mpc().robot(), utime);
  std::vector<unsigned char> b(m.getEncodedSize());
  m.encode(b.data(), 0, static_cast<int>(b.size()));
  lcm::ReceiveBuffer rbuf{b.data(), static_cast<uint32_t>(b.size()), recv_utime};
  node.onState(&rbuf, "STRIDE_STATE");
}

// Real time: a stamp that jumps far ahead of the time that passed is refused (else every later,
// correct estimate would be "out of order" and the controller locked out).
TEST(NodeRealTime, StampJumpingAheadIsRejected) {
  const ControllerConfig config = loadControllerConfig(configPath("stride_quad"));
  Recorder out;
  MpcNode node(config, out, TimeSource::RealTime);
  auto feed = [&](std::int64_t utime) { feedState(node, utime); };
  feed(1000000);
  feed(1001000);
  feed(1000000000000);  // 11 days later, a few microseconds after the last one arrived
  EXPECT_EQ(node.rejected(msg::Reject::BadField), 1);
  feed(1002000);
  EXPECT_EQ(node.acceptedStates(), 3);
}

// Issue 33's lock-out, deterministic: a controller started (or woken) while the robot runs finds
// a backlog in its queue. Taken at the time the tick drained it, the newest of the backlog looked
// fresh, and the next fresh state then "led" the clock by the backlog's age: refused, and every
// later one with it, for good. Arrival is when LCM received the message (recv_utime).
TEST(NodeRealTime, ABacklogDoesNotLockTheControllerOut) {
  const ControllerConfig config = loadControllerConfig(configPath("stride_quad"));
  Recorder out;
  MpcNode node(config, out, TimeSource::RealTime);
  timespec ts;
  clock_gettime(CLOCK_REALTIME, &ts);
  const std::int64_t wall = static_cast<std::int64_t>(ts.tv_sec) * 1000000 + ts.tv_nsec / 1000;
  auto feed = [&](std::int64_t utime, std::int64_t recv_utime) {
    feedState(node, utime, recv_utime);
  };
  // 1000 states of a 1 kHz robot received 2.5 .. 1.5 s ago (the queue's capacity), the next
  // 1.5 s dropped by the full queue, then the robot's fresh states.
  const std::int64_t t0 = 5000000;
  for (int i = 0; i < 1000; ++i) feed(t0 + 1000 * i, wall - 2500000 + 1000 * i);
  for (int i = 0; i < 100; ++i) feed(t0 + 2500000 + 1000 * i, wall + 1000 * i);
  EXPECT_EQ(node.rejected(), 0);
  EXPECT_EQ(node.acceptedStates(), 1100);
  EXPECT_EQ(node.clockRebasesAhead(), 0);
}

// A lead that persists is the robot's clock (a clock step; or no arrival time to tell a backlog
// by): refused for 0.2 s and 20 states, then taken, said and counted, never refused for good.
TEST(NodeRealTime, AStampLeadThatPersistsIsAClockOffset) {
  const ControllerConfig config = loadControllerConfig(configPath("stride_quad"));
  Recorder out;
  MpcNode node(config, out, TimeSource::RealTime);
  auto feed = [&](std::int64_t utime) { feedState(node, utime); };
  // The plan's time goes on from the first state's arrival (the start-up solve's time included).
  const auto first = std::chrono::steady_clock::now();
  feed(1000000);
  node.tick(Mpc::Clock::now() + std::chrono::seconds(10));
  const double plan_time = node.mpc().status().plan_time;
  // The robot's clock steps 30 s ahead; its states keep coming every 10 ms.
  const auto start = std::chrono::steady_clock::now();
  std::int64_t stamp = 31000000;
  while (node.clockRebasesAhead() == 0 &&
         std::chrono::steady_clock::now() - start < std::chrono::seconds(2)) {
    feed(stamp += 10000);
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  const double waited =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(node.clockRebasesAhead(), 1);
  EXPECT_GE(node.rejected(msg::Reject::BadField), 19);
  EXPECT_GE(waited, 0.2);
  EXPECT_LT(waited, 1.0);
  EXPECT_EQ(node.acceptedStates(), 2);
  for (int i = 0; i < 10; ++i) feed(stamp += 10000);
  EXPECT_EQ(node.acceptedStates(), 12) << "the new clock's states are taken";
  // The plan's time goes on from where it was, not 30 s later.
  node.tick(Mpc::Clock::now() + std::chrono::seconds(10));
  const double since_first = std::chrono::duration<double>(start - first).count() + waited;
  EXPECT_NEAR(node.mpc().status().plan_time, plan_time + since_first + 0.1, 0.1);
}

// Lock-step: a new robot whose clock started again (stamps back to 0). Out of order for 20 states,
// then taken as the new robot's clock; the ticks go on on its stamps.
TEST(NodeStamps, StampsThatStartAgainAreANewRobot) {
  const ControllerConfig config = loadControllerConfig(configPath("stride_quad"));
  Recorder out;
  MpcNode node(config, out, TimeSource::Stamps);
  auto feed = [&](std::int64_t utime) {
    feedState(node, utime);
    if (node.tickDue()) node.tick(Mpc::Clock::time_point::max());
  };
  for (std::int64_t t = 5000000; t <= 6000000; t += 5000) feed(t);
  const int policies = out.policies;
  for (std::int64_t t = 0; t < 19 * 5000; t += 5000) feed(t);
  EXPECT_EQ(out.policies, policies) << "19 states are not yet a new robot";
  EXPECT_EQ(node.clockRebasesBack(), 0);
  for (std::int64_t t = 19 * 5000; t <= 200000; t += 5000) feed(t);
  EXPECT_EQ(node.clockRebasesBack(), 1);
  EXPECT_EQ(node.rejected(msg::Reject::OutOfOrder), 19);
  EXPECT_GE(out.policies, policies + 20) << "a tick per state of the new robot";
  EXPECT_NEAR(node.mpc().status().plan_time, 1.0 + 0.2 - 19 * 0.005, 0.02);
}

// The wire contract goes out at the first tick and then once a second of the controller's clock.
TEST_F(NodeInput, PublishesTheRobotModelAtStartAndAt1Hz) {
  for (int i = 0; i <= 250; ++i) {  // 2.5 s of 100 Hz ticks on the states' stamps
    feed(good(1000000 + 10000L * i));
    node_.tick(Mpc::Clock::time_point::max());
  }
  EXPECT_EQ(out_.models, 3);
  const robot_model_t& m = out_.model;
  const Robot& robot = node_.mpc().robot();
  EXPECT_EQ(m.robot, "stride_quad");
  EXPECT_EQ(m.model_hash, modelHash(robot));
  EXPECT_EQ(m.model_hash, node_.mpc().policy().model_hash);
  EXPECT_EQ(m.nq, 19);
  EXPECT_EQ(m.nv, 18);
  EXPECT_EQ(m.nu, 12);
  ASSERT_EQ(m.njoints, 13);
  EXPECT_EQ(m.joint_types[0], "free-flyer");
  for (int i = 1; i < m.njoints; ++i) {  // wire order is the model's joint order
    const Joint& j = robot.model.joints[i + 1];
    EXPECT_EQ(m.joint_names[i], j.name);
    EXPECT_EQ(m.joint_types[i], "revolute");
    EXPECT_EQ(m.joint_idx_q[i], j.idx_q);
    EXPECT_EQ(m.joint_idx_v[i], j.idx_v);
  }
  ASSERT_EQ(m.ncontacts, 4);
  for (int c = 0; c < 4; ++c) EXPECT_EQ(m.contact_frames[c], robot.contacts[c].frame);
}

// For viewers: the whole predicted horizon at lcm.horizon_rate_hz (10 Hz), after ticks that
// solved; standing, every foot carries its share of the weight at knot 0.
TEST_F(NodeInput, PublishesTheHorizonAt10Hz) {
  ASSERT_EQ(config_.horizon_rate_hz, 10.0);
  for (int i = 0; i < 100; ++i) {  // 1 s of 100 Hz ticks
    feed(good(1000000 + 10000L * i));
    node_.tick(Mpc::Clock::time_point::max());
    node_.prepare(Mpc::Clock::time_point::max());
  }
  EXPECT_GE(out_.horizons, 8);  // a tick whose step was rejected skips its turn
  EXPECT_LE(out_.horizons, 10);
  const horizon_t& h = out_.horizon;
  const Robot& robot = node_.mpc().robot();
  EXPECT_EQ(h.model_hash, modelHash(robot));
  ASSERT_EQ(h.knots, node_.mpc().horizonKnots());
  ASSERT_EQ(h.ncontacts, 4);
  EXPECT_EQ(h.t[0], 0.0);  // knot 0 is the state
  EXPECT_NEAR(h.t[h.knots - 1], 1.0 - config_.locomotion.grid.back().dt, 0.02);  // a 1 s horizon
  for (int k = 1; k < h.knots; ++k) EXPECT_GE(h.t[k], h.t[k - 1]) << k;
  EXPECT_NEAR(h.q[0][2], robot.default_q[2], 0.02);
  EXPECT_EQ(h.contact_mask[0], 0xf);
  double fz = 0.0;
  for (int c = 0; c < 4; ++c) {
    EXPECT_GT(h.force[0][3 * c + 2], 0.0) << c;
    fz += h.force[0][3 * c + 2];
  }
  EXPECT_NEAR(fz, robot.model.totalMass() * 9.81, 0.1 * robot.model.totalMass() * 9.81);
  EXPECT_EQ(h.nfootholds, 0);  // standing: no touch-down planned (test_mpc.cpp: a trot's)
}

// The controller watches its policy channel: its own policies come back and count for nothing,
// another controller's are a rival (counted, in the status), bytes of another type are nobody's.
TEST_F(NodeInput, SeesARivalControllersPolicies) {
  auto feedPolicy = [&](const std::vector<unsigned char>& b) {
    lcm::ReceiveBuffer rbuf{const_cast<unsigned char*>(b.data()), static_cast<uint32_t>(b.size()),
                            0};
    node_.onPolicy(&rbuf, "STRIDE_POLICY");
  };
  policy_t p = node_.mpc().policy();
  std::vector<unsigned char> own(p.getEncodedSize());
  p.encode(own.data(), 0, static_cast<int>(own.size()));
  feedPolicy(own);
  EXPECT_EQ(node_.rivalPolicies(), 0);
  std::vector<unsigned char> garbage(own.size(), 0x5a);
  feedPolicy(garbage);
  EXPECT_EQ(node_.rivalPolicies(), 0);
  p.source_id = node_.sourceId() + 1;
  std::vector<unsigned char> rival(p.getEncodedSize());
  p.encode(rival.data(), 0, static_cast<int>(rival.size()));
  testing::internal::CaptureStderr();
  feedPolicy(rival);
  feedPolicy(rival);
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_EQ(node_.rivalPolicies(), 2);
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;  // said once per rival
  EXPECT_NE(err.find("another controller"), std::string::npos) << err;
  feed(good(1000));
  node_.tick(Mpc::Clock::time_point::max());
  EXPECT_EQ(node_.mpc().status().rival_policies, 2);
  EXPECT_EQ(node_.mpc().status().source_id, node_.sourceId());
}

// A key file of its own in a fresh temporary directory.
std::string newKeyFile() {
  char dir[] = "/tmp/stride-key-XXXXXX";
  EXPECT_NE(mkdtemp(dir), nullptr);
  const std::string path = std::string(dir) + "/key";
  msg::writeNewKeyFile(path);
  return path;
}

// Issue 33, authenticated messages: a controller with a key takes only states, commands, plans
// and maps signed with it. Unsigned, forged, replayed and another key's are refused, counted by
// reason (and as Reject::Unauthenticated), the first of each said once; what it publishes is
// signed (its policies verify with the key, and are not taken as a rival's).
// Issue 44: a robot whose clock is off by more than the freshness window (2 s behind, 2 s ahead
// of the controller's host) is refused, counted as stale or from the future, and said once with
// the offset; within the window it is taken. A junk state from the future signed with the key and
// the robot's sender id locks nobody out: the robot's next state is taken. A state of another
// robot run is refused while the run followed is alive (Reject::OtherSession), said once.
TEST(NodeSigned, AClockOffsetBeyondTheWindowIsRefusedAndSaid) {
  ControllerConfig config = loadControllerConfig(configPath("stride_quad"));
  config.key_file = newKeyFile();
  const msg::Key key = msg::loadKeyFile(config.key_file);
  struct Sink : Publisher {
    void publish(const std::string&, const void*, int) override {}
  } out;
  MpcNode node(config, out, TimeSource::Stamps);
  const msg::Signer robot(key, 7);
  timespec wall{};
  clock_gettime(CLOCK_REALTIME, &wall);
  const std::int64_t now = static_cast<std::int64_t>(wall.tv_sec) * 1000000 + wall.tv_nsec / 1000;
  const auto feed = [&](robot_state_t m, std::int64_t signed_at) {
    std::vector<std::uint8_t> b(m.getEncodedSize() + msg::kSignatureSize);
    const int n = m.encode(b.data(), 0, m.getEncodedSize());
    b.resize(robot.signAt("STRIDE_STATE", b.data(), n, static_cast<int>(b.size()), signed_at));
    // Arrived at `now` on this host's clock (LCM's recv_utime).
    lcm::ReceiveBuffer rbuf{b.data(), static_cast<uint32_t>(b.size()), now};
    node.onState(&rbuf, "STRIDE_STATE");
  };
  const auto state = [&](std::int64_t utime, std::int64_t session) {
    robot_state_t m = standingState(node.mpc().robot(), utime);
    m.session = session;
    return m;
  };
  testing::internal::CaptureStderr();
  feed(state(1000, 5), now - 2000000);
  feed(state(2000, 5), now - 2000000 + 1);
  feed(state(3000, 5), now + 2000000);
  EXPECT_EQ(node.acceptedStates(), 0);
  EXPECT_EQ(node.auth().refused(msg::Verdict::Stale), 2);
  EXPECT_EQ(node.auth().refused(msg::Verdict::Future), 1);
  // The robot's clock fixed (within the window): taken.
  feed(state(4000, 5), now - 400000);
  EXPECT_EQ(node.acceptedStates(), 1);
  // Junk with the key and the robot's id, stamped an hour ahead and 0.3 s ahead (its content
  // refused: not a unit quaternion): neither is remembered, the robot's next state is taken.
  robot_state_t junk = state(5000, 5);
  junk.q[3] = 2.0;
  feed(junk, now + 3600LL * 1000000);
  feed(junk, now + 300000);
  feed(state(6000, 5), now - 300000);
  EXPECT_EQ(node.acceptedStates(), 2);
  // Another run's state while this one is alive.
  feed(state(7000, 6), now - 200000);
  feed(state(8000, 5), now - 100000);
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_EQ(node.acceptedStates(), 3);
  EXPECT_EQ(node.rejected(msg::Reject::OtherSession), 1);
  EXPECT_EQ(node.auth().refused(msg::Verdict::Future), 2);
  EXPECT_NE(err.find("2.000 s behind this host's clock"), std::string::npos) << err;
  EXPECT_NE(err.find("2.000 s ahead of this host's clock"), std::string::npos) << err;
  EXPECT_NE(err.find("chrony or PTP"), std::string::npos) << err;
  EXPECT_NE(err.find("another run of the robot"), std::string::npos) << err;
  // Stale and future said once each, the refused junk content is not a signature's refusal, the
  // other run once.
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 3) << err;
}

TEST(NodeSigned, RefusesWhatIsNotSignedWithItsKey) {
  ControllerConfig config = loadControllerConfig(configPath("stride_quad"));
  config.key_file = newKeyFile();
  const msg::Key key = msg::loadKeyFile(config.key_file);
  const msg::Key other = msg::loadKeyFile(newKeyFile());
  struct Signed : Publisher {
    std::vector<std::uint8_t> policy;
    void publish(const std::string& channel, const void* data, int size) override {
      if (channel == "STRIDE_POLICY")
        policy.assign(static_cast<const std::uint8_t*>(data),
                      static_cast<const std::uint8_t*>(data) + size);
    }
  } out;
  MpcNode node(config, out, TimeSource::Stamps);
  msg::Signer robot(key, 7), impostor(other, 7);
  const auto bytes = [&](const robot_state_t& m, msg::Signer* signer) {
    std::vector<std::uint8_t> b(m.getEncodedSize() + msg::kSignatureSize);
    const int n = m.encode(b.data(), 0, m.getEncodedSize());
    b.resize(signer ? signer->sign("STRIDE_STATE", b.data(), n, static_cast<int>(b.size())) : n);
    return b;
  };
  const auto feed = [&](std::vector<std::uint8_t> b) {
    lcm::ReceiveBuffer rbuf{b.data(), static_cast<uint32_t>(b.size()), 0};
    node.onState(&rbuf, "STRIDE_STATE");
  };
  const auto state = [&](std::int64_t utime) { return standingState(node.mpc().robot(), utime); };
  testing::internal::CaptureStderr();
  feed(bytes(state(1000), &robot));
  EXPECT_EQ(node.acceptedStates(), 1);
  feed(bytes(state(2000), nullptr));  // unsigned
  feed(bytes(state(3000), nullptr));
  feed(bytes(state(4000), &impostor));  // another key
  std::vector<std::uint8_t> forged = bytes(state(5000), &robot);
  forged[20] ^= 1;  // altered on the way (the stamp's bytes)
  feed(forged);
  const std::vector<std::uint8_t> recorded = bytes(state(6000), &robot);
  feed(recorded);
  feed(recorded);  // replayed
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_EQ(node.acceptedStates(), 2);
  EXPECT_EQ(node.auth().refused(msg::Verdict::Unsigned), 2);
  EXPECT_EQ(node.auth().refused(msg::Verdict::WrongKey), 1);
  EXPECT_EQ(node.auth().refused(msg::Verdict::Forged), 1);
  EXPECT_EQ(node.auth().refused(msg::Verdict::Replayed), 1);
  EXPECT_EQ(node.rejected(msg::Reject::Unauthenticated), 5);
  for (const char* said : {"unsigned", "another key", "forged", "replayed"})
    EXPECT_NE(err.find(said), std::string::npos) << said << " in: " << err;
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 4) << "the first of each, once: " << err;

  // Commands: unsigned, another key's, forged and replayed ones change nothing; a signed one is
  // taken.
  command_t c{};
  c.utime = 7000;
  c.gait = "trot";
  c.vx = 0.3;
  const auto commandBytes = [&](msg::Signer* signer) {
    std::vector<std::uint8_t> b(c.getEncodedSize() + msg::kSignatureSize);
    const int n = c.encode(b.data(), 0, c.getEncodedSize());
    b.resize(signer ? signer->sign("STRIDE_COMMAND", b.data(), n, static_cast<int>(b.size())) : n);
    return b;
  };
  const auto sendCommand = [&](std::vector<std::uint8_t> b) {
    lcm::ReceiveBuffer rbuf{b.data(), static_cast<uint32_t>(b.size()), 0};
    node.onCommand(&rbuf, "STRIDE_COMMAND");
  };
  msg::Signer teleop(key, 9), other_teleop(other, 9);
  testing::internal::CaptureStderr();
  sendCommand(commandBytes(nullptr));
  sendCommand(commandBytes(&other_teleop));
  std::vector<std::uint8_t> forged_command = commandBytes(&teleop);
  forged_command[30] ^= 0x10;  // vx changed on the way
  sendCommand(forged_command);
  EXPECT_EQ(node.commands().counters().accepted, 0);
  c.utime = 8000;
  const std::vector<std::uint8_t> command = commandBytes(&teleop);
  sendCommand(command);
  EXPECT_EQ(node.commands().counters().accepted, 1);
  sendCommand(command);  // replayed
  const std::string command_err = testing::internal::GetCapturedStderr();
  EXPECT_EQ(node.commands().counters().accepted, 1);
  EXPECT_EQ(node.auth().refused(msg::Verdict::Unsigned), 3);
  EXPECT_EQ(node.auth().refused(msg::Verdict::WrongKey), 2);
  EXPECT_EQ(node.auth().refused(msg::Verdict::Forged), 2);
  EXPECT_EQ(node.auth().refused(msg::Verdict::Replayed), 2);
  EXPECT_EQ(node.commandsMalformed(), 4);
  EXPECT_EQ(std::count(command_err.begin(), command_err.end(), '\n'), 4)
      << "the command channel's first of each, once: " << command_err;

  // Its policy goes out signed; it verifies with the key, and comes back as its own, not a rival's.
  feed(bytes(state(9000), &robot));
  node.tick(Mpc::Clock::time_point::max());
  ASSERT_FALSE(out.policy.empty());
  msg::Verifier robot_side(key);
  int payload = 0;
  timespec wall{};
  clock_gettime(CLOCK_REALTIME, &wall);
  EXPECT_EQ(robot_side.check(
                "STRIDE_POLICY", out.policy.data(), static_cast<int>(out.policy.size()),
                static_cast<std::int64_t>(wall.tv_sec) * 1000000 + wall.tv_nsec / 1000, payload),
            msg::Verdict::Ok);
  lcm::ReceiveBuffer own{out.policy.data(), static_cast<uint32_t>(out.policy.size()), 0};
  node.onPolicy(&own, "STRIDE_POLICY");
  EXPECT_EQ(node.rivalPolicies(), 0);
  // A rival without the key: refused unread, not a rival.
  std::vector<std::uint8_t> unsigned_rival(out.policy.begin(), out.policy.begin() + payload);
  lcm::ReceiveBuffer rival{unsigned_rival.data(), static_cast<uint32_t>(unsigned_rival.size()), 0};
  testing::internal::CaptureStderr();
  node.onPolicy(&rival, "STRIDE_POLICY");
  testing::internal::GetCapturedStderr();
  EXPECT_EQ(node.rivalPolicies(), 0);
}

// Without a key, a signed message is read as the plain one it carries (a controller without a
// key next to a robot that signs: today's behaviour), and nothing is refused for it.
TEST_F(NodeInput, WithoutAKeySignedMessagesAreReadAsPlainOnes) {
  const msg::Key key = msg::loadKeyFile(newKeyFile());
  msg::Signer robot(key, 3);
  robot_state_t m = good(1000);
  std::vector<std::uint8_t> b(m.getEncodedSize() + msg::kSignatureSize);
  const int n = m.encode(b.data(), 0, m.getEncodedSize());
  b.resize(robot.sign("STRIDE_STATE", b.data(), n, static_cast<int>(b.size())));
  feed(b.data(), static_cast<int>(b.size()));
  EXPECT_EQ(node_.acceptedStates(), 1);
  EXPECT_EQ(node_.rejected(), 0);
  EXPECT_FALSE(node_.auth().keyed());
}

TEST_F(NodeInput, NoStateNoPolicy) {
  node_.tick(Mpc::Clock::time_point::max());
  node_.tick(Mpc::Clock::time_point::max());
  EXPECT_EQ(out_.policies, 0);
  EXPECT_EQ(out_.statuses, 2);
  EXPECT_EQ(node_.mpc().counters().ticks_without_state, 2);
}

TEST_F(NodeInput, MalformedPlansAreRejected) {
  contact_plan_t plan;
  plan.utime = 0;
  plan.cyclic = 1;
  plan.ncontacts = 1;
  plan.contacts = {"no_such_foot"};
  plan.nphases = 1;
  plan.duration = {0.5};
  plan.closed = {{1}};
  std::vector<unsigned char> b(plan.getEncodedSize());
  plan.encode(b.data(), 0, static_cast<int>(b.size()));
  lcm::ReceiveBuffer rbuf{b.data(), static_cast<uint32_t>(b.size()), 0};
  node_.onPlan(&rbuf, "STRIDE_PLAN");
  node_.applyPendingPlan();  // an unknown contact
  EXPECT_EQ(node_.rejected(msg::Reject::BadField), 1);
  plan.duration = {-1.0};
  plan.contacts = {"FL_foot"};
  b.assign(plan.getEncodedSize(), 0);
  plan.encode(b.data(), 0, static_cast<int>(b.size()));
  rbuf = {b.data(), static_cast<uint32_t>(b.size()), 0};
  node_.onPlan(&rbuf, "STRIDE_PLAN");
  EXPECT_EQ(node_.rejected(msg::Reject::BadField), 2);
  rbuf.data_size = 20;
  node_.onPlan(&rbuf, "STRIDE_PLAN");
  EXPECT_EQ(node_.rejected(), 3);
  EXPECT_EQ(node_.planUpdates(), 0);
  // A valid plan for this robot is taken.
  plan.contacts = {"FL_foot", "FR_foot", "HL_foot", "HR_foot"};
  plan.ncontacts = 4;
  plan.duration = {1.0};
  plan.closed = {{1, 1, 1, 1}};
  b.assign(plan.getEncodedSize(), 0);
  plan.encode(b.data(), 0, static_cast<int>(b.size()));
  rbuf = {b.data(), static_cast<uint32_t>(b.size()), 0};
  node_.onPlan(&rbuf, "STRIDE_PLAN");
  node_.applyPendingPlan();
  EXPECT_EQ(node_.planUpdates(), 1);
  // A negative stamp, as for every other message: the plan's time at a tick is the state's stamp
  // minus the plan's, which overflowed for one near -2^63.
  plan.utime = std::numeric_limits<std::int64_t>::min();
  plan.encode(b.data(), 0, static_cast<int>(b.size()));
  node_.onPlan(&rbuf, "STRIDE_PLAN");
  node_.applyPendingPlan();
  EXPECT_EQ(node_.rejected(msg::Reject::BadField), 3);
  EXPECT_EQ(node_.planUpdates(), 1);
}

}  // namespace test_messages
}  // namespace stride
