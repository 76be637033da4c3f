// The mock robot: sim_step/<robot> is one 1 ms Simulator::step of an in-house robot standing on
// the ground (its joints held by a PD, every contact point active), i.e. the physics share of one
// tick of stride-sim at 1 kHz.
// sim_step/stride_quad_rough: the same on ±3 cm rough ground (every foot on a cell, walls near):
// what the terrain's contact queries add. terrain_map/<terrain>: one 100 x 100 elevation map of
// 2 cm cells (stride-sim's default, 10 per second) sampled from a shipped terrain.
// Registered from a static initializer, so that main.cpp needs no change for this file.

#include <benchmark/benchmark.h>

#include <string>

#include "config/robot_config.hpp"
#include "sim/policy.hpp"
#include "sim/sim_node.hpp"
#include "sim/simulator.hpp"
#include "terrain/elevation_map.hpp"
#include "terrain/terrain_file.hpp"

namespace stride::bench {
namespace {

const Robot& simRobot(const std::string& name) {
  static const Robot quad =
      loadRobot(std::string(STRIDE_CONFIG_DIR) + "/robots/stride_quad/stride_quad.yaml");
  static const Robot humanoid =
      loadRobot(std::string(STRIDE_CONFIG_DIR) + "/robots/stride_humanoid/stride_humanoid.yaml");
  return name == "stride_quad" ? quad : humanoid;
}

void simStep(benchmark::State& state, const std::string& name, double kp, double kd, bool rough) {
  const Robot& robot = simRobot(name);
  sim::SimOptions options;
  if (rough) {
    terrain::TerrainSpec spec;
    spec.rough.push_back({{-1.0, -1.0}, {1.0, 1.0}, 0.1, 0.03, 1});
    options.terrain = std::make_shared<const terrain::Terrain>(spec);
  }
  sim::Simulator sim(robot, options);
  sim.reset(sim::startingPose(robot, sim.terrain()), Eigen::VectorXd::Zero(robot.model.nv));
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

void terrainMap(benchmark::State& state, const std::string& name, double x) {
  const terrain::Terrain world(
      terrain::loadTerrainFile(terrain::findTerrainFile(name, {std::string(STRIDE_CONFIG_DIR)})));
  terrain::ElevationMap map;
  map.resolution = 0.02;
  map.resize(100, 100);
  for (auto _ : state) {
    terrain::sampleTerrain(world, x, 0.0, map);
    benchmark::DoNotOptimize(map.height.data());
  }
}

const bool registered = [] {
  benchmark::RegisterBenchmark("sim_step/stride_quad", simStep, "stride_quad", 100.0, 2.0, false)
      ->Unit(benchmark::kMicrosecond);
  benchmark::RegisterBenchmark("sim_step/stride_quad_rough", simStep, "stride_quad", 100.0, 2.0,
                               true)
      ->Unit(benchmark::kMicrosecond);
  benchmark::RegisterBenchmark("sim_step/stride_humanoid", simStep, "stride_humanoid", 3000.0, 30.0,
                               false)
      ->Unit(benchmark::kMicrosecond);
  benchmark::RegisterBenchmark("terrain_map/stairs_anymal_c", terrainMap, "stairs_anymal_c", 2.5)
      ->Unit(benchmark::kMicrosecond);
  benchmark::RegisterBenchmark("terrain_map/rough_anymal_c", terrainMap, "rough_anymal_c", 3.0)
      ->Unit(benchmark::kMicrosecond);
  return true;
}();

}  // namespace
}  // namespace stride::bench
