// The policy the mock robot applies (messages/policy_interpolation.hpp, the wire's interpolation),
// its hold PD and stand-down (sim/policy.hpp) and its disturbance helpers (sim/disturbances.hpp).

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "messages/hold_pd.hpp"
#include "messages/policy_interpolation.hpp"
#include "sim/disturbances.hpp"
#include "sim_cases.hpp"
#include "solver/multibody/jacobian.hpp"
#include "solver/multibody/lie_group.hpp"

namespace stride {
namespace test_policy {

using msg::Policy;
using msg::PolicyEvaluator;
using msg::PolicyStatus;
using sim_test::robot;

// A 4-knot policy for stride_quad with random references (base poses far apart, so that the
// manifold interpolation matters), feedforwards and gains.
Policy randomPolicy(const Model& model, std::mt19937& rng) {
  const int nu = model.nv - 6, ndx = 2 * model.nv;
  Policy p;
  p.resize(4, model.nq, model.nv, nu);
  p.t0 = 0.3;
  p.dt = 0.02;
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int k = 0; k < p.knots; ++k) {
    Eigen::Map<Eigen::VectorXd>(p.xRef(k), model.nq) = randomConfiguration(model, rng);
    for (int i = 0; i < model.nv; ++i) p.xRef(k)[model.nq + i] = u(rng);
    for (int i = 0; i < nu; ++i) p.uFf(k)[i] = u(rng);
    for (int i = 0; i < nu * ndx; ++i) p.gain(k)[i] = u(rng);
  }
  return p;
}

Eigen::VectorXd knotQ(const Policy& p, int k) {
  return Eigen::Map<const Eigen::VectorXd>(p.xRef(k), p.nq);
}
Eigen::VectorXd knotV(const Policy& p, int k) {
  return Eigen::Map<const Eigen::VectorXd>(p.xRef(k) + p.nq, p.nv);
}

// u_k + K_k (x_k ⊖ x), written out from the wire layout.
Eigen::VectorXd knotTorque(const Model& model, const Policy& p, int k, const Eigen::VectorXd& q,
                           const Eigen::VectorXd& v) {
  Eigen::VectorXd dx(2 * p.nv);
  dx << difference(model, q, knotQ(p, k)), knotV(p, k) - v;
  Eigen::VectorXd tau = Eigen::Map<const Eigen::VectorXd>(p.uFf(k), p.nu);
  for (int i = 0; i < p.nu; ++i)
    for (int j = 0; j < 2 * p.nv; ++j)
      tau[i] += p.K[k * p.nu * 2 * p.nv + i * 2 * p.nv + j] * dx[j];
  return tau;
}

struct PolicySetup : ::testing::Test {
  const Model& model = robot("stride_quad").model;
  std::mt19937 rng{7};
  Policy policy = randomPolicy(model, rng);
  Eigen::VectorXd q = randomConfiguration(model, rng);
  Eigen::VectorXd v = Eigen::VectorXd::Random(model.nv);
  PolicyEvaluator eval{model, 12};
  Eigen::VectorXd tau = Eigen::VectorXd::Zero(12);
};

TEST_F(PolicySetup, ExactAtKnots) {
  ASSERT_TRUE(policy.isValid(model, 12));
  for (int k = 0; k < policy.knots; ++k) {
    const PolicyStatus s = eval.evaluate(policy, policy.t0 + k * policy.dt, q, v, tau);
    EXPECT_EQ(s, PolicyStatus::Ok) << "knot " << k;
    EXPECT_TRUE(tau.isApprox(knotTorque(model, policy, k, q, v), 1e-9)) << "knot " << k;
    EXPECT_LT(difference(model, knotQ(policy, k), eval.qRef()).norm(), 1e-9);
  }
}

TEST_F(PolicySetup, LinearBetweenKnotsAndGeodesicOnTheManifold) {
  const Eigen::VectorXd d01 = difference(model, knotQ(policy, 1), knotQ(policy, 2));
  for (double s : {0.1, 0.25, 0.5, 0.9}) {
    const double t = policy.t0 + (1 + s) * policy.dt;
    EXPECT_EQ(eval.evaluate(policy, t, q, v, tau), PolicyStatus::Ok);
    // τ is the blend of the two knots' τ (u and K linear, and K(x_ref ⊖ x) evaluated at the
    // interpolated reference for both).
    const Eigen::VectorXd qs = eval.qRef(), vs = eval.vRef();
    Eigen::VectorXd dx(2 * model.nv);
    dx << difference(model, q, qs), vs - v;
    Eigen::VectorXd expected(12);
    for (int i = 0; i < 12; ++i) {
      double a = 0, b = 0;
      for (int j = 0; j < 2 * model.nv; ++j) {
        a += policy.gain(1)[i * 2 * model.nv + j] * dx[j];
        b += policy.gain(2)[i * 2 * model.nv + j] * dx[j];
      }
      expected[i] = (1 - s) * (policy.uFf(1)[i] + a) + s * (policy.uFf(2)[i] + b);
    }
    EXPECT_TRUE(tau.isApprox(expected, 1e-10)) << "s = " << s;
    EXPECT_TRUE(vs.isApprox((1 - s) * knotV(policy, 1) + s * knotV(policy, 2), 1e-12));
    // On the geodesic from q1 to q2: s of the way from q1 and 1 − s of the way to q2 (the second
    // is a property of the path, not of how it was computed).
    EXPECT_TRUE(difference(model, knotQ(policy, 1), qs).isApprox(s * d01, 1e-9)) << "s = " << s;
    EXPECT_TRUE(difference(model, qs, knotQ(policy, 2)).isApprox((1 - s) * d01, 1e-9))
        << "s = " << s;
  }
  // With no gains, τ is exactly linear in t.
  std::fill(policy.K.begin(), policy.K.end(), 0.0);
  eval.evaluate(policy, policy.t0 + 1.3 * policy.dt, q, v, tau);
  for (int i = 0; i < 12; ++i)
    EXPECT_NEAR(tau[i], 0.7 * policy.uFf(1)[i] + 0.3 * policy.uFf(2)[i], 1e-12);
}

TEST_F(PolicySetup, InterpolatedQuaternionStaysUnit) {
  for (int i = 0; i <= 300; ++i) {
    eval.evaluate(policy, policy.t0 + i * 1e-4 * 2, q, v, tau);
    EXPECT_NEAR(eval.qRef().segment<4>(3).norm(), 1.0, 1e-12) << "t index " << i;
  }
}

TEST_F(PolicySetup, HoldsBeforeStartAndPastTheEnd) {
  const int last = policy.knots - 1;
  EXPECT_EQ(eval.evaluate(policy, policy.t0 - 0.5, q, v, tau), PolicyStatus::BeforeStart);
  EXPECT_TRUE(tau.isApprox(knotTorque(model, policy, 0, q, v), 1e-9));
  for (double after : {1e-6, 0.01, 10.0}) {
    EXPECT_EQ(eval.evaluate(policy, policy.t0 + last * policy.dt + after, q, v, tau),
              PolicyStatus::Exhausted);
    EXPECT_TRUE(tau.isApprox(knotTorque(model, policy, last, q, v), 1e-9));
  }
}

TEST_F(PolicySetup, RejectsMismatchedOrCorruptPolicies) {
  Policy wrong = policy;
  wrong.nq = 5;
  tau.setOnes();
  EXPECT_EQ(eval.evaluate(wrong, policy.t0, q, v, tau), PolicyStatus::Invalid);
  EXPECT_TRUE(tau.isZero());
  EXPECT_FALSE(wrong.isValid(model, 12));
  Policy nan = policy;
  nan.K[17] = std::nan("");
  EXPECT_FALSE(nan.isValid(model, 12));
  Policy quat = policy;
  quat.xRef(2)[6] += 0.1;
  EXPECT_FALSE(quat.isValid(model, 12));
  Policy short_k = policy;
  short_k.K.pop_back();
  EXPECT_FALSE(short_k.isValid(model, 12));
  EXPECT_EQ(eval.evaluate(short_k, policy.t0, q, v, tau), PolicyStatus::Invalid);
}

// K (x_ref ⊖ x) pushes the state toward x_ref: a positive joint error gives a positive torque
// through a positive gain, and in closed loop on the simulator (no gravity, floating in the air)
// the joints converge to the reference.
TEST(Policy, GainsPushTheStateTowardTheReference) {
  Model model = robot("stride_quad").model;
  model.gravity.setZero();
  const int nv = model.nv, nu = 12;
  const Eigen::VectorXd q_ref = robot("stride_quad").default_q;
  Policy p;
  p.resize(1, model.nq, nv, nu);
  Eigen::Map<Eigen::VectorXd>(p.xRef(0), model.nq) = q_ref;
  for (int i = 0; i < nu; ++i) {
    p.gain(0)[i * 2 * nv + 6 + i] = 2.0;        // on the joint position error
    p.gain(0)[i * 2 * nv + nv + 6 + i] = 0.05;  // on the joint velocity error
  }
  PolicyEvaluator eval(model, nu);
  Eigen::VectorXd q = q_ref, v = Eigen::VectorXd::Zero(nv), tau(nu);
  q[7 + 4] -= 0.2;  // FR_HFE below its reference
  eval.evaluate(p, 0.0, q, v, tau);
  EXPECT_NEAR(tau[4], 2.0 * 0.2, 1e-12);

  sim::Simulator sim(model, {});
  q.tail(12) += Eigen::VectorXd::LinSpaced(12, -0.2, 0.2);
  sim.reset(q, v);
  const double e0 = (sim.q().tail(12) - q_ref.tail(12)).norm();
  for (int i = 0; i < 1000; ++i) {
    eval.evaluate(p, sim.time(), sim.q(), sim.v(), tau);
    sim.step(tau);
  }
  EXPECT_LT((sim.q().tail(12) - q_ref.tail(12)).norm(), 0.05 * e0);
}

TEST(Policy, HoldPolicyIsAJointPd) {
  const Model& model = robot("stride_quad").model;
  const Eigen::VectorXd q_ref = robot("stride_quad").default_q;
  sim::HoldPolicy hold(model, q_ref, 10.0, 0.5);
  Eigen::VectorXd q = q_ref, v = Eigen::VectorXd::Zero(18), tau(12);
  q[0] += 1.0;  // the base is not actuated: no effect
  q[7 + 2] += 0.1;
  v[6 + 3] = 2.0;
  hold.torque(model, q, v, tau);
  Eigen::VectorXd expected = Eigen::VectorXd::Zero(12);
  expected[2] = -1.0;
  expected[3] = -1.0;
  EXPECT_TRUE(tau.isApprox(expected, 1e-12));
}

// One hold law (messages/hold_pd.hpp): the controller's hold fallback, sent as a policy (x_ref =
// the measured base and the default joints at rest, K from writeJointPdRow as PolicyWriter::hold
// writes it), gives through the robot's policy evaluation the torques the robot's own hold PD
// gives, at the same gains, plus the feed-forward.
TEST(Policy, TheControllersHoldPolicyIsTheRobotsHoldPd) {
  const Model& model = robot("stride_quad").model;
  const Eigen::VectorXd q_ref = robot("stride_quad").default_q;
  const int nq = model.nq, nv = model.nv, nu = actuatedDimension(model), ndx = 2 * nv;
  const double kp = msg::kDefaultHoldKp, kd = msg::kDefaultHoldKd;
  const sim::HoldPolicy hold(model, q_ref, kp, kd);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::VectorXd q = q_ref, v(nv), tau_hold(nu), tau_policy(nu);
  for (int i = 7; i < nq; ++i) q[i] += 0.3 * u(rng);
  for (int i = 0; i < nv; ++i) v[i] = u(rng);
  q[0] += 0.2;  // the measured base, which the hold's reference takes as it is

  Policy p;
  p.resize(1, nq, nv, nu);
  p.t0 = 0.0;
  p.dt = 0.01;
  for (int i = 0; i < nq; ++i) p.xRef(0)[i] = i < nq - nu ? q[i] : q_ref[i];
  Eigen::Map<Eigen::VectorXd> u_ff(p.uFf(0), nu);
  for (int r = 0; r < nu; ++r) {
    u_ff[r] = 0.5 * r;
    msg::writeJointPdRow(p.gain(0) + r * ndx, nv, 6 + r, kp, kd);
  }
  PolicyEvaluator eval(model, nu);
  ASSERT_EQ(eval.evaluate(p, 0.0, q, v, tau_policy), PolicyStatus::Ok);
  hold.torque(model, q, v, tau_hold);
  EXPECT_LT((tau_policy - (tau_hold + u_ff)).norm(), 1e-12) << tau_policy.transpose() << "\n"
                                                            << tau_hold.transpose();
  // And on each joint the law itself.
  for (int j = 0; j < nu; ++j)
    EXPECT_NEAR(tau_policy[j], msg::jointPd(u_ff[j], kp, kd, q_ref[7 + j], q[7 + j], v[6 + j]),
                1e-12);
}

// The stand-down (controller lost), sim/README.md "Controller loss".
std::vector<sim::StandDownContact> standDownContacts(const Robot& r) {
  std::vector<sim::StandDownContact> contacts;
  for (const ContactSpec& c : r.contacts) contacts.push_back({r.model.getFrameId(c.frame), c.dim});
  return contacts;
}

// Standing level at the default posture on its four feet: nothing to correct, so the last
// feed-forward alone at the start, fading out over the ramp, and zero once it has.
TEST(Policy, StandDownAtTheDefaultPostureOnlyFadesTheFeedForward) {
  const Robot& r = robot("stride_quad");
  sim::HoldPolicy hold(r.model, r.default_q, 10.0, 0.0);
  sim::StandDown down(r.model, hold, standDownContacts(r), sim::StandDownOptions{0.05, 0.2});
  const Eigen::VectorXd v = Eigen::VectorXd::Zero(18);
  const Eigen::VectorXd u_last = Eigen::VectorXd::LinSpaced(12, 1.0, 12.0);
  Eigen::VectorXd tau(12);
  down.begin(1.0, r.default_q, u_last);
  down.torque(1.0, r.default_q, v, 0b1111u, tau);
  EXPECT_TRUE(tau.isApprox(u_last, 1e-9));
  down.torque(1.1, r.default_q, v, 0b1111u, tau);
  EXPECT_TRUE(tau.isApprox(0.5 * u_last, 1e-9));
  down.torque(2.0, r.default_q, v, 0b1111u, tau);
  EXPECT_LT(tau.cwiseAbs().maxCoeff(), 1e-9);
}

// A planted foot is held at the default depth below the base, where it touched down: on flat
// ground a tilted body shows as feet at unequal depths in the base frame, and equalizing them
// levels it. FR's knee bent 0.3 rad further (its foot higher in the base frame, as under a body
// rolled to the right) with all four feet down: FR's knee straightens, harder than anything else
// moves. A foot in the air goes under its hip: FL bent the same way, off the ground, straightens
// hardest, while the three planted legs bring the centre of mass over their own centre.
TEST(Policy, StandDownHoldsPlantedFeetAtTheDefaultDepthAndBringsTheOthersUnderTheHips) {
  const Robot& r = robot("stride_quad");
  sim::HoldPolicy hold(r.model, r.default_q, 10.0, 0.0);
  sim::StandDown down(r.model, hold, standDownContacts(r), sim::StandDownOptions{0.05, 0.2});
  const Eigen::VectorXd v = Eigen::VectorXd::Zero(18);
  Eigen::VectorXd q = r.default_q, tau(12);
  q[7 + 5] -= 0.3;  // FR_KFE (default -1.6: more bent)
  down.begin(0.0, q, Eigen::VectorXd::Zero(12));
  down.torque(1.0, q, v, 0b1111u, tau);  // after the ramp: the PD alone
  EXPECT_GT(tau[5], 0.5);
  Eigen::Index largest;
  tau.cwiseAbs().maxCoeff(&largest);
  EXPECT_EQ(largest, 5);

  q = r.default_q;
  q[7 + 2] -= 0.3;  // FL_KFE
  down.begin(0.0, q, Eigen::VectorXd::Zero(12));
  down.torque(1.0, q, v, 0b1110u, tau);
  EXPECT_GT(tau[2], 0.5);
  tau.cwiseAbs().maxCoeff(&largest);
  EXPECT_EQ(largest, 2);
  // The planted legs carry the body toward their own centre (the tripod's, behind and to the
  // right): about the same hip abduction torque on each of the three, moving the base sideways.
  EXPECT_GT(std::abs(tau[3]), 0.5);
  EXPECT_NEAR(tau[3], tau[6], 0.01);
  EXPECT_NEAR(tau[3], tau[9], 0.01);
}

// The legs' step is solver/multibody/inverse_kinematics.hpp's since issue 43; before, the
// stand-down wrote its own damped least squares in the base's axes: e = [target − Rᵀ(p_f − p_b);
// the sole's F log3(Fᵀ B)] (F = Rᵀ R_f, B the default's foot in the base), capped at max_step, A =
// Rᵀ J on the leg's joints, dq = Aᵀ (A Aᵀ + (1 cm)² I)⁻¹ e. The step is invariant to that rotation:
// a tilted body with bent legs, feet in the air (each goes under its hip), gives the same torques
// to rounding on both robots (point feet and soles).
TEST(Policy, StandDownLegStepIsTheBaseFrameDampedLeastSquares) {
  for (const char* name : {"stride_quad", "stride_humanoid"}) {
    const Robot& r = robot(name);
    const Model& model = r.model;
    const int nv = model.nv, nu = nv - 6;
    const double kp = 10.0, max_step = 0.05;
    sim::HoldPolicy hold(r.model, r.default_q, kp, 0.0);
    sim::StandDown down(model, hold, standDownContacts(r), sim::StandDownOptions{0.05, 0.2});
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Eigen::VectorXd q = r.default_q;
    for (int i = 7; i < model.nq; ++i) q[i] += 0.15 * u(rng);
    const Eigen::Quaterniond tilt(
        Eigen::AngleAxisd(0.2, Eigen::Vector3d(1.0, 0.5, 0.0).normalized()));
    q.segment<4>(3) << tilt.x(), tilt.y(), tilt.z(), tilt.w();
    const Eigen::VectorXd v = Eigen::VectorXd::Zero(nv);
    Eigen::VectorXd tau(nu);
    down.begin(0.0, q, Eigen::VectorXd::Zero(nu));
    down.torque(1.0, q, v, 0u, tau);  // after the ramp: the PD alone, kp dq on a leg's joints

    Data d0(model), d(model);
    framesForwardKinematics(model, d0, r.default_q);
    computeJointJacobians(model, d, q);
    updateFramePlacements(model, d);
    const SE3& base0 = d0.oMi[1];
    const SE3& base = d.oMi[1];
    std::vector<int> users(nu, 0);
    for (const ContactSpec& c : r.contacts)
      for (int j = model.frames[model.getFrameId(c.frame)].parentJoint; j > 1;
           j = model.joints[j].parent)
        ++users[model.joints[j].idx_v - 6];
    int compared = 0;
    for (const ContactSpec& c : r.contacts) {
      const int f = model.getFrameId(c.frame), dim = c.dim == 6 ? 6 : 3;
      std::vector<int> cols;
      for (int j = model.frames[f].parentJoint; j > 1; j = model.joints[j].parent)
        if (users[model.joints[j].idx_v - 6] == 1) cols.push_back(model.joints[j].idx_v);
      const SE3 B = base0.actInv(d0.oMf[f]);
      Eigen::VectorXd e(dim);
      e.head<3>() = B.p - base.R.transpose() * (d.oMf[f].p - base.p);
      if (dim == 6) {
        const Eigen::Matrix3d F = base.R.transpose() * d.oMf[f].R;
        e.tail<3>() = F * log3(F.transpose() * B.R);
      }
      if (e.norm() > max_step) e *= max_step / e.norm();
      Matrix6Xd J = Matrix6Xd::Zero(6, nv);
      getFrameJacobian(model, d, f, ReferenceFrame::LocalWorldAligned, J);
      Eigen::MatrixXd A(dim, cols.size());
      for (std::size_t k = 0; k < cols.size(); ++k) {
        A.col(k).head<3>() = base.R.transpose() * J.col(cols[k]).head<3>();
        if (dim == 6) A.col(k).tail<3>() = base.R.transpose() * J.col(cols[k]).tail<3>();
      }
      Eigen::MatrixXd AAt = A * A.transpose();
      AAt.diagonal().array() += 0.01 * 0.01;
      const Eigen::VectorXd dq = A.transpose() * AAt.ldlt().solve(e);
      for (std::size_t k = 0; k < cols.size(); ++k, ++compared)
        EXPECT_NEAR(tau[cols[k] - 6], kp * dq[k], 1e-12 * std::max(1.0, std::abs(kp * dq[k])))
            << name << " " << c.frame << " joint " << cols[k];
    }
    EXPECT_GE(compared, 12) << name;
  }
}

// ---------------------------------------------------------------------------------------------
TEST(Disturbances, DelayReturnsTheStateOfNPushesAgo) {
  sim::StateDelay delay(2, 1, 3);
  double t;
  Eigen::VectorXd q(2), v(1);
  for (int i = 0; i < 10; ++i) {
    delay.push(0.1 * i, Eigen::Vector2d(i, -i), Eigen::VectorXd::Constant(1, 10.0 * i));
    const bool ready = delay.delayed(t, q, v);
    EXPECT_EQ(ready, i >= 3);
    if (!ready) continue;
    EXPECT_DOUBLE_EQ(t, 0.1 * (i - 3));
    EXPECT_EQ(q, Eigen::Vector2d(i - 3, 3 - i));
    EXPECT_EQ(v[0], 10.0 * (i - 3));
  }
  sim::StateDelay none(2, 1, 0);
  none.push(1.0, Eigen::Vector2d(1, 2), Eigen::VectorXd::Constant(1, 3.0));
  ASSERT_TRUE(none.delayed(t, q, v));
  EXPECT_EQ(q, Eigen::Vector2d(1, 2));
}

TEST(Disturbances, DroppedMessagesAtTheirRate) {
  sim::MessageDropper a(0.2, 1), b(0.2, 1), never(0.0, 1);
  int dropped = 0;
  for (int i = 0; i < 10000; ++i) {
    const bool d = a.drop();
    EXPECT_EQ(d, b.drop());
    dropped += d;
    EXPECT_FALSE(never.drop());
  }
  EXPECT_EQ(a.dropped(), dropped);
  EXPECT_NEAR(dropped / 10000.0, 0.2, 0.015);
}

TEST(Disturbances, PushScheduleSumsActivePushes) {
  sim::PushSchedule s;
  s.pushes.push_back({1.0, 0.2, Eigen::Vector3d(10, 0, 0), Eigen::Vector3d::Zero()});
  s.pushes.push_back({1.1, 0.5, Eigen::Vector3d(0, 5, 0), Eigen::Vector3d(0, 0, 1)});
  EXPECT_TRUE(s.wrenchAt(0.99).isZero());
  EXPECT_EQ(s.wrenchAt(1.0).head<3>(), Eigen::Vector3d(10, 0, 0));
  Vector6d both;
  both << 10, 5, 0, 0, 0, 1;
  EXPECT_EQ(s.wrenchAt(1.15), both);
  EXPECT_DOUBLE_EQ(s.activeUntil(1.15), 1.6);
  EXPECT_EQ(s.wrenchAt(1.2).head<3>(), Eigen::Vector3d(0, 5, 0));
  EXPECT_TRUE(s.wrenchAt(1.6).isZero());
  EXPECT_DOUBLE_EQ(s.activeUntil(2.0), 2.0);
}

}  // namespace test_policy
}  // namespace stride
