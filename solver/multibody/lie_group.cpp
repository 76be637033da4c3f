#include "solver/multibody/lie_group.hpp"

#include <cmath>

namespace stride {

namespace {
// Below this angle the closed forms lose digits to cancellation (e.g. (1 - cos t)/t^2 loses
// eps/t^2); Taylor series to t^8 are exact to ~1e-16 up to here, and the closed forms above it.
constexpr double kSmallAngle = 0.1;

// Coefficients of SO(3) series, in theta^2 where possible.
// A = sin t / t, B = (1 - cos t)/t^2, C = (t - sin t)/t^3.
struct SO3Coeffs {
  double A, B, C;
  explicit SO3Coeffs(double t) {
    const double t2 = t * t;
    if (t < kSmallAngle) {
      A = 1.0 - t2 / 6.0 * (1.0 - t2 / 20.0 * (1.0 - t2 / 42.0 * (1.0 - t2 / 72.0)));
      B = 0.5 - t2 / 24.0 * (1.0 - t2 / 30.0 * (1.0 - t2 / 56.0 * (1.0 - t2 / 90.0)));
      C = 1.0 / 6.0 - t2 / 120.0 * (1.0 - t2 / 42.0 * (1.0 - t2 / 72.0 * (1.0 - t2 / 110.0)));
    } else {
      const double s = std::sin(t), c = std::cos(t);
      A = s / t;
      B = (1.0 - c) / t2;
      C = (t - s) / (t2 * t);
    }
  }
};

// 1/t^2 - (1 + cos t) / (2 t sin t), the W^2 coefficient of the inverse SO(3) Jacobians.
double inverseJacobianCoeff(double t) {
  const double t2 = t * t;
  if (t < kSmallAngle)
    return 1.0 / 12.0 + t2 / 720.0 + t2 * t2 / 30240.0 + t2 * t2 * t2 / 1209600.0;
  return 1.0 / t2 - (1.0 + std::cos(t)) / (2.0 * t * std::sin(t));
}

// Left SO(3) Jacobian and its inverse.
Eigen::Matrix3d Jleft3(const Eigen::Vector3d& w) {
  const SO3Coeffs k(w.norm());
  const Eigen::Matrix3d W = skew(w);
  return Eigen::Matrix3d::Identity() + k.B * W + k.C * W * W;
}
Eigen::Matrix3d JleftInv3(const Eigen::Vector3d& w) {
  const Eigen::Matrix3d W = skew(w);
  return Eigen::Matrix3d::Identity() - 0.5 * W + inverseJacobianCoeff(w.norm()) * W * W;
}

// Barfoot's Q(rho, phi), the coupling block of the left SE(3) Jacobian [[Jl, Q], [0, Jl]].
Eigen::Matrix3d barfootQ(const Eigen::Vector3d& rho, const Eigen::Vector3d& phi) {
  const double t = phi.norm(), t2 = t * t;
  double a, b, c;
  if (t < kSmallAngle) {
    const double t4 = t2 * t2, t6 = t4 * t2;
    a = 1.0 / 6.0 - t2 / 120.0 + t4 / 5040.0 - t6 / 362880.0;
    b = 1.0 / 24.0 - t2 / 720.0 + t4 / 40320.0 - t6 / 3628800.0;
    c = 1.0 / 120.0 - t2 / 2520.0 + t4 / 120960.0 - t6 / 9979200.0;
  } else {
    const double s = std::sin(t), co = std::cos(t);
    a = (t - s) / (t2 * t);
    b = (t2 + 2.0 * co - 2.0) / (2.0 * t2 * t2);
    c = (2.0 * t - 3.0 * s + t * co) / (2.0 * t2 * t2 * t);
  }
  const Eigen::Matrix3d P = skew(rho), F = skew(phi);
  const Eigen::Matrix3d FP = F * P, PF = P * F, FPF = FP * F, FF = F * F;
  return 0.5 * P + a * (FP + PF + FPF) + b * (FF * P + PF * F - 3.0 * FPF) +
         c * (FPF * F + F * FPF);
}

double uniform(std::mt19937& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}

SE3 freeFlyerPlacement(const double* q) {
  const Eigen::Map<const Eigen::Quaterniond> quat(q + 3);
  return SE3(quat.toRotationMatrix(), Eigen::Map<const Eigen::Vector3d>(q));
}

void checkSizes(const Model& model, long q, long v, const char* fn) {
  if (q != model.nq) throwSizeError(fn, "q", model.nq, q);
  if (v != model.nv) throwSizeError(fn, "v", model.nv, v);
}
}  // namespace

Eigen::Matrix3d exp3(const Eigen::Vector3d& w) {
  const SO3Coeffs k(w.norm());
  const Eigen::Matrix3d W = skew(w);
  return Eigen::Matrix3d::Identity() + k.A * W + k.B * W * W;
}

Eigen::Vector3d log3(const Eigen::Matrix3d& R) {
  // Through the quaternion: accurate near 0 and up to pi, unlike acos of the trace.
  Eigen::Quaterniond quat(R);
  if (quat.w() < 0) quat.coeffs() = -quat.coeffs();
  const Eigen::Vector3d vec = quat.vec();
  const double s = vec.norm();
  const double t = 2.0 * std::atan2(s, quat.w());
  // t / sin(t/2) = 2 atan(s/w) / s, with its series near zero.
  const double k = s < 1e-8 ? 2.0 / quat.w() * (1.0 - s * s / (3.0 * quat.w() * quat.w())) : t / s;
  return k * vec;
}

Eigen::Matrix3d Jexp3(const Eigen::Vector3d& w) {
  const SO3Coeffs k(w.norm());
  const Eigen::Matrix3d W = skew(w);
  return Eigen::Matrix3d::Identity() - k.B * W + k.C * W * W;
}

Eigen::Matrix3d Jlog3(const Eigen::Matrix3d& R) {
  const Eigen::Vector3d w = log3(R);
  const Eigen::Matrix3d W = skew(w);
  return Eigen::Matrix3d::Identity() + 0.5 * W + inverseJacobianCoeff(w.norm()) * W * W;
}

SE3 exp6(const Vector6d& xi) {
  const Eigen::Vector3d w = xi.tail<3>();
  return SE3(exp3(w), Jleft3(w) * xi.head<3>());
}

Vector6d log6(const SE3& M) {
  Vector6d xi;
  xi.tail<3>() = log3(M.R);
  xi.head<3>() = JleftInv3(xi.tail<3>()) * M.p;
  return xi;
}

Matrix6d Jexp6(const Vector6d& xi) {
  // Right Jacobian = left Jacobian at -xi.
  Matrix6d J;
  const Eigen::Matrix3d Jr = Jexp3(xi.tail<3>());
  J.topLeftCorner<3, 3>() = Jr;
  J.topRightCorner<3, 3>() = barfootQ(-xi.head<3>(), -xi.tail<3>());
  J.bottomLeftCorner<3, 3>().setZero();
  J.bottomRightCorner<3, 3>() = Jr;
  return J;
}

Matrix6d Jlog6(const SE3& M) {
  const Vector6d xi = log6(M);
  const Eigen::Vector3d w = xi.tail<3>();
  const Eigen::Matrix3d W = skew(w);
  const Eigen::Matrix3d Jrinv =
      Eigen::Matrix3d::Identity() + 0.5 * W + inverseJacobianCoeff(w.norm()) * W * W;
  const Eigen::Matrix3d Q = barfootQ(-xi.head<3>(), -w);
  Matrix6d J;
  J.topLeftCorner<3, 3>() = Jrinv;
  J.topRightCorner<3, 3>() = -Jrinv * Q * Jrinv;
  J.bottomLeftCorner<3, 3>().setZero();
  J.bottomRightCorner<3, 3>() = Jrinv;
  return J;
}

Eigen::VectorXd neutral(const Model& model) {
  Eigen::VectorXd q = Eigen::VectorXd::Zero(model.nq);
  if (model.hasFreeFlyer()) q[6] = 1.0;
  return q;
}

Eigen::VectorXd randomConfiguration(const Model& model, std::mt19937& rng) {
  Eigen::VectorXd q(model.nq);
  for (int i = 1; i < model.njoints(); ++i) {
    const Joint& j = model.joints[i];
    if (j.type == JointType::FreeFlyer) {
      for (int k = 0; k < 3; ++k) {
        double lo = model.lowerPositionLimit[j.idx_q + k],
               hi = model.upperPositionLimit[j.idx_q + k];
        if (!std::isfinite(lo) || !std::isfinite(hi)) lo = -1.0, hi = 1.0;
        q[j.idx_q + k] = uniform(rng, lo, hi);
      }
      // Shoemake's uniform random rotation.
      const double u1 = uniform(rng, 0, 1), u2 = uniform(rng, 0, 2 * M_PI),
                   u3 = uniform(rng, 0, 2 * M_PI);
      const double a = std::sqrt(1 - u1), b = std::sqrt(u1);
      q.segment<4>(j.idx_q + 3) << a * std::sin(u2), a * std::cos(u2), b * std::sin(u3),
          b * std::cos(u3);
    } else {
      double lo = model.lowerPositionLimit[j.idx_q], hi = model.upperPositionLimit[j.idx_q];
      if (!std::isfinite(lo) || !std::isfinite(hi)) {
        lo = j.type == JointType::Revolute ? -M_PI : -1.0;
        hi = -lo;
      }
      q[j.idx_q] = uniform(rng, lo, hi);
    }
  }
  return q;
}

void normalize(const Model& model, Eigen::Ref<Eigen::VectorXd> q) {
  model.checkConfiguration(q, "normalize");
  if (model.hasFreeFlyer()) q.segment<4>(3).normalize();
}

bool isNormalized(const Model& model, const Eigen::Ref<const Eigen::VectorXd>& q,
                  double tolerance) {
  if (q.size() != model.nq) return false;
  return !model.hasFreeFlyer() || std::abs(q.segment<4>(3).norm() - 1.0) <= tolerance;
}

void integrate(const Model& model, const Eigen::Ref<const Eigen::VectorXd>& q,
               const Eigen::Ref<const Eigen::VectorXd>& v, Eigen::Ref<Eigen::VectorXd> qout) {
  checkSizes(model, q.size(), v.size(), "integrate");
  if (qout.size() != model.nq) throwSizeError("integrate", "qout", model.nq, qout.size());
  int start = 0;
  if (model.hasFreeFlyer()) {
    const SE3 M = freeFlyerPlacement(q.data()) * exp6(v.head<6>());
    Eigen::Quaterniond quat(M.R);
    // Stay in q's hemisphere so that small steps change q smoothly.
    if (quat.coeffs().dot(q.segment<4>(3)) < 0) quat.coeffs() = -quat.coeffs();
    qout.head<3>() = M.p;
    qout.segment<4>(3) = quat.coeffs().normalized();
    start = 1;
  }
  const int off_q = start ? 7 : 0, off_v = start ? 6 : 0;
  qout.tail(model.nq - off_q) = q.tail(model.nq - off_q) + v.tail(model.nv - off_v);
}

Eigen::VectorXd integrate(const Model& model, const Eigen::Ref<const Eigen::VectorXd>& q,
                          const Eigen::Ref<const Eigen::VectorXd>& v) {
  Eigen::VectorXd out(model.nq);
  integrate(model, q, v, out);
  return out;
}

void difference(const Model& model, const Eigen::Ref<const Eigen::VectorXd>& q0,
                const Eigen::Ref<const Eigen::VectorXd>& q1, Eigen::Ref<Eigen::VectorXd> dv) {
  model.checkConfiguration(q0, "difference");
  model.checkConfiguration(q1, "difference");
  if (dv.size() != model.nv) throwSizeError("difference", "dv", model.nv, dv.size());
  int off_q = 0, off_v = 0;
  if (model.hasFreeFlyer()) {
    dv.head<6>() = log6(freeFlyerPlacement(q0.data()).actInv(freeFlyerPlacement(q1.data())));
    off_q = 7;
    off_v = 6;
  }
  dv.tail(model.nv - off_v) = q1.tail(model.nq - off_q) - q0.tail(model.nq - off_q);
}

Eigen::VectorXd difference(const Model& model, const Eigen::Ref<const Eigen::VectorXd>& q0,
                           const Eigen::Ref<const Eigen::VectorXd>& q1) {
  Eigen::VectorXd out(model.nv);
  difference(model, q0, q1, out);
  return out;
}

void dIntegrate(const Model& model, const Eigen::Ref<const Eigen::VectorXd>& q,
                const Eigen::Ref<const Eigen::VectorXd>& v, Eigen::Ref<Eigen::MatrixXd> J,
                ArgumentPosition arg) {
  checkSizes(model, q.size(), v.size(), "dIntegrate");
  if (J.rows() != model.nv || J.cols() != model.nv)
    throwSizeError("dIntegrate", "J (rows)", model.nv, J.rows());
  J.setIdentity();
  if (!model.hasFreeFlyer()) return;
  if (arg == ArgumentPosition::First)
    J.topLeftCorner<6, 6>() = exp6(v.head<6>()).inverse().toActionMatrix();
  else
    J.topLeftCorner<6, 6>() = Jexp6(v.head<6>());
}

void dDifference(const Model& model, const Eigen::Ref<const Eigen::VectorXd>& q0,
                 const Eigen::Ref<const Eigen::VectorXd>& q1, Eigen::Ref<Eigen::MatrixXd> J,
                 ArgumentPosition arg) {
  model.checkConfiguration(q0, "dDifference");
  model.checkConfiguration(q1, "dDifference");
  if (J.rows() != model.nv || J.cols() != model.nv)
    throwSizeError("dDifference", "J (rows)", model.nv, J.rows());
  J.setIdentity();
  if (arg == ArgumentPosition::First) J = -J;
  if (!model.hasFreeFlyer()) return;
  const SE3 delta = freeFlyerPlacement(q0.data()).actInv(freeFlyerPlacement(q1.data()));
  const Matrix6d Jl = Jlog6(delta);
  if (arg == ArgumentPosition::Second)
    J.topLeftCorner<6, 6>() = Jl;
  else
    J.topLeftCorner<6, 6>() = -Jl * delta.inverse().toActionMatrix();
}

}  // namespace stride
