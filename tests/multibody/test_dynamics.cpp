// Property tests of the dynamics algorithms on the standard robots (solo12, talos_reduced, ur5,
// stride_quad, stride_humanoid): ABA / RNEA / CRBA agree with each other, Jacobians and
// accelerations agree with finite differences on the configuration manifold, the centre of mass
// and centroidal quantities are consistent, and simulating with ABA conserves energy and
// momentum. The identities themselves live in random_tree.hpp (namespace checks), shared with
// test_random_trees.

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "multibody/random_tree.hpp"

namespace stride {
namespace test_dynamics {

struct Case {
  std::string name;
  Model model;
  std::vector<checks::Sample> samples;
};

// Five random states per robot, three on talos (the largest).
const std::vector<Case>& cases() {
  static const std::vector<Case> all = [] {
    std::vector<Case> out;
    std::mt19937 rng(20240611);
    for (const RobotCase& rc : standardRobots()) {
      const int n = rc.name == "talos_reduced" ? 3 : 5;
      out.push_back({rc.name, rc.model, checks::randomSamples(rc.model, rng, n)});
    }
    return out;
  }();
  return all;
}

template <typename Check>
void forEachSample(Check&& check, int max_samples = 1000) {
  for (const Case& c : cases()) {
    SCOPED_TRACE(c.name);
    for (int k = 0; k < static_cast<int>(c.samples.size()) && k < max_samples; ++k) {
      SCOPED_TRACE("sample " + std::to_string(k));
      check(c.model, c.samples[k]);
    }
  }
}

TEST(StandardRobots, AreLoaded) {
  ASSERT_EQ(cases().size(), 5u);
  for (const Case& c : cases()) {
    SCOPED_TRACE(c.name);
    EXPECT_GT(c.model.nv, 5);
    EXPECT_GT(c.model.totalMass(), 0.0);
    EXPECT_EQ(c.model.hasFreeFlyer(), c.name != "ur5");
    EXPECT_EQ(c.model.nq, c.model.nv + (c.model.hasFreeFlyer() ? 1 : 0));
  }
}

TEST(Dynamics, AbaEqualsCrbaSolve) {
  forEachSample(checks::abaMatchesCrbaSolve);
}

TEST(Dynamics, RneaEqualsMassMatrixTimesAccelerationPlusBias) {
  forEachSample(checks::rneaMatchesMassMatrixAndBias);
}

TEST(Dynamics, MassMatrixIsSymmetricPositiveDefinite) {
  forEachSample(checks::massMatrixIsSpdAndGivesKineticEnergy);
}

TEST(Kinematics, FrameJacobiansMatchFiniteDifferences) {
  forEachSample([](const Model& model, const checks::Sample& s) {
    checks::placementJacobiansMatchFiniteDifferences(model, s, true);
  });
}

TEST(Kinematics, JointJacobiansMatchFiniteDifferences) {
  forEachSample([](const Model& model, const checks::Sample& s) {
    checks::placementJacobiansMatchFiniteDifferences(model, s, false);
  });
}

TEST(Kinematics, FrameAccelerationsMatchTimeDerivatives) {
  forEachSample(checks::frameAccelerationsMatchTimeDerivatives, 2);
}

TEST(CenterOfMass, JacobianMatchesFiniteDifferences) {
  forEachSample(checks::comJacobianMatchesFiniteDifferences);
}

TEST(Centroidal, MapTimesVelocityIsMomentum) {
  forEachSample(checks::centroidalMapMatchesMomentum);
}

// The full TALOS (issue 43): its 12 moving <mimic> gripper fingers load as independent joints for
// dynamics (urdf.hpp, MimicJoints), as the usual URDF parsers load them, and the three algorithms
// agree on the 50-joint tree.
TEST(Dynamics, FullTalosWithMimicJointsAsIndependentJointsAgrees) {
  const std::string path = STRIDE_SHARED_DIR "/robots/talos/talos_full_v2.urdf";
  const Model talos = buildModelFromUrdf(path, RootJoint::FreeFlyer);
  EXPECT_EQ(talos.nv, 6 + 44);  // 30 joints of talos_full_v2 + 2 gripper leaders + 12 mimics
  for (const MimicJoint& m : urdfMimicJoints(path)) EXPECT_TRUE(talos.existJoint(m.name)) << m.name;
  std::mt19937 rng(43);
  for (const checks::Sample& s : checks::randomSamples(talos, rng, 3)) {
    checks::abaMatchesCrbaSolve(talos, s);
    checks::rneaMatchesMassMatrixAndBias(talos, s);
    checks::massMatrixIsSpdAndGivesKineticEnergy(talos, s);
  }
}

TEST(Dynamics, WrongSizesThrow) {
  const Model& model = cases()[0].model;
  Data data(model);
  const Eigen::VectorXd q = neutral(model), v = Eigen::VectorXd::Zero(model.nv);
  const Eigen::VectorXd q_bad = Eigen::VectorXd::Zero(model.nq - 1);
  const Eigen::VectorXd v_bad = Eigen::VectorXd::Zero(model.nv + 1);
  EXPECT_THROW(aba(model, data, q_bad, v, v), std::invalid_argument);
  EXPECT_THROW(aba(model, data, q, v_bad, v), std::invalid_argument);
  EXPECT_THROW(aba(model, data, q, v, v_bad), std::invalid_argument);
  EXPECT_THROW(rnea(model, data, q_bad, v, v), std::invalid_argument);
  EXPECT_THROW(rnea(model, data, q, v_bad, v), std::invalid_argument);
  EXPECT_THROW(rnea(model, data, q, v, v_bad), std::invalid_argument);
  EXPECT_THROW(nonLinearEffects(model, data, q, v_bad), std::invalid_argument);
  EXPECT_THROW(computeGeneralizedGravity(model, data, q_bad), std::invalid_argument);
  EXPECT_THROW(crba(model, data, q_bad), std::invalid_argument);
  EXPECT_THROW(forwardKinematics(model, data, q, v, v_bad), std::invalid_argument);
  Matrix6Xd J(6, model.nv + 1);
  computeJointJacobians(model, data, q);
  EXPECT_THROW(getFrameJacobian(model, data, 1, ReferenceFrame::Local, J), std::invalid_argument);
  EXPECT_THROW(getJointJacobian(model, data, 1, ReferenceFrame::Local, J), std::invalid_argument);
}

// ------------------------------------------------------------------------------------------------
// Simulation with ABA: RK4 on (delta, v) with q = q0 ⊕ delta, delta' = dIntegrate(q0, delta,
// Second)^-1 v (the right Jacobian: exact), v' = aba(q, v, 0).

struct Trajectory {
  std::vector<double> kinetic, potential;
  std::vector<Vector6d> momentum;  // centroidal
  double mass = 0;
};

Trajectory simulate(const Model& model, const Eigen::VectorXd& q0, const Eigen::VectorXd& v0,
                    double duration, double dt) {
  const int nv = model.nv;
  Data data(model);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(nv);
  Eigen::VectorXd q(model.nq);
  Eigen::MatrixXd Jd(nv, nv);
  auto derivative = [&](const Eigen::VectorXd& delta, const Eigen::VectorXd& v,
                        Eigen::VectorXd& d_delta, Eigen::VectorXd& d_v) {
    integrate(model, q0, delta, q);
    dIntegrate(model, q0, delta, Jd, ArgumentPosition::Second);
    d_delta = Jd.partialPivLu().solve(v);
    d_v = aba(model, data, q, v, zero);
  };
  Trajectory traj;
  traj.mass = model.totalMass();
  auto record = [&](const Eigen::VectorXd& delta, const Eigen::VectorXd& v) {
    integrate(model, q0, delta, q);
    const Eigen::MatrixXd& M = crba(model, data, q);
    traj.kinetic.push_back(0.5 * v.dot(M * v));
    traj.potential.push_back(-traj.mass * model.gravity.dot(centerOfMass(model, data, q)));
    traj.momentum.push_back(computeCentroidalMomentum(model, data, q, v));
  };
  Eigen::VectorXd delta = zero, v = v0;
  Eigen::VectorXd k1d(nv), k1v(nv), k2d(nv), k2v(nv), k3d(nv), k3v(nv), k4d(nv), k4v(nv);
  record(delta, v);
  const int steps = static_cast<int>(std::lround(duration / dt));
  for (int n = 0; n < steps; ++n) {
    derivative(delta, v, k1d, k1v);
    derivative(delta + 0.5 * dt * k1d, v + 0.5 * dt * k1v, k2d, k2v);
    derivative(delta + 0.5 * dt * k2d, v + 0.5 * dt * k2v, k3d, k3v);
    derivative(delta + dt * k3d, v + dt * k3v, k4d, k4v);
    delta += dt / 6.0 * (k1d + 2.0 * k2d + 2.0 * k3d + k4d);
    v += dt / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
    record(delta, v);
  }
  return traj;
}

struct SimulationCase {
  std::string name;
  Model model;
  Eigen::VectorXd q0, v0;
};

// solo12, stride_quad, stride_humanoid and three random trees (two floating).
std::vector<SimulationCase> simulationCases(bool gravity) {
  std::vector<SimulationCase> out;
  std::mt19937 rng(7);
  for (const RobotCase& rc : standardRobots())
    if (rc.name == "solo12" || rc.name == "stride_quad" || rc.name == "stride_humanoid")
      out.push_back({rc.name, rc.model, {}, {}});
  out.push_back({"random_tree_ff_6", makeRandomTree(rng, 6, true), {}, {}});
  out.push_back({"random_tree_fixed_10", makeRandomTree(rng, 10, false), {}, {}});
  out.push_back({"random_tree_ff_15", makeRandomTree(rng, 15, true), {}, {}});
  for (SimulationCase& c : out) {
    if (!gravity) c.model.gravity.setZero();
    c.q0 = randomConfiguration(c.model, rng);
    c.v0 = randomVector(rng, c.model.nv);
  }
  return out;
}

constexpr double kDuration = 0.3, kDt = 1e-3, kConservation = 1e-8;

TEST(Simulation, KineticEnergyIsConservedWithoutGravity) {
  for (const SimulationCase& c : simulationCases(false)) {
    SCOPED_TRACE(c.name);
    const Trajectory traj = simulate(c.model, c.q0, c.v0, kDuration, kDt);
    const double T0 = traj.kinetic.front();
    ASSERT_GT(T0, 0.0);
    double worst = 0.0;
    for (double T : traj.kinetic) worst = std::max(worst, std::abs(T - T0) / T0);
    EXPECT_LT(worst, kConservation) << "T0 = " << T0 << ", T(end) = " << traj.kinetic.back();
  }
}

TEST(Simulation, TotalEnergyIsConservedWithGravity) {
  for (const SimulationCase& c : simulationCases(true)) {
    SCOPED_TRACE(c.name);
    const Trajectory traj = simulate(c.model, c.q0, c.v0, kDuration, kDt);
    const double E0 = traj.kinetic.front() + traj.potential.front();
    // Relative to the energy exchanged as well as the initial kinetic energy.
    double scale = 0.0, worst = 0.0;
    for (size_t k = 0; k < traj.kinetic.size(); ++k)
      scale = std::max(
          scale, std::max(traj.kinetic[k], std::abs(traj.potential[k] - traj.potential.front())));
    for (size_t k = 0; k < traj.kinetic.size(); ++k)
      worst = std::max(worst, std::abs(traj.kinetic[k] + traj.potential[k] - E0) / scale);
    EXPECT_LT(worst, kConservation);
    // The potential energy did change: gravity acted.
    EXPECT_GT(std::abs(traj.potential.back() - traj.potential.front()), 1e-3 * scale);
    if (c.model.hasFreeFlyer()) {
      // Free fall: linear momentum grows by m g t, angular momentum about the CoM is constant.
      const Vector6d h0 = traj.momentum.front();
      double worst_h = 0.0;
      for (size_t k = 0; k < traj.momentum.size(); ++k) {
        Vector6d expected = h0;
        expected.head<3>() += traj.mass * c.model.gravity * (kDt * static_cast<double>(k));
        worst_h = std::max(worst_h, (traj.momentum[k] - expected).norm() / h0.norm());
      }
      EXPECT_LT(worst_h, kConservation);
    }
  }
}

TEST(Simulation, CentroidalMomentumIsConservedOnFloatingBases) {
  int floating = 0;
  for (const SimulationCase& c : simulationCases(false)) {
    if (!c.model.hasFreeFlyer()) continue;
    ++floating;
    SCOPED_TRACE(c.name);
    const Trajectory traj = simulate(c.model, c.q0, c.v0, kDuration, kDt);
    const Vector6d h0 = traj.momentum.front();
    ASSERT_GT(h0.norm(), 0.0);
    double worst = 0.0;
    for (const Vector6d& h : traj.momentum) worst = std::max(worst, (h - h0).norm() / h0.norm());
    EXPECT_LT(worst, kConservation)
        << "h0 = " << h0.transpose() << "\nh(end) = " << traj.momentum.back().transpose();
  }
  EXPECT_EQ(floating, 5);
}

}  // namespace test_dynamics
}  // namespace stride
