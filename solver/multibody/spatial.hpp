#pragma once
// Spatial algebra (Featherstone, "Rigid Body Dynamics Algorithms", ch. 2), with Stride's
// conventions (ARCHITECTURE.md §3): 6-vectors are [linear; angular]; a motion is the velocity of
// the frame origin and the angular velocity, a force is [force; moment about the origin].
//
// Everything here is small, fixed size and inline: these are the inner loops of every algorithm.

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace stride {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Matrix6Xd = Eigen::Matrix<double, 6, Eigen::Dynamic>;
using Matrix3Xd = Eigen::Matrix<double, 3, Eigen::Dynamic>;
using RowMatrixXd = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// [a]x, the matrix of the cross product a x (.).
inline Eigen::Matrix3d skew(const Eigen::Vector3d& a) {
  Eigen::Matrix3d S;
  S << 0, -a.z(), a.y(), a.z(), 0, -a.x(), -a.y(), a.x(), 0;
  return S;
}

// Motion cross product v x m (the derivative of a motion m moving with velocity v).
inline Vector6d motionCross(const Vector6d& v, const Vector6d& m) {
  Vector6d r;
  const auto nu = v.head<3>(), w = v.tail<3>();
  r.head<3>() = w.cross(m.head<3>()) + nu.cross(m.tail<3>());
  r.tail<3>() = w.cross(m.tail<3>());
  return r;
}

// Force cross product v x* f (the derivative of a force f moving with velocity v).
inline Vector6d forceCross(const Vector6d& v, const Vector6d& f) {
  Vector6d r;
  const auto nu = v.head<3>(), w = v.tail<3>();
  r.head<3>() = w.cross(f.head<3>());
  r.tail<3>() = w.cross(f.tail<3>()) + nu.cross(f.head<3>());
  return r;
}

// A rigid placement (rotation R, translation p): maps coordinates in the child frame to the
// parent frame, x_parent = R x_child + p. Named like Featherstone/Pinocchio: liMi, oMi, oMf.
struct SE3 {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d p = Eigen::Vector3d::Zero();

  SE3() = default;
  SE3(const Eigen::Matrix3d& rotation, const Eigen::Vector3d& translation)
      : R(rotation), p(translation) {}
  static SE3 Identity() { return SE3(); }

  SE3 operator*(const SE3& m) const { return SE3(R * m.R, p + R * m.p); }
  SE3 inverse() const { return SE3(R.transpose(), -(R.transpose() * p)); }
  // this^-1 * m, without forming the inverse.
  SE3 actInv(const SE3& m) const { return SE3(R.transpose() * m.R, R.transpose() * (m.p - p)); }

  // Motion from the child frame to the parent frame: [R nu + p x R w; R w].
  Vector6d act(const Vector6d& m) const {
    Vector6d r;
    r.tail<3>().noalias() = R * m.tail<3>();
    r.head<3>().noalias() = R * m.head<3>();
    r.head<3>() += p.cross(r.tail<3>());
    return r;
  }
  // Motion from the parent frame to the child frame: [R^T (nu - p x w); R^T w].
  Vector6d actInv(const Vector6d& m) const {
    Vector6d r;
    r.head<3>().noalias() = R.transpose() * (m.head<3>() - p.cross(m.tail<3>()));
    r.tail<3>().noalias() = R.transpose() * m.tail<3>();
    return r;
  }
  // Force from the child frame to the parent frame: [R f; R n + p x R f].
  Vector6d actForce(const Vector6d& f) const {
    Vector6d r;
    r.head<3>().noalias() = R * f.head<3>();
    r.tail<3>().noalias() = R * f.tail<3>();
    r.tail<3>() += p.cross(r.head<3>());
    return r;
  }
  // Force from the parent frame to the child frame: [R^T f; R^T (n - p x f)].
  Vector6d actInvForce(const Vector6d& f) const {
    Vector6d r;
    r.head<3>().noalias() = R.transpose() * f.head<3>();
    r.tail<3>().noalias() = R.transpose() * (f.tail<3>() - p.cross(f.head<3>()));
    return r;
  }
  // Apply act() to each column of a 6 x n block of motions.
  template <typename In, typename Out>
  void actColumns(const Eigen::MatrixBase<In>& in, const Eigen::MatrixBase<Out>& out_) const {
    Eigen::MatrixBase<Out>& out = const_cast<Eigen::MatrixBase<Out>&>(out_);
    for (Eigen::Index k = 0; k < in.cols(); ++k) {
      out.template block<3, 1>(3, k).noalias() = R * in.template block<3, 1>(3, k);
      out.template block<3, 1>(0, k).noalias() = R * in.template block<3, 1>(0, k);
      out.template block<3, 1>(0, k) += p.cross(Eigen::Vector3d(out.template block<3, 1>(3, k)));
    }
  }
  // The 6x6 matrix of act() on motions: [R, [p]x R; 0, R].
  Matrix6d toActionMatrix() const {
    Matrix6d X;
    X.topLeftCorner<3, 3>() = R;
    X.topRightCorner<3, 3>().noalias() = skew(p) * R;
    X.bottomLeftCorner<3, 3>().setZero();
    X.bottomRightCorner<3, 3>() = R;
    return X;
  }
  bool isApprox(const SE3& m, double prec = 1e-12) const {
    return R.isApprox(m.R, prec) && p.isApprox(m.p, prec);
  }
};

// Spatial inertia of a body about the origin of the frame it is expressed in, stored as mass m,
// first moment h = m c (c: centre of mass) and rotational inertia I about the origin. In this form
// inertias expressed in the same frame simply add, which the composite-inertia sweeps rely on.
//   I * [nu; w] = [m nu - h x w; I w + h x nu]
//
// Like Eigen's fixed-size types, a default-constructed Inertia is uninitialized (the sweeps build
// one per joint and overwrite it at once); use Inertia::Zero() for an empty body.
struct Inertia {
  double m;
  Eigen::Vector3d h;
  Eigen::Matrix3d I;

  static Inertia Zero() {
    Inertia Y;
    Y.m = 0.0;
    Y.h.setZero();
    Y.I.setZero();
    return Y;
  }
  // From mass, centre of mass c and rotational inertia about the centre of mass (in this frame).
  static Inertia FromMassComInertia(double mass, const Eigen::Vector3d& c,
                                    const Eigen::Matrix3d& inertia_about_com) {
    Inertia Y;
    Y.m = mass;
    Y.h = mass * c;
    // Parallel axis theorem: I_o = I_c + m [c]x^T [c]x = I_c + m (|c|^2 Id - c c^T).
    Y.I = inertia_about_com +
          mass * (c.squaredNorm() * Eigen::Matrix3d::Identity() - c * c.transpose());
    return Y;
  }

  Eigen::Vector3d com() const { return m > 0 ? Eigen::Vector3d(h / m) : Eigen::Vector3d::Zero(); }
  // Rotational inertia about the centre of mass.
  Eigen::Matrix3d inertiaAboutCom() const {
    if (m <= 0) return I;
    const Eigen::Vector3d c = h / m;
    return I - m * (c.squaredNorm() * Eigen::Matrix3d::Identity() - c * c.transpose());
  }

  Inertia& operator+=(const Inertia& o) {
    m += o.m;
    h += o.h;
    I += o.I;
    return *this;
  }
  Inertia operator+(const Inertia& o) const {
    Inertia r = *this;
    r += o;
    return r;
  }

  Vector6d operator*(const Vector6d& v) const {
    Vector6d f;
    const auto nu = v.head<3>(), w = v.tail<3>();
    f.head<3>() = m * nu - h.cross(w);
    f.tail<3>().noalias() = I * w;
    f.tail<3>() += h.cross(nu);
    return f;
  }
  // Apply to each column of a 6 x n block.
  template <typename In, typename Out>
  void mulColumns(const Eigen::MatrixBase<In>& in, const Eigen::MatrixBase<Out>& out_) const {
    Eigen::MatrixBase<Out>& out = const_cast<Eigen::MatrixBase<Out>&>(out_);
    for (Eigen::Index k = 0; k < in.cols(); ++k) out.col(k) = (*this) * Vector6d(in.col(k));
  }

  // The same body expressed in the parent frame of the placement M (child -> parent).
  // h' = R h + m p;  I' = R I R^T - ([Rh]x[p]x + [p]x[Rh]x + m [p]x^2), and with
  // [a]x[b]x = b a^T - (a.b) Id the correction is  2 (h'.p) Id + m |p|^2 Id - p h'^T - h' p^T - m p
  // p^T. Written entry by entry on the 6 independent entries: every composite-inertia sweep runs it
  // once per joint, and the generic 3x3 products cost half as much again.
  Inertia transformedBy(const SE3& M) const {
    const Eigen::Matrix3d& R = M.R;
    const Eigen::Vector3d& p = M.p;
    Inertia r;
    r.m = m;
    const Eigen::Vector3d hr = R * h;
    r.h = hr + m * p;
    const Eigen::Matrix3d T = R * I;
    const double d = 2.0 * hr.dot(p) + m * p.squaredNorm();
    for (int a = 0; a < 3; ++a) {
      r.I(a, a) = T.row(a).dot(R.row(a)) - 2.0 * p[a] * hr[a] - m * p[a] * p[a] + d;
      for (int b = a + 1; b < 3; ++b)
        r.I(a, b) = r.I(b, a) =
            T.row(a).dot(R.row(b)) - p[a] * hr[b] - hr[a] * p[b] - m * p[a] * p[b];
    }
    return r;
  }

  // 6x6 matrix [m Id, -[h]x; [h]x, I].
  Matrix6d matrix() const {
    Matrix6d Y;
    Y.topLeftCorner<3, 3>() = m * Eigen::Matrix3d::Identity();
    const Eigen::Matrix3d H = skew(h);
    Y.topRightCorner<3, 3>() = -H;
    Y.bottomLeftCorner<3, 3>() = H;
    Y.bottomRightCorner<3, 3>() = I;
    return Y;
  }
  // Kinetic energy 1/2 v^T I v.
  double kineticEnergy(const Vector6d& v) const { return 0.5 * v.dot((*this) * v); }
};

}  // namespace stride
