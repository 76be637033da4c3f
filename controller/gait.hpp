#pragma once
// Gait generator: the contact plan the controller follows unless a planner sends one.
//
//   quadruped (4 contacts, YAML order front-left, front-right, hind-left, hind-right):
//     stand; trot = all feet, the FL-HR pair swings, all feet, the FR-HL pair swings;
//     walk  = one foot at a time (HL, FL, HR, FR), all feet between swings;
//   biped (2 contacts, YAML order left, right):
//     stand; walk = double support, the left foot swings, double support, the right swings.
// The plan stands for gait.stand seconds, repeats the cycle until gait.duration, then stands
// (the last phase is held). It is written out phase by phase (not cyclic) so that standing,
// stepping in place and walking are one plan; the controller's tick only queries it.

#include "controller/controller_config.hpp"
#include "solver/ocp/contact_plan.hpp"

namespace stride {

// Throws ConfigError for a gait the robot's contacts cannot do (e.g. trot on two feet).
ContactPlan makeGaitPlan(const GaitConfig& gait, const std::vector<ContactSpec>& contacts);

}  // namespace stride
