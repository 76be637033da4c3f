// Property tests of the configuration manifold (lie_group.hpp): SO(3) / SE(3) exponential and
// logarithm against independent references (Eigen's angle-axis, quadrature of the SE(3) flow,
// the power series of the right Jacobian), their Jacobians against central finite differences,
// and the whole-robot integrate / difference with their Jacobians, on the standard robots and on
// random trees.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "multibody/random_tree.hpp"
#include "solver/multibody/lie_group.hpp"

namespace stride {
namespace test_lie_group {

constexpr double kPi = M_PI;

// Angles that exercise every branch: exactly zero, the small-angle series (below 1e-4) and both
// sides of its threshold, the closed forms, and close to pi.
const std::vector<double>& testAngles() {
  static const std::vector<double> angles = {0.0,     1e-12, 1e-9, 1e-6,       0.99e-4,
                                             1.01e-4, 3e-4,  1e-3, 1e-2,       0.3,
                                             1.0,     2.0,   3.0,  kPi - 1e-3, kPi - 1e-6};
  return angles;
}

Eigen::Vector3d randomUnit(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
}

Vector6d twist(const Eigen::Vector3d& linear, const Eigen::Vector3d& angular) {
  Vector6d xi;
  xi << linear, angular;
  return xi;
}

// Rotation by the vector w, independently of exp3.
Eigen::Matrix3d angleAxis(const Eigen::Vector3d& w) {
  const double t = w.norm();
  if (t == 0.0) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(t, w / t).toRotationMatrix();
}

// exp of the body twist [v; w] as the flow of the constant twist: R = exp(w), p = ∫0^1 R(s) v ds
// (composite Simpson rule, 4000 intervals).
SE3 exp6Reference(const Vector6d& xi) {
  const Eigen::Vector3d v = xi.head<3>(), w = xi.tail<3>();
  const int n = 4000;
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (int k = 0; k <= n; ++k) {
    const double s = static_cast<double>(k) / n;
    const double weight = (k == 0 || k == n) ? 1.0 : (k % 2 ? 4.0 : 2.0);
    p += weight * (angleAxis(s * w) * v);
  }
  return SE3(angleAxis(w), p / (3.0 * n));
}

// The matrix of the motion cross product ad(xi) m = xi x m, built independently of spatial.hpp.
Matrix6d adMatrix(const Vector6d& xi) {
  Matrix6d ad = Matrix6d::Zero();
  ad.topLeftCorner<3, 3>() = skew(xi.tail<3>());
  ad.topRightCorner<3, 3>() = skew(xi.head<3>());
  ad.bottomRightCorner<3, 3>() = skew(xi.tail<3>());
  return ad;
}

// Right Jacobians as power series: Jr(x) = sum_k (-ad x)^k / (k+1)!.
template <int N>
Eigen::Matrix<double, N, N> rightJacobianSeries(const Eigen::Matrix<double, N, N>& ad) {
  using Mat = Eigen::Matrix<double, N, N>;
  Mat term = Mat::Identity(), sum = Mat::Identity();
  for (int k = 1; k < 80; ++k) {
    term = (-ad * term / (k + 1)).eval();
    sum += term;
  }
  return sum;
}

// Tolerance for the Jacobians against their series: machine precision, except that the
// (1 + cos t) / (t sin t) coefficient of the inverse Jacobians is computed with an absolute error
// ~eps / (pi - t) near pi (cancellation in 1 + cos t); the Jacobians themselves stay bounded there.
double jacobianTolerance(double t) {
  return std::max(1e-12, 1e-15 / (kPi - t));
}

// Random twists with the angular part of the given norm and a linear part up to 1.5.
Vector6d randomTwist(std::mt19937& rng, double angle) {
  std::uniform_real_distribution<double> u(0.0, 1.5);
  return twist(u(rng) * randomUnit(rng), angle * randomUnit(rng));
}

// ------------------------------------------------------------------------------------------------
// SO(3)

TEST(SO3, ExpMatchesAngleAxis) {
  std::mt19937 rng(1);
  for (double t : testAngles())
    for (int s = 0; s < 4; ++s) {
      const Eigen::Vector3d w = t * randomUnit(rng);
      EXPECT_LT((exp3(w) - angleAxis(w)).norm(), 1e-14) << "angle " << t;
      EXPECT_LT((exp3(w) * exp3(w).transpose() - Eigen::Matrix3d::Identity()).norm(), 1e-14);
    }
}

TEST(SO3, LogOfExpIsIdentity) {
  std::mt19937 rng(2);
  for (double t : testAngles())
    for (int s = 0; s < 4; ++s) {
      const Eigen::Vector3d w = t * randomUnit(rng);
      // log3 goes through the quaternion: accurate from 0 up to pi.
      EXPECT_LT((log3(exp3(w)) - w).norm(), 1e-12) << "angle " << t;
    }
  EXPECT_EQ(log3(Eigen::Matrix3d::Identity()), Eigen::Vector3d::Zero());
}

TEST(SO3, ExpOfLogIsIdentityUpToPi) {
  std::mt19937 rng(3);
  // Rotations by exactly pi (log is then defined up to sign: exp must return the same rotation).
  for (int k = 0; k < 3; ++k) {
    Eigen::Matrix3d R = -Eigen::Matrix3d::Identity();
    R(k, k) = 1.0;
    const Eigen::Vector3d w = log3(R);
    EXPECT_NEAR(w.norm(), kPi, 1e-12);
    EXPECT_LT((exp3(w) - R).norm(), 1e-12);
  }
  for (int s = 0; s < 20; ++s) {
    const Eigen::Matrix3d R =
        angleAxis(std::uniform_real_distribution<double>(0, kPi)(rng) * randomUnit(rng));
    EXPECT_LT((exp3(log3(R)) - R).norm(), 1e-13);
  }
  // Angles beyond pi come back as the equivalent rotation vector of norm <= pi.
  for (double t : {kPi + 1e-3, 4.0, 6.0, 2 * kPi - 1e-3}) {
    const Eigen::Vector3d w = t * randomUnit(rng);
    const Eigen::Vector3d l = log3(exp3(w));
    EXPECT_LE(l.norm(), kPi + 1e-12);
    EXPECT_NEAR(l.norm(), 2 * kPi - t, 1e-10);
    EXPECT_LT((exp3(l) - exp3(w)).norm(), 1e-12);
  }
}

TEST(SO3, JexpMatchesSeriesAndFiniteDifferences) {
  std::mt19937 rng(4);
  const double h = 1e-6;
  for (double t : testAngles())
    for (int s = 0; s < 3; ++s) {
      const Eigen::Vector3d w = t * randomUnit(rng);
      const Eigen::Matrix3d J = Jexp3(w);
      EXPECT_LT((J - rightJacobianSeries<3>(skew(w))).norm(), 1e-12) << "angle " << t;
      // exp3(w + d) = exp3(w) exp3(J d): column k = d/de log3(exp3(w)^T exp3(w + e e_k)).
      const Eigen::Matrix3d R0t = exp3(w).transpose();
      Eigen::Matrix3d fd;
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector3d e = h * Eigen::Vector3d::Unit(k);
        fd.col(k) = (log3(R0t * exp3(w + e)) - log3(R0t * exp3(w - e))) / (2 * h);
      }
      EXPECT_LT(relativeError(J, fd), 1e-6) << "angle " << t;
    }
}

TEST(SO3, JlogMatchesFiniteDifferencesAndInvertsJexp) {
  std::mt19937 rng(5);
  const double h = 1e-6;
  for (double t : testAngles())
    for (int s = 0; s < 3; ++s) {
      const Eigen::Vector3d w = t * randomUnit(rng);
      const Eigen::Matrix3d R = exp3(w);
      const Eigen::Matrix3d J = Jlog3(R);
      // log3(R exp3(d)) = log3(R) + J d.
      Eigen::Matrix3d fd;
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector3d e = h * Eigen::Vector3d::Unit(k);
        fd.col(k) = (log3(R * exp3(e)) - log3(R * exp3(-e))) / (2 * h);
      }
      EXPECT_LT(relativeError(J, fd), 1e-6) << "angle " << t;
      EXPECT_LT((J * Jexp3(w) - Eigen::Matrix3d::Identity()).norm(), 1e-9) << "angle " << t;
      const Eigen::Matrix3d series_inverse = rightJacobianSeries<3>(skew(w)).inverse();
      EXPECT_LT(relativeError(J, series_inverse), jacobianTolerance(t)) << "angle " << t;
    }
}

// ------------------------------------------------------------------------------------------------
// SE(3)

TEST(SE3, ExpMatchesFlowOfConstantTwist) {
  std::mt19937 rng(6);
  for (double t : testAngles())
    for (int s = 0; s < 3; ++s) {
      const Vector6d xi = randomTwist(rng, t);
      const SE3 M = exp6(xi), ref = exp6Reference(xi);
      EXPECT_LT((M.R - ref.R).norm(), 1e-13) << "angle " << t;
      EXPECT_LT((M.p - ref.p).norm(), 1e-12) << "angle " << t;
    }
  // Pure translation and one-parameter subgroup: exp(a xi) exp(b xi) = exp((a + b) xi).
  const Eigen::Vector3d v(0.3, -0.2, 0.5);
  EXPECT_TRUE(
      exp6(twist(v, Eigen::Vector3d::Zero())).isApprox(SE3(Eigen::Matrix3d::Identity(), v)));
  for (int s = 0; s < 10; ++s) {
    const Vector6d xi = randomTwist(rng, 1.0);
    EXPECT_TRUE((exp6(0.3 * xi) * exp6(0.5 * xi)).isApprox(exp6(0.8 * xi), 1e-12));
  }
}

TEST(SE3, LogOfExpIsIdentity) {
  std::mt19937 rng(7);
  for (double t : testAngles())
    for (int s = 0; s < 4; ++s) {
      const Vector6d xi = randomTwist(rng, t);
      // Near pi, the translation of log6 uses the same (1 + cos t) coefficient.
      EXPECT_LT((log6(exp6(xi)) - xi).norm(), std::max(1e-11, 1e-15 / (kPi - t))) << "angle " << t;
    }
  for (int s = 0; s < 20; ++s) {
    const SE3 M(angleAxis(std::uniform_real_distribution<double>(0, kPi)(rng) * randomUnit(rng)),
                randomUnit(rng) * 0.7);
    const SE3 back = exp6(log6(M));
    EXPECT_LT((back.R - M.R).norm(), 1e-13);
    EXPECT_LT((back.p - M.p).norm(), 1e-12);
  }
}

TEST(SE3, JexpMatchesFiniteDifferences) {
  std::mt19937 rng(8);
  const double h = 1e-6;
  for (double t : testAngles())
    for (int s = 0; s < 3; ++s) {
      const Vector6d xi = randomTwist(rng, t);
      const Matrix6d J = Jexp6(xi);
      const SE3 M0 = exp6(xi);
      Matrix6d fd;
      for (int k = 0; k < 6; ++k) {
        const Vector6d e = h * Vector6d::Unit(k);
        fd.col(k) = (log6(M0.actInv(exp6(xi + e))) - log6(M0.actInv(exp6(xi - e)))) / (2 * h);
      }
      EXPECT_LT(relativeError(J, fd), 1e-6) << "angle " << t;
    }
}

TEST(SE3, JlogMatchesFiniteDifferencesAndInvertsJexp) {
  std::mt19937 rng(9);
  const double h = 1e-6;
  for (double t : testAngles())
    for (int s = 0; s < 3; ++s) {
      const Vector6d xi = randomTwist(rng, t);
      const SE3 M = exp6(xi);
      const Matrix6d J = Jlog6(M);
      Matrix6d fd;
      for (int k = 0; k < 6; ++k) {
        const Vector6d e = h * Vector6d::Unit(k);
        fd.col(k) = (log6(M * exp6(e)) - log6(M * exp6(-e))) / (2 * h);
      }
      // log6 itself carries ~eps / (pi - t) absolute error near pi (see jacobianTolerance), which
      // central differences divide by h: at pi - 1e-6 they are meaningless, not the Jacobian.
      if (t < kPi - 1e-4) {
        EXPECT_LT(relativeError(J, fd), 1e-6) << "angle " << t;
      }
      EXPECT_LT((J * Jexp6(xi) - Matrix6d::Identity()).norm(), 1e-9) << "angle " << t;
      EXPECT_LT((Jexp6(xi) * J - Matrix6d::Identity()).norm(), 1e-9) << "angle " << t;
    }
}

// The SE(3) Jacobians against their power series to machine precision. Finite differences
// (above) cannot see errors below ~1e-8; a product like Jlog6 * Jexp6 = I cannot see errors the
// two share (the coupling block). The series sum_k (-ad xi)^k / (k+1)! is accurate to ~1e-15
// here (|ad xi| < 5), so every angle must reach ~1e-12 relative, up to the conditioning of the
// inverse, ~1 / (pi - t), for Jlog6 near pi.
TEST(SE3, JacobiansMatchSeriesToMachinePrecision) {
  std::mt19937 rng(17);
  for (double t : testAngles())
    for (int s = 0; s < 3; ++s) {
      const Vector6d xi = randomTwist(rng, t);
      const Matrix6d series = rightJacobianSeries<6>(adMatrix(xi));
      EXPECT_LT(relativeError(Jexp6(xi), series), 1e-12)
          << "Jexp6 at angle " << t << ", xi = " << xi.transpose();
      EXPECT_LT(relativeError(Jlog6(exp6(xi)), Matrix6d(series.inverse())), jacobianTolerance(t))
          << "Jlog6 at angle " << t << ", xi = " << xi.transpose();
    }
}

// ------------------------------------------------------------------------------------------------
// Whole configurations, on the standard robots and on random trees.

std::vector<RobotCase> manifoldModels() {
  std::vector<RobotCase> models = standardRobots();
  std::mt19937 rng(10);
  for (int k = 0; k < 8; ++k) {
    const bool ff = k % 2 == 0;
    models.push_back({"random_tree_" + std::to_string(k) + (ff ? "_ff" : "_fixed"),
                      makeRandomTree(rng, 1 + 3 * k, ff)});
  }
  return models;
}

// Random (q, v) pairs: v ~ U(-1, 1), plus for floating bases a base rotation close to pi and one
// close to zero.
std::vector<Eigen::VectorXd> testVelocities(const Model& model, std::mt19937& rng) {
  std::vector<Eigen::VectorXd> vs;
  for (int s = 0; s < 3; ++s) vs.push_back(randomVector(rng, model.nv));
  vs.push_back(Eigen::VectorXd::Zero(model.nv));
  if (model.hasFreeFlyer()) {
    Eigen::VectorXd v = randomVector(rng, model.nv);
    v.segment<3>(3) = (kPi - 1e-2) * randomUnit(rng);
    vs.push_back(v);
    v.segment<3>(3) = 1e-7 * randomUnit(rng);
    vs.push_back(v);
  }
  return vs;
}

TEST(Configuration, IntegrateAndDifferenceAreConsistent) {
  std::mt19937 rng(11);
  for (const RobotCase& rc : manifoldModels()) {
    SCOPED_TRACE(rc.name);
    const Model& model = rc.model;
    for (int s = 0; s < 3; ++s) {
      const Eigen::VectorXd q = randomConfiguration(model, rng);
      EXPECT_LT(difference(model, q, q).norm(), 1e-14);
      EXPECT_LT(difference(model, q, integrate(model, q, Eigen::VectorXd::Zero(model.nv))).norm(),
                1e-14);
      for (const Eigen::VectorXd& v : testVelocities(model, rng)) {
        const Eigen::VectorXd q1 = integrate(model, q, v);
        EXPECT_TRUE(isNormalized(model, q1, 1e-14));
        EXPECT_LT((difference(model, q, q1) - v).norm(), 1e-11 * std::max(1.0, v.norm()));
        // One-parameter subgroup: q ⊕ 0.3 v ⊕ 0.5 v = q ⊕ 0.8 v.
        const Eigen::VectorXd qa = integrate(model, integrate(model, q, 0.3 * v), 0.5 * v);
        EXPECT_LT(difference(model, integrate(model, q, 0.8 * v), qa).norm(), 1e-12);
        // And back: q ⊕ (q2 ⊖ q) = q2 for an unrelated configuration q2 (up to quaternion sign).
        const Eigen::VectorXd q2 = randomConfiguration(model, rng);
        const Eigen::VectorXd q2b = integrate(model, q, difference(model, q, q2));
        EXPECT_LT(difference(model, q2, q2b).norm(), 1e-11);
      }
    }
  }
}

TEST(Configuration, DIntegrateMatchesFiniteDifferences) {
  std::mt19937 rng(12);
  const double h = 1e-6;
  for (const RobotCase& rc : manifoldModels()) {
    SCOPED_TRACE(rc.name);
    const Model& model = rc.model;
    const int nv = model.nv;
    Eigen::MatrixXd J1(nv, nv), J2(nv, nv);
    for (int s = 0; s < 2; ++s) {
      const Eigen::VectorXd q = randomConfiguration(model, rng);
      for (const Eigen::VectorXd& v : testVelocities(model, rng)) {
        dIntegrate(model, q, v, J1, ArgumentPosition::First);
        dIntegrate(model, q, v, J2, ArgumentPosition::Second);
        const Eigen::VectorXd out = integrate(model, q, v);
        // Output perturbations are measured in the tangent space at q ⊕ v.
        const Eigen::MatrixXd fd1 = manifoldCentralDifference(
            model, q,
            [&](const Eigen::VectorXd& qq) {
              return Eigen::VectorXd(difference(model, out, integrate(model, qq, v)));
            },
            h);
        Eigen::MatrixXd fd2(nv, nv);
        for (int j = 0; j < nv; ++j) {
          const Eigen::VectorXd e = h * Eigen::VectorXd::Unit(nv, j);
          fd2.col(j) = (difference(model, out, integrate(model, q, v + e)) -
                        difference(model, out, integrate(model, q, v - e))) /
                       (2 * h);
        }
        EXPECT_LT(relativeError(J1, fd1), 1e-6) << "v = " << v.transpose();
        EXPECT_LT(relativeError(J2, fd2), 1e-6) << "v = " << v.transpose();
      }
      // At v = 0 both are the identity.
      dIntegrate(model, q, Eigen::VectorXd::Zero(nv), J1, ArgumentPosition::First);
      dIntegrate(model, q, Eigen::VectorXd::Zero(nv), J2, ArgumentPosition::Second);
      EXPECT_LT((J1 - Eigen::MatrixXd::Identity(nv, nv)).norm(), 1e-14);
      EXPECT_LT((J2 - Eigen::MatrixXd::Identity(nv, nv)).norm(), 1e-14);
    }
  }
}

TEST(Configuration, DDifferenceMatchesFiniteDifferences) {
  std::mt19937 rng(13);
  const double h = 1e-6;
  for (const RobotCase& rc : manifoldModels()) {
    SCOPED_TRACE(rc.name);
    const Model& model = rc.model;
    const int nv = model.nv;
    Eigen::MatrixXd J0(nv, nv), J1(nv, nv);
    for (int s = 0; s < 2; ++s) {
      const Eigen::VectorXd q0 = randomConfiguration(model, rng);
      for (const Eigen::VectorXd& v : testVelocities(model, rng)) {
        const Eigen::VectorXd q1 = integrate(model, q0, v);
        dDifference(model, q0, q1, J0, ArgumentPosition::First);
        dDifference(model, q0, q1, J1, ArgumentPosition::Second);
        const Eigen::MatrixXd fd0 = manifoldCentralDifference(
            model, q0, [&](const Eigen::VectorXd& qq) { return difference(model, qq, q1); }, h);
        const Eigen::MatrixXd fd1 = manifoldCentralDifference(
            model, q1, [&](const Eigen::VectorXd& qq) { return difference(model, q0, qq); }, h);
        EXPECT_LT(relativeError(J0, fd0), 1e-6) << "v = " << v.transpose();
        EXPECT_LT(relativeError(J1, fd1), 1e-6) << "v = " << v.transpose();
        // d(q1 ⊖ q0)/dq1 inverts d(q0 ⊕ v)/dv.
        Eigen::MatrixXd Jint(nv, nv);
        dIntegrate(model, q0, v, Jint, ArgumentPosition::Second);
        EXPECT_LT((J1 * Jint - Eigen::MatrixXd::Identity(nv, nv)).norm(), 1e-9);
      }
      dDifference(model, q0, q0, J0, ArgumentPosition::First);
      dDifference(model, q0, q0, J1, ArgumentPosition::Second);
      EXPECT_LT((J0 + Eigen::MatrixXd::Identity(nv, nv)).norm(), 1e-14);
      EXPECT_LT((J1 - Eigen::MatrixXd::Identity(nv, nv)).norm(), 1e-14);
    }
  }
}

// Every finite limit is respected; a quaternion is unit; otherwise the documented default ranges.
void expectWithinLimits(const Model& model, const Eigen::VectorXd& q) {
  ASSERT_EQ(q.size(), model.nq);
  EXPECT_TRUE(isNormalized(model, q, 1e-12));
  for (int i = 1; i < model.njoints(); ++i) {
    const Joint& j = model.joints[i];
    const int nlin = j.type == JointType::FreeFlyer ? 3 : 1;  // quaternion checked above
    for (int k = j.idx_q; k < j.idx_q + nlin; ++k) {
      double lo = model.lowerPositionLimit[k], hi = model.upperPositionLimit[k];
      if (!std::isfinite(lo) || !std::isfinite(hi)) {
        hi = j.type == JointType::Revolute ? kPi : 1.0;
        lo = -hi;
      }
      EXPECT_GE(q[k], lo) << j.name;
      EXPECT_LE(q[k], hi) << j.name;
    }
  }
}

TEST(Configuration, NeutralAndRandomConfigurationRespectLimits) {
  std::mt19937 rng(14);
  for (const RobotCase& rc : manifoldModels()) {
    SCOPED_TRACE(rc.name);
    const Model& model = rc.model;
    const Eigen::VectorXd q0 = neutral(model);
    expectWithinLimits(model, q0);
    if (model.hasFreeFlyer()) {
      EXPECT_EQ(q0.head<7>(), (Eigen::Matrix<double, 7, 1>() << 0, 0, 0, 0, 0, 0, 1).finished());
    }
    EXPECT_EQ(q0.tail(model.nq - (model.hasFreeFlyer() ? 7 : 0)).norm(), 0.0);
    Eigen::VectorXd previous = q0;
    for (int s = 0; s < 100; ++s) {
      const Eigen::VectorXd q = randomConfiguration(model, rng);
      expectWithinLimits(model, q);
      EXPECT_GT((q - previous).norm(), 0.0);  // actually random
      previous = q;
    }
  }
}

TEST(Configuration, RandomConfigurationUsesLimitsThatExcludeZero) {
  Model model;
  const int ff = model.addJoint(0, JointType::FreeFlyer, SE3::Identity(), "root_joint");
  const int r =
      model.addJoint(ff, JointType::Revolute, SE3::Identity(), "r", Eigen::Vector3d::UnitX());
  const int p =
      model.addJoint(r, JointType::Prismatic, SE3::Identity(), "p", Eigen::Vector3d(1, 2, 3));
  const int c =
      model.addJoint(p, JointType::Revolute, SE3::Identity(), "c", Eigen::Vector3d(0, 1, 1));
  const int u = model.addJoint(c, JointType::Prismatic, SE3::Identity(), "u");
  model.setJointLimits(r, 0.5, 0.7, 1, 1);
  model.setJointLimits(p, 1.0, 2.0, 1, 1);
  model.lowerPositionLimit[0] = 2.0;  // base x in [2, 3]; y, z default to [-1, 1]
  model.upperPositionLimit[0] = 3.0;
  EXPECT_EQ(model.joints[u].idx_q, 10);
  std::mt19937 rng(15);
  Eigen::Vector4d lo = Eigen::Vector4d::Constant(1e9), hi = -lo;
  Eigen::Matrix3d mean_rotation = Eigen::Matrix3d::Zero();
  const int n = 4000;
  for (int s = 0; s < n; ++s) {
    const Eigen::VectorXd q = randomConfiguration(model, rng);
    expectWithinLimits(model, q);
    EXPECT_GE(q[0], 2.0);
    EXPECT_LE(q[0], 3.0);
    const Eigen::Vector4d x(q[7], q[8], q[9], q[10]);  // r, p, continuous c, unlimited u
    lo = lo.cwiseMin(x);
    hi = hi.cwiseMax(x);
    mean_rotation += Eigen::Quaterniond(q[6], q[3], q[4], q[5]).toRotationMatrix() / n;
  }
  // The samples cover their intervals (uniform, not a constant or a sub-range).
  EXPECT_LT((lo - Eigen::Vector4d(0.5, 1.0, -kPi, -1.0)).norm(), 0.02);
  EXPECT_LT((hi - Eigen::Vector4d(0.7, 2.0, kPi, 1.0)).norm(), 0.02);
  // Uniform rotations have zero mean rotation matrix (each entry has standard deviation ~0.009).
  EXPECT_LT(mean_rotation.cwiseAbs().maxCoeff(), 0.05);
}

TEST(Configuration, WrongSizesThrow) {
  for (const RobotCase& rc : standardRobots()) {
    SCOPED_TRACE(rc.name);
    const Model& model = rc.model;
    const int nq = model.nq, nv = model.nv;
    const Eigen::VectorXd q = neutral(model), v = Eigen::VectorXd::Zero(nv);
    const Eigen::VectorXd q_bad = Eigen::VectorXd::Zero(nq + 1),
                          v_bad = Eigen::VectorXd::Zero(nv - 1);
    Eigen::VectorXd qout(nq), qout_bad(nq - 1), dv(nv), dv_bad(nv + 1);
    Eigen::MatrixXd J(nv, nv), J_rows(nv + 1, nv), J_cols(nv, nv - 1);

    EXPECT_THROW(integrate(model, q_bad, v, qout), std::invalid_argument);
    EXPECT_THROW(integrate(model, q, v_bad, qout), std::invalid_argument);
    EXPECT_THROW(integrate(model, q, v, qout_bad), std::invalid_argument);
    if (model.hasFreeFlyer()) {  // q passed as v and v as q: nq != nv
      EXPECT_THROW(integrate(model, q, q), std::invalid_argument);
      EXPECT_THROW(difference(model, v, q), std::invalid_argument);
    }
    EXPECT_THROW(difference(model, q_bad, q, dv), std::invalid_argument);
    EXPECT_THROW(difference(model, q, q_bad, dv), std::invalid_argument);
    EXPECT_THROW(difference(model, q, q, dv_bad), std::invalid_argument);
    for (ArgumentPosition arg : {ArgumentPosition::First, ArgumentPosition::Second}) {
      EXPECT_THROW(dIntegrate(model, q_bad, v, J, arg), std::invalid_argument);
      EXPECT_THROW(dIntegrate(model, q, v_bad, J, arg), std::invalid_argument);
      EXPECT_THROW(dIntegrate(model, q, v, J_rows, arg), std::invalid_argument);
      EXPECT_THROW(dIntegrate(model, q, v, J_cols, arg), std::invalid_argument);
      EXPECT_THROW(dDifference(model, q_bad, q, J, arg), std::invalid_argument);
      EXPECT_THROW(dDifference(model, q, q_bad, J, arg), std::invalid_argument);
      EXPECT_THROW(dDifference(model, q, q, J_rows, arg), std::invalid_argument);
      EXPECT_THROW(dDifference(model, q, q, J_cols, arg), std::invalid_argument);
    }
    EXPECT_THROW(normalize(model, qout_bad), std::invalid_argument);
    EXPECT_FALSE(isNormalized(model, q_bad));
    // Correct sizes do not throw.
    EXPECT_NO_THROW(integrate(model, q, v, qout));
    EXPECT_NO_THROW(difference(model, q, q, dv));
    EXPECT_NO_THROW(dIntegrate(model, q, v, J, ArgumentPosition::First));
    EXPECT_NO_THROW(dDifference(model, q, q, J, ArgumentPosition::Second));
  }
}

TEST(Configuration, NormalizeRestoresUnitQuaternion) {
  std::mt19937 rng(16);
  for (const RobotCase& rc : standardRobots()) {
    if (!rc.model.hasFreeFlyer()) continue;
    SCOPED_TRACE(rc.name);
    Eigen::VectorXd q = randomConfiguration(rc.model, rng);
    const Eigen::VectorXd ref = q;
    q.segment<4>(3) *= 1.7;
    EXPECT_FALSE(isNormalized(rc.model, q));
    normalize(rc.model, q);
    EXPECT_TRUE(isNormalized(rc.model, q, 1e-15));
    EXPECT_LT((q - ref).norm(), 1e-15);
  }
}

}  // namespace test_lie_group
}  // namespace stride
