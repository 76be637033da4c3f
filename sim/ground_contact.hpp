#pragma once
// Contact geometry of the mock robot: the points of the robot that may touch the terrain, and the
// per-step geometry of their constraints (the support under each point, the faces beside it) that
// the contact solve takes part in. The simulator finds contacts from this geometry, never from the
// controller's contact plan (ARCHITECTURE.md §6).

#include <string>
#include <vector>

#include "config/robot_config.hpp"
#include "solver/multibody/data.hpp"
#include "terrain/terrain.hpp"

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

// The constraints a point may have at once: its support and up to three vertical faces (a foot in
// the inner corner of two risers and a step).
constexpr int kConstraintsPerPoint = 4;

// The per-step geometry, written in place (sized once by resize()): for every point its world
// position and velocity Jacobian, and the terrain's constraints on it (terrain::Terrain::contacts),
// each with its rows of the Jacobian in its own frame [t1 t2 n].
struct ContactGeometry {
  Eigen::Matrix3Xd position;  // world position of each point
  // World-axes Jacobian of each point's velocity: rows 3i..3i+2 are point i's x, y, z velocity.
  Eigen::MatrixXd J;
  // Constraint slot s = kConstraintsPerPoint * i + k of point i: valid for k < count[i]; slot k = 0
  // is the support (always present).
  std::vector<int> count;
  std::vector<terrain::Contact> constraint;
  // Rows 3s..3s+2: the velocity of slot s's point along its t1, t2 and n.
  Eigen::MatrixXd Jc;

  void resize(int points, int nv);
  // The support's signed distance of point i (< 0: penetration).
  double height(int i) const { return constraint[kConstraintsPerPoint * i].distance; }
};

// Positions and point Jacobians of every point, from data.oMi and data.J (run crba or
// computeJointJacobians for the current q first), then the terrain's constraints on each point:
// faces within `margin` plus what the point travels in `h` at velocity v are looked for. Only the
// columns of the dofs supporting a point are written: the rest of J must be zero, as resize()
// leaves it (a point's supporting dofs never change). Allocates nothing.
void updateContactGeometry(const Model& model, const Data& data,
                           const std::vector<ContactPoint>& points, const terrain::Terrain& terrain,
                           const Eigen::VectorXd& v, double margin, double h,
                           ContactGeometry& geometry);

}  // namespace stride::sim
