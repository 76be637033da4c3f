// Faults around a healthy controller (issue 19), each in lock-step in one process, so each outcome
// is deterministic: the quadruped trots forward at 0.5 m/s while states go bad (NaN, stamps going
// back, a 1 s gap), another robot's policies flood the policy channel, or the mock robot itself is
// restarted. Each asserts that the robot did not fall, that it walks on, and the counters that
// say the fault was seen. The controller killed and restarted: test_controller_loss.cpp; a rival
// controller: test_closed_loop.cpp; drops, delay and noise: ClosedLoop.QuadrupedTrotsWith...
#include <gtest/gtest.h>
#include <stdlib.h>
#include <time.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <vector>

#include "controller_cases.hpp"
#include "drive_cases.hpp"
#include "messages/signing.hpp"
#include "tools/drive/closed_loop.hpp"
#include "tools/log/segments.hpp"

namespace stride {
namespace test_faults {

using drive::tiltDeg;

// Stand, trot from 1 s, forward at 0.5 m/s from 2 s, for `duration` seconds.
drive::Options trotForward(double duration) {
  return drive_cases::trotForward(duration, 1.0, 2.0);
}

// Issue 33: surviving is not recovering. trotForward, then from 2 s after the fault's end a turn
// while trotting on (0.3 rad/s) for 2.5 s: a command segment that starts after the fault, which
// the robot must track (logs::recovery).
drive::Options recoveryDrive(double fault_end) {
  drive::Options o = trotForward(fault_end + 4.5);
  o.script.push_back(o.script.back());
  o.script.back().at = fault_end + 2.0;
  o.script.back().yaw_rate = 0.3;
  return o;
}

// Control came back: every segment starting 2 s after the fault's end tracked (there is one at
// least), and the command in force tracked within 2 s of the fault's end.
void expectRecovered(const drive::Run& r, double fault_end) {
  const logs::Recovery rec = logs::recovery(r.segments(), r.baseSamples(), fault_end);
  std::printf("recovery after %.2f s: %d of %d segments tracked, command tracked %.2f s after\n",
              fault_end, rec.segments_after - rec.missed_after, rec.segments_after,
              rec.time_to_tracking);
  EXPECT_GE(rec.segments_after, 1);
  EXPECT_TRUE(rec.recovered);
  EXPECT_GE(rec.time_to_tracking, 0.0);
  EXPECT_LE(rec.time_to_tracking, 2.0);
}

ControllerConfig quad() {
  return loadControllerConfig(controller_cases::configPath("stride_quad"));
}

// Forward distance over the samples in [t0, t1].
double progress(const drive::Run& r, double t0, double t1) {
  double x0 = std::numeric_limits<double>::quiet_NaN(), x1 = x0;
  for (const drive::Sample& s : r.samples) {
    if (std::isnan(x0) && s.t >= t0) x0 = s.q[0];
    if (s.t <= t1) x1 = s.q[0];
  }
  return x1 - x0;
}

double maxTilt(const drive::Run& r) {
  double tilt = 0.0;
  for (const drive::Sample& s : r.samples) tilt = std::max(tilt, tiltDeg(s.q));
  return tilt;
}

// Every third state from 3 s to 5 s carries a NaN: refused (counted), the robot trots on, on the
// policies of the good states in between.
TEST(Faults, NaNStatesAreRefusedAndTheRobotTrotsOn) {
  drive::Options o = recoveryDrive(5.0);
  int spoiled = 0;
  o.state_fault = [&spoiled, n = 0](robot_state_t& m, double t) mutable {
    if (t >= 3.0 && t < 5.0 && n++ % 3 == 0) {
      m.v[4] = std::numeric_limits<double>::quiet_NaN();
      ++spoiled;
    }
    return true;
  };
  const drive::Run r = drive::run(quad(), o);
  EXPECT_FALSE(r.fell());
  EXPECT_GT(spoiled, 100);
  EXPECT_EQ(r.rejected, spoiled) << "each NaN state refused, no other";
  EXPECT_LT(maxTilt(r), 15.0);
  EXPECT_GT(progress(r, 3.0, 5.0), 0.8) << "walks on at ~0.5 m/s through it";
  EXPECT_EQ(r.sim.stand_downs, 0) << "the good states' policies cover the bad ones";
  expectRecovered(r, 5.0);
}

// Every fourth state from 3 s to 5 s is stamped 50 ms in the past (an estimator's clock jumping
// back): refused as out of order, the robot trots on.
TEST(Faults, StampsGoingBackAreRefusedAndTheRobotTrotsOn) {
  drive::Options o = recoveryDrive(5.0);
  int old = 0;
  o.state_fault = [&old, n = 0](robot_state_t& m, double t) mutable {
    if (t >= 3.0 && t < 5.0 && n++ % 4 == 0) {
      m.utime -= 50000;
      ++old;
    }
    return true;
  };
  const drive::Run r = drive::run(quad(), o);
  EXPECT_FALSE(r.fell());
  EXPECT_GT(old, 80);
  EXPECT_EQ(r.rejected, old) << "each old stamp refused, no other";
  EXPECT_LT(maxTilt(r), 15.0);
  EXPECT_GT(progress(r, 3.0, 5.0), 0.8);
  EXPECT_EQ(r.sim.stand_downs, 0);
  expectRecovered(r, 5.0);
}

// No state at all from 3 s to 4 s (the estimator or the network stalled): the controller has
// nothing to answer, the policy runs out, the robot stands down; when states come back the
// controller, alive all along, plans from the robot as it is and trots on.
TEST(Faults, AOneSecondGapInTheStatesIsSurvived) {
  drive::Options o = recoveryDrive(4.0);
  o.state_fault = [](robot_state_t&, double t) { return !(t >= 3.0 && t < 4.0); };
  const drive::Run r = drive::run(quad(), o);
  EXPECT_FALSE(r.fell());
  EXPECT_EQ(r.sim.stand_downs, 1);
  EXPECT_GT(r.sim.stand_down_steps, 800);
  EXPECT_GT(r.sim.states_dropped, 190);  // 200 periods of 5 ms
  EXPECT_LT(maxTilt(r), 15.0);
  std::printf("after the gap: tilt max %.1f deg, %.3f m in the last 2 s\n", maxTilt(r),
              progress(r, 6.0, 8.0));
  EXPECT_GT(progress(r, 6.0, 8.0), 0.8) << "trots on after the gap";
  expectRecovered(r, 4.0);
}

// 1000 policies a second of another robot's sizes (5 each 5 ms period, 23 kB each) arrive on the
// policy channel with the answers: every one refused on its raw bytes before any decoding, and
// the robot's run is bit for bit the run without the flood.
TEST(Faults, AFloodOfForeignPoliciesChangesNothingOnTheRobot) {
  drive::Options o = trotForward(5.0);
  const drive::Run calm = drive::run(quad(), o);
  o.flood_per_period = 5;
  const drive::Run flooded = drive::run(quad(), o);
  ASSERT_EQ(flooded.samples.size(), calm.samples.size());
  for (std::size_t i = 0; i < calm.samples.size(); ++i)
    ASSERT_EQ(flooded.samples[i].q, calm.samples[i].q) << "t " << calm.samples[i].t;
  EXPECT_FALSE(flooded.fell());
  const std::int64_t periods = static_cast<std::int64_t>(calm.samples.size());
  EXPECT_EQ(flooded.sim.policies_wrong_model, 5 * periods);
  EXPECT_EQ(flooded.sim.policies_rejected, 5 * periods);
  EXPECT_EQ(flooded.sim.policies, calm.sim.policies) << "no answer lost in the flood";
  expectRecovered(flooded, 0.0);  // the flood lasts the whole run
}

// The mock robot restarted (stride-sim killed at 3 s, back 1 s later with the robot standing at
// the origin, its clock going on): the controller, alive all along, takes the new robot as it
// comes and trots it forward.
TEST(Faults, TheMockRobotRestartedIsTakenOverByTheController) {
  drive::Options o = recoveryDrive(4.0);
  o.sim_lost_at = 3.0;
  const drive::Run r = drive::run(quad(), o);
  EXPECT_EQ(r.sim_starts, 2);
  EXPECT_FALSE(r.sim_before_restart.fell);
  EXPECT_FALSE(r.fell());
  EXPECT_LT(maxTilt(r), 15.0);
  EXPECT_GT(progress(r, 6.0, 8.0), 0.8) << "the new robot trots forward";
  expectRecovered(r, 4.0);
}

// Every fault of the lock-step closed loops in turn, in one drive with a key (issue 43): the
// controller killed and restarted (a stand-down, a new sender taken), bad states (NaN, stamps
// going back), an unsigned controller's and a keyed rival's policies, junk signed with the live
// controller's id from the future, a gap in the states (a stand-down), the mock robot restarted
// (another run of the robot, taken from scratch), the commands stopping (the deadman). Each
// fault's own test, with its own claims, runs in Release; the sanitized stage runs this drive in
// their place: the paths they take in 7 s of robot time instead of seven drives of 2-10 s each
// (tests/README.md, "Sanitizers").
TEST(Faults, EveryFaultInTurnInOneSignedDrive) {
  char dir[] = "/tmp/stride-tour-XXXXXX";
  ASSERT_NE(mkdtemp(dir), nullptr);
  ControllerConfig keyed = quad();
  keyed.key_file = std::string(dir) + "/key";
  msg::writeNewKeyFile(keyed.key_file);
  const msg::Key key = msg::loadKeyFile(keyed.key_file);

  // Trot from 0.5 s, forward at 0.5 m/s from 1 s; the commands stop at 6 s.
  drive::Options o = drive_cases::trotForward(7.0, 0.5, 1.0);
  o.commands_until = 6.0;
  o.controller_lost_at = 1.5;
  o.controller_back_after = 0.5;
  o.sim_lost_at = 5.0;
  o.sim_back_after = 0.3;
  int spoiled = 0, old = 0;
  // On the run's clock (the state's stamp: a restarted mock robot's own time starts at 0).
  const std::int64_t base = o.sim.utime_base;
  o.state_fault = [&spoiled, &old, base, n = 0](robot_state_t& m, double) mutable {
    const double t = (m.utime - base) * 1e-6;
    if (t >= 2.5 && t < 3.0 && n++ % 3 == 0) {
      m.v[4] = std::numeric_limits<double>::quiet_NaN();
      ++spoiled;
    } else if (t >= 3.0 && t < 3.4 && n++ % 4 == 0) {
      m.utime -= 50000;
      ++old;
    }
    return !(t >= 3.6 && t < 4.3);  // a gap of 0.7 s: the policy runs out
  };

  // The attacker: from 3.2 s to 3.4 s the live controller's newest policy again, once unsigned
  // (an unkeyed controller's) and once from another source signed with the key (a keyed rival's);
  // at 3.2 s and 3.5 s three junk policies under the live sender's id, stamped far ahead and
  // 0.3 s ahead.
  struct Attacker {
    lcm::Subscription* sub = nullptr;
    std::vector<std::uint8_t> last;  // the live controller's newest policy as sent
    std::uint32_t rival = 0;         // the sender id the rival signs with
    int unsigned_sent = 0, rival_sent = 0, junk_sent = 0;
    void onPolicy(const lcm::ReceiveBuffer* rbuf, const std::string&) {
      const auto* b = static_cast<const std::uint8_t*>(rbuf->data);
      const int n = static_cast<int>(rbuf->data_size);
      // Not the attacker's own: unsigned, the rival's, or junk (of no run).
      msg::SignatureClaim claim;
      policy_t p;
      if (!msg::readSignatureClaim(b, n, claim) || claim.sender == rival) return;
      const int payload = n - msg::kSignatureSize;
      if (p.decode(b, 0, payload) == payload && p.session != 0) last.assign(b, b + n);
    }
  };
  auto attacker = std::make_shared<Attacker>();
  const std::string channel = keyed.policy_channel;
  o.on_bus = [attacker, key, channel](lcm::LCM& bus, double t) {
    if (attacker->sub == nullptr)
      attacker->sub = bus.subscribe(channel, &Attacker::onPolicy, attacker.get());
    msg::SignatureClaim live;
    const int size = static_cast<int>(attacker->last.size());
    if (!msg::readSignatureClaim(attacker->last.data(), size, live)) return;
    const int payload = size - msg::kSignatureSize;
    policy_t p;
    if (p.decode(attacker->last.data(), 0, payload) != payload) return;
    std::vector<std::uint8_t> b(size);
    if (t >= 3.2 && t < 3.4) {
      bus.publish(channel, attacker->last.data(), static_cast<unsigned>(payload));
      ++attacker->unsigned_sent;
      policy_t rival = p;
      rival.source_id += 1;
      const int n = rival.encode(b.data(), 0, payload);
      if (attacker->rival == 0) attacker->rival = live.sender + 1;
      msg::Signer signer(key, attacker->rival);
      const int signed_size = signer.sign(channel.c_str(), b.data(), n, size);
      bus.publish(channel, b.data(), static_cast<unsigned>(signed_size));
      ++attacker->rival_sent;
    }
    if (attacker->junk_sent < 6 && t + 1e-9 >= (attacker->junk_sent == 0 ? 3.2 : 3.5)) {
      p.session = 0;  // of no run of the robot, with NaN gains: junk only a key holder can sign
      p.K[0][0] = std::numeric_limits<double>::quiet_NaN();
      const int n = p.encode(b.data(), 0, payload);
      const msg::Signer forger(key, live.sender);
      timespec wall{};
      clock_gettime(CLOCK_REALTIME, &wall);
      const std::int64_t now =
          static_cast<std::int64_t>(wall.tv_sec) * 1000000 + wall.tv_nsec / 1000;
      for (const std::int64_t at : {std::numeric_limits<std::int64_t>::max(),
                                    std::int64_t{now + 3600LL * 1000000}, now + 300000}) {
        bus.publish(channel, b.data(),
                    static_cast<unsigned>(forger.signAt(channel.c_str(), b.data(), n, size, at)));
        ++attacker->junk_sent;
      }
    }
  };

  const drive::Run r = drive::run(keyed, o);
  const sim::SimNodeStats& first = r.sim_before_restart;
  std::printf(
      "%d NaN and %d old states; %d unsigned, %d rival and %d junk policies; the first robot "
      "refused %lld unread, %lld of a rival, %lld of another run, stood down %lld times; %.3f m "
      "walked by the restarted robot in 5.5-6.5 s\n",
      spoiled, old, attacker->unsigned_sent, attacker->rival_sent, attacker->junk_sent,
      static_cast<long long>(first.policies_unauthenticated),
      static_cast<long long>(first.policies_rival),
      static_cast<long long>(first.policies_other_session),
      static_cast<long long>(first.stand_downs), progress(r, 5.5, 6.5));
  EXPECT_FALSE(first.fell);
  EXPECT_FALSE(r.fell());
  EXPECT_LT(maxTilt(r), 15.0);
  EXPECT_EQ(r.controller_starts, 2);
  EXPECT_EQ(r.sim_starts, 2);
  EXPECT_GT(spoiled, 30);
  EXPECT_GT(old, 15);
  // The restarted controller's refusals: the bad states, the attacker's policies refused unread,
  // and the new robot's first states (of another run until the one followed went silent).
  EXPECT_EQ(r.rejected - r.mpc_unauthenticated - r.mpc_other_session, spoiled + old)
      << "each bad state refused, no other";
  EXPECT_GT(attacker->unsigned_sent, 30);
  EXPECT_EQ(attacker->rival_sent, attacker->unsigned_sent);
  EXPECT_EQ(attacker->junk_sent, 6);
  // The first robot: the unsigned and the far-ahead junk refused unread, the junk inside the window
  // by its content (no run of the robot), the keyed rival by the source rule.
  EXPECT_EQ(first.policies_unauthenticated, attacker->unsigned_sent + 4);
  EXPECT_EQ(first.policies_other_session, 2);
  EXPECT_EQ(first.policies_rival, attacker->rival_sent);
  EXPECT_EQ(first.stand_downs, 2) << "the controller's death and the gap";
  EXPECT_EQ(r.command_counters.timeouts, 1) << "the deadman, once";
  EXPECT_GT(progress(r, 5.5, 6.5), 0.3) << "the new robot trots forward under the controller";
}

}  // namespace test_faults
}  // namespace stride
