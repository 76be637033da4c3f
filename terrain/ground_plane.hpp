#pragma once
// The ground the feet feel (issue 31, blind mode): a plane z = a + b x + c y through the feet in
// contact, as legged robots without perception estimate the terrain (the gait generator filters it
// across plans: locomotion/gait_generator.cpp). Fixed-size: no allocation, no throw.

#include <Eigen/Core>

namespace stride::terrain {

struct GroundPlane {
  double a = 0.0, b = 0.0, c = 0.0;  // z = a + b x + c y

  double height(double x, double y) const { return a + b * x + c * y; }
  Eigen::Vector2d gradient() const { return {b, c}; }
  Eigen::Vector3d normal() const { return Eigen::Vector3d(-b, -c, 1.0).normalized(); }
  // The plane through (x, y, z) with the gradient g.
  static GroundPlane through(double x, double y, double z, const Eigen::Vector2d& g) {
    return {z - g.x() * x - g.y() * y, g.x(), g.y()};
  }
};

// The plane through `n` foot positions (non-finite ones skipped), given what is known before:
// - feet spanning a plane (3 or more, not on one line): the least-squares plane;
// - feet on one line (2, or more aligned, like a trot's diagonal pair or a biped's soles): the
//   least-squares line's height and slope along it; across the line the prior's slope is kept
//   (a flat prior: no roll);
// - one foot (or all at one place): its height with the prior's slope (flat prior: level).
// Returns the number of feet used (0: `plane` is the prior, unchanged).
int fitGroundPlane(const Eigen::Vector3d* feet, int n, const GroundPlane& prior,
                   GroundPlane& plane);

}  // namespace stride::terrain
