// The mock robot's physics (sim/simulator.hpp): conservation laws without contact, plastic
// landing and resting contact, Coulomb friction (sliding and sticking), a humanoid standing on its
// soles, and the input guards (clamping, NaN).

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "sim_cases.hpp"
#include "solver/multibody/centroidal.hpp"
#include "solver/multibody/lie_group.hpp"

namespace stride {
namespace test_simulator {

using sim::SimOptions;
using sim::Simulator;
using sim::StepStatus;
using sim_test::robot;

constexpr double kG = 9.81;

// ---------------------------------------------------------------------------------------------
// Without gravity, contact or torque, a free-floating robot keeps its energy and momentum up to
// the integrator's O(h) error: the drift over 1 s is small, and smaller with a finer step.
struct Drift {
  double energy, linear, angular;  // relative to the initial values
};

Drift freeFloatingDrift(int substeps) {
  Model model = robot("stride_quad").model;
  model.gravity.setZero();
  SimOptions opt;
  opt.substeps = substeps;
  Simulator sim(model, {}, opt);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::VectorXd v(model.nv);
  for (int k = 0; k < model.nv; ++k) v[k] = (k < 6 ? 0.5 : 2.0) * u(rng);
  sim.reset(robot("stride_quad").default_q, v);
  Data data(model);
  const double e0 = sim.kineticEnergy();
  const Vector6d h0 = computeCentroidalMomentum(model, data, sim.q(), sim.v());
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(sim.nu());
  for (int i = 0; i < 1000; ++i) EXPECT_EQ(sim.step(zero), StepStatus::Ok);
  EXPECT_NEAR(sim.time(), 1.0, 1e-9);
  const Vector6d h1 = computeCentroidalMomentum(model, data, sim.q(), sim.v());
  return {std::abs(sim.kineticEnergy() - e0) / e0,
          (h1.head<3>() - h0.head<3>()).norm() / h0.head<3>().norm(),
          (h1.tail<3>() - h0.tail<3>()).norm() / h0.tail<3>().norm()};
}

TEST(Simulator, FreeFloatingConservesEnergyAndMomentum) {
  const Drift coarse = freeFloatingDrift(1), fine = freeFloatingDrift(4);
  EXPECT_LT(coarse.energy, 2e-2);
  EXPECT_LT(coarse.linear, 1e-2);
  EXPECT_LT(coarse.angular, 1e-2);
  // Integration error, not a bias of the scheme: it shrinks with the step.
  EXPECT_LT(fine.energy, 0.5 * coarse.energy);
  EXPECT_LT(fine.linear, 0.5 * coarse.linear);
  EXPECT_LT(fine.angular, 0.5 * coarse.angular);
  std::cout << "energy drift " << coarse.energy << " (h) " << fine.energy << " (h/4); linear "
            << coarse.linear << " / " << fine.linear << "; angular " << coarse.angular << " / "
            << fine.angular << "\n";
}

// ---------------------------------------------------------------------------------------------
// stride_quad dropped from 5 cm at its default posture, joints held by a PD: the feet land
// plastically (no rebound), nothing sinks, and the robot comes to rest on its feet carrying its
// weight.
TEST(Simulator, QuadDropLandsPlasticallyAndSettles) {
  const Robot& r = robot("stride_quad");
  Simulator sim(r);
  Eigen::VectorXd q0 = r.default_q;
  q0[2] += 0.05;
  sim.reset(q0, Eigen::VectorXd::Zero(r.model.nv));
  const sim::HoldPolicy hold = sim_test::holdDefault(r);
  Data data(r.model);
  Eigen::VectorXd tau(sim.nu());

  double min_height = 1e9, max_base_after_landing = -1e9;
  int touchdowns = 0;
  const size_t np = sim.contactPoints().size();
  std::vector<int> landed_at(np, -1);
  for (int i = 0; i < 1000; ++i) {
    hold.torque(r.model, sim.q(), sim.v(), tau);
    ASSERT_EQ(sim.step(tau), StepStatus::Ok) << "step " << i;
    if (touchdowns > 0) max_base_after_landing = std::max(max_base_after_landing, sim.q()[2]);
    for (size_t p = 0; p < np; ++p) {
      const sim::PointContact& c = sim.pointContacts()[p];
      min_height = std::min(min_height, c.height);
      if (landed_at[p] < 0 && c.in_contact) {
        landed_at[p] = i;
        ++touchdowns;
      } else if (landed_at[p] >= 0 && landed_at[p] == i - 1) {
        // The step after touch-down: the foot fell at ~1 m/s and is now at rest vertically on the
        // ground (the touch-down step itself may still close the last part of the gap: contacts
        // are taken within the step in which the foot reaches the ground). Elastic would be +1.
        const Eigen::Vector3d vf =
            sim_test::frameVelocity(r.model, data, sim.contactPoints()[p].frame, sim.q(), sim.v());
        EXPECT_NEAR(vf.z(), 0.0, 0.05) << "after the touch-down of " << sim.contactPoints()[p].name;
        EXPECT_TRUE(c.in_contact);
      }
    }
  }
  // The legs are PD springs (soft ones: a PD evaluated once per 1 ms step must be): the body
  // springs up a little on them, nowhere near the 5 cm it fell from.
  EXPECT_LT(max_base_after_landing, r.default_q[2] + 0.02);
  EXPECT_EQ(touchdowns, 4);
  EXPECT_GT(min_height, -2e-3);  // penetration below 2 mm at every step
  for (const sim::PointContact& c : sim.pointContacts()) {
    EXPECT_TRUE(c.in_contact);
    EXPECT_GT(c.height, -2e-3);
  }
  // At rest, at the nominal height (the joint PD sags a little under the weight).
  EXPECT_NEAR(sim.q()[2], r.default_q[2], 5e-3);
  EXPECT_LT(sim.v().lpNorm<Eigen::Infinity>(), 1e-2);
  const double weight = r.model.totalMass() * kG;
  EXPECT_NEAR(sim.totalNormalForce(), weight, 0.01 * weight);
  // The feet carry the weight with their friction inside the cone.
  for (int p = 0; p < sim.contactForces().cols(); ++p) {
    const Eigen::Vector3d f = sim.contactForces().col(p);
    EXPECT_LE(f.head<2>().norm(), sim.options().friction * f.z() + 1e-9);
  }
  std::cout << "settled base height " << sim.q()[2] << " (nominal " << r.default_q[2]
            << "), deepest point " << min_height << ", normal force " << sim.totalNormalForce()
            << " N for a weight of " << weight << " N\n";
}

// ---------------------------------------------------------------------------------------------
// Touch-downs are plastic impacts: the sled dropped flat from 5 cm stops dead on the ground, and
// dropped on a corner it never gains energy and comes to rest.
double mechanicalEnergy(Simulator& sim) {
  return sim.kineticEnergy() + sim.model().totalMass() * kG * sim.q()[2];
}

TEST(Simulator, TouchDownIsPlastic) {
  sim_test::Sled sled;
  Simulator sim(sled.model, sled.points);
  const Eigen::VectorXd none(0);
  Eigen::VectorXd q = sled.restingQ();
  q[2] += 0.05;
  sim.reset(q, Eigen::VectorXd::Zero(6));
  int landed = -1;
  for (int i = 0; i < 300; ++i) {
    sim.step(none);
    if (landed < 0 && sim.pointContacts()[0].in_contact) landed = i;
    if (landed >= 0 && i > landed) {
      // At rest on the ground from the step after contact on: no rebound, no sinking.
      EXPECT_NEAR(sim.q()[2], sled.kHalfZ, 1e-6) << "step " << i;
      EXPECT_NEAR(sim.v()[2], 0.0, 1e-6) << "step " << i;
    }
  }
  ASSERT_GT(landed, 0);
  // Free fall until then: t = sqrt(2 h / g) ~ 101 ms.
  EXPECT_NEAR(landed, 100, 2);

  // On a corner: tilted about x and y, then let go.
  q = sled.restingQ();
  q[2] += 0.1;
  const Eigen::Quaterniond tilt(Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 1, 0).normalized()));
  q.segment<4>(3) = tilt.coeffs();
  sim.reset(q, Eigen::VectorXd::Zero(6));
  const double e0 = mechanicalEnergy(sim);
  double deepest = 0.0;
  for (int i = 0; i < 1500; ++i) {
    sim.step(none);
    EXPECT_LE(mechanicalEnergy(sim), e0 + 1e-3) << "step " << i;
    for (const sim::PointContact& c : sim.pointContacts()) deepest = std::min(deepest, c.height);
  }
  EXPECT_GT(deepest, -2e-3);
  EXPECT_LT(sim.v().norm(), 1e-3);
  EXPECT_NEAR(sim.q()[2], sled.kHalfZ, 1e-3);  // flat on the ground
  EXPECT_NEAR(sim.totalNormalForce(), sled.kMass * kG, 1e-3 * kG);
}

// Started 5 mm inside the ground, the sled is pushed out at the capped correction speed and
// comes to rest on the surface without being thrown up.
TEST(Simulator, PenetrationIsCorrectedGently) {
  sim_test::Sled sled;
  Simulator sim(sled.model, sled.points);
  Eigen::VectorXd q = sled.restingQ();
  q[2] -= 0.005;
  sim.reset(q, Eigen::VectorXd::Zero(6));
  const Eigen::VectorXd none(0);
  double highest = -1.0;
  for (int i = 0; i < 500; ++i) {
    sim.step(none);
    EXPECT_LE(sim.v()[2], sim.options().max_correction_velocity + 1e-9);
    highest = std::max(highest, sim.q()[2]);
  }
  EXPECT_LT(highest, sled.kHalfZ + 1e-3);
  EXPECT_NEAR(sim.q()[2], sled.kHalfZ, sim.options().penetration_slop + 1e-5);
  EXPECT_LT(sim.v().norm(), 1e-6);
}

// ---------------------------------------------------------------------------------------------
// Coulomb friction on the sled: launched at 0.5 m/s it decelerates at μ g and stops after
// v²/(2 μ g); pushed below μ m g it sticks, above it slides with (F − μ m g)/m.
TEST(Simulator, SlidingDeceleratesAtMuG) {
  sim_test::Sled sled;
  Simulator sim(sled.model, sled.points);
  const double mu = sim.options().friction, v0 = 0.5;
  // Settle first so that the corners carry the weight, then launch.
  sim.reset(sled.restingQ(), Eigen::VectorXd::Zero(6));
  const Eigen::VectorXd none(0);
  for (int i = 0; i < 100; ++i) sim.step(none);
  Eigen::VectorXd v = Eigen::VectorXd::Zero(6);
  v[0] = v0;
  const Eigen::VectorXd q_start = sim.q();
  sim.reset(q_start, v);
  // Velocity after 40 ms: v0 − μ g t while it slides (it stops after ~64 ms).
  for (int i = 0; i < 40; ++i) sim.step(none);
  EXPECT_NEAR(sim.v()[0], v0 - mu * kG * 0.040, 0.01 * v0);
  for (const sim::PointContact& c : sim.pointContacts()) {
    // Sliding: each corner's friction is on the cone, opposing the motion.
    EXPECT_NEAR(-c.force.x(), mu * c.force.z(), 1e-6 * kG);
    EXPECT_NEAR(c.force.y(), 0.0, 1e-9);
  }
  for (int i = 0; i < 200; ++i) sim.step(none);
  EXPECT_LT(sim.v().head<3>().norm(), 1e-4);  // stopped, and stays stopped
  const double distance = sim.q()[0] - q_start[0], expected = v0 * v0 / (2 * mu * kG);
  EXPECT_NEAR(distance, expected, 0.03 * expected);
  std::cout << "slide distance " << distance << " m, Coulomb " << expected << " m\n";
}

// The quadruped launched forward at 0.5 m/s while standing. It is no sled: its front feet catch,
// it pitches and hops on its PD legs, so its centre of mass follows no closed form. But at every
// step each foot obeys Coulomb's law: a sliding foot's friction is μ times its normal force and
// points against its sliding velocity; a foot whose friction is inside the cone does not slide.
TEST(Simulator, QuadSlidingFeetObeyCoulomb) {
  const Robot& r = robot("stride_quad");
  Simulator sim(r);
  const sim::HoldPolicy hold = sim_test::holdDefault(r);
  Eigen::VectorXd tau(sim.nu());
  for (int i = 0; i < 500; ++i) {
    hold.torque(r.model, sim.q(), sim.v(), tau);
    sim.step(tau);
  }
  Eigen::VectorXd v = Eigen::VectorXd::Zero(r.model.nv);
  v[0] = 0.5;
  sim.reset(sim.q(), v, sim.time());
  const double mu = sim.options().friction;
  Data data(r.model);
  int sliding = 0, sticking = 0;
  for (int i = 0; i < 300; ++i) {
    hold.torque(r.model, sim.q(), sim.v(), tau);
    ASSERT_EQ(sim.step(tau), StepStatus::Ok);
    for (size_t p = 0; p < sim.contactPoints().size(); ++p) {
      const sim::PointContact& c = sim.pointContacts()[p];
      if (!c.in_contact || c.force.z() < 0.5) continue;  // the load of a foot just touching down
      const Eigen::Vector2d vt =
          sim_test::frameVelocity(r.model, data, sim.contactPoints()[p].frame, sim.q(), sim.v())
              .head<2>();
      const Eigen::Vector2d ft = c.force.head<2>();
      if (vt.norm() > 0.02) {
        ++sliding;
        EXPECT_NEAR(ft.norm(), mu * c.force.z(), 1e-3 * c.force.z()) << "step " << i;
        EXPECT_GT(-ft.dot(vt) / (ft.norm() * vt.norm()), std::cos(0.05)) << "step " << i;
      } else if (vt.norm() < 1e-3) {
        ++sticking;
        EXPECT_LE(ft.norm(), mu * c.force.z() * (1 + 1e-9)) << "step " << i;
      }
    }
  }
  EXPECT_GT(sliding, 20);
  EXPECT_GT(sticking, 20);
  EXPECT_LT(sim.v().lpNorm<Eigen::Infinity>(), 0.1);  // stopped on its feet
  for (const sim::PointContact& c : sim.pointContacts()) EXPECT_TRUE(c.in_contact);
}

TEST(Simulator, StaticFrictionHoldsBelowMuMgAndSlipsAbove) {
  sim_test::Sled sled;
  const double m = sled.kMass;
  for (double ratio : {0.5, 1.5}) {
    Simulator sim(sled.model, sled.points);
    const double mu = sim.options().friction;
    sim.reset(sled.restingQ(), Eigen::VectorXd::Zero(6));
    const Eigen::VectorXd none(0);
    for (int i = 0; i < 100; ++i) sim.step(none);
    const double x0 = sim.q()[0];
    Vector6d push = Vector6d::Zero();
    push[0] = ratio * mu * m * kG;
    sim.applyExternalWrench(push, sim.time() + 0.5);
    for (int i = 0; i < 500; ++i) ASSERT_EQ(sim.step(none), StepStatus::Ok);
    const double drift = sim.q()[0] - x0;
    if (ratio < 1.0) {
      EXPECT_LT(std::abs(drift), 1e-4) << "pushed with " << ratio << " μ m g";
    } else {
      const double a = (push[0] - mu * m * kG) / m, expected = 0.5 * a * 0.5 * 0.5;
      EXPECT_NEAR(drift, expected, 0.03 * expected) << "pushed with " << ratio << " μ m g";
    }
    // The push has ended: nothing keeps it sliding for long.
    for (int i = 0; i < 500; ++i) sim.step(none);
    EXPECT_LT(sim.v().head<3>().norm(), 1e-4);
  }
}

// ---------------------------------------------------------------------------------------------
// stride_humanoid on its two soles (four corners each), joints held by a PD: stands for 2 s.
TEST(Simulator, HumanoidStandsOnItsSoles) {
  const Robot& r = robot("stride_humanoid");
  Simulator sim(r);
  EXPECT_EQ(sim.contactPoints().size(), 8u);
  const sim::HoldPolicy hold = sim_test::holdDefault(r);
  Eigen::VectorXd tau(sim.nu());
  for (int i = 0; i < 2000; ++i) {
    hold.torque(r.model, sim.q(), sim.v(), tau);
    ASSERT_EQ(sim.step(tau), StepStatus::Ok) << "step " << i;
  }
  EXPECT_NEAR(sim.q()[2], r.default_q[2], 0.02);
  const Eigen::Quaterniond quat(sim.q()[6], sim.q()[3], sim.q()[4], sim.q()[5]);
  EXPECT_LT(quat.angularDistance(Eigen::Quaterniond::Identity()), 0.02);
  EXPECT_LT(sim.v().lpNorm<Eigen::Infinity>(), 5e-2);
  for (const sim::PointContact& c : sim.pointContacts()) {
    EXPECT_TRUE(c.in_contact);
    EXPECT_GT(c.height, -2e-3);
  }
  const double weight = r.model.totalMass() * kG;
  EXPECT_NEAR(sim.totalNormalForce(), weight, 0.02 * weight);
  EXPECT_NEAR(sim.normalForce(0), sim.normalForce(1), 0.1 * weight);  // symmetric posture
  std::cout << "humanoid base height " << sim.q()[2] << " (nominal " << r.default_q[2]
            << "), PGS sweeps " << sim.counters().last_pgs_iterations << ", unconverged "
            << sim.counters().pgs_unconverged << "\n";
}

// ---------------------------------------------------------------------------------------------
// Input guards.
TEST(Simulator, ClampsTorquesToEffortLimits) {
  const Robot& r = robot("stride_quad");
  const Eigen::VectorXd big = Eigen::VectorXd::Constant(12, 100.0);
  Eigen::VectorXd limit(12);
  for (int i = 0; i < 12; ++i) limit[i] = r.model.effortLimit[6 + i];
  ASSERT_TRUE((limit.array() == 2.7).all());

  Simulator clamped(r), at_limit(r);
  clamped.step(big);
  at_limit.step(limit);
  EXPECT_TRUE(clamped.appliedTorque().isApprox(limit));
  EXPECT_EQ(clamped.counters().clamped_steps, 1);
  EXPECT_EQ(at_limit.counters().clamped_steps, 0);
  EXPECT_TRUE(clamped.v().isApprox(at_limit.v(), 1e-12));

  SimOptions opt;
  opt.clamp_torques = false;
  Simulator free(r, opt);
  free.step(big);
  EXPECT_TRUE(free.appliedTorque().isApprox(big));
  EXPECT_GT((free.v() - clamped.v()).norm(), 1.0);
}

TEST(Simulator, RejectsNonFiniteTorque) {
  const Robot& r = robot("stride_quad");
  Simulator sim(r), reference(r);
  Eigen::VectorXd tau = Eigen::VectorXd::Constant(12, 1.0);
  tau[4] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(sim.step(tau), StepStatus::RejectedTorque);
  tau[4] = std::numeric_limits<double>::infinity();
  EXPECT_EQ(sim.step(tau), StepStatus::RejectedTorque);
  EXPECT_EQ(sim.counters().rejected_torques, 2);
  EXPECT_EQ(sim.counters().steps, 2);
  EXPECT_TRUE(sim.appliedTorque().isZero());
  EXPECT_TRUE(sim.q().allFinite() && sim.v().allFinite());
  // Exactly a zero-torque step.
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(12);
  reference.step(zero);
  reference.step(zero);
  EXPECT_TRUE(sim.q().isApprox(reference.q(), 1e-14));
  EXPECT_TRUE(sim.v().isApprox(reference.v(), 1e-14));
  // A finite torque afterwards is applied again.
  EXPECT_EQ(sim.step(zero), StepStatus::Ok);
  EXPECT_EQ(sim.lastStatus(), StepStatus::Ok);
}

TEST(Simulator, RejectsBadArguments) {
  const Robot& r = robot("stride_quad");
  Simulator sim(r);
  EXPECT_THROW(sim.step(Eigen::VectorXd::Zero(3)), std::invalid_argument);
  Eigen::VectorXd q = r.default_q;
  q[0] = std::nan("");
  EXPECT_THROW(sim.reset(q, Eigen::VectorXd::Zero(18)), std::invalid_argument);
  EXPECT_THROW(sim.reset(r.default_q, Eigen::VectorXd::Zero(17)), std::invalid_argument);
  SimOptions bad;
  bad.dt = 0.0;
  EXPECT_THROW(Simulator(r, bad), std::invalid_argument);
  bad = SimOptions();
  bad.substeps = 0;
  EXPECT_THROW(Simulator(r, bad), std::invalid_argument);
  bad = SimOptions();
  bad.max_velocity = 0.0;
  EXPECT_THROW(Simulator(r, bad), std::invalid_argument);
}

// A step that leaves physics (a joint spun past max_velocity: no robot turns at 1000 rad/s) is
// held and reported as a non-finite state, so that the run stops as diverged instead of going on
// with numbers that mean nothing; just under the bound it steps as usual.
TEST(Simulator, AVelocityPastTheBoundIsADivergence) {
  const Robot& r = robot("stride_quad");
  SimOptions opt;
  opt.max_velocity = 50.0;
  Simulator sim(r, opt);
  Eigen::VectorXd q = r.default_q;
  q[2] += 0.5;  // in the air: nothing but the joint's own speed
  Eigen::VectorXd v = Eigen::VectorXd::Zero(r.model.nv);
  v[6] = 49.0;
  sim.reset(q, v);
  EXPECT_EQ(sim.step(Eigen::VectorXd::Zero(sim.nu())), StepStatus::Ok);
  v[6] = 60.0;
  sim.reset(q, v);
  const Eigen::VectorXd q_before = sim.q();
  EXPECT_EQ(sim.step(Eigen::VectorXd::Zero(sim.nu())), StepStatus::NonFiniteState);
  EXPECT_EQ(sim.q(), q_before);
  EXPECT_TRUE(sim.v().isZero());
  EXPECT_EQ(sim.counters().nonfinite_states, 1);
}

// Contact candidates come from the geometry: the quadruped's feet are at its foot frames, a sole's
// points at its corners; in the default posture all of them are on the ground.
TEST(GroundContact, CandidatePointsFromTheRobotConfig) {
  const Robot& quad = robot("stride_quad");
  const auto qp = sim::contactPointsFromRobot(quad);
  ASSERT_EQ(qp.size(), 4u);
  for (const auto& p : qp) EXPECT_TRUE(p.offset.isZero());
  const Robot& hum = robot("stride_humanoid");
  const auto hp = sim::contactPointsFromRobot(hum);
  ASSERT_EQ(hp.size(), 8u);
  EXPECT_EQ(hp[0].name, "L_sole/fl");
  EXPECT_EQ(hp[7].contact, 1);
  for (const Robot* r : {&quad, &hum}) {
    Simulator sim(*r);
    sim.step(Eigen::VectorXd::Zero(sim.nu()));
    for (const auto& c : sim.pointContacts()) {
      EXPECT_TRUE(c.candidate);
      EXPECT_NEAR(c.height, 0.0, 2e-4);  // the YAML's base height puts the soles on z = 0
    }
  }
  // Lifted by 1 cm: no point is a candidate and no force acts.
  Simulator sim(quad);
  Eigen::VectorXd q = quad.default_q;
  q[2] += 0.01;
  sim.reset(q, Eigen::VectorXd::Zero(18));
  sim.step(Eigen::VectorXd::Zero(12));
  for (const auto& c : sim.pointContacts()) EXPECT_FALSE(c.candidate);
  EXPECT_EQ(sim.totalNormalForce(), 0.0);
  // A raised ground moves the contact with it.
  SimOptions opt;
  opt.ground_height = 0.01;
  Simulator raised(quad, opt);
  raised.reset(q, Eigen::VectorXd::Zero(18));
  raised.step(Eigen::VectorXd::Zero(12));
  for (const auto& c : raised.pointContacts()) EXPECT_TRUE(c.in_contact);
}

}  // namespace test_simulator
}  // namespace stride
