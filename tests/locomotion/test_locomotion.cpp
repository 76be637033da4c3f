// Contact plans and the locomotion problem: plan queries and validation, the knots update() sets
// up, and FDDP / box-FDDP solves of solo12 standing and trotting and talos_reduced standing and
// stepping from a standing warm start, checked for convergence, monotonic cost, closed gaps,
// friction, swing-foot lift and landing, and torque bounds; DDP and FDDP agree; the solution does
// not depend on the thread count.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include <cmath>
#include <cstdio>

#include "locomotion_cases.hpp"
#include "solver/contact/contact_dynamics.hpp"
#include "solver/ddp/solver.hpp"
#include "solver/multibody/aba.hpp"
#include "solver/multibody/centroidal.hpp"
#include "solver/multibody/lie_group.hpp"
#include "solver/ocp/residual_frame.hpp"
#include "solver/ocp/residual_state.hpp"
#include "terrain/steppability.hpp"

namespace stride {
namespace test_locomotion {

using loco_cases::Case;
using loco_cases::Problem;

const std::string kShared = STRIDE_SHARED_DIR;

// ---------------------------------------------------------------------------- plans

ContactSet fourFeet(const Model& model) {
  ContactSet s;
  for (const char* foot : {"FL_FOOT", "FR_FOOT", "HL_FOOT", "HR_FOOT"})
    s.add(model, foot, 3, ReferenceFrame::LocalWorldAligned);
  return s;
}

const Model& solo() {
  static const Model m =
      buildModelFromUrdf(kShared + "/robots/solo12/solo12.urdf", RootJoint::FreeFlyer);
  return m;
}

TEST(ContactPlan, Queries) {
  ContactPlan plan = loco_cases::soloTrot(0.1, 0.2);  // [0, 0.1) [0.1, 0.3) [0.3, 0.4) [0.4, 0.6)
  EXPECT_DOUBLE_EQ(plan.duration(), 0.6);
  EXPECT_EQ(plan.phaseAt(-1.0), 0);
  EXPECT_EQ(plan.phaseAt(0.05), 0);
  EXPECT_EQ(plan.phaseAt(0.1), 1);
  EXPECT_EQ(plan.phaseAt(10 * 0.01), 1);  // 0.09999999999999999: a knot time, rounding absorbed
  EXPECT_EQ(plan.phaseAt(0.35), 2);
  EXPECT_EQ(plan.phaseAt(0.59), 3);
  EXPECT_EQ(plan.phaseAt(0.65), 0);  // wraps
  EXPECT_EQ(plan.phaseAt(6.0 + 0.15), 1);
  EXPECT_DOUBLE_EQ(plan.phaseStart(2), 0.3);
  EXPECT_THROW(plan.phaseStart(4), std::invalid_argument);
  EXPECT_TRUE(plan.isClosed("FL_FOOT", 0.05));
  EXPECT_FALSE(plan.isClosed("FL_FOOT", 0.2));
  EXPECT_TRUE(plan.isClosed("FR_FOOT", 0.2));
  EXPECT_FALSE(plan.isClosed("FR_FOOT", 0.5));
  EXPECT_FALSE(plan.isClosed("FR_FOOT", 0.6 + 0.5));
  plan.cyclic = false;
  EXPECT_EQ(plan.phaseAt(0.65), 3);  // the last phase is held
  EXPECT_TRUE(plan.isClosed("FL_FOOT", 100.0));
  EXPECT_FALSE(plan.isClosed("FR_FOOT", 100.0));

  // The schedule: the same answers by index, touch-downs and swings.
  plan.cyclic = true;
  const ContactSet feet = fourFeet(solo());
  const ContactSchedule s(plan, feet);
  const int FL = feet.find("FL_FOOT"), FR = feet.find("FR_FOOT");
  EXPECT_EQ(s.phaseAt(0.65), 4);  // global: second pass, phase 0
  EXPECT_EQ(s.localPhase(4), 0);
  EXPECT_DOUBLE_EQ(s.phaseStart(5), 0.7);
  EXPECT_FALSE(s.closedAt(FL, 0.2));
  EXPECT_TRUE(s.closedAt(FL, 0.3));
  // FL lands at 0.3, 0.9, 1.5, ...; FR at 0.6, 1.2, ...
  EXPECT_EQ(s.touchdowns(FL, s.phaseAt(0.29)), 0);
  EXPECT_EQ(s.touchdowns(FL, s.phaseAt(0.3)), 1);
  EXPECT_EQ(s.touchdowns(FL, s.phaseAt(1.0)), 2);
  EXPECT_EQ(s.touchdowns(FR, s.phaseAt(0.59)), 0);
  EXPECT_EQ(s.touchdowns(FR, s.phaseAt(0.6)), 1);
  EXPECT_EQ(s.touchdowns(FR, s.phaseAt(60.05)), 100);
  const ContactSchedule::Swing sw = s.swing(FL, s.phaseAt(0.8));
  EXPECT_NEAR(sw.lift_off, 0.7, 1e-12);
  EXPECT_NEAR(sw.touch_down, 0.9, 1e-12);
  EXPECT_EQ(sw.footholds, 1);
  // A plan that does not repeat: a foot that never lands again has no touch-down.
  ContactPlan once = plan;
  once.cyclic = false;
  once.phases.pop_back();  // ends in double support
  once.phases.push_back({0.2, {"FL_FOOT", "HR_FOOT"}});
  const ContactSchedule o(once, feet);
  EXPECT_EQ(o.phaseAt(5.0), 3);
  EXPECT_TRUE(std::isinf(o.swing(FR, 3).touch_down));
  EXPECT_NEAR(o.swing(FR, 3).lift_off, 0.4, 1e-12);
}

TEST(ContactPlan, ValidationNamesTheProblem) {
  const ContactSet feet = fourFeet(solo());
  auto message = [&](const ContactPlan& p) {
    try {
      p.validate(feet);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(message(ContactPlan{}).find("no phase"), std::string::npos);
  for (double d : {0.0, -0.1, std::nan(""), HUGE_VAL}) {
    ContactPlan p = loco_cases::soloTrot();
    p.phases[2].duration = d;
    EXPECT_NE(message(p).find("phase 2"), std::string::npos) << d;
  }
  ContactPlan p = loco_cases::soloTrot();
  p.phases[1].contacts.push_back("LF_FOOT");
  EXPECT_NE(message(p).find("'LF_FOOT'"), std::string::npos);
  p = loco_cases::soloTrot();
  p.phases[3].contacts.push_back("FL_FOOT");
  EXPECT_NE(message(p).find("twice"), std::string::npos);
  EXPECT_EQ(message(loco_cases::soloTrot()), "");
  EXPECT_THROW(ContactSchedule(ContactPlan{}, feet), std::invalid_argument);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(solo().nq + solo().nv);
  x[6] = 1.0;
  LocomotionOptions bad;
  bad.dt = 0.0;
  EXPECT_THROW(LocomotionProblem(solo(), feet, x, bad), std::invalid_argument);
  EXPECT_THROW(LocomotionProblem(solo(), feet, x.head(5)), std::invalid_argument);
}

// ---------------------------------------------------------------------------- knots

const KnotModel& knotAt(const LocomotionProblem& loco, int k) {
  return static_cast<const KnotModel&>(loco.problem().knot(k));
}

// The knots update() configures: contacts and cone terms follow the plan, swing terms are on
// while a foot is open and at its touch-down knot, which is an impulse knot.
TEST(LocomotionProblem, UpdateConfiguresKnots) {
  Case c = loco_cases::make(Problem::SoloTrot, kShared);
  LocomotionProblem& loco = *c.loco;
  const GaitGenerator& s = *c.ref;
  const int FL = loco.contacts().find("FL_FOOT");
  const double dt = loco.options().dt;
  for (double t0 : {0.0, 0.13, 0.47}) {
    ASSERT_TRUE(c.update(t0));
    int impulses = 0;
    // Impulse knots take no time: the contact knot after one stands for the same time.
    double expected_t = t0;
    bool after_impulse = false;
    for (int k = 0; k < loco.problem().horizon(); ++k) {
      const KnotModel& knot = knotAt(loco, k);
      const double t = loco.knotTime(k);
      EXPECT_NEAR(t, expected_t, 1e-12) << k;
      const bool closed = s.closed(FL, t), before = s.closed(FL, t - dt);
      EXPECT_EQ(knot.contacts().isActive(FL), closed) << t;
      EXPECT_EQ(knot.costs()[knot.costs().find("cone_FL_FOOT")].active, closed);
      const CostTerm& swing = knot.costs()[knot.costs().find("swing_FL_FOOT")];
      EXPECT_EQ(swing.active, !closed || !before) << t;
      bool lands = false;
      for (int f = 0; f < 4; ++f) lands = lands || (s.closed(f, t) && !s.closed(f, t - dt));
      const bool impulse = lands && !after_impulse;
      EXPECT_EQ(knot.mode() == KnotMode::Impulse, impulse) << t;
      impulses += impulse;
      after_impulse = impulse;
      if (!impulse) expected_t += dt;
      if (swing.active) {
        const auto& r = static_cast<const FrameTranslationResidual&>(*swing.residual);
        EXPECT_EQ(r.reference(), s.foot(FL, t));
      }
    }
    EXPECT_GE(impulses, 2) << t0;
    EXPECT_NEAR(loco.knotTime(loco.problem().horizon()), expected_t, 1e-12);
  }
  EXPECT_FALSE(loco.update(std::nan(""), s));
  EXPECT_FALSE(loco.update(std::numeric_limits<double>::infinity(), s));
  EXPECT_FALSE(c.update(std::nan("")));
  // The swing arc: from where the foot stands (stance 0), apex half way up, the next foothold
  // at touch-down (FL swings 0.1-0.3 s).
  ASSERT_TRUE(c.update(0.0));
  const Eigen::Vector3d p0 = s.stance(FL, 0).p, p1 = s.stance(FL, 1).p;
  EXPECT_NEAR(s.stance(FL, 0).lift_off, 0.1, 1e-12);
  EXPECT_NEAR(s.stance(FL, 1).touch_down, 0.3, 1e-12);
  EXPECT_NEAR(p0.z(), 0.0, 1e-12);
  EXPECT_TRUE(s.foot(FL, 0.1).isApprox(p0));
  const Eigen::Vector3d apex = s.foot(FL, 0.2);
  EXPECT_NEAR(apex.z(), s.options().swing_height, 1e-12);
  EXPECT_NEAR(apex.x(), 0.5 * (p0.x() + p1.x()), 1e-12);
  EXPECT_GT(p1.x(), p0.x() + 0.01);  // commanded forward
  EXPECT_TRUE(s.foot(FL, 0.3).isApprox(p1));
  EXPECT_TRUE(s.foot(FL, 0.35).isApprox(p1));
  EXPECT_TRUE(s.foot(FL, 0.65).isApprox(p1));

  // After a shift the knots are rebuilt for the new start time, as a fresh problem's.
  Case fresh = loco_cases::make(Problem::SoloTrot, kShared);
  ASSERT_TRUE(c.update(0.0));
  loco.problem().shift(7);
  ASSERT_TRUE(c.update(7 * dt));
  ASSERT_TRUE(fresh.update(7 * dt));
  for (int k = 0; k < loco.problem().horizon(); ++k) {
    const KnotModel &a = knotAt(loco, k), &b = knotAt(*fresh.loco, k);
    EXPECT_EQ(a.mode(), b.mode()) << k;
    for (int f = 0; f < 4; ++f) EXPECT_EQ(a.contacts().isActive(f), b.contacts().isActive(f));
    for (int i = 0; i < a.costs().size(); ++i) EXPECT_EQ(a.costs()[i].active, b.costs()[i].active);
  }

  // Impulses off: contact knots only.
  Case no_impulse = loco_cases::make(Problem::SoloTrot, kShared,
                                     [](LocomotionOptions& o) { o.impulses = false; });
  for (int k = 0; k < no_impulse.loco->problem().horizon(); ++k)
    EXPECT_EQ(knotAt(*no_impulse.loco, k).mode(), KnotMode::Contact);
}

TEST(LocomotionProblem, ASwingToAFootholdNearAnEdgeWeighsEveryAxis) {
  // With swing_horizontal lighter than swing the solver may move a foothold by a few cm; not one a
  // map placed near an edge (FL lands at 0.3 s 5 cm before a 5 cm riser: within the edge search
  // radius, 8 cm), whose swing weighs `swing` on every axis. FL's swing is 0.1-0.3 s.
  Case c = loco_cases::make(Problem::SoloTrot, kShared, [](LocomotionOptions& o) {
    o.weights.swing = 1e4;
    o.weights.swing_horizontal = 1e3;
  });
  LocomotionProblem& loco = *c.loco;
  const int FL = loco.contacts().find("FL_FOOT");
  auto flSwingWeights = [&]() {
    Eigen::Vector3d w = Eigen::Vector3d::Zero();
    for (int k = 0; k < loco.problem().horizon(); ++k) {
      const double t = loco.knotTime(k);
      if (t <= 0.11 || t >= 0.29) continue;
      const KnotModel& knot = knotAt(loco, k);
      const CostTerm& swing = knot.costs()[knot.costs().find("swing_FL_FOOT")];
      EXPECT_TRUE(swing.active) << t;
      if (w.isZero()) w = swing.activation.weights;
      EXPECT_EQ(swing.activation.weights, w) << t;  // the same along the swing
    }
    return w;
  };
  ASSERT_TRUE(c.update(0.0));
  const double landing = c.ref->stance(FL, 1).p.x();
  EXPECT_EQ(flSwingWeights(), Eigen::Vector3d(1e3, 1e3, 1e4));  // blind
  auto mapWithRiserAt = [&](double edge) {
    terrain::ElevationMap m;
    m.resolution = 0.01;
    m.origin_x = -1.0;
    m.origin_y = -1.0;
    m.resize(201, 201);
    for (int r = 0; r < m.rows; ++r)
      for (int col = 0; col < m.cols; ++col)
        m.at(r, col) = m.origin_x + col * m.resolution >= edge ? 0.05f : 0.0f;
    terrain::Steppability st({}, m.rows * m.cols);
    EXPECT_TRUE(st.update(m));
    return st;
  };
  const terrain::Steppability near = mapWithRiserAt(landing + 0.05);
  c.ref->setMap(&near);
  ASSERT_TRUE(c.update(0.0));
  EXPECT_NEAR(c.ref->stance(FL, 1).p.x(), landing, 0.01);  // 5 cm before it is safe
  EXPECT_TRUE(c.ref->stance(FL, 1).near_edge);
  EXPECT_EQ(flSwingWeights(), Eigen::Vector3d(1e4, 1e4, 1e4));
  const terrain::Steppability far = mapWithRiserAt(landing + 0.2);
  c.ref->setMap(&far);
  ASSERT_TRUE(c.update(0.0));
  EXPECT_FALSE(c.ref->stance(FL, 1).near_edge);
  EXPECT_EQ(flSwingWeights(), Eigen::Vector3d(1e3, 1e3, 1e4));
}

// On raised ground and on a flight of stairs, the control reference of every knot holds the posture
// of the COMMANDED body height, blended between the crouch postures exactly as the joints'
// reference is: the ground under the feet raises the base reference, not the offset of the body
// over the feet (a control reference fed the base's height above the nominal one sat at the highest
// posture's torques, 30 cm up, while the joints asked for the commanded one).
TEST(LocomotionProblem, OnStairsTheControlReferenceHoldsTheCommandedHeight) {
  Case c = loco_cases::make(Problem::SoloTrot, kShared);
  const loco_cases::Robot& r = *c.robot;
  LocomotionProblem& loco = *c.loco;
  GaitGeneratorOptions g = c.ref->options();
  g.max_height = 0.04;  // solo12's (config/controller/solo12.yaml): postures every 1 cm
  GaitGenerator gen(r.model, r.contacts, r.x_nominal, g);
  gen.timeline().reset(gen.timeline().addPattern(loco_cases::soloTrot()), 0.0);
  ASSERT_EQ(gen.crouchPostures().size(), 9u);
  loco.setPostures(gen.crouchPostures(), g.max_height);
  // A commanded height half way between two solved postures: 1.5 cm is u = 5.5 of 0..8.
  BodyCommand command = c.velocity;
  command.height = 0.015;
  gen.setCommand(command);
  const int nq = r.model.nq;
  auto holding = [&](int i) {
    Eigen::VectorXd q = r.x_nominal.head(nq);
    q.tail(nq - 7) = gen.crouchPostures()[i];
    return loco.holdingControlsOf(q);
  };
  const std::vector<Eigen::VectorXd> u5 = holding(5), u6 = holding(6), u8 = holding(8);
  const Eigen::VectorXd joints = 0.5 * (gen.crouchPostures()[5] + gen.crouchPostures()[6]);
  // The robot stands 30 cm up (feet, base and all).
  Eigen::VectorXd x0 = r.x_nominal;
  x0[2] += 0.3;
  auto check = [&](const char* where) {
    ASSERT_TRUE(gen.plan(0.0, x0, 0.0, loco.span()));
    ASSERT_TRUE(loco.update(0.0, gen));
    Eigen::VectorXd x_ref(x0.size());
    double worst = 0.0, worst_vs_highest = 0.0;
    for (int k = 0; k < loco.problem().horizon(); ++k) {
      const double t = loco.knotTime(k);
      gen.state(t, x_ref);
      EXPECT_GT(x_ref[2] - r.x_nominal[2], 0.25) << where << " knot " << k;  // on the ground
      EXPECT_NEAR((x_ref.segment(7, nq - 7) - joints).norm(), 0.0, 1e-12) << where << " " << k;
      const KnotModel& knot = knotAt(loco, k);
      const Eigen::VectorXd& u =
          static_cast<const ControlResidual&>(*knot.costs()[knot.costs().find("control")].residual)
              .reference();
      const unsigned mask = loco.contactMask(k);
      const Eigen::VectorXd expected = 0.5 * (u5[mask] + u6[mask]);
      worst = std::max(worst, (u - expected).cwiseAbs().maxCoeff());
      worst_vs_highest = std::max(worst_vs_highest, (u - u8[mask]).cwiseAbs().maxCoeff());
    }
    std::printf("%s: |u_ref - u(commanded 1.5 cm)| <= %.3g N m, |u_ref - u(highest)| <= %.3g\n",
                where, worst, worst_vs_highest);
    EXPECT_LT(worst, 1e-12) << where;
  };
  check("raised ground (blind)");
  // A flight of stairs up ahead of the robot (10 cm risers, 20 cm treads from x = 0.25) on a map
  // that is 30 cm high under it.
  terrain::ElevationMap m;
  m.resolution = 0.01;
  m.origin_x = -1.0;
  m.origin_y = -1.0;
  m.resize(201, 301);
  for (int row = 0; row < m.rows; ++row)
    for (int col = 0; col < m.cols; ++col) {
      const double x = m.origin_x + col * m.resolution;
      m.at(row, col) =
          static_cast<float>(0.3 + 0.1 * std::max(0.0, std::floor((x - 0.25) / 0.2) + 1.0));
    }
  terrain::Steppability stairs({}, m.rows * m.cols);
  ASSERT_TRUE(stairs.update(m));
  gen.setMap(&stairs);
  check("stairs (map)");
}

// A non-uniform grid (LocomotionOptions::grid): the first segment's knots from t0, then each
// longer segment from its first boundary on the plan clock, so the long knots sit at fixed plan
// times from tick to tick; weights scale with the duration; impulse knots take no time.
// In flight (no contact closed) the torque that holds a posture is zero (issue 45): the whole body
// then falls at g with every joint still (ABA of the posture at rest, u = 0), where the fixed-base
// gravity torques the table held before swung the legs.
TEST(LocomotionProblem, FlightHoldsAPostureWithZeroTorque) {
  Case c = loco_cases::make(Problem::SoloTrot, kShared);
  const loco_cases::Robot& r = *c.robot;
  const int nq = r.model.nq, nv = r.model.nv;
  EXPECT_EQ(c.loco->holdingControl(0u).cwiseAbs().maxCoeff(), 0.0);
  Data data(r.model);
  const Eigen::VectorXd q = r.x_nominal.head(nq);
  const Eigen::VectorXd a =
      aba(r.model, data, q, Eigen::VectorXd::Zero(nv), Eigen::VectorXd::Zero(nv));
  // The base's linear acceleration in its own frame is gravity rotated into it.
  const Eigen::Quaterniond o(q[6], q[3], q[4], q[5]);
  const Eigen::Vector3d g_base = o.conjugate() * Eigen::Vector3d(0.0, 0.0, -9.81);
  EXPECT_LT((a.head<3>() - g_base).norm(), 1e-9);
  EXPECT_LT(a.segment<3>(3).norm(), 1e-9);
  EXPECT_LT(a.tail(nv - 6).cwiseAbs().maxCoeff(), 1e-9);
  // With every foot down the table still holds the stance's torques (not zero).
  EXPECT_GT(c.loco->holdingControl(0xfu).cwiseAbs().maxCoeff(), 0.1);
}

TEST(LocomotionProblem, GridKnotsSitAtFixedPlanTimes) {
  const std::vector<KnotSegment> grid = {{10, 0.01}, {10, 0.02}, {15, 0.03}};
  Case c =
      loco_cases::make(Problem::SoloTrot, kShared, [&](LocomotionOptions& o) { o.grid = grid; });
  LocomotionProblem& loco = *c.loco;
  EXPECT_EQ(loco.options().knots, 35);
  EXPECT_DOUBLE_EQ(loco.options().dt, 0.01);
  EXPECT_NEAR(loco.span(), 0.1 + 0.2 + 0.45, 1e-12);
  const int T = loco.problem().horizon();
  std::vector<double> tail_previous;  // start times of the 30 ms knots at the last t0
  for (double t0 : {0.0, 0.01, 0.02, 0.13, 0.14, 0.47}) {
    ASSERT_TRUE(c.update(t0));
    std::vector<double> tail;
    int contact_knots = 0, impulses = 0;
    for (int k = 0; k < T; ++k) {
      const KnotModel& knot = knotAt(loco, k);
      const double t = loco.knotTime(k), next = loco.knotTime(k + 1);
      const CostTerm& state = knot.costs()[knot.costs().find("state")];
      if (knot.mode() == KnotMode::Impulse) {
        ++impulses;
        EXPECT_DOUBLE_EQ(next, t) << k;  // no time
        EXPECT_DOUBLE_EQ(state.weight, 1.0);
        continue;
      }
      const double dt = knot.dt();
      EXPECT_NEAR(next - t, dt, 1e-12) << k;
      EXPECT_NEAR(state.weight, dt / 0.01, 1e-9) << k;  // a knot weighs its duration
      if (contact_knots < 10) {
        EXPECT_DOUBLE_EQ(dt, 0.01) << k;
      }
      EXPECT_LE(dt, 0.03 + 1e-12);
      if (std::abs(dt - 0.03) < 1e-12) {
        const double n = t / 0.03;
        EXPECT_NEAR(n, std::round(n), 1e-6) << "a 30 ms knot at " << t;
        tail.push_back(t);
      }
      ++contact_knots;
    }
    EXPECT_GE(impulses, 1) << t0;
    EXPECT_LE(loco.knotTime(T), t0 + loco.span() + 1e-9);
    EXPECT_GE(tail.size(), 10u) << t0;
    // Moved on by 10 ms, the long knots still sit where they were (those in both windows).
    for (double t : tail_previous) {
      if (t >= tail.front() - 1e-9 && t <= tail.back() + 1e-9) {
        EXPECT_TRUE(
            std::any_of(tail.begin(), tail.end(), [&](double u) { return std::abs(u - t) < 1e-9; }))
            << t << " at t0 " << t0;
      }
    }
    tail_previous = tail;
  }
  // Durations that decrease, or a segment without knots, are refused.
  for (const auto& bad : std::vector<std::vector<KnotSegment>>{
           {{10, 0.02}, {10, 0.01}}, {{10, 0.01}, {0, 0.02}}, {{10, 0.01}, {5, -0.02}}}) {
    LocomotionOptions o = loco.options();
    o.grid = bad;
    EXPECT_THROW(LocomotionProblem(c.robot->model, c.robot->contacts, c.robot->x_nominal, o),
                 std::invalid_argument);
  }
}

// ---------------------------------------------------------------------------- solves

// What a solution looks like, measured.
struct Measures {
  // Contact knots: the least μ f_z - |f_t| over closed contacts [N], and the least f_z [N].
  double min_cone_margin = HUGE_VAL;
  double min_normal = HUGE_VAL;
  double min_impulse_margin = HUGE_VAL;  // impulse knots: μ Λ_z - |Λ_t| [N s]
  double lowest_apex = 0.0;              // the lowest, over swings, of the foot's highest point [m]
  double max_landing = 0.0;  // the largest distance between a landed foot and its foothold [m]
  int swings = 0;
};

Measures measure(Case& c, const Solver& solver) {
  LocomotionProblem& loco = *c.loco;
  ShootingProblem& problem = loco.problem();
  problem.calc(solver.xs(), solver.us());
  const Model& model = *problem.state().model();
  const GaitGenerator& s = *c.ref;
  const double mu = loco_cases::kGroundFriction;
  Measures m;
  Data data(model);
  const int T = problem.horizon(), nc = loco.contacts().size();
  std::vector<double> highest(nc, 0.0);
  std::vector<char> was_closed(nc, 1);
  double apex = HUGE_VAL;
  for (int k = 0; k <= T; ++k) {
    // Knot times from the problem: an impulse knot and the contact knot after it share one.
    const double t = loco.knotTime(k);
    framesForwardKinematics(model, data, solver.xs()[k].head(model.nq));
    for (int c = 0; c < nc; ++c) {
      const Eigen::Vector3d p = data.oMf[loco.contacts()[c].frame].p;
      const bool closed = s.closed(c, t);
      const bool landed = closed && k > 0 && !was_closed[c];
      was_closed[c] = closed;
      if (!closed) highest[c] = std::max(highest[c], p.z());
      if (landed) {  // landed at this knot
        m.max_landing = std::max(m.max_landing, (p - s.foot(c, t)).norm());
        apex = std::min(apex, highest[c]);
        highest[c] = 0.0;
        ++m.swings;
      }
    }
    if (k == T) break;
    const auto& knot = static_cast<const KnotModel&>(problem.knot(k));
    const auto& d = static_cast<const KnotActionData&>(problem.data(k));
    const Eigen::VectorXd& f = d.forces();  // λ, or the impulses Λ on an impulse knot
    int offset = 0;
    for (int c = 0; c < nc; ++c) {
      if (!knot.contacts().isActive(c)) continue;
      const Eigen::Vector3d fc = f.segment<3>(offset);  // world axes (LOCAL_WORLD_ALIGNED)
      const double margin = mu * fc.z() - fc.head<2>().norm();
      if (knot.mode() == KnotMode::Impulse) {
        m.min_impulse_margin = std::min(m.min_impulse_margin, margin);
      } else {
        m.min_cone_margin = std::min(m.min_cone_margin, margin);
        m.min_normal = std::min(m.min_normal, fc.z());
      }
      offset += knot.contacts()[c].dim;
    }
  }
  m.lowest_apex = m.swings > 0 ? apex : 0.0;
  return m;
}

// xs = the references (the nominal posture carried along), us = the holding torques.
SolveStatus solveFromStanding(Case& c, Solver& solver, int max_iterations) {
  std::vector<Eigen::VectorXd> xs, us;
  c.warmStart(xs, us);
  EXPECT_TRUE(solver.setWarmStart(xs, us));
  return solver.solve(max_iterations);
}

void expectMonotonicOnceFeasible(const Solver& solver) {
  for (int i = 1; i < solver.statsCount(); ++i) {
    const IterationStats &a = solver.stats()[i - 1], &b = solver.stats()[i];
    if (a.gap < 1e-9) {
      EXPECT_LE(b.cost, a.cost * (1.0 + 1e-12)) << "iteration " << i;
    }
  }
}

// A push: x0 = x_nominal with the base velocity v_base (world axes) and the joint velocities that
// keep every foot still (the contacts hold velocities, they do not correct them).
void push(LocomotionProblem& loco, const Eigen::Vector3d& v_base) {
  const Model& model = *loco.problem().state().model();
  Data data(model);
  ContactSet all = loco.contacts();
  ContactData cd(model, all);
  const Eigen::VectorXd q = loco.nominal().head(model.nq), zero = Eigen::VectorXd::Zero(model.nv);
  ASSERT_EQ(contactDynamics(model, data, all, cd, q, zero, zero), ContactStatus::Ok);
  const Eigen::MatrixXd Jc = cd.Jc.topRows(all.nc());
  Eigen::VectorXd v = Eigen::VectorXd::Zero(model.nv);
  v.head<3>() = v_base;  // base at the identity orientation: local = world axes
  v.tail(model.nv - 6) = -Jc.rightCols(model.nv - 6)
                              .completeOrthogonalDecomposition()
                              .solve(Jc.leftCols(6) * v.head(6));
  ASSERT_LT((Jc * v).norm(), 1e-9);
  Eigen::VectorXd x0 = loco.nominal();
  x0.tail(model.nv) = v;
  ASSERT_TRUE(loco.problem().setX0(x0));
}

struct SolveCase {
  Problem problem;
  int max_iterations;
  // Standing still from the holding torques is already optimal (x_nominal is an equilibrium and
  // every cost is zero there): the standing cases start with a push instead.
  double push;  // base speed [m/s] of the push (0: none)
  Integrator integrator = Integrator::Euler;
};

class LocomotionSolve : public ::testing::TestWithParam<SolveCase> {};

TEST_P(LocomotionSolve, FddpConvergesToAFeasibleGait) {
  const SolveCase sc = GetParam();
  Case c = loco_cases::make(sc.problem, kShared,
                            [&sc](LocomotionOptions& o) { o.integrator = sc.integrator; });
  LocomotionProblem& loco = *c.loco;
  for (int k = 0; k < loco.problem().horizon(); ++k)
    ASSERT_EQ(static_cast<const KnotModel&>(loco.problem().knot(k)).integrator(), sc.integrator);
  Solver solver(loco.problem(), SolverKind::Fddp);
  if (std::getenv("STRIDE_DEBUG")) solver.callback = Solver::printIterationTable;
  const bool pushed = sc.push > 0.0;
  if (pushed) push(loco, sc.push * Eigen::Vector3d(1.0, 1.0, 0.0).normalized());
  const double cost0 = [&] {
    std::vector<Eigen::VectorXd> xs, us;
    c.warmStart(xs, us);
    return loco.problem().calc(xs, us);
  }();
  const SolveStatus status = solveFromStanding(c, solver, sc.max_iterations);
  EXPECT_EQ(status, SolveStatus::Converged) << toString(status);
  EXPECT_LT(solver.gap(), 1e-9);
  if (!pushed) {  // (a pushed robot starts elsewhere)
    EXPECT_LE(solver.cost(), cost0);
  }
  expectMonotonicOnceFeasible(solver);
  const Measures m = measure(c, solver);
  const Model& model = c.robot->model;
  const double weight_impulse = model.totalMass() * 9.81 * loco.options().dt;
  std::printf(
      "[ %s %s ] %d iterations, cost %.9g (standing start %.6g), gap %.2e, min cone margin "
      "%.4g N, min normal %.4g N, min impulse cone margin %.3g N s (weight x dt %.3g N s), "
      "swings %d, lowest apex %.4f m, worst landing %.2e m\n",
      loco_cases::name(sc.problem), toString(sc.integrator), solver.iterations(), solver.cost(),
      cost0, solver.gap(), m.min_cone_margin, m.min_normal, m.min_impulse_margin, weight_impulse,
      m.swings, m.lowest_apex, m.max_landing);
  EXPECT_GE(m.min_cone_margin, 0.0);
  EXPECT_GT(m.min_normal, 0.0);
  // A soft landing has near-zero impulses, so the cone on them is met up to rounding-sized
  // violations of the penalty: at most 1 % of the impulse of the robot's weight over one knot.
  if (m.min_impulse_margin < HUGE_VAL) {
    EXPECT_GE(m.min_impulse_margin, -1e-2 * weight_impulse);
  }
  if (sc.problem == Problem::SoloTrot || sc.problem == Problem::TalosStep) {
    EXPECT_GE(m.swings, sc.problem == Problem::SoloTrot ? 4 : 1);
    EXPECT_GE(m.lowest_apex, 0.5 * c.ref->options().swing_height);
    EXPECT_LT(m.max_landing, 5e-3);
  }
}

// In flight (no contact closed) the planned motion has only gravity on it (issue 45): at every
// flight knot the rate of the centroidal momentum, from the knot's state and the acceleration its
// dynamics gave (v_{k+1} = v_k + dt a_k, semi-implicit Euler), is the weight's, (m g, 0): the
// linear momentum falls by m g per second and the angular momentum about the centre of mass does
// not change. Over the flight the centre of mass follows its take-off velocity's ballistic arc, to
// the Euler steps' first-order error.
TEST(LocomotionSolve, FlightKnotsConserveCentroidalMomentum) {
  Case c = loco_cases::make(Problem::SoloPronk, kShared);
  LocomotionProblem& loco = *c.loco;
  Solver solver(loco.problem(), SolverKind::Fddp);
  if (std::getenv("STRIDE_DEBUG")) solver.callback = Solver::printIterationTable;
  solveFromStanding(c, solver, 100);
  EXPECT_LT(solver.gap(), 1e-9);
  const Model& model = c.robot->model;
  const int nq = model.nq, nv = model.nv, T = loco.problem().horizon();
  const double m = model.totalMass(), g = 9.81;
  Data data(model);
  auto state = [&](int k, Eigen::Vector3d& com, Eigen::Vector3d& vcom) {
    const Eigen::VectorXd& x = solver.xs()[k];
    computeCentroidalMomentum(model, data, x.head(nq), x.tail(nv));
    com = data.com;
    vcom = data.vcom;
  };
  // dh/dt at (q, v) moving with acceleration a: central differences along the motion.
  auto rate = [&](const Eigen::VectorXd& q, const Eigen::VectorXd& v, const Eigen::VectorXd& a) {
    const double eps = 1e-6;
    const Vector6d up =
        computeCentroidalMomentum(model, data, integrate(model, q, eps * v), v + eps * a);
    const Vector6d down =
        computeCentroidalMomentum(model, data, integrate(model, q, -eps * v), v - eps * a);
    return ((up - down) / (2.0 * eps)).eval();
  };
  Vector6d weight = Vector6d::Zero();
  weight[2] = -m * g;
  int flights = 0, flight_knots = 0;
  double worst_rate = 0.0, worst_landing = 0.0, highest_rise = 0.0;
  for (int k = 1; k < T; ++k) {
    // A flight: contact knots with no contact closed from k on; knot `end` touches down.
    if (loco.contactMask(k) != 0u || loco.contactMask(k - 1) == 0u) continue;
    int end = k;
    while (end < T && loco.contactMask(end) == 0u) ++end;
    ++flights;
    for (int j = k; j < end; ++j) {
      const Eigen::VectorXd& x = solver.xs()[j];
      const double dt = loco.knotTime(j + 1) - loco.knotTime(j);
      const Eigen::VectorXd a = (solver.xs()[j + 1].tail(nv) - x.tail(nv)) / dt;
      worst_rate = std::max(worst_rate, (rate(x.head(nq), x.tail(nv), a) - weight).norm());
      ++flight_knots;
    }
    Eigen::Vector3d c0, v0, c1, v1;
    state(k, c0, v0);
    state(end, c1, v1);
    const double t_air = loco.knotTime(end) - loco.knotTime(k);
    const Eigen::Vector3d ballistic =
        c0 + t_air * v0 + 0.5 * t_air * t_air * Eigen::Vector3d(0.0, 0.0, -g);
    worst_landing = std::max(worst_landing, (c1 - ballistic).norm());
    highest_rise = std::max(highest_rise, v0.z() * v0.z() / (2.0 * g));
    std::printf(
        "flight from %.3f s for %.3f s: take-off CoM velocity (%.3f %.3f %.3f) m/s, landed "
        "%.2e m from its ballistic point\n",
        loco.knotTime(k), t_air, v0.x(), v0.y(), v0.z(), (c1 - ballistic).norm());
  }
  std::printf("%d flights, %d knots: |dh/dt - (m g, 0)| <= %.2e (m g = %.2f N)\n", flights,
              flight_knots, worst_rate, m * g);
  EXPECT_EQ(flights, 2);
  EXPECT_GE(flight_knots, 30);
  // A contact force left on in flight would be of the order of m g.
  EXPECT_LT(worst_rate, 1e-5 * m * g);
  // The centre of mass moves by dt v_{k+1} per Euler step: off the exact arc by ½ g dt t_air,
  // 1 cm for 0.2 s of 10 ms steps (plus the base's rotation, small here).
  EXPECT_LT(worst_landing, 0.5 * g * 0.01 * 0.2 + 3e-3);
  // It jumps: the take-off speed carries the centre of mass up by several centimetres.
  EXPECT_GT(highest_rise, 0.03);
}

INSTANTIATE_TEST_SUITE_P(Problems, LocomotionSolve,
                         ::testing::Values(SolveCase{Problem::SoloStand, 50, 0.05},
                                           SolveCase{Problem::SoloTrot, 150, 0.0},
                                           SolveCase{Problem::TalosStand, 50, 0.2},
                                           SolveCase{Problem::TalosStep, 100, 0.0}),
                         [](const auto& info) {
                           return std::string(loco_cases::name(info.param.problem));
                         });

// The same with every contact knot by RK4 (the trot's impulse knots unchanged): standing after a
// push and the trot converge as with Euler.
INSTANTIATE_TEST_SUITE_P(Rk4, LocomotionSolve,
                         ::testing::Values(SolveCase{Problem::SoloStand, 50, 0.05, Integrator::Rk4},
                                           SolveCase{Problem::SoloTrot, 150, 0.0, Integrator::Rk4}),
                         [](const auto& info) {
                           return std::string(loco_cases::name(info.param.problem));
                         });

// Torque limits at 80 % of the unconstrained solution's peak torque: the box solver keeps every
// control inside while the bounds are active, and the gait stays feasible.
TEST(LocomotionBox, TrotWithinTightTorqueLimits) {
  Case free = loco_cases::make(Problem::SoloTrot, kShared);
  Solver unconstrained(free.loco->problem(), SolverKind::Fddp);
  solveFromStanding(free, unconstrained, 100);
  double peak = 0.0;
  for (const auto& u : unconstrained.us()) peak = std::max(peak, u.cwiseAbs().maxCoeff());
  const double limit = 0.8 * peak;

  Case c = loco_cases::make(Problem::SoloTrot, kShared);
  Solver solver(c.loco->problem(), SolverKind::BoxFddp);
  if (std::getenv("STRIDE_DEBUG")) solver.callback = Solver::printIterationTable;
  const int nu = c.loco->problem().maxNu();
  solver.setControlBounds(Eigen::VectorXd::Constant(nu, -limit),
                          Eigen::VectorXd::Constant(nu, limit));
  // From standing the box solver creeps (steps of a few percent while the clamped set settles);
  // it starts from the unconstrained gait clamped to the limits instead, as a receding horizon
  // would from its previous solution.
  std::vector<Eigen::VectorXd> us = unconstrained.us();
  for (auto& u : us) u = u.cwiseMax(-limit).cwiseMin(limit);
  ASSERT_TRUE(solver.setWarmStart(unconstrained.xs(), us));
  // With clamped torques the Gauss-Newton model switches its free set between iterations and the
  // tail converges slowly: stop when a full step is predicted to gain less than 1e-3 on a cost of
  // ~89 (1e-5 relative), far below anything that changes the gait.
  solver.options.stop_tolerance = 1e-3;
  const SolveStatus status = solver.solve(100);
  EXPECT_EQ(status, SolveStatus::Converged) << toString(status);
  EXPECT_LT(solver.gap(), 1e-9);
  double max_u = 0.0;
  int at_bound = 0;
  for (const auto& u : solver.us()) {
    max_u = std::max(max_u, u.cwiseAbs().maxCoeff());
    at_bound += (u.cwiseAbs().array() >= limit - 1e-9).count();
  }
  const Measures m = measure(c, solver);
  std::printf(
      "[ box ] unconstrained peak %.4f N m, limit %.4f, box solution max %.4f, %d controls "
      "at the bound, %d iterations, cost %.9g (unconstrained %.9g), min cone margin %.4g N, "
      "lowest apex %.4f m\n",
      peak, limit, max_u, at_bound, solver.iterations(), solver.cost(), unconstrained.cost(),
      m.min_cone_margin, m.lowest_apex);
  EXPECT_LE(max_u, limit + 1e-12);
  EXPECT_GT(at_bound, 0);
  EXPECT_GE(solver.cost(), unconstrained.cost());
  EXPECT_GE(m.min_cone_margin, 0.0);
  EXPECT_GE(m.lowest_apex, 0.5 * c.ref->options().swing_height);

  // The model's own effort limits (solo12's URDF: 1000 N m, never active) through the options.
  Case lim = loco_cases::make(Problem::SoloTrot, kShared,
                              [](LocomotionOptions& o) { o.torque_limits = true; });
  EXPECT_EQ(lim.loco->controlUpper(), lim.robot->model.effortLimit.tail(nu));
  EXPECT_EQ(lim.loco->controlLower(), -lim.robot->model.effortLimit.tail(nu));
}

// On a feasible warm start DDP and FDDP run the same iterations: solo12 standing after a push,
// the holding torques rolled out from x0 for both (over 0.5 s: open loop, the push carries the
// robot into a singular posture within a second).
TEST(LocomotionSolvers, DdpAndFddpAgreeOnStanding) {
  double costs[2];
  int iterations[2];
  for (int i = 0; i < 2; ++i) {
    Case c =
        loco_cases::make(Problem::SoloStand, kShared, [](LocomotionOptions& o) { o.knots = 50; });
    push(*c.loco, Eigen::Vector3d(0.05, 0.0, 0.0));
    std::vector<Eigen::VectorXd> xs, us;
    c.warmStart(xs, us);
    Solver rollout(c.loco->problem(), SolverKind::Ddp);
    ASSERT_TRUE(rollout.setWarmStart(xs, us));
    rollout.solve(0);  // Ddp rolls the controls out from x0
    Solver solver(c.loco->problem(), i == 0 ? SolverKind::Ddp : SolverKind::Fddp);
    ASSERT_TRUE(solver.setWarmStart(rollout.xs(), us));
    EXPECT_EQ(solver.solve(50), SolveStatus::Converged);
    expectMonotonicOnceFeasible(solver);
    costs[i] = solver.cost();
    iterations[i] = solver.iterations();
    EXPECT_GT(rollout.cost(), 2.0 * costs[i]);  // a push worth correcting
  }
  std::printf("[ ddp/fddp ] DDP %.12g (%d iterations), FDDP %.12g (%d iterations)\n", costs[0],
              iterations[0], costs[1], iterations[1]);
  EXPECT_NEAR(costs[0], costs[1], 1e-6 * std::abs(costs[1]));
}

// calc / calcDiff in parallel give the same bits: each knot writes only its own data and the
// total is summed in knot order.
TEST(LocomotionSolvers, ThreadCountDoesNotChangeTheSolution) {
  std::vector<Eigen::VectorXd> xs[2], us[2];
  for (int threads : {1, 2}) {
    Case c = loco_cases::make(Problem::SoloTrot, kShared);
    c.loco->problem().setThreads(threads);
    Solver solver(c.loco->problem(), SolverKind::Fddp);
    solveFromStanding(c, solver, 20);
    xs[threads - 1] = solver.xs();
    us[threads - 1] = solver.us();
  }
  for (size_t k = 0; k < xs[0].size(); ++k) EXPECT_TRUE(xs[0][k] == xs[1][k]) << k;
  for (size_t k = 0; k < us[0].size(); ++k) EXPECT_TRUE(us[0][k] == us[1][k]) << k;
}

// Real-time iteration: the derivatives and the backward pass do not read x0, so an iteration
// prepared before x0 changed gives the same bits as one done entirely after.
// Solver::retimeWarmStart on a grid moved by one short knot: a knot at an old knot's time takes
// that knot's state, control and gain bit for bit (the pre-impact state for an impulse knot, the
// post-impact one for the knot after it); a knot between two old ones a state on the way between
// them and the control interpolated with the same weight.
TEST(LocomotionSolvers, RetimeMovesTheTrajectoryOntoTheNewGrid) {
  Case c = loco_cases::make(Problem::SoloTrot, kShared, [](LocomotionOptions& o) {
    o.grid = {{10, 0.01}, {10, 0.02}, {15, 0.03}};
  });
  ShootingProblem& problem = c.loco->problem();
  Solver solver(problem, SolverKind::Fddp);
  solveFromStanding(c, solver, 30);
  ASSERT_LT(solver.gap(), 1e-6);
  const std::vector<double> from = c.loco->knotTimes();
  const std::vector<Eigen::VectorXd> xs = solver.xs(), us = solver.us();
  const std::vector<Eigen::MatrixXd> K = solver.K();
  const StateSpace& space = problem.state();
  // The next tick's grid: 10 ms later (the problem keeps its knots in place: the test compares
  // trajectories, not knot models).
  ASSERT_TRUE(c.update(from[0] + 0.01));
  const std::vector<double>& to = c.loco->knotTimes();
  solver.retimeWarmStart(from, to);
  const int T = problem.horizon();
  int exact = 0, between = 0;
  Eigen::VectorXd d(space.ndx()), e(space.ndx());
  for (int k = 0; k <= T; ++k) {
    const double t = to[k];
    const auto first = std::lower_bound(from.begin(), from.end(), t - 1e-9) - from.begin();
    if (first <= T && std::abs(from[first] - t) < 1e-9) {
      int j = static_cast<int>(first);
      if (k > 0 && to[k - 1] == to[k])  // the knot after an impulse knot: post-impact
        while (j < T && std::abs(from[j + 1] - t) < 1e-9) ++j;
      EXPECT_TRUE(solver.xs()[k] == xs[j]) << k;
      if (k < T) {
        EXPECT_TRUE(solver.us()[k] == us[std::min(j, T - 1)]) << k;
        EXPECT_TRUE(solver.K()[k] == K[std::min(j, T - 1)]) << k;
      }
      ++exact;
    } else if (first <= T && first > 0) {
      const int a = static_cast<int>(first) - 1, b = static_cast<int>(first);
      const double w = (t - from[a]) / (from[b] - from[a]);
      space.difference(xs[a], xs[b], d);
      space.difference(xs[a], solver.xs()[k], e);
      EXPECT_LT((e - w * d).norm(), 1e-9 * (1.0 + d.norm())) << k;
      if (k < T && b < T) {
        EXPECT_LT((solver.us()[k] - ((1 - w) * us[a] + w * us[b])).norm(), 1e-9) << k;
      }
      ++between;
    } else {  // past the old end: the last state
      EXPECT_TRUE(solver.xs()[k] == xs[T]) << k;
    }
  }
  EXPECT_GE(exact, 10);   // the short knots, and the long ones at fixed plan times
  EXPECT_GE(between, 1);  // the knots where a segment's alignment moved
  EXPECT_FALSE(solver.prepared());
}

TEST(LocomotionSolvers, PreparedIterationMatchesAFullOneAtTheNewState) {
  Case c = loco_cases::make(Problem::SoloTrot, kShared);
  ShootingProblem& problem = c.loco->problem();
  Solver solver(problem, SolverKind::BoxFddp);
  solver.setControlBounds(c.loco->controlLower(), c.loco->controlUpper());
  solveFromStanding(c, solver, 3);  // a trajectory with gaps and a policy, mid-way
  const std::vector<Eigen::VectorXd> xs0 = solver.xs(), us0 = solver.us();
  const double mu = solver.regularization();
  const Eigen::VectorXd x0_old = problem.x0();
  Eigen::VectorXd x0_new = x0_old;
  x0_new[0] += 0.01;                     // base 1 cm forward
  x0_new[c.robot->model.nq + 5] += 0.3;  // base yaw rate
  x0_new[10] += 0.05;                    // a joint

  std::vector<Eigen::VectorXd> xs[2], us[2];
  std::vector<Eigen::MatrixXd> K[2];
  int passes[2] = {0, 0};
  for (int prepared : {0, 1}) {
    ASSERT_TRUE(solver.setWarmStart(xs0, us0));
    EXPECT_FALSE(solver.prepared());
    solver.setRegularization(mu);
    if (prepared) {
      problem.setX0(x0_old);
      SolveStatus why = SolveStatus::MaxIterations;
      ASSERT_TRUE(solver.prepare(Solver::Clock::time_point::max(), why)) << toString(why);
      EXPECT_TRUE(solver.prepared());
    }
    problem.setX0(x0_new);
    solver.solve(1);
    EXPECT_EQ(solver.iterations(), 1);
    EXPECT_FALSE(solver.prepared());
    passes[prepared] = solver.backwardPasses();  // the preparation's count, not one more
    xs[prepared] = solver.xs();
    us[prepared] = solver.us();
    K[prepared] = solver.K();
  }
  EXPECT_GT(solver.stats()[0].step, 0.0);
  EXPECT_GE(passes[0], 1);
  EXPECT_EQ(passes[0], passes[1]);
  for (size_t k = 0; k < xs[0].size(); ++k) EXPECT_TRUE(xs[0][k] == xs[1][k]) << k;
  for (size_t k = 0; k < us[0].size(); ++k) EXPECT_TRUE(us[0][k] == us[1][k]) << k;
  for (size_t k = 0; k < K[0].size(); ++k) EXPECT_TRUE(K[0][k] == K[1][k]) << k;
  // The step started from the new state, not the old one: it closed the fraction `step` of the
  // gap between the new state and the trajectory's first state.
  Eigen::VectorXd d(problem.state().ndx());
  problem.state().difference(x0_new, xs[1][0], d);
  const double step = solver.stats()[0].step;
  Eigen::VectorXd d_old(problem.state().ndx());
  problem.state().difference(x0_new, xs0[0], d_old);
  EXPECT_LE(d.norm(), (1.0 - step) * d_old.norm() + 1e-9) << "step " << step;
}

}  // namespace test_locomotion
}  // namespace stride
