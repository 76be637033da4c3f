// The mock robot: sim_step/<robot> is one 1 ms Simulator::step of an in-house robot standing on
// the ground (its joints held by a PD, every contact point active), i.e. the physics share of one
// tick of stride-sim at 1 kHz.
// Registered from a static initializer, so that main.cpp needs no change for this file.

#include <benchmark/benchmark.h>

#include <string>

#include "config/robot_config.hpp"
#include "sim/policy.hpp"
#include "sim/simulator.hpp"

namespace stride::bench {
namespace {

const Robot& simRobot(const std::string& name) {
  static const Robot quad =
      loadRobot(std::string(STRIDE_CONFIG_DIR) + "/robots/stride_quad/stride_quad.yaml");
  static const Robot humanoid =
      loadRobot(std::string(STRIDE_CONFIG_DIR) + "/robots/stride_humanoid/stride_humanoid.yaml");
  return name == "stride_quad" ? quad : humanoid;
}

void simStep(benchmark::State& state, const std::string& name, double kp, double kd) {
  const Robot& robot = simRobot(name);
  sim::Simulator sim(robot);
  const sim::HoldPolicy hold(robot.model, robot.default_q, kp, kd, sim.options().dt);
  Eigen::VectorXd tau(sim.nu());
  // Settle on the ground first: the timed steps are resting contact with a warm start, as when
  // standing.
  for (int i = 0; i < 500; ++i) {
    hold.torque(robot.model, sim.q(), sim.v(), tau);
    sim.step(tau);
  }
  for (auto _ : state) {
    hold.torque(robot.model, sim.q(), sim.v(), tau);
    sim.step(tau);
    benchmark::ClobberMemory();
  }
  int in_contact = 0;
  for (const sim::PointContact& c : sim.pointContacts()) in_contact += c.in_contact;
  state.counters["contacts"] = in_contact;
  state.counters["pgs_sweeps"] = sim.counters().last_pgs_iterations;
}

const bool registered = [] {
  benchmark::RegisterBenchmark("sim_step/stride_quad", simStep, "stride_quad", 100.0, 2.0)
      ->Unit(benchmark::kMicrosecond);
  benchmark::RegisterBenchmark("sim_step/stride_humanoid", simStep, "stride_humanoid", 3000.0, 30.0)
      ->Unit(benchmark::kMicrosecond);
  return true;
}();

}  // namespace
}  // namespace stride::bench
