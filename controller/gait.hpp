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

// A contact plan from a YAML file (gait.plan_file):
//   cyclic: false
//   phases:
//     - {duration: 1.0, contacts: [L_sole, R_sole]}
//     - {duration: 0.6, contacts: [R_sole]}
// Throws ConfigError naming the file and the phase. The contact names are checked against the
// robot when the controller compiles the plan.
ContactPlan loadContactPlan(const std::string& path);

// The plan the configuration asks for: the file when gait.plan_file is set, else the gait.
ContactPlan makePlan(const GaitConfig& gait, const std::vector<ContactSpec>& contacts);

}  // namespace stride
