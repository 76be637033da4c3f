#pragma once
// The robot as it really is, when it differs from the description the controller plans with
// (sim/README.md, "Model mismatch"): the mock robot integrates a copy of the robot with other
// masses, a payload, a shifted centre of mass and other torque limits; the controller's model and
// the robot's own low-level loop (hold PD, stand-down) keep the nominal description.

#include <string>
#include <utility>
#include <vector>

#include "config/robot_config.hpp"

namespace stride::sim {

struct PlantOptions {
  // (body, factor): the mass and inertia of the joint that carries the body (a link name; the
  // links fixed to it scale with it) times the factor; "base": the free-flyer's body; an empty
  // body: every moving body.
  std::vector<std::pair<std::string, double>> mass_scale;
  // A point mass rigidly on the base (fixed-base robots: on the last joint), at this offset from
  // its frame's origin, in its axes [kg, m].
  double payload = 0.0;
  Eigen::Vector3d payload_at = Eigen::Vector3d::Zero();
  // The base's centre of mass moved by this much in its axes (its mass and its rotational inertia
  // about the centre of mass kept) [m].
  Eigen::Vector3d com_offset = Eigen::Vector3d::Zero();
  // Every joint's effort limit times this: motors weaker (< 1) than the description says.
  double torque_limit_scale = 1.0;

  bool enabled() const;
};

// "BODY:F" or "F" (every body); false for anything else, a non-finite or non-positive factor.
bool parseMassScale(const std::string& text, std::pair<std::string, double>& scale);

// The robot as the mock robot integrates it. Throws std::invalid_argument for a body the robot
// does not have, a negative payload or a non-positive torque limit scale.
Robot plantOf(const Robot& robot, const PlantOptions& options);

}  // namespace stride::sim
