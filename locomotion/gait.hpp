#pragma once
// The gaits a commanded robot walks with, as cyclic contact patterns for its ContactTimeline
// (locomotion/contact_timeline.hpp, which switches between them foot by foot). The walking gaits
// start with a phase where every foot is down, so a switch between two of them happens there.
//
//   quadruped (4 contacts, YAML order front-left, front-right, hind-left, hind-right):
//     stand;
//     trot = all feet, the FL-HR pair swings, all feet, the FR-HL pair swings;
//     pace = all feet, the left pair (FL-HL) swings, all feet, the right pair swings;
//     walk = one foot at a time (HL, FL, HR, FR), all feet between swings;
//     and with flights (every foot in the air, issue 45):
//     pronk = all feet, flight;
//     bound = the front pair down, flight, the hind pair down, flight;
//     flying_trot = the FL-HR pair down, flight, the FR-HL pair down, flight;
//   biped (2 contacts, YAML order left, right):
//     stand; walk = double support, the left foot swings, double support, the right swings;
//     hop = both feet down, flight;
//   any other number of contacts: stand.
// A walking gait's phases last `support` (all feet down) and `swing`; a gait with flights has
// `support` for each stance (the feet that are down) and `flight` for each flight.

#include <string>
#include <vector>

#include "config/robot_config.hpp"
#include "locomotion/contact_plan.hpp"

namespace stride {

struct GaitTiming {
  double support = 0.1;  // each all-feet (double support) phase; with flights each stance [s]
  double swing = 0.2;    // each swing phase [s] (walking gaits)
  double flight = 0.15;  // each flight phase [s] (gaits with flights)
};

// Whether a gait has flight phases (its timing is support and flight, not support and swing).
bool hasFlight(const std::string& gait);

// The gaits a robot with these contacts can walk with; "stand" first.
std::vector<std::string> gaitNames(int contacts);

// The cyclic pattern of a gait. Throws ConfigError for a gait the contacts cannot do (e.g. trot
// on two feet) or a timing that is not positive.
ContactPlan makeGaitPattern(const std::string& gait, const GaitTiming& timing,
                            const std::vector<ContactSpec>& contacts);

// A contact plan from a YAML file (gait.plan_file):
//   cyclic: false
//   phases:
//     - {duration: 1.0, contacts: [L_sole, R_sole]}
//     - {duration: 0.6, contacts: [R_sole]}
// Throws ConfigError naming the file and the phase. The contact names are checked against the
// robot when the controller compiles the plan.
ContactPlan loadContactPlan(const std::string& path);

}  // namespace stride
