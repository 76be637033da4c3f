#pragma once
// The fall criterion, written once (issue 43): the mock robot's verdict on every physics step
// (SimNode, its summary's `fell`) and the log summary's on every logged state (stride-log-summary,
// tools/log/segments.hpp) are this one test, with the same defaults.
//
// Fallen: the base's height above the terrain under it below `height_fraction` of its height
// above the terrain at the start, or the base tilted more than `max_tilt_deg`. Low over the ground
// under the base, not low in the world: a robot on a lower floor or down a staircase is
// upright.
//
// Header-only, no Stride include: tools/log (which links nothing heavy) uses it without linking
// the mock robot (sim/README.md, "Falls").

#include <algorithm>
#include <cmath>

namespace stride::sim {

struct FallLimits {
  double height_fraction = 0.5;  // of the base's first height above the terrain
  double max_tilt_deg = 60.0;    // [deg]
};

// The base's tilt [rad], the angle between its z axis and the world's, from its quaternion
// (x, y, z, w; normalized first: an estimate is unit only to within the messages' tolerance).
inline double baseTilt(double qx, double qy, double qz, double qw) {
  const double n2 = qx * qx + qy * qy + qz * qz + qw * qw;
  return std::acos(std::clamp(1.0 - 2.0 * (qx * qx + qy * qy) / n2, -1.0, 1.0));
}

// above: the base's height above the terrain under it; first_above: the same at the start;
// tilt: baseTilt [rad].
inline bool fallen(double above, double first_above, double tilt, const FallLimits& limits) {
  return above < limits.height_fraction * first_above || tilt * 180.0 / M_PI > limits.max_tilt_deg;
}

}  // namespace stride::sim
