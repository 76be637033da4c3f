// The commanded robot's references, against times and positions computed by hand:
//   ContactTimeline  a trot (support 0.1 s, swing 0.2 s) played from 0: which feet are down, when
//                    they change, gait switches at the next all-feet-down phase (replaced,
//                    cancelled), per foot to and from patterns that never have every foot
//                    down (a pronk), refused when a foot could never join, across segment
//                    boundaries, forgetting the past;
//   GaitGenerator    on the in-house quadruped (stride_quad): the base reference of a straight
//                    line, a pure turn, a ramp, a body height change and the joint posture that
//                    keeps the feet in place at that height; footholds at mid-stance and
//                    the swing arcs between them; a gait switch at a phase boundary; feet latched
//                    where they were measured; the Raibert correction of the next touch-down only;
//                    the leash of the base reference and of the footholds; bad input refused.
// The allocation-free tick (plan, queries, switches, LocomotionProblem::update) is checked in
// test_locomotion_no_alloc.cpp, whose binary counts allocations.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "config/robot_config.hpp"
#include "locomotion/gait_generator.hpp"
#include "solver/multibody/center_of_mass.hpp"
#include "solver/multibody/frames.hpp"
#include "terrain/steppability.hpp"

namespace stride {
namespace test_gait_generator {

constexpr double kPi = 3.14159265358979323846;
constexpr double kNever = ContactTimeline::kNever;
constexpr double kTime = 1e-12;  // sums of phase durations carry rounding (0.1 + 0.2 != 0.3)

// Contacts in the robot YAML's order.
constexpr int FL = 0, FR = 1, HL = 2, HR = 3;
const char* const kFeet[] = {"FL_foot", "FR_foot", "HL_foot", "HR_foot"};

struct Quad {
  Robot robot;
  ContactSet contacts;
  Eigen::VectorXd x_nominal;
};

const Quad& quad() {
  static const Quad q = [] {
    Quad r;
    r.robot = loadRobot(std::string(STRIDE_CONFIG_DIR) + "/robots/stride_quad/stride_quad.yaml");
    for (const char* foot : kFeet)
      r.contacts.add(r.robot.model, foot, 3, ReferenceFrame::LocalWorldAligned);
    r.x_nominal = Eigen::VectorXd::Zero(r.robot.model.nq + r.robot.model.nv);
    r.x_nominal.head(r.robot.model.nq) = r.robot.default_q;
    return r;
  }();
  return q;
}

std::vector<std::string> feetExcept(std::initializer_list<int> lifted) {
  std::vector<std::string> closed;
  for (int c = 0; c < 4; ++c)
    if (std::find(lifted.begin(), lifted.end(), c) == lifted.end()) closed.push_back(kFeet[c]);
  return closed;
}

// [0, .1) all feet, [.1, .3) FL + HR up, [.3, .4) all, [.4, .6) FR + HL up, repeating.
ContactPlan trot() {
  ContactPlan p;
  p.cyclic = true;
  p.phases = {{0.1, feetExcept({})},
              {0.2, feetExcept({FL, HR})},
              {0.1, feetExcept({})},
              {0.2, feetExcept({FR, HL})}};
  return p;
}
// The same timing with the left pair, then the right pair up.
ContactPlan pace() {
  ContactPlan p = trot();
  p.phases[1].contacts = feetExcept({FL, HL});
  p.phases[3].contacts = feetExcept({FR, HR});
  return p;
}
ContactPlan stand() {
  ContactPlan p;
  p.cyclic = true;
  p.phases = {{0.5, feetExcept({})}};
  return p;
}

// ============================================================================ ContactTimeline

struct Timeline {
  ContactTimeline tl{quad().contacts};
  int trot = tl.addPattern(test_gait_generator::trot());
  int stand = tl.addPattern(test_gait_generator::stand());
  int pace = tl.addPattern(test_gait_generator::pace());
};

TEST(ContactTimeline, TrotQueries) {
  Timeline T;
  ContactTimeline& tl = T.tl;
  tl.reset(T.trot, 0.0);
  EXPECT_EQ(tl.patterns(), 3);
  EXPECT_EQ(tl.contacts(), 4);
  EXPECT_EQ(tl.patternAt(0.3), T.trot);

  // closed: a boundary counts as after it (a knot time 0.1 = 10 × 0.01 included).
  EXPECT_TRUE(tl.closed(FL, 0.0));
  EXPECT_TRUE(tl.closed(FL, 0.05));
  EXPECT_FALSE(tl.closed(FL, 0.1));
  EXPECT_FALSE(tl.closed(FL, 10 * 0.01));
  EXPECT_FALSE(tl.closed(HR, 0.2));
  EXPECT_TRUE(tl.closed(FR, 0.2));
  EXPECT_TRUE(tl.closed(FL, 0.3));
  EXPECT_TRUE(tl.closed(FL, 0.5));
  EXPECT_FALSE(tl.closed(FR, 0.5));
  EXPECT_FALSE(tl.closed(HL, 0.5));
  EXPECT_TRUE(tl.closed(FR, 0.6));
  EXPECT_FALSE(tl.closed(FL, 0.6 + 0.2));    // second cycle
  EXPECT_FALSE(tl.closed(FL, 60.0 + 0.15));  // the hundred-and-first

  // mask: bit c for contact c.
  EXPECT_EQ(tl.mask(0.05), 0xfu);
  EXPECT_EQ(tl.mask(0.2), (1u << FR) | (1u << HL));
  EXPECT_EQ(tl.mask(0.35), 0xfu);
  EXPECT_EQ(tl.mask(0.5), (1u << FL) | (1u << HR));
  EXPECT_EQ(tl.mask(0.6 + 0.5), (1u << FL) | (1u << HR));

  // nextChange: the first change after t (a change at t itself is past).
  EXPECT_NEAR(tl.nextChange(FL, 0.0), 0.1, kTime);
  EXPECT_NEAR(tl.nextChange(FL, 0.1), 0.3, kTime);
  EXPECT_NEAR(tl.nextChange(FL, 0.2), 0.3, kTime);
  EXPECT_NEAR(tl.nextChange(FL, 0.3), 0.7, kTime);  // down through the FR-HL swing: lifts at 0.7
  EXPECT_NEAR(tl.nextChange(FR, 0.0), 0.4, kTime);
  EXPECT_NEAR(tl.nextChange(FR, 0.45), 0.6, kTime);
  EXPECT_NEAR(tl.nextChange(HL, 6.45), 6.6, kTime);

  // lastChange: the last change at or before t, or the segment's start.
  EXPECT_NEAR(tl.lastChange(FL, 0.05), 0.0, kTime);
  EXPECT_NEAR(tl.lastChange(FL, 0.1), 0.1, kTime);
  EXPECT_NEAR(tl.lastChange(FL, 0.2), 0.1, kTime);
  EXPECT_NEAR(tl.lastChange(FL, 0.35), 0.3, kTime);
  EXPECT_NEAR(tl.lastChange(FL, 0.65), 0.3, kTime);  // down from 0.3 to 0.7, across the cycle
  EXPECT_NEAR(tl.lastChange(FR, 0.5), 0.4, kTime);
  EXPECT_NEAR(tl.lastChange(FR, 0.65), 0.6, kTime);
  EXPECT_NEAR(tl.lastChange(HR, 6.2), 6.1, kTime);

  // Played from another start: everything moves with it.
  tl.reset(T.trot, 2.0);
  EXPECT_TRUE(tl.closed(FL, 2.05));
  EXPECT_FALSE(tl.closed(FL, 2.15));
  EXPECT_NEAR(tl.nextChange(FL, 2.0), 2.1, kTime);
  EXPECT_NEAR(tl.lastChange(FR, 2.5), 2.4, kTime);
}

TEST(ContactTimeline, SwitchAtTheNextAllFeetDownPhase) {
  Timeline T;
  ContactTimeline& tl = T.tl;
  // Requested in the FL-HR swing: switches when that swing ends, at 0.3.
  tl.reset(T.trot, 0.0);
  EXPECT_NEAR(tl.switchTo(T.stand, 0.15), 0.3, kTime);
  EXPECT_EQ(tl.lastPattern(), T.stand);
  EXPECT_NEAR(tl.lastSwitch(), 0.3, kTime);
  EXPECT_EQ(tl.patternAt(0.2), T.trot);
  EXPECT_EQ(tl.patternAt(0.3), T.stand);
  EXPECT_FALSE(tl.closed(FL, 0.2));  // the swing in progress finishes
  EXPECT_EQ(tl.mask(0.29), (1u << FR) | (1u << HL));
  for (double t = 0.3; t < 10.0; t += 0.01) EXPECT_EQ(tl.mask(t), 0xfu) << t;
  EXPECT_NEAR(tl.nextChange(FL, 0.15), 0.3, kTime);  // lands, and never lifts again
  EXPECT_EQ(tl.nextChange(FL, 0.3), kNever);
  EXPECT_EQ(tl.nextChange(FR, 0.15), kNever);       // the trot would have lifted it at 0.4
  EXPECT_NEAR(tl.lastChange(FR, 0.5), 0.3, kTime);  // the stand's segment starts at 0.3

  // Requested exactly at the start of an all-feet-down phase: there and then.
  tl.reset(T.trot, 0.0);
  EXPECT_NEAR(tl.switchTo(T.stand, 0.3), 0.3, kTime);
  EXPECT_TRUE(tl.closed(HL, 0.45));
  // Requested inside one (past its start): the next one, at 0.6.
  tl.reset(T.trot, 0.0);
  EXPECT_NEAR(tl.switchTo(T.stand, 0.35), 0.6, kTime);
  EXPECT_FALSE(tl.closed(FR, 0.45));
  EXPECT_TRUE(tl.closed(FR, 0.6));
  EXPECT_TRUE(tl.closed(FR, 0.75));

  // From a stand (every phase has every foot down): at once, the trot's phase 0 there.
  tl.reset(T.stand, 0.0);
  EXPECT_DOUBLE_EQ(tl.switchTo(T.trot, 1.234), 1.234);
  EXPECT_TRUE(tl.closed(FL, 1.234 + 0.05));
  EXPECT_FALSE(tl.closed(FL, 1.234 + 0.15));
  EXPECT_FALSE(tl.closed(FR, 1.234 + 0.5));
  EXPECT_NEAR(tl.nextChange(FL, 1.234), 1.334, kTime);
  EXPECT_NEAR(tl.lastChange(FR, 1.234 + 0.45), 1.634, kTime);
}

TEST(ContactTimeline, PendingSwitchReplacedOrCancelled) {
  Timeline T;
  ContactTimeline& tl = T.tl;
  tl.reset(T.trot, 0.0);
  ASSERT_NEAR(tl.switchTo(T.stand, 0.15), 0.3, kTime);
  // Another request before 0.3 replaces it: a pace from 0.3 instead of the stand.
  EXPECT_NEAR(tl.switchTo(T.pace, 0.2), 0.3, kTime);
  EXPECT_EQ(tl.lastPattern(), T.pace);
  EXPECT_EQ(tl.patternAt(0.35), T.pace);
  EXPECT_FALSE(tl.closed(HL, 0.45));  // the pace lifts the left pair at 0.4
  EXPECT_TRUE(tl.closed(FR, 0.45));
  // Across the boundary: FL lands at 0.3 (the trot's swing), lifts at 0.4 (the pace's).
  EXPECT_NEAR(tl.nextChange(FL, 0.2), 0.3, kTime);
  EXPECT_NEAR(tl.nextChange(FL, 0.3), 0.4, kTime);
  // Asking for the pattern in force cancels the pending switch.
  EXPECT_DOUBLE_EQ(tl.switchTo(T.trot, 0.25), 0.25);
  EXPECT_EQ(tl.lastPattern(), T.trot);
  EXPECT_DOUBLE_EQ(tl.lastSwitch(), 0.0);
  EXPECT_EQ(tl.patternAt(0.5), T.trot);
  EXPECT_FALSE(tl.closed(FR, 0.45));
  EXPECT_TRUE(tl.closed(HL, 0.35));
  EXPECT_NEAR(tl.nextChange(FL, 0.3), 0.7, kTime);
  // A switch already in force at t is not pending: asking for the pattern before it is a new
  // switch, at the stand's next instant (at once).
  ASSERT_NEAR(tl.switchTo(T.stand, 0.15), 0.3, kTime);
  EXPECT_DOUBLE_EQ(tl.switchTo(T.trot, 0.5), 0.5);
  EXPECT_EQ(tl.patternAt(0.4), T.stand);
  EXPECT_EQ(tl.patternAt(0.5), T.trot);
  EXPECT_FALSE(tl.closed(FL, 0.65));
}

TEST(ContactTimeline, NextChangeAcrossSegments) {
  Timeline T;
  ContactTimeline& tl = T.tl;
  tl.reset(T.stand, 0.0);
  ASSERT_DOUBLE_EQ(tl.switchTo(T.trot, 1.0), 1.0);
  EXPECT_NEAR(tl.nextChange(FL, 0.5), 1.1, kTime);  // the stand never changes; the trot does
  EXPECT_NEAR(tl.nextChange(FR, 0.5), 1.4, kTime);
  EXPECT_NEAR(tl.lastChange(FL, 1.05), 1.0, kTime);
  EXPECT_NEAR(tl.lastChange(FL, 0.5), 0.0, kTime);
  // Back to a stand requested during the FR-HL swing (1.4-1.6): FR lands at 1.6 for good.
  ASSERT_NEAR(tl.switchTo(T.stand, 1.45), 1.6, kTime);
  EXPECT_NEAR(tl.nextChange(FR, 1.45), 1.6, kTime);
  EXPECT_EQ(tl.nextChange(FR, 1.6), kNever);
  EXPECT_EQ(tl.nextChange(FL, 1.45), kNever);       // down from 1.3, stays down
  EXPECT_NEAR(tl.nextChange(FL, 0.5), 1.1, kTime);  // still: three segments now
  EXPECT_EQ(tl.mask(1.5), (1u << FL) | (1u << HR));
  EXPECT_EQ(tl.mask(1.6), 0xfu);
}

// Per-foot switches (issue 45): to and from patterns with no instant of every foot down, each foot
// joining the new pattern when it is down both as it goes and in the new pattern.
TEST(ContactTimeline, PerFootSwitchNeverCutsASwing) {
  Timeline T;
  ContactTimeline& tl = T.tl;
  // Never every foot down: the trot without its all-feet phases (FL-HR up for 0.2 s, FR-HL up).
  ContactPlan lifted;
  lifted.cyclic = true;
  lifted.phases = {{0.2, feetExcept({FL, HR})}, {0.2, feetExcept({FR, HL})}};
  const int bad = tl.addPattern(lifted);

  // Into it, asked in the trot's FL-HR swing: its clock starts at the trot's next all-feet phase
  // (0.3). FR and HL are down in both there and join at once; FL and HR, just landed, would be up
  // in its first phase: they stay down (the trot's) and join when it puts them down, at 0.5.
  tl.reset(T.trot, 0.0);
  EXPECT_NEAR(tl.switchTo(bad, 0.15), 0.3, kTime);
  EXPECT_EQ(tl.patternAt(0.35), bad);
  EXPECT_NEAR(tl.lastJoin(FR), 0.3, kTime);
  EXPECT_NEAR(tl.lastJoin(FL), 0.5, kTime);
  EXPECT_FALSE(tl.closed(FL, 0.2));  // the swing in progress finishes
  EXPECT_EQ(tl.mask(0.35), 0xfu);
  EXPECT_EQ(tl.mask(0.45), 0xfu);  // the trot would have lifted FR-HL, the new pattern FL-HR
  EXPECT_EQ(tl.mask(0.55), (1u << FL) | (1u << HR));
  EXPECT_EQ(tl.mask(0.75), (1u << FR) | (1u << HL));
  EXPECT_NEAR(tl.nextChange(FL, 0.2), 0.3, kTime);  // lands at 0.3, next lifts at 0.7
  EXPECT_NEAR(tl.nextChange(FL, 0.3), 0.7, kTime);
  EXPECT_NEAR(tl.nextChange(FR, 0.35), 0.5, kTime);
  EXPECT_NEAR(tl.lastChange(FR, 0.45), 0.3, kTime);  // joined at 0.3
  EXPECT_FALSE(tl.standsAt(10.0));

  // Out of it, asked in its FL-HR swing: its next phase start (0.2; it has no all-feet phase).
  // FL and HR land there and join the stand; FR and HL, lifted at 0.2, land at 0.4 and join.
  tl.reset(bad, 0.0);
  EXPECT_NEAR(tl.switchTo(T.stand, 0.05), 0.2, kTime);
  EXPECT_EQ(tl.mask(0.1), (1u << FR) | (1u << HL));
  EXPECT_EQ(tl.mask(0.3), (1u << FL) | (1u << HR));
  EXPECT_FALSE(tl.standsAt(0.3));
  for (double t = 0.4; t < 5.0; t += 0.01) EXPECT_EQ(tl.mask(t), 0xfu) << t;
  EXPECT_TRUE(tl.standsAt(0.4));
  EXPECT_NEAR(tl.nextChange(FR, 0.25), 0.4, kTime);
  EXPECT_EQ(tl.nextChange(FR, 0.4), kNever);
  EXPECT_EQ(tl.nextChange(FL, 0.05), 0.2);
  EXPECT_EQ(tl.nextChange(FL, 0.2), kNever);

  // A pronk's flight (every foot up) and back to the trot at the pronk's next all-feet phase.
  ContactPlan pronk;
  pronk.cyclic = true;
  pronk.phases = {{0.1, feetExcept({})}, {0.2, feetExcept({FL, FR, HL, HR})}};
  const int hop = tl.addPattern(pronk);
  tl.reset(T.trot, 0.0);
  ASSERT_NEAR(tl.switchTo(hop, 0.15), 0.3, kTime);
  EXPECT_EQ(tl.mask(0.35), 0xfu);
  EXPECT_EQ(tl.mask(0.45), 0u);
  EXPECT_NEAR(tl.nextChange(HL, 0.45), 0.6, kTime);
  EXPECT_NEAR(tl.switchTo(T.trot, 0.45), 0.6, kTime);  // lands from the flight, then trots
  EXPECT_EQ(tl.mask(0.55), 0u);
  EXPECT_EQ(tl.mask(0.65), 0xfu);
  EXPECT_EQ(tl.mask(0.75), (1u << FR) | (1u << HL));
}

TEST(ContactTimeline, RefusesASwitchAFootCouldNotJoin) {
  Timeline T;
  ContactTimeline& tl = T.tl;
  ContactPlan three_legs;  // FL never down
  three_legs.cyclic = true;
  three_legs.phases = {{0.3, feetExcept({FL})}};
  const int limp = tl.addPattern(three_legs);  // compiles: it can still be played from a reset
  tl.reset(T.trot, 0.0);
  ASSERT_NEAR(tl.switchTo(T.stand, 0.15), 0.3, kTime);  // pending
  EXPECT_EQ(tl.switchTo(limp, 0.2), kNever);
  // Nothing changed: the stand is still pending at 0.3.
  EXPECT_EQ(tl.lastPattern(), T.stand);
  EXPECT_NEAR(tl.lastSwitch(), 0.3, kTime);
  EXPECT_EQ(tl.patternAt(0.2), T.trot);
  EXPECT_EQ(tl.mask(0.5), 0xfu);
  EXPECT_EQ(tl.switchTo(99, 0.2), kNever);  // no such pattern
  EXPECT_EQ(tl.lastPattern(), T.stand);

  // A pattern in force that never puts FL down cannot be left either.
  tl.reset(limp, 0.0);
  EXPECT_EQ(tl.switchTo(T.stand, 0.05), kNever);
  EXPECT_EQ(tl.lastPattern(), limp);
  EXPECT_EQ(tl.mask(0.05), 0xeu);
}

TEST(ContactTimeline, Forget) {
  Timeline T;
  ContactTimeline& tl = T.tl;
  tl.reset(T.stand, 0.0);
  ASSERT_DOUBLE_EQ(tl.switchTo(T.trot, 1.0), 1.0);
  ASSERT_NEAR(tl.switchTo(T.stand, 1.15), 1.3, kTime);  // stand 0-1, trot 1-1.3, stand from 1.3
  tl.forget(0.5);                                       // nothing ended before 0.5
  EXPECT_EQ(tl.patternAt(0.5), T.stand);
  EXPECT_EQ(tl.patternAt(1.1), T.trot);
  tl.forget(1.2);  // the first stand ended at 1.0: gone; the trot is in force at 1.2
  EXPECT_EQ(tl.patternAt(1.2), T.trot);
  EXPECT_FALSE(tl.closed(FL, 1.2));
  EXPECT_NEAR(tl.lastChange(FL, 1.2), 1.1, kTime);
  EXPECT_NEAR(tl.nextChange(FL, 1.2), 1.3, kTime);
  EXPECT_EQ(tl.lastPattern(), T.stand);
  tl.forget(1.35);                        // the trot ended at 1.3
  EXPECT_EQ(tl.patternAt(1.1), T.stand);  // the earliest segment known now
  EXPECT_EQ(tl.patternAt(1.35), T.stand);
  EXPECT_NEAR(tl.lastChange(FL, 2.0), 1.3, kTime);
  tl.forget(100.0);  // the segment in force stays
  EXPECT_EQ(tl.patternAt(100.0), T.stand);
  EXPECT_EQ(tl.mask(100.0), 0xfu);
}

// More switches than segments kept: the oldest are dropped, the newest still answer.
TEST(ContactTimeline, ManySwitchesWithoutForget) {
  Timeline T;
  ContactTimeline& tl = T.tl;
  tl.reset(T.stand, 0.0);
  for (int i = 0; i < 3 * ContactTimeline::kMaxSegments; ++i) {
    const double t = 1.0 + i;
    const int to = i % 2 == 0 ? T.trot : T.stand;
    // From a stand at once; from the trot (requested 0.15 into its cycle) at 0.3 into it.
    const double expected = i % 2 == 0 ? t : t - 1.0 + 0.3;
    const double request = i % 2 == 0 ? t : t - 1.0 + 0.15;
    ASSERT_NEAR(tl.switchTo(to, request), expected, kTime) << i;
    EXPECT_EQ(tl.lastPattern(), to);
    EXPECT_EQ(tl.patternAt(expected + 0.01), to);
  }
  // The last two: a trot at 3K - 1, a stand from 3K - 0.7 (K segments kept).
  const double trot_at = 3.0 * ContactTimeline::kMaxSegments - 1.0;
  EXPECT_FALSE(tl.closed(FL, trot_at + 0.2));
  EXPECT_TRUE(tl.closed(FL, trot_at + 0.4));
  EXPECT_NEAR(tl.nextChange(FL, trot_at + 0.2), trot_at + 0.3, kTime);
}

// ============================================================================ GaitGenerator

GaitGeneratorOptions hand() {
  GaitGeneratorOptions o;
  o.swing_height = 0.05;
  o.foothold_gain = 0.0;
  o.max_position_lead = 100.0;
  o.max_yaw_lead = 100.0;
  o.max_foothold_lead = 100.0;
  o.horizon = 1.0;
  o.sample_dt = 0.01;
  return o;
}

// The quadruped's nominal posture, computed: foot positions and orientations, CoM, base height.
struct Nominal {
  Eigen::Vector3d foot[4];
  Eigen::Matrix3d foot_R[4];
  Eigen::Vector3d com;
  double z;
  Nominal() {
    const Quad& r = quad();
    Data data(r.robot.model);
    const Eigen::VectorXd q = r.x_nominal.head(r.robot.model.nq);
    framesForwardKinematics(r.robot.model, data, q);
    for (int c = 0; c < 4; ++c) {
      foot[c] = data.oMf[r.contacts[c].frame].p;
      foot_R[c] = data.oMf[r.contacts[c].frame].R;
    }
    com = centerOfMass(r.robot.model, data, q);
    z = q[2];
  }
};

struct Generator {
  std::unique_ptr<GaitGenerator> gen;
  int trot = 0, stand = 0;
  explicit Generator(const GaitGeneratorOptions& o = hand(),
                     const ContactPlan& gait = test_gait_generator::trot()) {
    const Quad& r = quad();
    gen = std::make_unique<GaitGenerator>(r.robot.model, r.contacts, r.x_nominal, o);
    trot = gen->timeline().addPattern(gait);
    stand = gen->timeline().addPattern(test_gait_generator::stand());
    gen->timeline().reset(trot, 0.0);
  }
  GaitGenerator* operator->() { return gen.get(); }
  GaitGenerator& operator*() { return *gen; }
};

BodyCommand velocity(double vx, double vy = 0.0, double yaw_rate = 0.0, double height = 0.0) {
  BodyCommand c;
  c.vx = vx;
  c.vy = vy;
  c.yaw_rate = yaw_rate;
  c.height = height;
  return c;
}

Eigen::Matrix3d Rz(double yaw) {
  return Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
}

// x with its base at (x, y) turned by yaw (the joints at the nominal posture).
Eigen::VectorXd placed(double x, double y, double yaw) {
  Eigen::VectorXd s = quad().x_nominal;
  s[0] = x;
  s[1] = y;
  const Eigen::Quaterniond o(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()));
  s.segment<4>(3) << o.x(), o.y(), o.z(), o.w();
  return s;
}

// The swing arc by hand: a + ½(1 - cos πs)(b - a) + h sin(πs) e_z.
Eigen::Vector3d arc(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double s, double h) {
  Eigen::Vector3d p = a + 0.5 * (1.0 - std::cos(kPi * s)) * (b - a);
  p.z() += h * std::sin(kPi * s);
  return p;
}

TEST(GaitGenerator, NominalStanceOffsets) {
  const Nominal n;
  Generator g;
  for (int c = 0; c < 4; ++c) {
    // Relative to the base, at their height on the ground (the base at x = y = 0, no yaw).
    EXPECT_NEAR((g->stanceOffset(c) - n.foot[c]).norm(), 0.0, 1e-12) << c;
    EXPECT_NEAR(n.foot[c].z(), 0.0, 1e-6) << "stride_quad's feet stand on z = 0";
  }
  // The four feet are spread around the base (front ahead, left to the left).
  EXPECT_GT(n.foot[FL].x(), 0.1);
  EXPECT_LT(n.foot[HL].x(), -0.1);
  EXPECT_GT(n.foot[FL].y(), 0.05);
  EXPECT_LT(n.foot[FR].y(), -0.05);
  EXPECT_EQ(g->footholdGain(), 0.0);
  // The default gain: the capture point's time constant sqrt(h / g).
  GaitGeneratorOptions o = hand();
  o.foothold_gain = -1.0;
  Generator d(o);
  EXPECT_NEAR(d->footholdGain(), std::sqrt(n.z / 9.81), 1e-12);
}

// 0.5 m/s forward in force and as target, trotting, from standing at the origin.
TEST(GaitGenerator, StraightLine) {
  const Nominal n;
  const Quad& r = quad();
  Generator g;
  g->setCommand(velocity(0.5));
  ASSERT_TRUE(g->plan(0.0, r.x_nominal, 0.0, 1.0));

  Eigen::VectorXd x_ref(r.x_nominal.size());
  const int nq = r.robot.model.nq;
  for (double t : {0.0, 0.25, 0.5, 0.73, 1.0, 1.6}) {
    const Eigen::Vector3d b = g->basePosition(t);
    EXPECT_NEAR(b.x(), 0.5 * t, 1e-12) << t;
    EXPECT_NEAR(b.y(), 0.0, 1e-12) << t;
    EXPECT_NEAR(b.z(), n.z, 1e-12) << t;
    EXPECT_NEAR(g->baseYaw(t), 0.0, 1e-12);
    g->state(t, x_ref);
    EXPECT_NEAR(x_ref[0], 0.5 * t, 1e-12);
    EXPECT_NEAR(x_ref[2], n.z, 1e-12);
    EXPECT_NEAR(x_ref[6], 1.0, 1e-12);  // no turn, no tilt
    EXPECT_NEAR(x_ref[nq + 0], 0.5, 1e-12) << "forward velocity reference";
    EXPECT_NEAR(x_ref.segment<5>(nq + 1).norm(), 0.0, 1e-12);
    EXPECT_EQ((x_ref.segment(7, nq - 7) - r.x_nominal.segment(7, nq - 7)).norm(), 0.0)
        << "joints: nominal";
    EXPECT_EQ(x_ref.tail(r.robot.model.nv - 6).norm(), 0.0) << "joints at rest";
    const Eigen::Vector3d com = g->com(t);
    EXPECT_NEAR(com.x(), n.com.x() + 0.5 * t, 1e-12);
    EXPECT_NEAR(com.z(), n.com.z(), 1e-12);
  }

  // FL: down until 0.1, swings to 0.3, down until 0.7 (mid-stance 0.5: base at 0.25), swings,
  // down 0.9-1.3 (mid 1.1), the first touch-down after the window (1.5, mid 1.7).
  ASSERT_EQ(g->stances(FL), 4);
  const GaitGenerator::Stance& s0 = g->stance(FL, 0);
  EXPECT_NEAR(s0.touch_down, 0.0, kTime);
  EXPECT_NEAR(s0.lift_off, 0.1, kTime);
  EXPECT_NEAR((s0.p - n.foot[FL]).norm(), 0.0, 1e-12) << "where it was measured";
  const double td[] = {0.0, 0.3, 0.9, 1.5}, lo[] = {0.1, 0.7, 1.3, 1.9};
  const double base_x[] = {0.0, 0.25, 0.55, 0.85};
  for (int i = 1; i < 4; ++i) {
    const GaitGenerator::Stance& s = g->stance(FL, i);
    EXPECT_NEAR(s.touch_down, td[i], kTime) << i;
    EXPECT_NEAR(s.lift_off, lo[i], kTime) << i;
    EXPECT_NEAR(s.p.x(), n.foot[FL].x() + base_x[i], 1e-9) << i;
    EXPECT_NEAR(s.p.y(), n.foot[FL].y(), 1e-12) << i;
    EXPECT_NEAR(s.p.z(), n.foot[FL].z(), 1e-12) << i;
  }
  // FR: down until 0.4, lands at 0.6 until 1.0 (mid 0.8: base at 0.4), then 1.2 (mid 1.4).
  ASSERT_EQ(g->stances(FR), 3);
  EXPECT_NEAR(g->stance(FR, 0).lift_off, 0.4, kTime);
  EXPECT_NEAR(g->stance(FR, 1).touch_down, 0.6, kTime);
  EXPECT_NEAR(g->stance(FR, 1).lift_off, 1.0, kTime);
  EXPECT_NEAR(g->stance(FR, 1).p.x(), n.foot[FR].x() + 0.4, 1e-9);
  EXPECT_NEAR(g->stance(FR, 2).p.x(), n.foot[FR].x() + 0.7, 1e-9);

  // The swing arc: at the stances' positions while down, the apex half way at 0.2.
  const Eigen::Vector3d a = g->stance(FL, 0).p, b = g->stance(FL, 1).p;
  EXPECT_NEAR((g->foot(FL, 0.05) - a).norm(), 0.0, 1e-12);
  EXPECT_NEAR((g->foot(FL, 0.1) - a).norm(), 0.0, 1e-12);
  const Eigen::Vector3d apex = g->foot(FL, 0.2);
  EXPECT_NEAR(apex.x(), n.foot[FL].x() + 0.125, 1e-9);
  EXPECT_NEAR(apex.y(), n.foot[FL].y(), 1e-12);
  EXPECT_NEAR(apex.z(), n.foot[FL].z() + 0.05, 1e-12);
  for (double t : {0.12, 0.15, 0.26, 0.29})
    EXPECT_NEAR((g->foot(FL, t) - arc(a, b, (t - 0.1) / 0.2, 0.05)).norm(), 0.0, 1e-12) << t;
  EXPECT_NEAR((g->foot(FL, 0.3) - b).norm(), 0.0, 1e-12);
  EXPECT_NEAR((g->foot(FL, 0.55) - b).norm(), 0.0, 1e-12);
  // The FR-HL pair is down during the FL-HR swing.
  EXPECT_NEAR((g->foot(FR, 0.2) - n.foot[FR]).norm(), 0.0, 1e-12);
  EXPECT_TRUE(g->closed(FR, 0.2));
  EXPECT_FALSE(g->closed(FL, 0.2));
  EXPECT_EQ(g->mask(0.2), (1u << FR) | (1u << HL));
  // No turn: feet keep their nominal headings.
  for (double t : {0.05, 0.2, 0.5})
    EXPECT_TRUE(g->footRotation(FL, t).isApprox(n.foot_R[FL], 1e-12)) << t;
}

// Turning in place at 1 rad/s.
TEST(GaitGenerator, PureTurn) {
  const Nominal n;
  const Quad& r = quad();
  const int nq = r.robot.model.nq;
  Generator g;
  g->setCommand(velocity(0.0, 0.0, 1.0));
  ASSERT_TRUE(g->plan(0.0, r.x_nominal, 0.0, 1.0));
  Eigen::VectorXd x_ref(r.x_nominal.size());
  for (double t : {0.0, 0.3, 0.5, 1.0}) {
    EXPECT_NEAR(g->baseYaw(t), t, 1e-12);
    EXPECT_NEAR(g->basePosition(t).head<2>().norm(), 0.0, 1e-12) << "turns in place";
    g->state(t, x_ref);
    const Eigen::Quaterniond o(x_ref[6], x_ref[3], x_ref[4], x_ref[5]);
    EXPECT_TRUE(o.toRotationMatrix().isApprox(Rz(t), 1e-12)) << t;
    EXPECT_NEAR(x_ref[nq + 5], 1.0, 1e-12) << "yaw rate reference";
    EXPECT_NEAR(x_ref.segment<5>(nq).norm(), 0.0, 1e-12);
    const Eigen::Vector3d com_xy(n.com.x(), n.com.y(), 0.0);
    EXPECT_NEAR((g->com(t).head<2>() - (Rz(t) * com_xy).head<2>()).norm(), 0.0, 1e-12);
  }
  // FL lands at 0.3 for 0.4 s: mid-stance 0.5, its nominal place turned by 0.5 rad.
  for (int c : {FL, HR}) {
    const Eigen::Vector3d expected = Rz(0.5) * n.foot[c];
    EXPECT_NEAR((g->stance(c, 1).p - expected).norm(), 0.0, 1e-12) << c;
    EXPECT_NEAR((g->stance(c, 2).p - Rz(1.1) * n.foot[c]).norm(), 0.0, 1e-12) << c;
  }
  // FR lands at 0.6 (mid-stance 0.8).
  EXPECT_NEAR((g->stance(FR, 1).p - Rz(0.8) * n.foot[FR]).norm(), 0.0, 1e-12);
  // Headings: the nominal one while down at the start, turned by 0.5 from the touch-down on, half
  // of that (the cosine ramp at s = ½) at the swing's middle.
  EXPECT_TRUE(g->footRotation(FL, 0.05).isApprox(n.foot_R[FL], 1e-12));
  EXPECT_TRUE(g->footRotation(FL, 0.2).isApprox(Rz(0.25) * n.foot_R[FL], 1e-12));
  EXPECT_TRUE(g->footRotation(FL, 0.4).isApprox(Rz(0.5) * n.foot_R[FL], 1e-12));
  EXPECT_NEAR(g->stance(FL, 1).yaw - g->stance(FL, 0).yaw, 0.5, 1e-12);
}

// The horizon holds the command in force: the base moves at its velocity and turns at its yaw
// rate from the anchor on (the controller smooths a change between ticks, CommandFilter).
TEST(GaitGenerator, TheHorizonHoldsTheCommandInForce) {
  const Quad& r = quad();
  const int nq = r.robot.model.nq;
  Generator g;
  g->setCommand(velocity(0.5, 0.0, 1.0));
  ASSERT_TRUE(g->plan(0.0, r.x_nominal, 0.0, 1.0));
  Eigen::VectorXd x_ref(r.x_nominal.size());
  for (int k : {0, 10, 30, 50, 70, 100}) {  // on the base samples
    const double t = 0.01 * k;
    EXPECT_NEAR(g->baseYaw(t), t, 1e-12) << t;
    g->state(t, x_ref);
    EXPECT_NEAR(x_ref[nq], 0.5, 1e-12) << "the velocity in force, all along";
    EXPECT_NEAR(x_ref[nq + 5], 1.0, 1e-12);
    // On the arc of radius v / w = 0.5 m (midpoint rule: within h² of it).
    const Eigen::Vector3d p = g->basePosition(t);
    EXPECT_NEAR(p.x(), 0.5 * std::sin(t), 1e-4) << t;
    EXPECT_NEAR(p.y(), 0.5 * (1.0 - std::cos(t)), 1e-4) << t;
  }
  // Straight ahead, between samples too.
  g->setCommand(velocity(0.5));
  ASSERT_TRUE(g->plan(0.0, r.x_nominal, 0.0, 1.0));
  for (double t : {0.0, 0.055, 0.3, 0.4949, 1.0})
    EXPECT_NEAR(g->basePosition(t).x(), 0.5 * t, 1e-12);
  // A new command replaces the old from the anchor on: no ramp inside the horizon.
  g->setCommand(velocity(0.2));
  ASSERT_TRUE(g->plan(0.0, r.x_nominal, 0.0, 1.0));
  EXPECT_NEAR(g->basePosition(0.8).x(), 0.16, 1e-12);
}

// A pronk (issue 45): 0.3 s on all feet, 0.2 s in the air. The base reference takes off and lands
// with the legs stretched (max_height above the nominal height), follows the ballistic arc in the
// air and, on the ground, brakes the landing to rest at a constant deceleration over a crouch of
// 2 max_height (at least 4 cm), and pushes from that crouch to the next take-off's speed alike;
// its vertical velocity is the height's derivative throughout (continuous at take-off and
// touch-down). Before the first flight it crouches from its level in 0.2 s, then pushes.
TEST(GaitGenerator, FlightsFollowTheBallisticArc) {
  GaitGeneratorOptions o = hand();
  o.max_height = 0.02;
  ContactPlan pronk;
  pronk.cyclic = true;
  pronk.phases = {{0.3, feetExcept({})}, {0.2, feetExcept({FL, FR, HL, HR})}};
  Generator g(o, pronk);
  const Quad& r = quad();
  ASSERT_TRUE(g->plan(0.0, r.x_nominal, 0.0, 1.0));
  ASSERT_GE(g->flights(), 2);
  EXPECT_NEAR(g->flight(0).lift_off, 0.3, kTime);
  EXPECT_NEAR(g->flight(0).touch_down, 0.5, kTime);
  EXPECT_NEAR(g->flight(1).lift_off, 0.8, kTime);
  const double z0 = r.x_nominal[2], e = 0.02, grav = 9.81, v = 0.5 * grav * 0.2;
  const int nq = r.robot.model.nq;
  Eigen::VectorXd x(r.x_nominal.size());
  auto z = [&](double t) {
    g->state(t, x);
    return x[2];
  };
  auto vz = [&](double t) {
    g->state(t, x);
    return x[nq + 2];  // the nominal tilt is level: the base frame's z is the world's
  };
  // The crouch: 4 cm below the take-off height, reached at rest 2 (4 cm) / v after a touch-down.
  const double crouch = e - 0.04, brake = 2.0 * 0.04 / v;
  EXPECT_NEAR(z(0.01), z0, 1e-12);  // standing, before the crouch (from 0.3 - brake - 0.2)
  EXPECT_NEAR(vz(0.01), 0.0, 1e-12);
  EXPECT_NEAR(z(0.3 - brake), z0 + crouch, 1e-9);  // the push starts from it
  EXPECT_NEAR(z(0.5 + brake), z0 + crouch, 1e-9);  // the landing's braking ends in it
  EXPECT_NEAR(vz(0.5 + brake), 0.0, 1e-9);
  EXPECT_NEAR(z(0.3), z0 + e, 1e-9);                           // take-off
  EXPECT_NEAR(z(0.4), z0 + e + 0.5 * grav * 0.1 * 0.1, 1e-9);  // the apex
  EXPECT_NEAR(vz(0.4), 0.0, 1e-9);
  EXPECT_NEAR(vz(0.3 + 1e-9), v, 1e-6);  // the take-off speed, on both sides
  EXPECT_NEAR(vz(0.3 - 1e-9), v, 1e-6);
  EXPECT_NEAR(vz(0.5 - 1e-9), -v, 1e-6);  // landing
  EXPECT_NEAR(vz(0.5 + 1e-9), -v, 1e-6);
  EXPECT_NEAR(z(0.65), z0 + crouch, 1e-9);  // held between the flights
  // The braking's deceleration is v² / (2 (4 cm)), constant.
  EXPECT_NEAR((vz(0.52) - vz(0.51)) / 0.01, v * v / 0.08, 1e-6);
  // The vertical velocity is the height's slope everywhere but at the phase boundaries.
  for (double t = 0.013; t < 1.0; t += 0.01) {
    const double h = 1e-6, slope = (z(t + h) - z(t - h)) / (2.0 * h);
    EXPECT_NEAR(vz(t), slope, 1e-5) << t;
  }
  // The posture follows (postureBlend clamps it to the range): in the air the highest body
  // height's (the legs stretched), standing before the crouch the nominal one.
  EXPECT_NEAR(g->height(0.4), e + 0.5 * grav * 0.1 * 0.1, 1e-9);
  EXPECT_NEAR(g->height(0.01), 0.0, 1e-12);
}

TEST(GaitGenerator, BodyHeightOfTheCommandInForce) {
  const Nominal n;
  const Quad& r = quad();
  Generator g;
  g->setCommand(velocity(0.0, 0.0, 0.0, 0.04));
  ASSERT_TRUE(g->plan(0.0, r.x_nominal, 0.0, 1.0));
  Eigen::VectorXd x_ref(r.x_nominal.size());
  for (int k : {0, 10, 20, 40, 60, 100}) {
    const double t = 0.01 * k;
    EXPECT_NEAR(g->basePosition(t).z(), n.z + 0.04, 1e-12) << t;
    g->state(t, x_ref);
    EXPECT_NEAR(x_ref[2], n.z + 0.04, 1e-12) << t;
    EXPECT_NEAR(g->com(t).z(), n.com.z() + 0.04, 1e-12) << t;
  }
  // Feet stay on the ground: only the base rises.
  EXPECT_NEAR(g->stance(FL, 1).p.z(), n.foot[FL].z(), 1e-12);
}

// The joints' reference follows the body height: the posture of each height keeps every foot on
// its nominal place (solved at 9 heights across max_height, interpolated between them).
TEST(GaitGenerator, BodyHeightPostureKeepsTheFeetInPlace) {
  const Nominal n;
  const Quad& r = quad();
  GaitGeneratorOptions o = hand();
  o.max_height = 0.02;  // postures every 5 mm from -2 to +2 cm
  Generator g(o);
  Data data(r.robot.model);
  Eigen::VectorXd x_ref(r.x_nominal.size());
  for (double h : {-0.02, -0.0125, 0.0, 0.0075, 0.02}) {
    g->setCommand(velocity(0.0, 0.0, 0.0, h));
    ASSERT_TRUE(g->plan(0.0, r.x_nominal, 0.0, 1.0));
    g->state(0.0, x_ref);
    EXPECT_NEAR(x_ref[2], n.z + h, 1e-12);
    framesForwardKinematics(r.robot.model, data, x_ref.head(r.robot.model.nq));
    // On a solved height, exactly; between two, within the interpolation's error.
    const double tolerance = std::fmod(std::abs(h), 0.005) < 1e-9 ? 1e-9 : 2e-4;
    for (int c = 0; c < 4; ++c) {
      EXPECT_LT((data.oMf[r.contacts[c].frame].p - n.foot[c]).norm(), tolerance)
          << "height " << h << " foot " << c;
    }
    if (h != 0.0) {  // the legs really moved
      EXPECT_GT((x_ref.segment(7, 12) - r.x_nominal.segment(7, 12)).norm(), 1e-3) << h;
    }
  }
  // Heights the legs cannot reach are refused at construction, naming the height.
  o.max_height = 0.2;
  try {
    Generator too_high(o);
    FAIL() << "a 20 cm body height must be refused";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("max_height"), std::string::npos) << e.what();
  }
}

// Trot to stand, asked at 0.15 (FL and HR in the air): the switch is at 0.3.
TEST(GaitGenerator, GaitSwitchAtAPhaseBoundary) {
  const Nominal n;
  const Quad& r = quad();
  Generator g;
  g->setCommand(velocity(0.5));
  ASSERT_TRUE(g->plan(0.0, r.x_nominal, 0.0, 1.0));
  ASSERT_NEAR(g->timeline().switchTo(g.stand, 0.15), 0.3, kTime);
  ASSERT_TRUE(g->plan(0.15, r.x_nominal, 0.15, 1.15));
  for (double t = 0.3; t < 1.15; t += 0.01) EXPECT_EQ(g->mask(t), 0xfu) << t;
  for (int c : {FL, HR}) {
    ASSERT_EQ(g->stances(c), 2) << c;
    EXPECT_EQ(g->stance(c, 0).touch_down, -kNever);
    EXPECT_NEAR(g->stance(c, 0).lift_off, 0.1, kTime);
    EXPECT_NEAR(g->stance(c, 1).touch_down, 0.3, kTime);
    EXPECT_EQ(g->stance(c, 1).lift_off, kNever) << "never lifts again";
    // Mid-stance capped at 0.3 + 0.5 = 0.8: the base reference is at 0.5 × 0.8 there.
    EXPECT_NEAR(g->stance(c, 1).p.x(), n.foot[c].x() + 0.4, 1e-9) << c;
    EXPECT_NEAR(g->stance(c, 1).p.y(), n.foot[c].y(), 1e-12) << c;
    // It lands there and stays.
    EXPECT_NEAR((g->foot(c, 0.3) - g->stance(c, 1).p).norm(), 0.0, 1e-12);
    EXPECT_NEAR((g->foot(c, 1.1) - g->stance(c, 1).p).norm(), 0.0, 1e-12);
  }
  for (int c : {FR, HL}) {  // down since 0 and for good
    ASSERT_EQ(g->stances(c), 1) << c;
    EXPECT_NEAR(g->stance(c, 0).touch_down, 0.0, kTime);
    EXPECT_EQ(g->stance(c, 0).lift_off, kNever);
    EXPECT_NEAR((g->foot(c, 0.9) - n.foot[c]).norm(), 0.0, 1e-12);
  }
}

// Feet that are down keep where they were measured; feet in the air keep where they lifted from.
TEST(GaitGenerator, LatchesTheMeasuredFeet) {
  const Nominal n;
  const Quad& r = quad();
  Generator g;
  Data data(r.robot.model);
  auto feet = [&](const Eigen::VectorXd& x, Eigen::Vector3d(&p)[4]) {
    framesForwardKinematics(r.robot.model, data, x.head(r.robot.model.nq));
    for (int c = 0; c < 4; ++c) p[c] = data.oMf[r.contacts[c].frame].p;
  };
  const Eigen::VectorXd x0 = placed(0.03, -0.02, 0.1);
  Eigen::Vector3d p0[4], p1[4];
  feet(x0, p0);
  ASSERT_TRUE(g->plan(0.0, x0, 0.0, 1.0));
  for (int c = 0; c < 4; ++c) {
    EXPECT_NEAR((g->stance(c, 0).p - p0[c]).norm(), 0.0, 1e-12) << c;
    EXPECT_NEAR((g->foot(c, 0.0) - p0[c]).norm(), 0.0, 1e-12) << c;
    const Eigen::Matrix3d R = Rz(0.1) * n.foot_R[c];  // the base turned by 0.1
    EXPECT_NEAR(g->stance(c, 0).yaw, std::atan2(R(1, 0), R(0, 0)), 1e-12) << c;
  }
  // At 0.15 FL and HR are in the air, FR and HL down: the robot has slid by 1 cm.
  const Eigen::VectorXd x1 = placed(0.04, -0.02, 0.1);
  feet(x1, p1);
  ASSERT_TRUE(g->plan(0.15, x1, 0.15, 1.15));
  for (int c : {FR, HL}) {
    EXPECT_NEAR((g->stance(c, 0).p - p1[c]).norm(), 0.0, 1e-12) << c;
    EXPECT_NEAR((g->foot(c, 0.2) - p1[c]).norm(), 0.0, 1e-12) << c;
  }
  for (int c : {FL, HR}) {
    EXPECT_NEAR((g->stance(c, 0).p - p0[c]).norm(), 0.0, 1e-12) << c;
    // The swing starts from there: at 0.1 + a little, close to it.
    EXPECT_NEAR((g->foot(c, 0.1) - p0[c]).norm(), 0.0, 1e-12) << c;
  }
}

// Blind, the ground is where the feet down stand (issue 31): the robot on a floor 3 cm below the
// nominal plans its base, centre of mass and footholds 3 cm lower (less the 5 mm dead band); a
// floor within the dead band plans exactly as the nominal one; a step change of the feet's height
// is followed with the time constant.
TEST(GaitGenerator, TheGroundTheFeetFeel) {
  const Nominal n;
  GaitGeneratorOptions o = hand();
  o.ground_time_constant = 0.2;
  o.ground_dead_band = 0.005;
  auto lowered = [](double dz) {
    Eigen::VectorXd x = placed(0.0, 0.0, 0.0);
    x[2] += dz;
    return x;
  };
  Generator low(o);
  low->setCommand(velocity(0.3));
  ASSERT_TRUE(low->plan(0.0, lowered(-0.03), 0.0, 1.0));
  EXPECT_NEAR(low->ground(), -0.025, 1e-12);
  Generator flat(o);
  flat->setCommand(velocity(0.3));
  ASSERT_TRUE(flat->plan(0.0, lowered(0.0), 0.0, 1.0));
  EXPECT_EQ(flat->ground(), 0.0);
  for (double t : {0.0, 0.35, 0.8}) {
    EXPECT_NEAR(low->basePosition(t).z(), flat->basePosition(t).z() - 0.025, 1e-12) << t;
    EXPECT_NEAR(low->com(t).z(), flat->com(t).z() - 0.025, 1e-12) << t;
    Eigen::VectorXd a(quad().x_nominal.size()), b(a.size());
    low->state(t, a);
    flat->state(t, b);
    EXPECT_NEAR(a[2], b[2] - 0.025, 1e-12) << t;
  }
  // Each planned touch-down (after the feet down at 0) lands on the felt ground.
  for (int c = 0; c < 4; ++c)
    for (int i = 1; i < low->stances(c); ++i)
      EXPECT_NEAR(low->stance(c, i).p.z(), n.foot[c].z() - 0.025, 1e-12) << c << " " << i;
  // Feet 3 mm high: within the dead band, the nominal ground exactly.
  Generator within(o);
  ASSERT_TRUE(within->plan(0.0, lowered(0.003), 0.0, 1.0));
  EXPECT_EQ(within->ground(), 0.0);
  EXPECT_EQ(within->basePosition(0.5).z(), n.z);
  // Standing (all feet down) on a floor that rises by 4 cm at 0.05: after one plan 0.2 s later the
  // filter has gone dt / (tau + dt) = 1/2 of the way (2 cm, 1.5 cm past the dead band).
  GaitGeneratorOptions standing = o;
  Generator step(standing, test_gait_generator::stand());
  ASSERT_TRUE(step->plan(0.0, lowered(0.0), 0.0, 1.0));
  ASSERT_TRUE(step->plan(0.2, lowered(0.04), 0.2, 1.2));
  EXPECT_NEAR(step->ground(), 0.015, 1e-12);
  ASSERT_TRUE(step->plan(0.4, lowered(0.04), 0.4, 1.4));
  EXPECT_NEAR(step->ground(), 0.025, 1e-12);  // 3 cm, less the band
}

// Blind, on a slope (issue 31): the robot standing pitched nose-up by 10 degrees (its feet,
// coplanar in the body, on a plane of slope tan 10 degrees along x): the ground the feet feel has
// that slope less the 0.03 dead band, every planned touch-down lies on it, and the base pitches
// with it. At 1 degree (within the band) everything is as on level ground.
TEST(GaitGenerator, BlindTheGroundIsThePlaneTheFeetStandOn) {
  const Nominal n;
  auto pitched = [&](double deg) {
    Eigen::VectorXd x = placed(0.0, 0.0, 0.0);
    const Eigen::Quaterniond o(Eigen::AngleAxisd(-deg * kPi / 180.0, Eigen::Vector3d::UnitY()));
    x.segment<4>(3) << o.x(), o.y(), o.z(), o.w();
    return x;
  };
  Generator g;
  g->setCommand(velocity(0.3));
  ASSERT_TRUE(g->plan(0.0, pitched(10.0), 0.0, 1.0));
  const double slope = std::tan(10.0 * kPi / 180.0) - 0.03;
  EXPECT_NEAR(g->groundSlope().x(), slope, 1e-9);
  EXPECT_NEAR(g->groundSlope().y(), 0.0, 1e-9);
  // The plane through the touch-downs: their heights differ by the slope times their distance.
  const GaitGenerator::Stance &a = g->stance(FL, 1), &b = g->stance(HL, 1);
  EXPECT_NEAR((a.p.z() - n.foot[FL].z()) - (b.p.z() - n.foot[HL].z()), slope * (a.p.x() - b.p.x()),
              1e-9);
  EXPECT_EQ(a.source, StanceSource::Blind);
  Eigen::VectorXd x(quad().x_nominal.size());
  g->state(0.5, x);
  const Eigen::Vector3d nose =
      Eigen::Quaterniond(x[6], x[3], x[4], x[5]) * Eigen::Vector3d::UnitX();
  EXPECT_NEAR(std::atan2(nose.z(), nose.x()), std::atan(slope), 1e-9);
  Generator level;
  level->setCommand(velocity(0.3));
  ASSERT_TRUE(level->plan(0.0, pitched(1.0), 0.0, 1.0));
  EXPECT_EQ(level->groundSlope(), Eigen::Vector2d::Zero());
  level->state(0.5, x);
  EXPECT_EQ(Eigen::Quaterniond(x[6], x[3], x[4], x[5]).w(), 1.0);
}

// A foot reported loaded in the second half of its swing has landed early: its reference stays
// where it is until its touch-down time (the timeline unchanged), counted once; in the first half,
// or not reported, the arc goes on.
TEST(GaitGenerator, AFootThatLandsEarlyStaysWhereItLanded) {
  Generator g, arc;
  g->setCommand(velocity(0.3));
  arc->setCommand(velocity(0.3));
  const Eigen::VectorXd x = placed(0.0, 0.0, 0.0);  // FL measured at its nominal place
  const Nominal n;
  // FL and HR swing from 0.1 to 0.3 (trot); FL (with FR and HL, down) reported loaded, HR not. At
  // 0.15 (first half) the report changes nothing.
  g->setMeasuredContacts(0b0111);
  ASSERT_TRUE(g->plan(0.15, x, 0.15, 1.15));
  ASSERT_TRUE(arc->plan(0.15, x, 0.15, 1.15));
  EXPECT_FALSE(g->stance(FL, 1).early);
  EXPECT_NEAR((g->foot(FL, 0.25) - arc->foot(FL, 0.25)).norm(), 0.0, 1e-12);
  // At 0.22 (past half): landed early, where it is measured, until 0.3; the other feet as planned.
  ASSERT_TRUE(g->plan(0.22, x, 0.22, 1.22));
  ASSERT_TRUE(arc->plan(0.22, x, 0.22, 1.22));
  EXPECT_TRUE(g->stance(FL, 1).early);
  EXPECT_EQ(g->stance(FL, 1).touch_down, arc->stance(FL, 1).touch_down);
  for (double t : {0.22, 0.26, 0.29})
    EXPECT_NEAR((g->foot(FL, t) - n.foot[FL]).norm(), 0.0, 1e-9) << t;
  EXPECT_GT((arc->foot(FL, 0.26) - n.foot[FL]).norm(), 0.01);
  EXPECT_NEAR((g->foot(HR, 0.26) - arc->foot(HR, 0.26)).norm(), 0.0, 1e-12);
  ASSERT_TRUE(g->plan(0.25, x, 0.25, 1.25));
  EXPECT_EQ(g->earlyTouchDowns(), 1);
  // Not reported loaded: the arc again.
  g->setMeasuredContacts(0b0110);
  ASSERT_TRUE(g->plan(0.26, x, 0.26, 1.26));
  EXPECT_FALSE(g->stance(FL, 1).early);
  g->clearMeasuredContacts();
  ASSERT_TRUE(g->plan(0.27, x, 0.27, 1.27));
  EXPECT_FALSE(g->stance(FL, 1).early);
  EXPECT_EQ(g->earlyTouchDowns(), 1);
}

// The velocity beyond the command moves each foot's next touch-down, and only that one.
TEST(GaitGenerator, RaibertCorrectionOfTheNextTouchDown) {
  const Nominal n;
  const Quad& r = quad();
  const int nq = r.robot.model.nq;
  GaitGeneratorOptions o = hand();
  o.foothold_gain = 0.1;
  o.max_foothold_correction = 0.1;
  Generator g(o), plain;  // plain: gain 0
  Eigen::VectorXd x = r.x_nominal;
  x[nq] = 0.2;  // measured 0.2 m/s forward, commanded 0
  ASSERT_TRUE(g->plan(0.0, x, 0.0, 1.0));
  ASSERT_TRUE(plain->plan(0.0, x, 0.0, 1.0));
  for (int c = 0; c < 4; ++c) {
    ASSERT_EQ(g->stances(c), plain->stances(c));
    ASSERT_GE(g->stances(c), 3);
    const Eigen::Vector3d shift = g->stance(c, 1).p - plain->stance(c, 1).p;
    EXPECT_NEAR(shift.x(), 0.02, 1e-12) << c;  // 0.1 s × 0.2 m/s
    EXPECT_NEAR(shift.y(), 0.0, 1e-12) << c;
    EXPECT_NEAR(shift.z(), 0.0, 1e-12) << c;
    EXPECT_NEAR(plain->stance(c, 1).p.x(), n.foot[c].x(), 1e-12) << "commanded to stand still";
    for (int i = 2; i < g->stances(c); ++i)
      EXPECT_NEAR((g->stance(c, i).p - plain->stance(c, i).p).norm(), 0.0, 1e-12) << c << i;
    EXPECT_NEAR((g->stance(c, 0).p - plain->stance(c, 0).p).norm(), 0.0, 1e-12);
  }

  // Capped: 0.01 m at most, along the excess (0.2, 0.1) m/s.
  o.max_foothold_correction = 0.01;
  Generator capped(o);
  x[nq + 1] = 0.1;
  ASSERT_TRUE(capped->plan(0.0, x, 0.0, 1.0));
  ASSERT_TRUE(plain->plan(0.0, x, 0.0, 1.0));
  const Eigen::Vector2d dir = Eigen::Vector2d(0.2, 0.1).normalized();
  for (int c = 0; c < 4; ++c) {
    const Eigen::Vector3d shift = capped->stance(c, 1).p - plain->stance(c, 1).p;
    EXPECT_NEAR((shift.head<2>() - 0.01 * dir).norm(), 0.0, 1e-12) << c;
    EXPECT_NEAR((capped->stance(c, 2).p - plain->stance(c, 2).p).norm(), 0.0, 1e-12) << c;
  }

  // In world axes, against the command: heading along +y, 0.3 m/s forward (base frame) with 0.1
  // commanded: 0.2 m/s too fast along +y.
  o.max_foothold_correction = 0.1;
  Generator turned(o), turned_plain;
  Eigen::VectorXd xt = placed(0.0, 0.0, 0.5 * kPi);
  xt[nq] = 0.3;
  turned->setCommand(velocity(0.1));
  turned_plain->setCommand(velocity(0.1));
  ASSERT_TRUE(turned->plan(0.0, xt, 0.0, 1.0));
  ASSERT_TRUE(turned_plain->plan(0.0, xt, 0.0, 1.0));
  for (int c = 0; c < 4; ++c) {
    const Eigen::Vector3d shift = turned->stance(c, 1).p - turned_plain->stance(c, 1).p;
    EXPECT_NEAR((shift.head<2>() - Eigen::Vector2d(0.0, 0.02)).norm(), 0.0, 1e-12) << c;
  }

  // A later plan: the touch-down at 0.3 is past at 0.35, the next one (0.9) takes the shift.
  ASSERT_TRUE(g->plan(0.35, x, 0.35, 1.35));
  ASSERT_TRUE(plain->plan(0.35, x, 0.35, 1.35));
  const Eigen::Vector2d excess = Eigen::Vector2d(0.2, 0.1) * 0.1;
  EXPECT_NEAR(g->stance(FL, 1).touch_down, 0.9, kTime);
  EXPECT_NEAR((g->stance(FL, 1).p - plain->stance(FL, 1).p).head<2>().norm(), excess.norm(), 1e-12);
  EXPECT_NEAR(g->stance(FR, 1).touch_down, 0.6, kTime);  // FR still has its 0.6 ahead
  EXPECT_NEAR((g->stance(FR, 1).p - plain->stance(FR, 1).p).head<2>().norm(), excess.norm(), 1e-12);
  EXPECT_NEAR((g->stance(FR, 2).p - plain->stance(FR, 2).p).norm(), 0.0, 1e-12);
}

// The base reference runs ahead of a robot that does not follow, on a leash; footholds too.
TEST(GaitGenerator, LeashToTheMeasuredBase) {
  const Nominal n;
  const Quad& r = quad();
  GaitGeneratorOptions o = hand();
  o.max_position_lead = 0.1;
  o.max_yaw_lead = 0.3;
  o.max_foothold_lead = 0.05;
  Generator g(o);
  g->setCommand(velocity(0.5));
  ASSERT_TRUE(g->plan(0.0, r.x_nominal, 0.0, 1.0));
  EXPECT_NEAR(g->basePosition(1.0).x(), 0.5, 1e-12);  // the first plan is anchored at the robot
  ASSERT_TRUE(g->plan(1.0, r.x_nominal, 1.0, 2.0));   // the robot has not moved
  EXPECT_NEAR(g->basePosition(1.0).x(), 0.1, 1e-12) << "max_position_lead ahead";
  EXPECT_NEAR(g->basePosition(1.0).y(), 0.0, 1e-12);
  EXPECT_NEAR(g->basePosition(1.4).x(), 0.3, 1e-12);
  // Footholds: within 5 cm of the same command carried from the robot (at the origin at t = 1).
  // FL is down 0.9-1.3; its next stance is 1.5-1.9 (mid 1.7): 0.35 from the robot, 0.45 on the
  // reference, so 0.35 + 0.05.
  EXPECT_NEAR(g->stance(FL, 1).touch_down, 1.5, kTime);
  EXPECT_NEAR(g->stance(FL, 1).p.x(), n.foot[FL].x() + 0.4, 1e-9);
  EXPECT_NEAR(g->stance(FL, 1).p.y(), n.foot[FL].y(), 1e-12);
  for (int c = 0; c < 4; ++c)
    for (int i = 0; i < g->stances(c); ++i) {
      const GaitGenerator::Stance& s = g->stance(c, i);
      if (s.touch_down <= 1.0) continue;  // latched
      const double mid = s.touch_down + std::min(0.5 * (s.lift_off - s.touch_down), 0.5);
      const Eigen::Vector3d on_robot = n.foot[c] + Eigen::Vector3d(0.5 * (mid - 1.0), 0.0, 0.0);
      EXPECT_LE((s.p - on_robot).norm(), 0.05 + 1e-12) << c << " " << i;
      EXPECT_NEAR((s.p - on_robot).norm(), 0.05, 1e-9) << "the reference leads by 0.1 > 0.05";
    }

  // Yaw: 1 rad/s for 1 s with the robot not turning: 0.3 rad ahead.
  Generator t(o);
  t->setCommand(velocity(0.0, 0.0, 1.0));
  ASSERT_TRUE(t->plan(0.0, r.x_nominal, 0.0, 1.0));
  ASSERT_TRUE(t->plan(1.0, r.x_nominal, 1.0, 2.0));
  EXPECT_NEAR(t->baseYaw(1.0), 0.3, 1e-12);
  EXPECT_NEAR(t->baseYaw(1.5), 0.8, 1e-12);
  // A robot within the leash keeps the reference where the last plan had it.
  Generator w(o);
  w->setCommand(velocity(0.5));
  ASSERT_TRUE(w->plan(0.0, r.x_nominal, 0.0, 1.0));
  ASSERT_TRUE(w->plan(0.1, placed(0.02, 0.01, 0.0), 0.1, 1.1));
  EXPECT_NEAR(w->basePosition(0.1).x(), 0.05, 1e-12);
  EXPECT_NEAR(w->basePosition(0.1).y(), 0.0, 1e-12);
}

TEST(GaitGenerator, BadInputChangesNothing) {
  const Quad& r = quad();
  const int nq = r.robot.model.nq, nx = nq + r.robot.model.nv;
  Generator g;
  g->setCommand(velocity(0.3));
  ASSERT_TRUE(g->plan(0.0, r.x_nominal, 0.0, 1.0));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const Eigen::Vector3d base = g->basePosition(0.5), fl1 = g->stance(FL, 1).p;
  const Eigen::Vector3d fr0 = g->stance(FR, 0).p;
  const int n_fl = g->stances(FL);
  Eigen::VectorXd x = placed(0.05, 0.05, 0.2);  // would move everything, were it taken
  g->setCommand(velocity(-0.3));
  EXPECT_FALSE(g->plan(nan, x, 0.1, 1.1));
  EXPECT_FALSE(g->plan(inf, x, 0.1, 1.1));
  EXPECT_FALSE(g->plan(0.1, x, nan, 1.1));
  EXPECT_FALSE(g->plan(0.1, x, 0.1, inf));
  EXPECT_FALSE(g->plan(0.1, x, 0.1, 1.2)) << "a window longer than the horizon";
  EXPECT_FALSE(g->plan(0.1, x, 1.1, 0.1)) << "a window that ends before it begins";
  EXPECT_FALSE(g->plan(2e9, x, 2e9, 2e9 + 1.0)) << "an absurd time";
  EXPECT_FALSE(g->plan(0.1, x.head(nx - 1), 0.1, 1.1)) << "a wrong size";
  Eigen::VectorXd bad = x;
  bad[nq + 2] = nan;
  EXPECT_FALSE(g->plan(0.1, bad, 0.1, 1.1));
  bad = x;
  bad[0] = inf;
  EXPECT_FALSE(g->plan(0.1, bad, 0.1, 1.1));
  bad = x;
  bad.segment<4>(3).setZero();  // no orientation
  EXPECT_FALSE(g->plan(0.1, bad, 0.1, 1.1));
  EXPECT_EQ(g->basePosition(0.5), base);
  EXPECT_EQ(g->stance(FL, 1).p, fl1);
  EXPECT_EQ(g->stance(FR, 0).p, fr0);
  EXPECT_EQ(g->stances(FL), n_fl);
  // And the next good plan is as if the bad ones never came.
  Generator h;
  h->setCommand(velocity(0.3));
  ASSERT_TRUE(h->plan(0.0, r.x_nominal, 0.0, 1.0));
  h->setCommand(velocity(-0.3));
  ASSERT_TRUE(h->plan(0.1, x, 0.1, 1.1));
  ASSERT_TRUE(g->plan(0.1, x, 0.1, 1.1));
  EXPECT_EQ(g->basePosition(0.7), h->basePosition(0.7));
  for (int c = 0; c < 4; ++c) {
    ASSERT_EQ(g->stances(c), h->stances(c));
    for (int i = 0; i < g->stances(c); ++i) EXPECT_EQ(g->stance(c, i).p, h->stance(c, i).p);
  }
}

TEST(GaitGenerator, ConstructionRefusesBadOptions) {
  const Quad& r = quad();
  auto make = [&](const GaitGeneratorOptions& o) {
    GaitGenerator g(r.robot.model, r.contacts, r.x_nominal, o);
  };
  EXPECT_NO_THROW(make(hand()));
  GaitGeneratorOptions o = hand();
  o.horizon = 0.0;
  EXPECT_THROW(make(o), std::invalid_argument);
  o = hand();
  o.sample_dt = -0.01;
  EXPECT_THROW(make(o), std::invalid_argument);
  o = hand();
  o.max_foothold_correction = -1.0;
  EXPECT_THROW(make(o), std::invalid_argument);
  EXPECT_THROW(GaitGenerator(r.robot.model, r.contacts, r.x_nominal.head(5), hand()),
               std::invalid_argument);
}

// ============================================================================ On a map (issue 31)

// A map of 1 cm cells over [-1, 2] x [-1, 1] with the height h(x, y) at each cell's centre.
template <class H>
terrain::Steppability mapOf(H h, const terrain::SteppabilityOptions& options = {}) {
  terrain::ElevationMap m;
  m.resolution = 0.01;
  m.origin_x = -1.0;
  m.origin_y = -1.0;
  m.resize(201, 301);
  for (int r = 0; r < m.rows; ++r)
    for (int c = 0; c < m.cols; ++c)
      m.at(r, c) =
          static_cast<float>(h(m.origin_x + c * m.resolution, m.origin_y + r * m.resolution));
  terrain::Steppability st(options, m.rows * m.cols);
  EXPECT_TRUE(st.update(m));
  return st;
}

TEST(GaitGenerator, OnARampTheBodyAndTheConesFollowTheSurface) {
  // z = 0.2 (x + 1): every touch-down after the first lands on it; once every foot has (t = 0.9),
  // the base stands at its nominal height above the mean of the footholds' surface heights,
  // pitched nose-up by atan(0.2), and a foot down there has its cone along the ramp's normal.
  const double slope = 0.2;
  const terrain::Steppability ramp = mapOf([&](double x, double) { return slope * (x + 1.0); });
  Generator g;
  g->setCommand(velocity(0.3));
  g->setMap(&ramp);
  ASSERT_TRUE(g->plan(0.0, placed(0.0, 0.0, 0.0), 0.0, 1.0));
  const Nominal n;
  const Eigen::Vector3d up_the_ramp = Eigen::Vector3d(-slope, 0.0, 1.0).normalized();
  for (int c = 0; c < 4; ++c)
    for (int i = 1; i < g->stances(c); ++i) {
      const GaitGenerator::Stance& s = g->stance(c, i);
      EXPECT_TRUE(s.source == StanceSource::Nominal) << c << " " << i;
      EXPECT_NEAR(s.p.z() - n.foot[c].z(), slope * (s.p.x() + 1.0), 0.006) << c << " " << i;
      EXPECT_NEAR((s.normal - up_the_ramp).norm(), 0.0, 1e-4) << c << " " << i;
    }
  const double t = 0.9;  // FL, HR landed at 0.3 and 0.9; FR, HL at 0.6
  double mean = 0.0;
  for (int c = 0; c < 4; ++c) mean += slope * (g->foot(c, t).x() + 1.0) / 4.0;
  Eigen::VectorXd x(quad().x_nominal.size());
  g->state(t, x);
  EXPECT_NEAR(x[2] - n.z, mean, 0.006);
  const Eigen::Quaterniond o(x[6], x[3], x[4], x[5]);
  const Eigen::Vector3d nose = o * Eigen::Vector3d::UnitX();
  EXPECT_NEAR(std::atan2(nose.z(), nose.x()), std::atan(slope), 0.01);
  for (int c = 0; c < 4; ++c)
    if (g->closed(c, t)) {
      EXPECT_NEAR((g->footNormal(c, t) - up_the_ramp).norm(), 0.0, 1e-4);
    }
  // Without the map: level, on the ground the feet feel.
  g->setMap(nullptr);
  ASSERT_TRUE(g->plan(0.0, placed(0.0, 0.0, 0.0), 0.0, 1.0));
  g->state(t, x);
  EXPECT_NEAR(x[2], n.z, 1e-12);
  EXPECT_NEAR(std::abs(Eigen::Quaterniond(x[6], x[3], x[4], x[5]).w()), 1.0, 1e-12);
}

TEST(GaitGenerator, OnAMapTheSwingClearsABox) {
  // A box 8 cm high across FL's first swing (lift-off at 0.1 s, touch-down at 0.3 s, 6 cm further
  // on at 0.3 m/s): the arc passes over every cell of the box with the clearance, where the blind
  // arc (5 cm apex) would go through it.
  const Nominal n;
  Generator blind;
  blind->setCommand(velocity(0.3));
  ASSERT_TRUE(blind->plan(0.0, placed(0.0, 0.0, 0.0), 0.0, 1.0));
  const double x0 = n.foot[FL].x(), x1 = blind->stance(FL, 1).p.x();
  ASSERT_GT(x1 - x0, 0.05);
  const double lo = x0 + 0.35 * (x1 - x0), hi = x0 + 0.65 * (x1 - x0);
  const terrain::Steppability box =
      mapOf([&](double x, double) { return x >= lo && x <= hi ? 0.08 : 0.0; });
  Generator g(hand());
  g->setCommand(velocity(0.3));
  g->setMap(&box);
  ASSERT_TRUE(g->plan(0.0, placed(0.0, 0.0, 0.0), 0.0, 1.0));
  EXPECT_GT(g->stance(FL, 1).swing_height, 0.08);
  int over = 0;
  bool blind_hits = false;
  for (double t = 0.1; t <= 0.3; t += 0.001) {
    const Eigen::Vector3d p = g->foot(FL, t), q = blind->foot(FL, t);
    int r, c;
    if (box.cellOf(p.x(), p.y(), r, c) && box.height(r, c) > 0.0f) {
      ++over;
      EXPECT_GT(p.z() - n.foot[FL].z(), 0.08) << t;
    }
    if (box.cellOf(q.x(), q.y(), r, c) && box.height(r, c) > 0.0f)
      blind_hits = blind_hits || q.z() - n.foot[FL].z() < 0.08;
  }
  EXPECT_GT(over, 10);
  EXPECT_TRUE(blind_hits);
}

TEST(GaitGenerator, OnAMapASwingsFootholdIsHeldFromItsMiddle) {
  // FL swings from 0.1 s to 0.3 s. A command raised from 0.3 to 0.6 m/s moves that swing's
  // foothold when it is planned again before the swing's middle (0.2 s), and blind at any time; on
  // a map, from the middle on, the foothold stays where it was going (a target that jumps late is
  // one the foot cannot reach). FR's next step is still planned afresh.
  const terrain::Steppability flat = mapOf([](double, double) { return 0.0; });
  struct Moves {
    double fl, fr;
  };
  auto after = [&](const terrain::Steppability* map, double t) {
    Generator g;
    g->setCommand(velocity(0.3));
    if (map) g->setMap(map);
    EXPECT_TRUE(g->plan(0.0, placed(0.0, 0.0, 0.0), 0.0, 1.0));
    EXPECT_TRUE(g->plan(0.15, placed(0.045, 0.0, 0.0), 0.15, 1.15));
    const Eigen::Vector3d fl = g->stance(FL, 1).p, fr = g->stance(FR, 1).p;
    g->setCommand(velocity(0.6));
    EXPECT_TRUE(g->plan(t, placed(0.3 * t, 0.0, 0.0), t, t + 1.0));
    EXPECT_NEAR(g->stance(FL, 1).touch_down, 0.3, 1e-9);
    return Moves{g->stance(FL, 1).p.x() - fl.x(), g->stance(FR, 1).p.x() - fr.x()};
  };
  const Moves early = after(&flat, 0.18), late = after(&flat, 0.22), blind = after(nullptr, 0.22);
  EXPECT_GT(early.fl, 0.005);  // before the middle: moved with the command
  EXPECT_EQ(late.fl, 0.0);     // after it: held, bit for bit
  EXPECT_GT(blind.fl, 0.005);  // blind: as before (flat ground plans as it did)
  EXPECT_GT(late.fr, 0.005);
}

TEST(GaitGenerator, OnAMapAFootholdAcrossAnUnsafeBandIsKeptWhenTheBodyLags) {
  // A 5 cm riser 5 mm past FL's nominal touch-down (0.3 s), edges unsafe within 10 cm: the foot
  // steps across the band (10.5 cm on) rather than short of it (9.5 cm back, counted twice). When
  // the body then lags 2 cm, the place across is 12.5 cm on, beyond max_foothold_shift (12 cm):
  // planned afresh, the foot would step short of the band; planned again, its choice is kept
  // (within 1.5 x max_foothold_shift), not flipped 20 cm back in mid-swing.
  GaitGeneratorOptions o = hand();
  o.max_foothold_lead = 0.0;  // footholds from the measured body
  o.max_foothold_shift = 0.12;
  auto fl = [&](const terrain::Steppability* map, bool plan_first, double lag) {
    Generator g(o);
    g->setCommand(velocity(0.3));
    if (plan_first) {
      if (map) g->setMap(map);
      EXPECT_TRUE(g->plan(0.15, placed(0.045, 0.0, 0.0), 0.15, 1.15));
    }
    if (map) g->setMap(map);
    EXPECT_TRUE(g->plan(0.16, placed(0.048 - lag, 0.0, 0.0), 0.16, 1.16));
    EXPECT_NEAR(g->stance(FL, 1).touch_down, 0.3, 1e-9);
    return g->stance(FL, 1).p.x();
  };
  const double nominal = fl(nullptr, true, 0.0), edge = nominal + 0.005;
  EXPECT_NEAR(fl(nullptr, true, 0.02), nominal - 0.02, 1e-9);  // the nominal follows the body
  terrain::SteppabilityOptions wide;
  wide.min_edge_distance = 0.1;
  wide.edge_search_radius = 0.12;
  const terrain::Steppability box =
      mapOf([&](double x, double) { return x >= edge ? 0.05 : 0.0; }, wide);
  const double across = fl(&box, true, 0.0);
  EXPECT_GE(across, edge + 0.1 - 1e-9);
  EXPECT_LT(across, edge + 0.12);
  EXPECT_LE(fl(&box, false, 0.02), edge - 0.1 + 1e-9);  // afresh: short of the band
  EXPECT_EQ(fl(&box, true, 0.02), across);              // again: kept
}

}  // namespace test_gait_generator
}  // namespace stride
