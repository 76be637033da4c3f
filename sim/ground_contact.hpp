#pragma once
// Contact geometry of the mock robot: the points of the robot that may touch the ground, a flat
// ground, and the per-step detection of which points are close enough to take part in the contact
// solve. The simulator finds contacts from this geometry, never from the controller's contact plan
// (ARCHITECTURE.md §6).

#include <string>
#include <vector>

#include "config/robot_config.hpp"
#include "solver/multibody/data.hpp"

namespace stride::sim {

// A point rigidly attached to a frame that can touch the ground.
struct ContactPoint {
  std::string name;  // "<frame>" for a point foot, "<frame>/<corner>" for a sole corner
  int frame = 0;     // model frame index
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();  // in the frame's axes, from its origin
  int contact = 0;  // index of the robot contact (Robot::contacts) it belongs to
};

// The candidate points of a robot: a dim-3 contact is its frame origin (the quadruped's foot
// frames sit at the ground-touching point); a dim-6 sole gives its 4 corners (±hx, ±hy in the sole
// frame, from Robot::sole_half_extents). Throws std::invalid_argument for a sole without extents.
std::vector<ContactPoint> contactPointsFromRobot(const Robot& robot);

// Flat ground z = height with normal +z; friction tangents are the world x and y axes.
struct FlatGround {
  double height = 0.0;
  double heightAbove(const Eigen::Vector3d& p) const { return p.z() - height; }
};

// Per-point geometry of one step, written in place (sized once by resize()).
struct ContactGeometry {
  Eigen::Matrix3Xd position;  // world position of each point
  Eigen::VectorXd height;     // signed height above the ground (< 0: penetration)
  // World-axes Jacobian of each point's velocity: rows 3i..3i+2 are point i's x, y, z velocity.
  Eigen::MatrixXd J;

  void resize(int points, int nv);
};

// Positions, heights and point Jacobians of every point, from data.oMi and data.J (run crba or
// computeJointJacobians for the current q first). Only the columns of the dofs supporting a point
// are written: the rest of J must be zero, as resize() leaves it (a point's supporting dofs never
// change). Allocates nothing.
void updateContactGeometry(const Model& model, const Data& data,
                           const std::vector<ContactPoint>& points, const FlatGround& ground,
                           ContactGeometry& geometry);

}  // namespace stride::sim
