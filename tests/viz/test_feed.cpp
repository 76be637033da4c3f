// What stride-viz makes of messages (viz/server/feed.hpp, frames.hpp, wire.hpp, robot_files.hpp):
// malformed bytes on every channel are counted by reason and change nothing; the frames of a real
// session hold what the page draws; estimated forces carry the robot's weight; the URDF the page
// gets names no file outside the server.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <lcm/lcm-cpp.hpp>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>

#include "messages/signing.hpp"
#include "viz/server/feed.hpp"
#include "viz/server/frames.hpp"
#include "viz/server/log_document.hpp"
#include "viz/server/robot_files.hpp"
#include "viz/server/wire.hpp"
#include "viz_cases.hpp"

namespace stride::viz {
namespace test_feed {

using namespace stride::viz::test;

RobotSource quadSource() {
  RobotSource s;
  s.yaml = quadYaml();
  return s;
}

void take(Feed& feed, const std::string& channel, const std::vector<unsigned char>& bytes) {
  feed.take(channel, bytes.data(), static_cast<int>(bytes.size()));
}

// Big-endian int32 written at `at` (a count field of an encoded message).
void poke32(std::vector<unsigned char>& buf, std::size_t at, std::int32_t value) {
  std::uint32_t u;
  std::memcpy(&u, &value, 4);
  for (int i = 0; i < 4; ++i) buf[at + i] = static_cast<unsigned char>(u >> (24 - 8 * i));
}

TEST(Feed, MalformedMessagesOnEveryChannelAreCountedAndDropped) {
  Feed feed(Channels{}, quadSource());
  const Channels ch;
  const std::vector<unsigned char> garbage = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13};
  for (const std::string& c : ch.all()) {
    take(feed, c, garbage);
    take(feed, c, {});
  }
  // A state of another robot (hash), a NaN, a broken quaternion, too many contact flags.
  robot_state_t s = standingState(1000);
  s.model_hash ^= 1;
  take(feed, ch.state, encode(s));
  s = standingState(1000);
  s.q[8] = std::numeric_limits<double>::quiet_NaN();
  take(feed, ch.state, encode(s));
  s = standingState(1000);
  s.q[6] = 0.5;
  take(feed, ch.state, encode(s));
  s = standingState(1000);
  s.ncontacts = 9;
  s.contact.resize(9, 1);
  take(feed, ch.state, encode(s));
  // A model whose joint count claims 2^31 (its decoder would size a vector by it).
  std::vector<unsigned char> model = encode(quadModel());
  const std::size_t njoints_at = 8 + 4 + quad().name.size() + 1 + 8 + 12;
  poke32(model, njoints_at, std::numeric_limits<std::int32_t>::max());
  take(feed, ch.model, model);
  // A model string whose length is 0 or negative.
  model = encode(quadModel());
  poke32(model, 8, 0);
  take(feed, ch.model, model);
  poke32(model, 8, -5);
  take(feed, ch.model, model);
  // A horizon claiming 2^31 knots, one with a NaN force, one with a mask of a fifth contact.
  std::vector<unsigned char> h = encode(standingHorizon(1000, 20));
  poke32(h, 8 + 16, std::numeric_limits<std::int32_t>::max());
  take(feed, ch.horizon, h);
  horizon_t bad = standingHorizon(1000, 20);
  bad.force[3][2] = std::numeric_limits<double>::infinity();
  take(feed, ch.horizon, encode(bad));
  bad = standingHorizon(1000, 20);
  bad.contact_mask[5] = 0b10000;
  take(feed, ch.horizon, encode(bad));
  // A status whose last string's length runs past the end, and one stamped negative.
  mpc_status_t st{};
  st.gait = "trot";
  std::vector<unsigned char> status = encode(st);
  // jump_refusal: length, "\0", then 2 int64, an int8, a double and 2 int64 (the terrain fields)
  poke32(status, status.size() - 41 - 1 - 4, 1000);
  take(feed, ch.status, status);
  st.utime = -1;
  take(feed, ch.status, encode(st));
  // A command with a NaN.
  command_t cmd{};
  cmd.vx = std::numeric_limits<double>::quiet_NaN();
  take(feed, ch.command, encode(cmd));
  // A map claiming 2^31 rows, one with an infinite height.
  std::vector<unsigned char> map = encode(boxStepMap(1000, 20, 20));
  poke32(map, 8 + 32, std::numeric_limits<std::int32_t>::max());
  take(feed, ch.terrain, map);
  terrain_t steep = boxStepMap(1000, 20, 20);
  steep.height[0][0] = std::numeric_limits<float>::infinity();
  take(feed, ch.terrain, encode(steep));

  for (const std::string& c : ch.all()) EXPECT_EQ(feed.accepted(c), 0) << c;
  EXPECT_EQ(feed.rejected(ch.state), 2 + 4);
  EXPECT_EQ(feed.rejected(ch.model), 2 + 3);
  EXPECT_EQ(feed.rejected(ch.horizon), 2 + 3);
  EXPECT_EQ(feed.rejected(ch.status), 2 + 2);
  EXPECT_EQ(feed.rejected(ch.command), 2 + 1);
  EXPECT_EQ(feed.rejected(ch.terrain), 2 + 2);
  const Json counters = feed.counters()["channels"];
  EXPECT_EQ(counters[ch.state]["rejected"]["another robot's model (hash or sizes)"], 1);
  EXPECT_EQ(counters[ch.state]["rejected"]["base quaternion not unit"], 1);
  EXPECT_EQ(counters[ch.horizon]["rejected"]["non-finite value"], 1);
  EXPECT_TRUE(feed.frame(FrameKind::State).is_null());
  EXPECT_TRUE(feed.frame(FrameKind::Plan).is_null());
  EXPECT_TRUE(feed.frame(FrameKind::Status).is_null());
  EXPECT_TRUE(feed.frame(FrameKind::Terrain).is_null());

  // Good messages still go through after all that.
  take(feed, ch.model, encode(quadModel()));
  take(feed, ch.state, encode(standingState(2000)));
  take(feed, ch.horizon, encode(standingHorizon(2000, 20)));
  EXPECT_EQ(feed.accepted(ch.model), 1);
  EXPECT_EQ(feed.accepted(ch.state), 1);
  EXPECT_EQ(feed.accepted(ch.horizon), 1);
  const Json state = feed.frame(FrameKind::State);
  ASSERT_FALSE(state.is_null());
  EXPECT_EQ(state["q"].size(), 19u);
  EXPECT_EQ(state["forces"], Json::array());  // no policy yet
}

// The chosen footholds of a horizon (issue 31) are checked like the rest: their count on the bytes
// (at most 4 per contact, the exact size), then each one finite, after the state, of an existing
// contact, from a known source. A refused horizon changes nothing the feed holds.
TEST(Feed, MalformedFootholdsAreRefused) {
  const Robot& r = quad();
  const int nc = static_cast<int>(r.contacts.size());
  const msg::WireModel model{modelHash(r), r.model.nq, r.model.nv, r.model.nv - 6, "stride_quad"};
  horizon_t out;
  auto decode = [&](const std::vector<unsigned char>& b) {
    return decodeHorizon(b.data(), static_cast<int>(b.size()), model, nc, 100, true, out);
  };
  horizon_t h = standingHorizon(1000, 20);
  addFootholds(h);
  ASSERT_EQ(decode(encode(h)), msg::Reject::None);
  EXPECT_EQ(out.nfootholds, 3);
  EXPECT_EQ(out.foothold[2], h.foothold[2]);
  EXPECT_EQ(out.foothold_source, h.foothold_source);
  // None at all, and the most the controller sends (4 per contact).
  EXPECT_EQ(decode(encode(standingHorizon(1000, 20))), msg::Reject::None);
  EXPECT_EQ(out.nfootholds, 0);
  horizon_t most = standingHorizon(1000, 20);
  most.nfootholds = msg::kHorizonFootholdsPerContact * nc;
  most.foothold_contact.assign(most.nfootholds, 3);
  most.foothold_time.assign(most.nfootholds, 0.5);
  most.foothold.assign(most.nfootholds, std::vector<double>{0.1, 0.2, 0.0});
  most.foothold_source.assign(most.nfootholds, 5);
  EXPECT_EQ(decode(encode(most)), msg::Reject::None);
  EXPECT_EQ(out.nfootholds, 16);

  // Counts: one more than 4 per contact, 2^31, negative, and one that disagrees with the size.
  horizon_t many = most;
  ++many.nfootholds;
  many.foothold_contact.push_back(0);
  many.foothold_time.push_back(0.5);
  many.foothold.push_back({0.0, 0.0, 0.0});
  many.foothold_source.push_back(0);
  EXPECT_EQ(decode(encode(many)), msg::Reject::WrongSize);
  horizon_t no_footholds = standingHorizon(1000, 20);
  const std::size_t count_at = encode(no_footholds).size() - 4;
  std::vector<unsigned char> b = encode(h);
  poke32(b, count_at, std::numeric_limits<std::int32_t>::max());
  EXPECT_EQ(decode(b), msg::Reject::WrongSize);
  poke32(b, count_at, -1);
  EXPECT_EQ(decode(b), msg::Reject::WrongSize);
  poke32(b, count_at, 2);  // 3 footholds' bytes follow
  EXPECT_EQ(decode(b), msg::Reject::WrongSize);
  b = encode(h);
  b.pop_back();  // truncated
  EXPECT_EQ(decode(b), msg::Reject::WrongSize);
  EXPECT_EQ(decode(std::vector<unsigned char>(b.begin(), b.begin() + count_at + 2)),
            msg::Reject::WrongSize);  // not even the count

  // Content: a fifth contact's, a negative contact, an unknown source, a time not after the
  // state, a NaN position, an infinite time.
  auto bad = [&](auto edit) {
    horizon_t m = standingHorizon(1000, 20);
    addFootholds(m);
    edit(m);
    return decode(encode(m));
  };
  EXPECT_EQ(bad([&](horizon_t& m) { m.foothold_contact[1] = nc; }), msg::Reject::BadField);
  EXPECT_EQ(bad([](horizon_t& m) { m.foothold_contact[0] = -1; }), msg::Reject::BadField);
  EXPECT_EQ(bad([](horizon_t& m) { m.foothold_source[2] = msg::kFootholdSources; }),
            msg::Reject::BadField);
  EXPECT_EQ(bad([](horizon_t& m) { m.foothold_source[2] = -1; }), msg::Reject::BadField);
  EXPECT_EQ(bad([](horizon_t& m) { m.foothold_time[0] = 0.0; }), msg::Reject::BadField);
  EXPECT_EQ(bad([](horizon_t& m) { m.foothold[1][2] = std::nan(""); }), msg::Reject::NonFinite);
  EXPECT_EQ(bad([](horizon_t& m) { m.foothold_time[2] = std::numeric_limits<double>::infinity(); }),
            msg::Reject::NonFinite);

  // Through the feed: counted by reason, the good plan kept.
  Feed feed(Channels{}, quadSource());
  const Channels ch;
  b = encode(h);
  poke32(b, count_at, std::numeric_limits<std::int32_t>::max());
  take(feed, ch.horizon, b);
  horizon_t fifth = h;
  fifth.foothold_contact[0] = nc;
  take(feed, ch.horizon, encode(fifth));
  EXPECT_EQ(feed.rejected(ch.horizon), 2);
  EXPECT_EQ(feed.accepted(ch.horizon), 0);
  EXPECT_TRUE(feed.frame(FrameKind::Plan).is_null());
}

TEST(Feed, StatesBeforeTheRobotIsKnownAreDropped) {
  RobotSource none;
  none.config_dirs = {"/nonexistent"};
  Feed feed(Channels{}, none);
  take(feed, Channels{}.state, encode(standingState(1000)));
  EXPECT_EQ(feed.rejected(Channels{}.state), 1);
  EXPECT_TRUE(feed.modelFrame().is_null());
  // The model names a robot that is not in the config folders: said, counted, nothing loaded.
  take(feed, Channels{}.model, encode(quadModel()));
  EXPECT_EQ(feed.rejected(Channels{}.model), 1);
  ASSERT_EQ(feed.warnings().size(), 1u);
  EXPECT_NE(feed.warnings()[0].find("stride_quad"), std::string::npos);
}

// The viewer only reads: a signed message (issue 33: a signature trailer after the LCM bytes) is
// taken as the plain one it carries, unverified; a signed state of another model is still refused.
TEST(Feed, SignedMessagesAreReadAsThePlainOnes) {
  Feed feed(Channels{}, quadSource());
  msg::Signer signer(msg::makeKey({9, 9, 9}), 4);
  const auto sign = [&](std::vector<unsigned char> b, const std::string& channel) {
    const int n = static_cast<int>(b.size());
    b.resize(b.size() + msg::kSignatureSize);
    b.resize(signer.sign(channel.c_str(), b.data(), n, static_cast<int>(b.size())));
    return b;
  };
  take(feed, Channels{}.model, sign(encode(quadModel()), Channels{}.model));
  ASSERT_NE(feed.robot(), nullptr);
  take(feed, Channels{}.state, sign(encode(standingState(1000)), Channels{}.state));
  EXPECT_EQ(feed.accepted(Channels{}.state), 1);
  EXPECT_EQ(feed.rejected(Channels{}.state), 0);
  robot_state_t other = standingState(2000);
  other.model_hash ^= 1;
  take(feed, Channels{}.state, sign(encode(other), Channels{}.state));
  EXPECT_EQ(feed.rejected(Channels{}.state), 1);
}

TEST(Feed, TheRobotIsFoundByTheNameOnTheWire) {
  RobotSource by_name;
  by_name.config_dirs = {"/nonexistent", STRIDE_CONFIG_DIR};
  Feed feed(Channels{}, by_name);
  take(feed, Channels{}.model, encode(quadModel()));
  ASSERT_NE(feed.robot(), nullptr);
  EXPECT_EQ(feed.robot()->name, "stride_quad");
  const Json model = feed.modelFrame();
  EXPECT_EQ(model["nq"], 19);
  EXPECT_EQ(model["joints"].size(), 13u);
  EXPECT_EQ(model["contacts"].size(), 4u);
  EXPECT_EQ(model["floating"], true);
  EXPECT_FALSE(model.contains("warning"));
  EXPECT_TRUE(feed.warnings().empty());
}

TEST(Feed, AHorizonGivesFeetFootholdsAndPlannedForces) {
  Feed feed(Channels{}, quadSource());
  take(feed, Channels{}.horizon, encode(standingHorizon(5000000, 30)));
  const Json plan = feed.frame(FrameKind::Plan);
  ASSERT_FALSE(plan.is_null());
  EXPECT_DOUBLE_EQ(plan["t"].get<double>(), 5.0);
  ASSERT_EQ(plan["base"].size(), 30u);
  EXPECT_NEAR(plan["base"][29][0].get<double>(), 0.029, 1e-9);
  ASSERT_EQ(plan["feet"].size(), 30u);
  ASSERT_EQ(plan["feet"][0].size(), 4u);
  for (const Json& foot : plan["feet"][0]) EXPECT_NEAR(foot[2].get<double>(), 0.0, 1e-6);
  // Stances start at knot 0 (all four) and at knot 20 (the two that lifted at knot 10).
  ASSERT_EQ(plan["footholds"].size(), 6u);
  EXPECT_EQ(plan["footholds"][4][3], 1);
  EXPECT_EQ(plan["footholds"][5][3], 2);
  EXPECT_NEAR(plan["footholds"][4][0].get<double>(), plan["feet"][20][1][0].get<double>(), 1e-9);
  ASSERT_EQ(plan["forces"].size(), 4u);
  EXPECT_DOUBLE_EQ(plan["forces"][0][2].get<double>(), 6.0);
  EXPECT_EQ(plan["chosen_footholds"], Json::array());  // this horizon chose none
  EXPECT_TRUE(feed.frame(FrameKind::Plan).is_null());  // framed once

  // The footholds the gait generator chose, as the horizon carries them: [x, y, z, contact, time
  // after t, source].
  horizon_t h = standingHorizon(5100000, 30);
  addFootholds(h);
  take(feed, Channels{}.horizon, encode(h));
  const Json chosen = feed.frame(FrameKind::Plan)["chosen_footholds"];
  ASSERT_EQ(chosen.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) EXPECT_DOUBLE_EQ(chosen[i][j].get<double>(), h.foothold[i][j]);
    EXPECT_EQ(chosen[i][3], h.foothold_contact[i]);
    EXPECT_DOUBLE_EQ(chosen[i][4].get<double>(), h.foothold_time[i]);
    EXPECT_EQ(chosen[i][5], h.foothold_source[i]);
  }
}

// The session log (stride-drive: the quadruped stands, then trots): the state frames of the
// standing second carry forces whose vertical sum is the robot's weight, within what its
// accelerations allow.
TEST(Feed, EstimatedForcesOfAStandingRobotCarryItsWeight) {
  const std::string log = sessionLog();
  ASSERT_FALSE(log.empty());
  Feed feed(Channels{}, quadSource());
  const LogDocument doc = readLog(log, feed, {}, Json::object());
  const double weight = quad().model.totalMass() * 9.81;
  int standing = 0;
  double t0 = -1;
  for (const Json& f : doc.document["frames"]) {
    if (f["type"] != "state") continue;
    if (t0 < 0) t0 = f["t"].get<double>();
    if (f["forces"].empty() || f["t"].get<double>() - t0 > 0.9) continue;
    double fz = 0;
    for (const Json& force : f["forces"]) fz += force[2].get<double>();
    EXPECT_NEAR(fz, weight, 0.25 * weight) << "t " << f["t"];
    ++standing;
  }
  EXPECT_GE(standing, 50);
  EXPECT_GT(feed.counters()["forces"]["estimated"].get<long>(), 0);
}

// A policy holding the default posture with feed-forward `u` on every joint and no gains: each
// gives the standing robot its own forces.
policy_t constantPolicy(std::int64_t utime, double u) {
  const Robot& r = quad();
  const int nu = r.model.nv - 6;
  policy_t p;
  msg::shape(p, 2, r.model.nq, r.model.nv, nu);
  p.utime = p.knot0_utime = utime;
  p.model_hash = modelHash(r);
  p.source_id = 1;
  p.tick = 0;
  p.t0 = 0.0;
  p.dt = 0.01;
  p.status = 0;
  for (int k = 0; k < 2; ++k) {
    std::copy(r.default_q.data(), r.default_q.data() + r.model.nq, p.x_ref[k].begin());
    std::fill(p.u_ff[k].begin(), p.u_ff[k].end(), u);
  }
  p.phase = 0b1111;
  return p;
}

// Which policy's torque a state's forces use: the answer to that state when it comes before the
// next state (a robot in lock-step waits for it), else the policy held when the state came (a
// robot in real time does not wait). Before the first policy, states are framed as they come.
TEST(Feed, AStateIsEstimatedWithThePolicyTheRobotApplied) {
  Feed feed(Channels{}, quadSource());
  const Channels ch;
  FrameBuilder reference(quad());
  auto forcesWith = [&](const policy_t& p, std::int64_t utime) {
    reference.setPolicy(p);
    return reference.state(standingState(utime))["forces"];
  };
  take(feed, ch.state, encode(standingState(1000)));
  ASSERT_EQ(feed.pendingUtime(FrameKind::State), 1000);  // no policy yet: framed as it comes
  EXPECT_EQ(feed.frame(FrameKind::State)["forces"], Json::array());

  // Lock-step: state, then its answer.
  const policy_t a = constantPolicy(1000, 0.0), b = constantPolicy(2000, 0.5);
  take(feed, ch.policy, encode(a));
  take(feed, ch.state, encode(standingState(2000)));
  EXPECT_EQ(feed.pendingUtime(FrameKind::State), -1) << "waits for its answer";
  take(feed, ch.policy, encode(b));
  ASSERT_EQ(feed.pendingUtime(FrameKind::State), 2000);
  const Json locked = feed.frame(FrameKind::State);
  EXPECT_EQ(locked["forces"], forcesWith(b, 2000));
  EXPECT_NE(locked["forces"], forcesWith(a, 2000));

  // Real time: a state, a policy answering an older state, the next state: the first state goes
  // with the policy held when it came (b), not the one that came after it (c).
  const policy_t c = constantPolicy(2500, -0.5);
  take(feed, ch.state, encode(standingState(3000)));
  take(feed, ch.policy, encode(c));
  EXPECT_EQ(feed.pendingUtime(FrameKind::State), -1);
  take(feed, ch.state, encode(standingState(4000)));
  ASSERT_EQ(feed.pendingUtime(FrameKind::State), 3000);
  const Json real_time = feed.frame(FrameKind::State);
  EXPECT_EQ(real_time["forces"], forcesWith(b, 3000));
  EXPECT_NE(real_time["forces"], forcesWith(c, 3000));
}

// mpc_status_t has no counts but three strings; lcm-gen's decoder reads 2^31 - 1 characters past
// the buffer for a length of -2^31 (found by the fuzzer, tests/fuzz): the lengths are checked on
// the bytes first (msg::checkStatusWire), whichever string and whatever the length.
TEST(Feed, StatusStringLengthsAreCheckedOnTheBytes) {
  Feed feed(Channels{}, quadSource());
  const std::string& ch = Channels{}.status;
  mpc_status_t st{};
  st.utime = 1000;
  st.wrong_model_cause = "cause";
  st.gait = "trot";
  st.jump_refusal = "why";
  const std::vector<unsigned char> good = encode(st);
  // wrong_model_cause's length field after 166 bytes of fixed fields (type hash included);
  // jump_refusal's before its 4 bytes and the 41 bytes of fixed fields after it; gait's before its
  // 5 bytes and the 37 fixed ones before jump_refusal's length.
  const std::size_t cause_at = 166, refusal_at = good.size() - 41 - 4 - 4,
                    gait_at = refusal_at - 37 - 5 - 4;
  long refused = 0;
  for (const std::size_t at : {cause_at, gait_at, refusal_at}) {
    for (const std::int32_t len : {std::numeric_limits<std::int32_t>::min(), -1, 0, 1000,
                                   std::numeric_limits<std::int32_t>::max()}) {
      std::vector<unsigned char> bad = good;
      poke32(bad, at, len);
      EXPECT_EQ(feed.take(ch, bad.data(), static_cast<int>(bad.size())), Feed::Took::None)
          << "length " << len << " at " << at;
      ++refused;
    }
  }
  std::vector<unsigned char> bad = good;
  bad[cause_at + 4 + 5] = 'x';  // "cause" without its NUL
  EXPECT_EQ(feed.take(ch, bad.data(), static_cast<int>(bad.size())), Feed::Took::None);
  bad = good;
  bad.push_back(0);  // one byte more than the strings imply
  EXPECT_EQ(feed.take(ch, bad.data(), static_cast<int>(bad.size())), Feed::Took::None);
  EXPECT_EQ(feed.rejected(ch), refused + 2);
  EXPECT_EQ(msg::checkStatusWire(good.data(), static_cast<int>(good.size())), msg::Reject::None);
  EXPECT_EQ(feed.take(ch, good.data(), static_cast<int>(good.size())), Feed::Took::Status);
  EXPECT_EQ(feed.frame(FrameKind::Status)["gait"], "trot");
}

// Stamps are the sender's: a policy at either end of int64 is taken and a state framed with it
// (the differences of stamps overflowed, undefined behaviour found by the message fuzzer).
TEST(Feed, PoliciesStampedAtTheEndsOfInt64AreTakenAndFramed) {
  const Channels ch;
  for (const std::int64_t stamp :
       {std::numeric_limits<std::int64_t>::min(), std::numeric_limits<std::int64_t>::max()}) {
    Feed feed(Channels{}, quadSource());
    take(feed, ch.horizon, encode(standingHorizon(1000, 20)));
    policy_t p = constantPolicy(1000, 0.0);
    p.utime = p.knot0_utime = stamp;
    EXPECT_EQ(feed.take(ch.policy, encode(p).data(), static_cast<int>(encode(p).size())),
              Feed::Took::Policy)
        << stamp;
    take(feed, ch.state, encode(standingState(2000)));
    take(feed, ch.state, encode(standingState(3000)));  // frames the first with the policy
    const Json state = feed.frame(FrameKind::State);
    ASSERT_FALSE(state.is_null()) << stamp;
    EXPECT_EQ(state["t"], 0.002) << stamp;
    EXPECT_FALSE(feed.frame(FrameKind::Plan).is_null()) << stamp;
  }
}

// Each refusal cause is said once, but a bus may carry any number of them (every model hash, every
// robot name): the warnings stop at Feed::kMaxWarnings, the last saying so; the counts go on.
TEST(Feed, WarningsAreBounded) {
  Feed feed(Channels{}, quadSource());
  const Channels ch;
  take(feed, ch.model, encode(quadModel()));
  testing::internal::CaptureStderr();
  for (int i = 0; i < 1000; ++i) {
    robot_model_t other = quadModel();
    other.robot = "robot_" + std::to_string(i);
    other.model_hash = i;
    take(feed, ch.model, encode(other));
    robot_state_t s = standingState(1000 + i);
    s.model_hash = 1000000 + i;
    take(feed, ch.state, encode(s));
  }
  const std::string err = testing::internal::GetCapturedStderr();
  ASSERT_EQ(feed.warnings().size(), Feed::kMaxWarnings);
  EXPECT_NE(feed.warnings().back().find("the later ones are not kept"), std::string::npos)
      << feed.warnings().back();
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), static_cast<long>(Feed::kMaxWarnings));
  EXPECT_EQ(feed.rejected(ch.model), 1000);
  EXPECT_EQ(feed.rejected(ch.state), 1000);
  // Still accepting what is good.
  take(feed, ch.state, encode(standingState(5000)));
  EXPECT_EQ(feed.accepted(ch.state), 1);
}

// stride-viz --all-frames (LogOptions of rate 0): every accepted state and plan of the log is a
// frame (the horizons come at 10 Hz, under the default plan rate); by default the 200 Hz states
// are decimated to 100 per second.
TEST(Feed, RatesOfZeroKeepEveryFrameOfTheLog) {
  const std::string log = sessionLog();
  ASSERT_FALSE(log.empty());
  const auto count = [&](const LogOptions& options, Json& counters) {
    Feed feed(Channels{}, quadSource());
    const LogDocument doc = readLog(log, feed, options, Json::object());
    counters = feed.counters();
    std::map<std::string, long> n;
    for (const Json& f : doc.document["frames"]) ++n[f["type"].get<std::string>()];
    return n;
  };
  Json counters;
  const auto all = count({0.0, 0.0, 0.0}, counters);
  const long states = counters["channels"][Channels{}.state]["accepted"].get<long>();
  const long horizons = counters["channels"][Channels{}.horizon]["accepted"].get<long>();
  EXPECT_EQ(all.at("state"), states);
  EXPECT_GE(all.at("plan"), horizons);  // and the policies' plans between horizons
  const auto decimated = count({}, counters);
  EXPECT_LT(decimated.at("state"), states);
}

// An elevation map (terrain_t) becomes one terrain frame: its numbers as the page draws them,
// heights row-major, null for unknown cells; it needs no robot.
TEST(Feed, ATerrainMapBecomesATerrainFrame) {
  RobotSource none;
  none.config_dirs = {"/nonexistent"};
  Feed feed(Channels{}, none);
  const std::string& ch = Channels{}.terrain;
  const terrain_t map = boxStepMap(2500000, 100, 100, 1.0, -0.5);
  EXPECT_EQ(feed.take(ch, encode(map).data(), static_cast<int>(encode(map).size())),
            Feed::Took::Terrain);
  EXPECT_EQ(feed.pendingUtime(FrameKind::Terrain), 2500000);
  const Json f = feed.frame(FrameKind::Terrain);
  ASSERT_FALSE(f.is_null());
  EXPECT_EQ(f["type"], "terrain");
  EXPECT_DOUBLE_EQ(f["t"].get<double>(), 2.5);
  EXPECT_DOUBLE_EQ(f["origin_x"].get<double>(), 0.01);
  EXPECT_DOUBLE_EQ(f["origin_y"].get<double>(), -1.49);
  EXPECT_DOUBLE_EQ(f["resolution"].get<double>(), 0.02);
  EXPECT_EQ(f["rows"], 100);
  EXPECT_EQ(f["cols"], 100);
  const Json& h = f["heights"];
  ASSERT_EQ(h.size(), 100u * 100u);
  int unknown = 0, step = 0;
  for (int r = 0; r < 100; ++r)
    for (int c = 0; c < 100; ++c) {
      const Json& cell = h[static_cast<std::size_t>(r) * 100 + c];
      if (std::isnan(map.height[r][c])) {
        EXPECT_TRUE(cell.is_null()) << r << " " << c;
        ++unknown;
        continue;
      }
      ASSERT_TRUE(cell.is_number()) << r << " " << c;
      EXPECT_EQ(cell.get<double>(), map.height[r][c] != 0.0f ? 0.05 : 0.0) << r << " " << c;
      step += map.height[r][c] != 0.0f;
    }
  EXPECT_EQ(unknown, 25);
  // x > 0.3 m: columns 15..99 (x from 0.01 m).
  EXPECT_EQ(step, 100 * 85);
  EXPECT_TRUE(feed.frame(FrameKind::Terrain).is_null());  // framed once
  EXPECT_EQ(feed.pendingUtime(FrameKind::Terrain), -1);
  EXPECT_EQ(feed.accepted(ch), 1);
  EXPECT_EQ(feed.counters()["channels"][ch]["accepted"], 1);
}

// Malformed maps are refused, counted by reason, and change nothing: the next frame is of the last
// good map.
TEST(Feed, MalformedMapsAreRefusedAndCounted) {
  Feed feed(Channels{}, quadSource());
  const std::string& ch = Channels{}.terrain;
  const auto takeMap = [&](const std::vector<unsigned char>& b) {
    return feed.take(ch, b.data(), static_cast<int>(b.size()));
  };
  ASSERT_EQ(takeMap(encode(boxStepMap(2000000, 30, 40))), Feed::Took::Terrain);
  std::vector<unsigned char> b = encode(boxStepMap(2100000, 30, 40));
  b.resize(b.size() - 4);  // a cell short
  EXPECT_EQ(takeMap(b), Feed::Took::None);
  b = encode(boxStepMap(2100000, 30, 40));
  poke32(b, 8 + 32, 600);  // 600 x 40 cells claimed, 30 x 40 sent
  EXPECT_EQ(takeMap(b), Feed::Took::None);
  EXPECT_EQ(takeMap(encode(boxStepMap(2100000, 513, 512))), Feed::Took::None);  // over 512 x 512
  terrain_t bad = boxStepMap(2100000, 30, 40);
  bad.resolution = 0.0;
  EXPECT_EQ(takeMap(encode(bad)), Feed::Took::None);
  bad.resolution = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(takeMap(encode(bad)), Feed::Took::None);
  bad = boxStepMap(2100000, 30, 40);
  bad.height[3][4] = -std::numeric_limits<float>::infinity();
  EXPECT_EQ(takeMap(encode(bad)), Feed::Took::None);
  bad = boxStepMap(-1, 30, 40);
  EXPECT_EQ(takeMap(encode(bad)), Feed::Took::None);
  EXPECT_EQ(takeMap(encode(boxStepMap(1900000, 30, 40))), Feed::Took::None);  // older
  // Another type on the channel.
  std::vector<unsigned char> state = encode(standingState(2100000));
  EXPECT_EQ(takeMap(state), Feed::Took::None);

  EXPECT_EQ(feed.accepted(ch), 1);
  EXPECT_EQ(feed.rejected(ch), 9);
  const Json r = feed.counters()["channels"][ch]["rejected"];
  EXPECT_EQ(r[msg::describe(msg::Reject::WrongSize)], 3) << r;
  EXPECT_EQ(r[msg::describe(msg::Reject::BadField)], 3) << r;
  EXPECT_EQ(r[msg::describe(msg::Reject::NonFinite)], 1) << r;
  EXPECT_EQ(r[msg::describe(msg::Reject::OutOfOrder)], 1) << r;
  EXPECT_EQ(r[msg::describe(msg::Reject::Undecodable)], 1) << r;
  const Json f = feed.frame(FrameKind::Terrain);
  ASSERT_FALSE(f.is_null());
  EXPECT_DOUBLE_EQ(f["t"].get<double>(), 2.0);
  EXPECT_EQ(f["rows"], 30);
  // A map stamped more than a second before the last is a restarted robot's: followed.
  EXPECT_EQ(takeMap(encode(boxStepMap(500000, 30, 40))), Feed::Took::Terrain);
}

// From a log, maps are framed at most kTerrainFrameRate a second of log time (10 Hz maps for 3 s:
// the ones at 0, 0.5, ..., 2.5 s), whatever --all-frames does to the other kinds.
TEST(Feed, LogMapsAreFramedTwiceASecond) {
  char dir[] = "/tmp/stride-viz-terrain-XXXXXX";
  ASSERT_NE(::mkdtemp(dir), nullptr);
  const std::string path = std::string(dir) + "/maps.lcmlog";
  {
    lcm::LogFile log(path, "w");
    ASSERT_TRUE(log.good());
    for (int i = 0; i < 30; ++i) {
      const std::vector<unsigned char> bytes =
          encode(boxStepMap(100000 * i, 20, 25, 0.01 * i, 0.0));
      lcm::LogEvent e{};
      e.eventnum = i;
      e.timestamp = 100000 * i;
      e.channel = Channels{}.terrain;
      e.datalen = static_cast<std::int32_t>(bytes.size());
      e.data = const_cast<unsigned char*>(bytes.data());
      ASSERT_EQ(log.writeEvent(&e), 0);
    }
  }
  for (const LogOptions& options : {LogOptions{}, LogOptions{0.0, 0.0, 0.0}}) {
    Feed feed(Channels{}, quadSource());
    const LogDocument doc = readLog(path, feed, options, Json::object());
    std::vector<double> times;
    for (const Json& f : doc.document["frames"]) {
      ASSERT_EQ(f["type"], "terrain");
      times.push_back(f["t"].get<double>());
      const int i = static_cast<int>(std::lround(f["t"].get<double>() * 10));
      EXPECT_NEAR(f["origin_x"].get<double>(), 0.01 * i - 0.24, 1e-9);
      EXPECT_EQ(f["heights"].size(), 20u * 25u);
    }
    EXPECT_EQ(times, (std::vector<double>{0.0, 0.5, 1.0, 1.5, 2.0, 2.5}));
    EXPECT_EQ(feed.accepted(Channels{}.terrain), 30);
  }
  std::filesystem::remove_all(dir);
}

TEST(RobotFiles, TheUrdfNamesOnlyTheServersUrls) {
  Robot solo = loadRobot(std::string(STRIDE_CONFIG_DIR) + "/robots/solo12/solo12.yaml",
                         {STRIDE_ROBOT_PACKAGES});
  const RobotFiles files = rewriteUrdf(solo.urdf_path, {STRIDE_ROBOT_PACKAGES});
  EXPECT_EQ(files.urdf.find("package://"), std::string::npos);
  ASSERT_FALSE(files.files.empty());
  for (std::size_t i = 0; i < files.files.size(); ++i) {
    const std::string url = robotFileUrl(static_cast<int>(i), files.files[i]);
    EXPECT_NE(files.urdf.find("filename=\"" + url + "\""), std::string::npos) << url;
    EXPECT_EQ(files.files[i].url_name.find('/'), std::string::npos);
  }
  // Every file named once, whatever the number of links using it.
  for (std::size_t i = 0; i < files.files.size(); ++i)
    for (std::size_t j = i + 1; j < files.files.size(); ++j)
      EXPECT_NE(files.files[i].name, files.files[j].name);
  // The URDF is still one urdfdom reads: the same robot.
  EXPECT_NE(files.urdf.find("<robot"), std::string::npos);
}

TEST(RobotFiles, ANameFromTheWireNeverLeavesTheConfigFolders) {
  const std::vector<std::string> dirs = {STRIDE_CONFIG_DIR};
  EXPECT_EQ(findRobotYaml("stride_quad", dirs), quadYaml());
  std::vector<std::string> tried;
  for (const char* name : {"../stride_quad", "stride_quad/../stride_quad", "", ".", "a b"}) {
    EXPECT_EQ(findRobotYaml(name, dirs, &tried), "") << name;
  }
  EXPECT_TRUE(tried.empty());  // refused before looking anywhere
}

}  // namespace test_feed
}  // namespace stride::viz
