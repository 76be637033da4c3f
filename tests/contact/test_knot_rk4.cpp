// The RKMK-4 knot (solver/contact/knot_rk4.hpp): its Jacobians against central finite
// differences on the manifold for every robot class, its order (momentum of a free-floating body
// without gravity, where Euler drifts; agreement with Euler to O(dt²) and with a fine Euler
// reference over a short horizon), the knot's contract on bad input, and no allocation.

#include <gtest/gtest.h>

#include "allocation_counter.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>

#include "config/robot_config.hpp"
#include "multibody/random_tree.hpp"
#include "solver/contact/knot_rk4.hpp"
#include "solver/multibody/centroidal.hpp"
#include "solver/multibody/lie_group.hpp"
#include "solver/multibody/urdf.hpp"

namespace stride {
namespace test_knot_rk4 {

using test_support::allocations;

// The Euler knot's tolerance (test_contact_dynamics.cpp, kContactTol), with a step ten times
// longer: RK4's later stages run at v + dt a, and with random states and ±5 N m on solo12's
// 0.1 kg legs (v̇ ~ 1e4) the differences of v⁺ lose eps |v̇| dt κ / h to rounding, 3-7e-6 at
// h = 1e-6 (they fall as 1/h: 2e-7 at 1e-5, 3e-8 at 1e-4; truncation is below that at 1e-5).
constexpr double kStep = 1e-5;
constexpr double kTol = 2e-6;

struct Case {
  std::string name;
  Model model;
  ContactSet contacts;
};

Model shared(const std::string& urdf, RootJoint root = RootJoint::FreeFlyer) {
  return buildModelFromUrdf(STRIDE_SHARED_DIR "/robots/" + urdf, root);
}

Robot inHouse(const std::string& name) {
  return loadRobot(STRIDE_CONFIG_DIR "/robots/" + name + "/" + name + ".yaml");
}

// One of each robot class: fixed-base arms (with and without a contact), point-foot quadrupeds
// with 2-4 point contacts (local and world-aligned forces, Baumgarte terms), flat-foot humanoids
// with 6D contacts, free-flyers without contacts (an empty set, and a set with every contact
// switched off), and random trees.
std::vector<Case> cases() {
  std::vector<Case> out;
  {
    Case c{"ur5 (fixed base), no contact", shared("ur5/ur5_robot.urdf", RootJoint::Fixed), {}};
    out.push_back(std::move(c));
  }
  {
    Case c{"ur5 (fixed base), tool point", shared("ur5/ur5_robot.urdf", RootJoint::Fixed), {}};
    c.contacts.add(c.model, "tool0", 3, ReferenceFrame::LocalWorldAligned, 0.0, 3.0);
    out.push_back(std::move(c));
  }
  {
    std::mt19937 rng(5);
    Case c{"random fixed-base tree", makeRandomTree(rng, 7, false), {}};
    out.push_back(std::move(c));
  }
  {
    Case c{"solo12 4 points LOCAL", shared("solo12/solo12.urdf"), {}};
    for (const char* f : {"FL_FOOT", "FR_FOOT", "HL_FOOT", "HR_FOOT"})
      c.contacts.add(c.model, f, 3);
    out.push_back(std::move(c));
  }
  {
    Case c{"solo12 2 points LWA + Baumgarte", shared("solo12/solo12.urdf"), {}};
    for (const char* f : {"FL_FOOT", "HR_FOOT"})
      c.contacts.add(c.model, f, 3, ReferenceFrame::LocalWorldAligned, 30.0, 5.0);
    c.contacts.setReference(
        0, SE3(exp3(Eigen::Vector3d(0.1, 0.2, -0.1)), Eigen::Vector3d(0.1, 0.2, 0.0)));
    out.push_back(std::move(c));
  }
  {
    Robot quad = inHouse("stride_quad");
    Case c{"stride_quad 3 points", quad.model, {}};
    for (const auto& s : quad.contacts) c.contacts.add(c.model, s.frame, s.dim);
    c.contacts.setActive(2, false);
    out.push_back(std::move(c));
  }
  {
    Case c{"talos 2 soles", shared("talos/talos_reduced.urdf"), {}};
    c.contacts.add(c.model, "left_sole_link", 6);
    c.contacts.add(c.model, "right_sole_link", 6, ReferenceFrame::LocalWorldAligned, 10.0, 2.0);
    c.contacts.setReference(
        1, SE3(exp3(Eigen::Vector3d(0.05, -0.1, 0.3)), Eigen::Vector3d(0.0, -0.1, 0.02)));
    out.push_back(std::move(c));
  }
  {
    Robot hum = inHouse("stride_humanoid");
    Case c{"stride_humanoid 1 sole", hum.model, {}};
    for (const auto& s : hum.contacts) c.contacts.add(c.model, s.frame, s.dim);
    c.contacts.setActive(1, false);
    out.push_back(std::move(c));
  }
  {
    Case c{"solo12 no contact (empty set)", shared("solo12/solo12.urdf"), {}};
    out.push_back(std::move(c));
  }
  {
    Robot quad = inHouse("stride_quad");
    Case c{"stride_quad flight (all contacts off)", quad.model, {}};
    for (const auto& s : quad.contacts) c.contacts.add(c.model, s.frame, s.dim);
    for (int k = 0; k < c.contacts.size(); ++k) c.contacts.setActive(k, false);
    out.push_back(std::move(c));
  }
  {
    std::mt19937 rng(7);
    Case c{"random floating tree, no contact", makeRandomTree(rng, 9, true), {}};
    out.push_back(std::move(c));
  }
  return out;
}

struct State {
  Eigen::VectorXd q, v, u;
};

State randomState(const Model& model, std::mt19937& rng, double torque = 5.0) {
  State s;
  s.q = randomConfiguration(model, rng);
  std::uniform_real_distribution<double> u(-1, 1);
  s.v = Eigen::VectorXd::NullaryExpr(model.nv, [&] { return u(rng); });
  s.u = Eigen::VectorXd::NullaryExpr(actuatedDimension(model), [&] { return torque * u(rng); });
  return s;
}

// max|a - b| / max(1, max|b|)
double relErr(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  if (a.rows() != b.rows() || a.cols() != b.cols()) return 1e9;
  if (b.size() == 0) return 0.0;
  return (a - b).cwiseAbs().maxCoeff() / std::max(1.0, b.cwiseAbs().maxCoeff());
}

// x1 ⊖ x0 in the tangent space, [q1 ⊖ q0; v1 - v0].
Eigen::VectorXd stateDiff(const Model& model, const Eigen::VectorXd& q0, const Eigen::VectorXd& v0,
                          const Eigen::VectorXd& q1, const Eigen::VectorXd& v1) {
  Eigen::VectorXd d(2 * model.nv);
  d << difference(model, q0, q1), v1 - v0;
  return d;
}

TEST(KnotRk4, TruncatedDexpInvIsTheInverseRightJacobianToFourthOrder) {
  // Jlog6(exp6(θ)) is the exact inverse right Jacobian: the series cut after ad² errs by the
  // ad⁴ term, O(|θ|⁴) (the ad³ coefficient is zero), so halving θ divides the error by ~16. The
  // left-trivialized sign (-½) would err at O(|θ|).
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int t = 0; t < 5; ++t) {
    const Vector6d theta = Vector6d::NullaryExpr([&] { return u(rng); }),
                   v = Vector6d::NullaryExpr([&] { return u(rng); });
    double previous = 0.0;
    for (const double s : {0.1, 0.05, 0.025}) {
      const Vector6d exact = Jlog6(exp6(s * theta)) * v;
      const double err = (dexpInvTruncated(s * theta, v) - exact).norm();
      EXPECT_LT(err, 0.05 * std::pow(s, 4) * v.norm()) << "scale " << s;
      if (previous > 0) {
        EXPECT_GT(previous / err, 12.0) << "scale " << s;
      }
      previous = err;
    }
    // Its Jacobians against central differences.
    Matrix6d Dt, Dv, Nt, Nv;
    dexpInvTruncatedJacobians(theta, v, Dt, Dv);
    for (int j = 0; j < 6; ++j) {
      const Vector6d e = kStep * Vector6d::Unit(j);
      Nt.col(j) = (dexpInvTruncated(theta + e, v) - dexpInvTruncated(theta - e, v)) / (2 * kStep);
      Nv.col(j) = (dexpInvTruncated(theta, v + e) - dexpInvTruncated(theta, v - e)) / (2 * kStep);
    }
    EXPECT_LT(relErr(Dt, Nt), 1e-8);
    EXPECT_LT(relErr(Dv, Nv), 1e-8);
  }
}

TEST(KnotRk4, JacobiansMatchFiniteDifferences) {
  std::mt19937 rng(9);
  const double dt = 0.01;
  for (Case& c : cases()) {
    SCOPED_TRACE(c.name);
    const Model& m = c.model;
    Data data(m);
    Rk4Data rd(m, c.contacts);
    const State s = randomState(m, rng);
    ASSERT_EQ(knotDynamicsRk4Derivatives(m, data, c.contacts, rd, s.q, s.v, s.u, dt),
              ContactStatus::Ok);
    const int nv = m.nv, nc = rd.contact.nc;
    const Eigen::VectorXd q_next = rd.q_next;
    const Eigen::MatrixXd Fx = rd.Fx, Fu = rd.Fu, Gx = rd.Gx.topRows(nc), Gu = rd.Gu.topRows(nc);
    // The value path gives the same x⁺ and λ as the derivative path.
    Data d2(m);
    Rk4Data r2(m, c.contacts);
    ASSERT_EQ(knotDynamicsRk4(m, d2, c.contacts, r2, s.q, s.v, s.u, dt), ContactStatus::Ok);
    EXPECT_LT((r2.q_next - rd.q_next).norm(), 1e-12);
    EXPECT_LT((r2.v_next - rd.v_next).norm(), 1e-12 * std::max(1.0, rd.v_next.norm()));
    EXPECT_LT((r2.contact.lambda.head(nc) - rd.contact.lambda.head(nc)).norm(),
              1e-12 * std::max(1.0, rd.contact.lambda.norm()));
    // Output in the tangent space: [q⁺ ⊖ q⁺_0; v⁺; λ].
    auto out = [&](const Eigen::VectorXd& q, const Eigen::VectorXd& v, const Eigen::VectorXd& u) {
      EXPECT_EQ(knotDynamicsRk4(m, d2, c.contacts, r2, q, v, u, dt), ContactStatus::Ok);
      Eigen::VectorXd o(2 * nv + nc);
      o << difference(m, q_next, r2.q_next), r2.v_next, r2.contact.lambda.head(nc);
      return o;
    };
    const long rows = 2 * nv + nc;
    Eigen::MatrixXd Nq(rows, nv), Nv(rows, nv), Nu(rows, rd.nu);
    for (int k = 0; k < nv; ++k) {
      Eigen::VectorXd e = Eigen::VectorXd::Zero(nv);
      e[k] = kStep;
      Nq.col(k) = (out(integrate(m, s.q, e), s.v, s.u) - out(integrate(m, s.q, -e), s.v, s.u)) /
                  (2 * kStep);
      Nv.col(k) = (out(s.q, s.v + e, s.u) - out(s.q, s.v - e, s.u)) / (2 * kStep);
    }
    for (int k = 0; k < rd.nu; ++k) {
      Eigen::VectorXd e = Eigen::VectorXd::Zero(rd.nu);
      e[k] = kStep;
      Nu.col(k) = (out(s.q, s.v, s.u + e) - out(s.q, s.v, s.u - e)) / (2 * kStep);
    }
    const double e_xq = relErr(Fx.leftCols(nv), Nq.topRows(2 * nv)),
                 e_xv = relErr(Fx.rightCols(nv), Nv.topRows(2 * nv)),
                 e_u = relErr(Fu, Nu.topRows(2 * nv));
    EXPECT_LT(e_xq, kTol) << "Fx (q)";
    EXPECT_LT(e_xv, kTol) << "Fx (v)";
    EXPECT_LT(e_u, kTol) << "Fu";
    EXPECT_LT(relErr(Gx.leftCols(nv), Nq.bottomRows(nc)), kTol) << "Gx (q)";
    EXPECT_LT(relErr(Gx.rightCols(nv), Nv.bottomRows(nc)), kTol) << "Gx (v)";
    EXPECT_LT(relErr(Gu, Nu.bottomRows(nc)), kTol) << "Gu";
    std::printf("  %-40s nv %2d nc %2d  Fx(q) %.1e  Fx(v) %.1e  Fu %.1e\n", c.name.c_str(), nv, nc,
                e_xq, e_xv, e_u);
    // Stage 1 is the knot's own: λ and the kinematics left in the caller's workspaces are those
    // of contact dynamics at x (the Euler knot's).
    Data d3(m);
    KnotData kd(m, c.contacts);
    ASSERT_EQ(knotDynamics(m, d3, c.contacts, kd, s.q, s.v, s.u, dt), ContactStatus::Ok);
    EXPECT_TRUE(kd.contact.lambda.head(nc) == rd.contact.lambda.head(nc));
    EXPECT_TRUE(kd.contact.ddq == rd.contact.ddq);
    for (int j = 1; j < m.njoints(); ++j) EXPECT_TRUE(d3.oMi[j].p == data.oMi[j].p);
  }
}

// ---- Order ----

// The astronaut of tools/paper: the free-floating stride_humanoid without gravity and without
// contacts, joint torques and an initial spin, nothing external, so the centroidal momentum is
// conserved exactly by the flow.
struct Astronaut {
  Model model;
  ContactSet none;
  Eigen::VectorXd q0, v0, u;
  Astronaut() {
    const Robot robot = inHouse("stride_humanoid");
    model = robot.model;
    model.gravity.setZero();
    q0 = robot.default_q;
    std::mt19937 rng(21);
    std::uniform_real_distribution<double> r(-1, 1);
    v0 = Eigen::VectorXd::Zero(model.nv);
    v0.head<6>() << 0.1, -0.05, 0.1, 0.5, -0.8, 1.0;  // a tumbling base
    for (int j = 6; j < model.nv; ++j) v0[j] = 0.5 * r(rng);
    u = Eigen::VectorXd::NullaryExpr(actuatedDimension(model), [&] { return 0.05 * r(rng); });
  }
};

// The largest |h(t) - h(0)| over [0, T] with knots of dt.
template <bool Rk4>
double momentumDrift(const Astronaut& a, double dt, double T) {
  const Model& m = a.model;
  Data data(m), dh(m);
  KnotData kd(m, a.none);
  Rk4Data rd(m, a.none);
  Eigen::VectorXd q = a.q0, v = a.v0;
  const Vector6d h0 = computeCentroidalMomentum(m, dh, q, v);
  double drift = 0.0;
  const int n = static_cast<int>(std::lround(T / dt));
  for (int k = 0; k < n; ++k) {
    if (Rk4) {
      EXPECT_EQ(knotDynamicsRk4(m, data, a.none, rd, q, v, a.u, dt), ContactStatus::Ok);
      q = rd.q_next;
      v = rd.v_next;
    } else {
      EXPECT_EQ(knotDynamics(m, data, a.none, kd, q, v, a.u, dt), ContactStatus::Ok);
      q = kd.q_next;
      v = kd.v_next;
    }
    drift = std::max(drift, (computeCentroidalMomentum(m, dh, q, v) - h0).norm());
  }
  return drift;
}

// The drifts over the same time with knots of 20, 10 and 5 ms.
struct Drifts {
  double d20, d10, d5;
};

// What a 4th-order integrator achieves on the astronaut: a drift below 1e-6 of |h0| with 10 ms
// knots, which halving the knots divides by at least 10 (16 asymptotically; Euler's halves).
bool conservesToFourthOrder(const Drifts& d, double h0) {
  return d.d10 < 1e-6 * h0 && d.d20 / d.d10 > 10.0 && d.d10 / d.d5 > 10.0;
}

TEST(KnotRk4, ConservesMomentumOfAFreeFloatingBodyToFourthOrder) {
  const Astronaut a;
  Data dh(a.model);
  const double h0 = computeCentroidalMomentum(a.model, dh, a.q0, a.v0).norm();
  const double T = 1.0;
  const Drifts rk4{momentumDrift<true>(a, 0.02, T), momentumDrift<true>(a, 0.01, T),
                   momentumDrift<true>(a, 0.005, T)};
  const Drifts euler{momentumDrift<false>(a, 0.02, T), momentumDrift<false>(a, 0.01, T),
                     momentumDrift<false>(a, 0.005, T)};
  std::printf(
      "  |h0| %.4f; max |h - h0| over %.1f s:\n"
      "    dt 0.02:  Euler %.3e  RK4 %.3e\n"
      "    dt 0.01:  Euler %.3e  RK4 %.3e\n"
      "    dt 0.005: Euler %.3e  RK4 %.3e\n"
      "    halving dt divides the drift: Euler %.2f, %.2f; RK4 %.2f, %.2f\n",
      h0, T, euler.d20, rk4.d20, euler.d10, rk4.d10, euler.d5, rk4.d5, euler.d20 / euler.d10,
      euler.d10 / euler.d5, rk4.d20 / rk4.d10, rk4.d10 / rk4.d5);
  EXPECT_TRUE(conservesToFourthOrder(rk4, h0));
  EXPECT_LT(rk4.d10, 1e-3 * euler.d10);
  // The same check fails with Euler, which shows it can fail: Euler's drift is large and falls
  // only linearly with dt.
  EXPECT_FALSE(conservesToFourthOrder(euler, h0));
  EXPECT_GT(euler.d10, 1e-3 * h0);
  EXPECT_LT(euler.d10 / euler.d5, 3.0);
}

// x⁺ of n knots of dt from (q, v), each knot by `sub` Euler sub-steps of dt / sub (Rk4: one RKMK
// step per knot).
template <bool Rk4>
std::pair<Eigen::VectorXd, Eigen::VectorXd> rollout(const Case& c, const State& s, double dt, int n,
                                                    int sub = 1) {
  Data data(c.model);
  KnotData kd(c.model, c.contacts);
  Rk4Data rd(c.model, c.contacts);
  Eigen::VectorXd q = s.q, v = s.v;
  for (int k = 0; k < n; ++k) {
    if (Rk4) {
      EXPECT_EQ(knotDynamicsRk4(c.model, data, c.contacts, rd, q, v, s.u, dt), ContactStatus::Ok);
      q = rd.q_next;
      v = rd.v_next;
      continue;
    }
    for (int j = 0; j < sub; ++j) {
      EXPECT_EQ(knotDynamics(c.model, data, c.contacts, kd, q, v, s.u, dt / sub),
                ContactStatus::Ok);
      q = kd.q_next;
      v = kd.v_next;
    }
  }
  return {q, v};
}

TEST(KnotRk4, AgreesWithEulerToSecondOrderAndConvergesFaster) {
  std::mt19937 rng(4);
  for (Case& c : cases()) {
    SCOPED_TRACE(c.name);
    const Model& m = c.model;
    const State s = randomState(m, rng, 0.5);
    // One knot: both are consistent, Euler to first order, so they differ by O(dt²); halving dt
    // divides the difference by ~4.
    double previous = 0.0;
    for (const double dt : {0.002, 0.001, 0.0005}) {
      const auto e = rollout<false>(c, s, dt, 1), r = rollout<true>(c, s, dt, 1);
      const double diff = stateDiff(m, e.first, e.second, r.first, r.second).norm();
      if (previous > 0) {
        EXPECT_GT(previous / diff, 3.0) << "dt " << dt;
        EXPECT_LT(previous / diff, 7.0) << "dt " << dt;
      }
      previous = diff;
    }
    // Over a short horizon (5 knots of 10 ms), against Euler at 1000 sub-steps per knot: RK4 is
    // far closer than Euler at the knot length. And its own convergence is of order 4: halving
    // the knots divides the change by ~16 (from 5 ms knots on: the light legs' fastest modes
    // leave the 10 ms knots outside the asymptotic range on some states).
    const double dt = 0.01;
    const int n = 5;
    const auto ref = rollout<false>(c, s, dt, n, 1000);
    const auto e = rollout<false>(c, s, dt, n), r = rollout<true>(c, s, dt, n);
    const double err_e = stateDiff(m, ref.first, ref.second, e.first, e.second).norm(),
                 err_r = stateDiff(m, ref.first, ref.second, r.first, r.second).norm();
    EXPECT_LT(err_r, 0.05 * err_e);
    const auto r2 = rollout<true>(c, s, dt / 2, 2 * n), r4 = rollout<true>(c, s, dt / 4, 4 * n),
               r8 = rollout<true>(c, s, dt / 8, 8 * n);
    const double d1 = stateDiff(m, r4.first, r4.second, r2.first, r2.second).norm(),
                 d2 = stateDiff(m, r8.first, r8.second, r4.first, r4.second).norm();
    EXPECT_GT(d1 / d2, 10.0);
    std::printf(
        "  %-40s 50 ms: Euler err %.2e, RK4 err %.2e (vs Euler/1000); RK4 self-ratio %.1f\n",
        c.name.c_str(), err_e, err_r, d1 / d2);
  }
}

// ---- Contract ----

TEST(KnotRk4, BadInputHoldsTheState) {
  Case c = cases()[3];  // solo12, 4 points
  std::mt19937 rng(1);
  const State s = randomState(c.model, rng);
  Data data(c.model);
  Rk4Data rd(c.model, c.contacts);
  Eigen::VectorXd u = s.u;
  u[0] = std::nan("");
  EXPECT_EQ(knotDynamicsRk4Derivatives(c.model, data, c.contacts, rd, s.q, s.v, u, 0.01),
            ContactStatus::NonFinite);
  EXPECT_TRUE(rd.q_next == s.q);
  EXPECT_TRUE(rd.v_next == s.v);
  EXPECT_TRUE(rd.contact.lambda.isZero(0.0));
  EXPECT_EQ(knotDynamicsRk4(c.model, data, c.contacts, rd, s.q, s.v, s.u, std::nan("")),
            ContactStatus::NonFinite);
  Eigen::VectorXd v = s.v;
  v[2] = std::numeric_limits<double>::infinity();
  EXPECT_EQ(knotDynamicsRk4(c.model, data, c.contacts, rd, s.q, v, s.u, 0.01),
            ContactStatus::NonFinite);
  EXPECT_TRUE(rd.q_next == s.q);
  EXPECT_TRUE(rd.contact.lambda.isZero(0.0));
  // A finite state whose first stage overflows (v² terms beyond the largest double): a later
  // stage fails, and the knot holds the state and zeroes stage 1's λ all the same.
  v = 1e160 * s.v;
  EXPECT_NE(knotDynamicsRk4Derivatives(c.model, data, c.contacts, rd, s.q, v, s.u, 0.01),
            ContactStatus::Ok);
  EXPECT_TRUE(rd.q_next == s.q);
  EXPECT_TRUE(rd.v_next == v);
  EXPECT_TRUE(rd.contact.lambda.isZero(0.0));
  EXPECT_THROW(
      knotDynamicsRk4(c.model, data, c.contacts, rd, s.q, s.v, Eigen::VectorXd::Zero(3), 0.01),
      std::invalid_argument);
}

TEST(KnotRk4, DoesNotAllocate) {
  std::mt19937 rng(2);
  for (Case& c : cases()) {
    SCOPED_TRACE(c.name);
    const State s = randomState(c.model, rng);
    Data data(c.model);
    Rk4Data rd(c.model, c.contacts);
    Eigen::VectorXd u = s.u;
    // Warm: nothing is sized lazily, but the first call is not the one that counts.
    ASSERT_EQ(knotDynamicsRk4Derivatives(c.model, data, c.contacts, rd, s.q, s.v, u, 0.01),
              ContactStatus::Ok);
    EXPECT_EQ(
        allocations([&] { knotDynamicsRk4(c.model, data, c.contacts, rd, s.q, s.v, u, 0.01); }), 0);
    EXPECT_EQ(allocations([&] {
                knotDynamicsRk4Derivatives(c.model, data, c.contacts, rd, s.q, s.v, u, 0.01);
              }),
              0);
    u[0] = std::nan("");
    EXPECT_EQ(allocations([&] {
                knotDynamicsRk4Derivatives(c.model, data, c.contacts, rd, s.q, s.v, u, 0.01);
              }),
              0);
  }
}

// ---- Cost (printed, not asserted: the machine is shared) ----

}  // namespace test_knot_rk4
}  // namespace stride
