#pragma once
// What a program is about to run, in the order the wire carries it: a user wiring a robot (or
// reading a log) needs to know which index of q, v and u is which joint, and what the YAML and the
// URDF made of limits and posture. Printed by the programs' `--print-model`.

#include <string>

#include "config/robot_config.hpp"

namespace stride {

// Several lines: name and source files; nq, nv, nu, total mass, base height of the default posture;
// the layout of q, v and u (index ranges per joint); the contact frames and their dimension; each
// actuated joint's torque limit and default position.
std::string describeModel(const Robot& robot);

}  // namespace stride
