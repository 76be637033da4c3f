#include "terrain/ground_plane.hpp"

#include <Eigen/LU>
#include <cmath>
#include <stdexcept>

namespace stride::terrain {

namespace {
// Feet whose horizontal spread is below this [m^2] stand on one place: height only.
constexpr double kMinSpread = 1e-8;
// Feet whose spread across their principal line is below this fraction (of variances: about 3 %
// of the spread along it) are on one line: the plane across them would amplify their noise.
constexpr double kMinAspect = 1e-3;

struct Moments {
  int n = 0;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  Eigen::Matrix2d sxy = Eigen::Matrix2d::Zero();  // horizontal scatter about the mean
  Eigen::Vector2d sz = Eigen::Vector2d::Zero();   // horizontal x height scatter
};

Moments moments(const Eigen::Vector3d* feet, int n) {
  Moments m;
  for (int i = 0; i < n; ++i)
    if (feet[i].allFinite()) {
      m.mean += feet[i];
      ++m.n;
    }
  if (m.n == 0) return m;
  m.mean /= m.n;
  for (int i = 0; i < n; ++i)
    if (feet[i].allFinite()) {
      const Eigen::Vector3d d = feet[i] - m.mean;
      m.sxy.noalias() += d.head<2>() * d.head<2>().transpose();
      m.sz += d.head<2>() * d.z();
    }
  return m;
}
}  // namespace

int fitGroundPlane(const Eigen::Vector3d* feet, int n, const GroundPlane& prior,
                   GroundPlane& plane) {
  const Moments m = feet ? moments(feet, n) : Moments{};
  if (m.n == 0) {
    plane = prior;
    return 0;
  }
  const double trace = m.sxy.trace(), det = m.sxy.determinant();
  Eigen::Vector2d g = prior.gradient();
  if (m.n >= 3 && trace > kMinSpread && det > kMinAspect * trace * trace) {
    g = m.sxy.inverse() * m.sz;
  } else if (trace > kMinSpread) {
    // The principal direction of the feet: the slope along it is measured, the one across it is
    // the prior's.
    const double theta = 0.5 * std::atan2(2.0 * m.sxy(0, 1), m.sxy(0, 0) - m.sxy(1, 1));
    const Eigen::Vector2d d(std::cos(theta), std::sin(theta));
    const double along = d.dot(m.sz) / d.dot(m.sxy * d);
    g = g - g.dot(d) * d + along * d;
  }
  plane = GroundPlane::through(m.mean.x(), m.mean.y(), m.mean.z(), g);
  return m.n;
}

}  // namespace stride::terrain
