#pragma once
// A robot's identity on the wire (robot_model_t.model_hash, carried by every robot_state_t and
// policy_t): what a receiver checks before it reads q, v or a policy index by index. Two robots
// share a hash exactly when their messages mean the same thing at every index and their bodies
// move alike: the same joints (names and types) in the same order, the same contact frames in the
// same order (the phase bits and contact flags), and the same kinematic tree (each joint's parent,
// placement and axis, each contact frame's placement; rounded to 1 mm and 1e-3). ANYmal B and
// ANYmal C name every joint alike and differ there (issue 34). Masses, inertias and limits are not
// part of it: a retuned URDF of the same robot keeps talking to its controller.

#include <cstdint>
#include <string>
#include <vector>

#include "config/robot_config.hpp"

namespace stride {

// 64-bit FNV-1a over "joint name, type" for every joint in model order (the base's free-flyer
// first), then every joint's parent index, placement (translation in mm, rotation in 1e-3, as
// integers in text) and axis, then every contact frame's name, parent joint and placement, each
// string terminated by a NUL byte so that no two lists hash alike by concatenation. Stored as
// int64 (LCM has no unsigned type).
std::int64_t modelHash(const Robot& robot);

// The joints that own coordinates, in wire order, with their types as robot_model_t names them
// (free-flyer, revolute, prismatic).
struct WireJoint {
  std::string name, type;
  int idx_q = 0, idx_v = 0;
};
std::vector<WireJoint> wireJoints(const Model& model);

}  // namespace stride
