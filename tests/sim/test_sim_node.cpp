// stride-sim's LCM side (sim/sim_node.hpp): the wire contract on the robot's end. States carry the
// robot's model hash; a policy of another model is refused, counted, and each cause said once.

#include <gtest/gtest.h>

#include <stdlib.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <limits>
#include <string>
#include <vector>

#include "config/model_hash.hpp"
#include "messages/signing.hpp"
#include "sim/sim_node.hpp"
#include "sim_cases.hpp"
#include "tools/log/segments.hpp"

namespace stride {
namespace test_sim_node {

struct Sink : Publisher {
  robot_state_t state;
  void publish(const std::string&, const void* data, int size) override {
    state.decode(data, 0, size);
  }
};

std::vector<unsigned char> encode(const policy_t& p) {
  std::vector<unsigned char> b(p.getEncodedSize());
  p.encode(b.data(), 0, static_cast<int>(b.size()));
  return b;
}

// A policy that holds the default posture, in `robot`'s sizes, stamped with `hash`.
policy_t holdPolicy(const Robot& robot, int nq, int nv, std::int64_t hash) {
  policy_t p;
  msg::shape(p, 2, nq, nv, nv - 6);
  p.model_hash = hash;
  p.source_id = 1;
  p.session = 0;  // the caller answers its robot's run
  p.tick = 0;
  p.t0 = 0.0;
  p.phase = 0;  // lcm-gen leaves the fields unset
  p.utime = p.knot0_utime = 1000000;
  p.dt = 0.01;
  p.status = 0;
  for (int k = 0; k < 2; ++k) {
    p.x_ref[k][6] = 1.0;  // a unit quaternion in any size
    for (int i = 0; i < std::min(nq, robot.model.nq); ++i) p.x_ref[k][i] = robot.default_q[i];
  }
  return p;
}

TEST(SimNode, StatesCarryTheModelHashAndAnotherModelsPoliciesAreRefused) {
  const Robot& robot = sim_test::robot("stride_quad");
  Sink out;
  sim::SimNode node(robot, sim::SimOptions{}, sim::SimNodeOptions{}, out);
  node.reset(robot.default_q, Eigen::VectorXd::Zero(robot.model.nv));
  ASSERT_GE(node.publishState(), 0);
  EXPECT_EQ(out.state.model_hash, modelHash(robot));

  auto feed = [&](policy_t p) {
    p.session = node.session();  // answers this run
    std::vector<unsigned char> b = encode(p);
    lcm::ReceiveBuffer rbuf{b.data(), static_cast<uint32_t>(b.size()), 0};
    node.onPolicy(&rbuf, "STRIDE_POLICY");
  };
  char ours[17];
  msg::formatHash(modelHash(robot), ours);
  testing::internal::CaptureStderr();
  feed(holdPolicy(robot, 19, 18, modelHash(robot) ^ 1));  // same sizes, another layout
  feed(holdPolicy(robot, 19, 18, modelHash(robot) ^ 1));
  feed(holdPolicy(robot, 29, 28, 99));  // another robot's sizes
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_EQ(node.stats().policies, 0);
  EXPECT_EQ(node.stats().policies_rejected, 3);
  EXPECT_EQ(node.stats().policies_wrong_model, 3);
  // Each cause once, saying what was expected and what came.
  EXPECT_NE(err.find("stride-sim: refused a policy on 'STRIDE_POLICY': expected hash " +
                     std::string(ours) + " (stride_quad, nq 19, nv 18), got hash"),
            std::string::npos)
      << err;
  EXPECT_NE(err.find("expected nq 19, nv 18 (stride_quad, hash " + std::string(ours) +
                     "), got nq 29, nv 28 (hash 0000000000000063)"),
            std::string::npos)
      << err;
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 2) << err;

  feed(holdPolicy(robot, 19, 18, modelHash(robot)));
  EXPECT_EQ(node.stats().policies, 1);
  EXPECT_TRUE(node.answered(1000000));
}

// Issue 33, authenticated messages: a robot with a key signs its states and takes only policies
// signed with it. A rival or a forger without the key changes nothing: unsigned, forged,
// replayed and another key's policies are refused unread and counted.
TEST(SimNode, WithAKeyOnlySignedPoliciesAreTaken) {
  const Robot& robot = sim_test::robot("stride_quad");
  char dir[] = "/tmp/stride-key-XXXXXX";
  ASSERT_NE(mkdtemp(dir), nullptr);
  msg::writeNewKeyFile(std::string(dir) + "/key");
  msg::writeNewKeyFile(std::string(dir) + "/other");
  const msg::Key key = msg::loadKeyFile(std::string(dir) + "/key");
  const msg::Key other = msg::loadKeyFile(std::string(dir) + "/other");
  struct Raw : Publisher {
    std::vector<std::uint8_t> state;
    void publish(const std::string&, const void* data, int size) override {
      state.assign(static_cast<const std::uint8_t*>(data),
                   static_cast<const std::uint8_t*>(data) + size);
    }
  } out;
  sim::SimNodeOptions options;
  options.key = key;
  sim::SimNode node(robot, sim::SimOptions{}, options, out);
  node.reset(robot.default_q, Eigen::VectorXd::Zero(robot.model.nv));
  ASSERT_GE(node.publishState(), 0);
  // Its state verifies with the key, and carries the plain state.
  msg::Verifier controller(key);
  int payload = 0;
  timespec wall{};
  clock_gettime(CLOCK_REALTIME, &wall);
  ASSERT_EQ(controller.check("STRIDE_STATE", out.state.data(), static_cast<int>(out.state.size()),
                             static_cast<std::int64_t>(wall.tv_sec) * 1000000 + wall.tv_nsec / 1000,
                             payload),
            msg::Verdict::Ok);
  robot_state_t state;
  ASSERT_EQ(state.decode(out.state.data(), 0, payload), payload);
  EXPECT_EQ(state.model_hash, modelHash(robot));

  msg::Signer ours(key, 11), theirs(other, 11);
  const auto bytes = [&](std::int64_t utime, msg::Signer* signer) {
    policy_t p = holdPolicy(robot, 19, 18, modelHash(robot));
    p.session = node.session();
    p.utime = p.knot0_utime = utime;
    std::vector<std::uint8_t> b = encode(p);
    const int n = static_cast<int>(b.size());
    b.resize(b.size() + msg::kSignatureSize);
    b.resize(signer ? signer->sign("STRIDE_POLICY", b.data(), n, static_cast<int>(b.size())) : n);
    return b;
  };
  const auto feed = [&](std::vector<std::uint8_t> b) {
    lcm::ReceiveBuffer rbuf{b.data(), static_cast<uint32_t>(b.size()), 0};
    node.onPolicy(&rbuf, "STRIDE_POLICY");
  };
  testing::internal::CaptureStderr();
  feed(bytes(1000000, nullptr));
  feed(bytes(1000000, &theirs));
  std::vector<std::uint8_t> forged = bytes(1000000, &ours);
  forged[100] ^= 4;  // a gain changed on the way
  feed(forged);
  EXPECT_EQ(node.stats().policies, 0);
  const std::vector<std::uint8_t> good = bytes(1000000, &ours);
  feed(good);
  EXPECT_EQ(node.stats().policies, 1);
  feed(good);  // replayed
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_EQ(node.stats().policies, 1);
  EXPECT_EQ(node.stats().policies_unauthenticated, 4);
  EXPECT_EQ(node.stats().policies_rejected, 4);
  EXPECT_EQ(node.stats().policies_rival, 0);
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 4) << "the first of each reason: " << err;
}

// Issue 44: a robot run has an identity its states carry (robot_state_t.session, new at every
// start and reset) and its policies must answer: a policy made for another run (a recording, a
// lock-step run whose clock also started at 0) is refused whatever its stamps, counted and said
// once, and does not take the robot from its controller.
TEST(SimNode, APolicyForAnotherRunIsRefused) {
  const Robot& robot = sim_test::robot("stride_quad");
  Sink out;
  sim::SimNode node(robot, sim::SimOptions{}, sim::SimNodeOptions{}, out);
  node.reset(robot.default_q, Eigen::VectorXd::Zero(robot.model.nv));
  const std::int64_t first = node.session();
  ASSERT_NE(first, 0);
  ASSERT_GE(node.publishState(), 0);
  EXPECT_EQ(out.state.session, first);
  node.reset(robot.default_q, Eigen::VectorXd::Zero(robot.model.nv));
  EXPECT_NE(node.session(), first) << "a reset is another run";
  const auto feed = [&](std::int64_t session, std::int64_t source) {
    policy_t p = holdPolicy(robot, 19, 18, modelHash(robot));
    p.session = session;
    p.source_id = source;
    p.utime = p.knot0_utime = 1000000;
    std::vector<unsigned char> b = encode(p);
    lcm::ReceiveBuffer rbuf{b.data(), static_cast<uint32_t>(b.size()), 0};
    node.onPolicy(&rbuf, "STRIDE_POLICY");
  };
  testing::internal::CaptureStderr();
  feed(first, 7);  // the previous run's
  feed(0, 7);
  feed(node.session() ^ 1, 7);
  EXPECT_EQ(node.stats().policies, 0);
  EXPECT_EQ(node.stats().policies_other_session, 3);
  EXPECT_EQ(node.stats().policies_rejected, 3);
  feed(node.session(), 8);  // this run's controller: taken, and followed
  EXPECT_EQ(node.stats().policies, 1);
  feed(first, 7);  // another run's policies never count as a rival's nor switch the source
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_EQ(node.stats().policies_other_session, 4);
  EXPECT_EQ(node.stats().policies_rival, 0);
  EXPECT_EQ(node.stats().source_switches, 0);
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  EXPECT_NE(err.find("another run of the robot"), std::string::npos) << err;
}

// A valid policy whose knot 0 sits at any stamp, down to -2^63 µs: its time on the robot's clock
// was an int64 difference that overflowed (undefined behaviour, found by the message fuzzer,
// tests/fuzz; UndefinedBehaviorSanitizer sees it in tools/test.sh --sanitize). Long past its
// end, it is not applied: the robot stands down.
TEST(SimNode, APolicyOfAnyStampIsTakenWithoutOverflow) {
  const Robot& robot = sim_test::robot("stride_quad");
  Sink out;
  sim::SimNode node(robot, sim::SimOptions{}, sim::SimNodeOptions{}, out);
  for (const std::int64_t knot0 : {std::numeric_limits<std::int64_t>::min(), std::int64_t{0},
                                   std::numeric_limits<std::int64_t>::max()}) {
    node.reset(robot.default_q, Eigen::VectorXd::Zero(robot.model.nv));
    policy_t p = holdPolicy(robot, 19, 18, modelHash(robot));
    p.session = node.session();
    p.knot0_utime = knot0;
    std::vector<unsigned char> b = encode(p);
    lcm::ReceiveBuffer rbuf{b.data(), static_cast<uint32_t>(b.size()), 0};
    node.onPolicy(&rbuf, "STRIDE_POLICY");
    EXPECT_EQ(node.stats().policies, 1) << knot0;
    EXPECT_TRUE(node.advance(10)) << knot0;
    EXPECT_EQ(node.stats().steps, 10) << knot0;
    if (knot0 < 0) {
      EXPECT_EQ(node.stats().stand_downs, 1) << knot0;  // long past its end
    }
  }
}

// Why the robot did not follow its controller, in words (issue 32): a robot that never had a
// policy, a policy that arrived already past its end (a latency longer than the policy: the robot
// stood down with nothing but "standing down" lines before), said once each on stderr and in the
// summaries' `why`.
TEST(SimNode, APolicyPastItsEndOnArrivalIsSaidSo) {
  const Robot& robot = sim_test::robot("stride_quad");
  Sink out;
  sim::SimNode node(robot, sim::SimOptions{}, sim::SimNodeOptions{}, out);
  node.reset(robot.default_q, Eigen::VectorXd::Zero(robot.model.nv));
  EXPECT_EQ(sim::whyText(node.stats()), "");
  ASSERT_TRUE(node.advance(50));  // 50 ms on the hold PD
  EXPECT_EQ(sim::whyText(node.stats()),
            "no policy came: the robot stood on its hold PD for the whole run");

  auto feed = [&](double knot0) {
    policy_t p = holdPolicy(robot, 19, 18, modelHash(robot));
    p.session = node.session();
    p.utime = p.knot0_utime = 1000000 + static_cast<std::int64_t>(std::llround(knot0 * 1e6));
    std::vector<unsigned char> b = encode(p);
    lcm::ReceiveBuffer rbuf{b.data(), static_cast<uint32_t>(b.size()), 0};
    node.onPolicy(&rbuf, "STRIDE_POLICY");
  };
  // Knot 0 at the state of 0 s, 10 ms long, arriving at 50 ms: 40 ms past its end.
  testing::internal::CaptureStderr();
  feed(0.0);
  feed(0.001);
  feed(0.002);
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_EQ(node.stats().policies, 3);
  EXPECT_EQ(node.stats().policies_expired, 3);
  EXPECT_NE(err.find("stride-sim: a policy arrived 0.040 s after its end: it covers 0.010 s from a "
                     "state 0.050 s old"),
            std::string::npos)
      << err;
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 2) << err;  // the first two
  ASSERT_TRUE(node.advance(10));
  EXPECT_EQ(node.stats().stand_downs, 1);
  EXPECT_EQ(node.stats().policy_steps, 0);
  EXPECT_EQ(sim::whyText(node.stats()),
            "3 of 3 policies arrived at or after their end (up to 0.040 s after; a policy covers "
            "0.010 s): the estimates' latency and the controller's answer together took as long "
            "as a policy lasts or longer; past a policy's end the robot stood down (1 times); no "
            "policy was ever in force: the robot stood for the whole run");
  // One in time (the state of 60 ms, now): followed; the expired ones are still said.
  feed(0.06);
  ASSERT_TRUE(node.advance(5));
  EXPECT_EQ(node.stats().policies_expired, 3);
  EXPECT_EQ(node.stats().policy_steps, 5);
  const std::string why = sim::whyText(node.stats());
  EXPECT_NE(why.find("3 of 4 policies arrived at or after their end"), std::string::npos) << why;
  EXPECT_EQ(why.find("whole run"), std::string::npos) << why;
}

// A 0.4 s policy holding the default posture with a joint PD in its gains (K's joint columns), no
// feed-forward: the robot sags on it, differently for each state it feeds back.
policy_t gainPolicy(const Robot& robot) {
  const int nq = robot.model.nq, nv = robot.model.nv, nu = nv - 6;
  policy_t p;
  msg::shape(p, 40, nq, nv, nu);
  p.model_hash = modelHash(robot);
  p.source_id = 1;
  p.session = 0;  // the caller answers its robot's run
  p.tick = 0;
  p.t0 = 0.0;
  p.phase = 0;  // lcm-gen leaves the fields unset
  p.utime = p.knot0_utime = 1000000;
  p.dt = 0.01;
  p.status = 0;
  for (int k = 0; k < 40; ++k) {
    for (int i = 0; i < nq; ++i) p.x_ref[k][i] = robot.default_q[i];
    for (int i = 0; i < nu; ++i) {
      p.K[k][i * 2 * nv + 6 + i] = 3.0;        // position
      p.K[k][i * 2 * nv + nv + 6 + i] = 0.05;  // velocity
    }
  }
  return p;
}

// The policy above as the evaluator reads it.
msg::Policy asPolicy(const policy_t& m, const Robot& robot) {
  msg::Policy p;
  p.resize(m.knots, robot.model.nq, robot.model.nv, robot.model.nv - 6);
  p.t0 = 0.0;
  p.dt = m.dt;
  for (int k = 0; k < m.knots; ++k) {
    std::copy(m.x_ref[k].begin(), m.x_ref[k].end(), p.xRef(k));
    std::copy(m.u_ff[k].begin(), m.u_ff[k].end(), p.uFf(k));
    std::copy(m.K[k].begin(), m.K[k].end(), p.gain(k));
  }
  return p;
}

// The robot's loop applies the feedback to what it senses. Noise-free (the default), that is the
// truth, bit for bit as a loop that reads the simulator's state; with 5 steps of sensing latency,
// bit for bit a loop that reads the state of 5 steps ago.
TEST(SimNode, NoiseFreeSensingIsTheTruthAndLatencyFeedsBackTheOldState) {
  const Robot& robot = sim_test::robot("stride_quad");
  const policy_t message = gainPolicy(robot);
  const msg::Policy policy = asPolicy(message, robot);
  for (int latency : {0, 5}) {
    Sink out;
    sim::SimNodeOptions o;
    o.sensing.latency = latency;
    sim::SimNode node(robot, sim::SimOptions{}, o, out);
    node.reset(robot.default_q, Eigen::VectorXd::Zero(robot.model.nv));
    policy_t answer = message;
    answer.session = node.session();
    std::vector<unsigned char> b = encode(answer);
    lcm::ReceiveBuffer rbuf{b.data(), static_cast<uint32_t>(b.size()), 0};
    node.onPolicy(&rbuf, "STRIDE_POLICY");
    ASSERT_TRUE(node.advance(200));
    EXPECT_EQ(node.stats().policy_steps, 200);

    sim::Simulator sim(robot, sim::SimOptions{});
    sim.reset(robot.default_q, Eigen::VectorXd::Zero(robot.model.nv));
    msg::PolicyEvaluator evaluator(robot.model, 12);
    std::vector<Eigen::VectorXd> qs{sim.q()}, vs{sim.v()};
    Eigen::VectorXd tau(12);
    for (int k = 0; k < 200; ++k) {
      const int seen = std::max(0, k - latency);
      evaluator.evaluate(policy, sim.time(), qs[seen], vs[seen], tau);
      sim.step(tau);
      qs.push_back(sim.q());
      vs.push_back(sim.v());
    }
    EXPECT_EQ(node.simulator().q(), sim.q()) << "latency " << latency;
    EXPECT_EQ(node.simulator().v(), sim.v()) << "latency " << latency;
    // The estimate published now is the state of `latency` steps ago, stamped with its time.
    const std::int64_t stamp = node.publishState();
    EXPECT_EQ(stamp, 1000000 + 1000 * (200 - latency));
    for (int i = 0; i < robot.model.nq; ++i) EXPECT_EQ(out.state.q[i], qs[200 - latency][i]);
  }
}

// One fall criterion (sim/fall.hpp): a quadruped let go (no hold PD) collapses, and the mock
// robot's verdict (its summary's `fell`, checked on every physics step) and the log summary's
// (logs::fallen on each state as a log holds it, above the terrain under the base, from the
// first state's height) agree at every step: not fallen until the same step, with the same
// default limits and the same maximum tilt.
TEST(SimNode, TheRobotAndTheLogSummaryAgreeOnAFall) {
  const Robot& robot = sim_test::robot("stride_quad");
  Sink out;
  sim::SimNodeOptions o;
  o.hold_kp = 0.0;
  o.hold_kd = 0.0;
  sim::SimNode node(robot, sim::SimOptions{}, o, out);
  node.reset(robot.default_q, Eigen::VectorXd::Zero(robot.model.nv));
  const auto sample = [&] {
    logs::BaseSample b;
    const Eigen::VectorXd& q = node.simulator().q();
    for (int i = 0; i < 7; ++i) b.q[i] = q[i];
    b.ground = node.simulator().terrain().height(q[0], q[1]);
    return b;
  };
  const logs::BaseSample first = sample();
  const double first_height = first.q[2] - first.ground;
  EXPECT_EQ(first_height, node.stats().above0);
  const logs::FallLimits limits = logs::SegmentOptions{}.fall;
  EXPECT_EQ(limits.height_fraction, o.fall.height_fraction);
  EXPECT_EQ(limits.max_tilt_deg, o.fall.max_tilt_deg);
  double max_tilt_deg = 0.0;
  bool fell = false;
  int steps = 0;
  while (!fell && steps < 5000) {
    const bool going = node.advance(1);
    ++steps;
    const logs::BaseSample b = sample();
    fell = logs::fallen(b, first_height, limits);
    max_tilt_deg = std::max(max_tilt_deg, logs::tilt(b.q) * 180.0 / M_PI);
    ASSERT_EQ(fell, node.stats().fell) << "step " << steps;
    ASSERT_EQ(going, !fell) << "step " << steps;
  }
  EXPECT_TRUE(fell) << "no fall in " << steps << " steps";
  EXPECT_GT(steps, 10);
  EXPECT_EQ(max_tilt_deg, node.stats().max_tilt_deg);
}

// The model mismatch moves the robot, not the wire: the states still carry the nominal model's
// hash (the controller plans with the robot it knows), and a heavier robot sags more.
TEST(SimNode, AHeavierRobotIsTheSameRobotOnTheWire) {
  const Robot& robot = sim_test::robot("stride_quad");
  const policy_t message = gainPolicy(robot);
  double z[2];
  for (int heavy : {0, 1}) {
    Sink out;
    sim::SimNodeOptions o;
    if (heavy) o.plant.payload = 1.0;
    sim::SimNode node(robot, sim::SimOptions{}, o, out);
    EXPECT_NEAR(node.simulator().model().totalMass(), robot.model.totalMass() + heavy, 1e-12);
    node.reset(robot.default_q, Eigen::VectorXd::Zero(robot.model.nv));
    policy_t answer = message;
    answer.session = node.session();
    std::vector<unsigned char> b = encode(answer);
    lcm::ReceiveBuffer rbuf{b.data(), static_cast<uint32_t>(b.size()), 0};
    node.onPolicy(&rbuf, "STRIDE_POLICY");
    ASSERT_TRUE(node.advance(100));
    node.publishState();
    EXPECT_EQ(out.state.model_hash, modelHash(robot));
    z[heavy] = node.simulator().q()[2];
  }
  EXPECT_LT(z[1], z[0] - 1e-3);
}

}  // namespace test_sim_node
}  // namespace stride
