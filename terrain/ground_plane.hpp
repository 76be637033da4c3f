#pragma once
// The ground the feet feel (issue 31, blind mode): a plane z = a + b x + c y through the feet in
// contact, filtered across updates, as legged robots without perception estimate the terrain.
// Everything here is fixed-size: no allocation, no throw.

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

struct GroundPlaneOptions {
  // [s] of the first-order filter across updates (0: no filtering, each fit taken as it is).
  double time_constant = 0.25;
};

// The fit, filtered: height (at the feet's centroid) and slope each approach the latest fit as
// 1 - exp(-dt / time_constant), whatever the update rate, so the estimate does not jump with each
// step. The first update after construction or reset() takes the fit as it is (a robot standing on
// ground 5 cm off knows it at once); reset(plane) starts from a plane instead.
class GroundPlaneEstimator {
 public:
  // Throws std::invalid_argument for a time constant that is negative or not finite.
  explicit GroundPlaneEstimator(const GroundPlaneOptions& options = {});

  // Forgets the history: the next update takes its fit as it is.
  void reset();
  // Starts from `plane` (filtered from it on the next update).
  void reset(const GroundPlane& plane);
  // One update with the feet in contact now and the time since the previous update (dt <= 0 or
  // non-finite: the estimate holds). Returns the number of feet used; 0 (no foot in contact) holds
  // the estimate.
  int update(const Eigen::Vector3d* feet, int n, double dt);

  const GroundPlane& plane() const { return plane_; }
  // The latest unfiltered fit (with the estimate as its prior).
  const GroundPlane& fit() const { return fit_; }
  double height(double x, double y) const { return plane_.height(x, y); }
  Eigen::Vector3d normal() const { return plane_.normal(); }
  bool initialized() const { return initialized_; }
  const GroundPlaneOptions& options() const { return options_; }

 private:
  GroundPlaneOptions options_;
  GroundPlane plane_, fit_;
  bool initialized_ = false;
};

}  // namespace stride::terrain
