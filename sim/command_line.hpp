#pragma once
// The mock robot's options, shared by stride-sim and stride-drive: the same names, the same
// meaning and the same help in both (sim/README.md, "Sensing", "Actuators", "Model mismatch").

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "sim/sim_node.hpp"

namespace stride::sim {

// What the command line holds until it is checked (finishMockRobotOptions).
struct MockRobotArgs {
  std::vector<std::string> mass_scales;
  std::vector<double> payload, com_offset;
  double noise_v = 0.0;
};

// Adds the sensing, the estimates' way to the controller (--delay, --drop, --seed), the
// actuators, the model mismatch and the ground's friction (--mu) to `app`.
void addMockRobotOptions(CLI::App& app, SimNodeOptions& node, SimOptions& physics,
                         MockRobotArgs& args);
// After parsing: fills what needed checking. False after writing "<program>: ..." to stderr.
bool finishMockRobotOptions(const MockRobotArgs& args, SimNodeOptions& node, const char* program);

// What the mock robot differs in from a perfect one, in a few words ("sensing: latency 3 steps,
// ...; actuators: ...; plant: ..."), empty when nothing: for the programs' first line.
std::string describeMockRobot(const SimNodeOptions& node, const SimOptions& physics);

}  // namespace stride::sim
