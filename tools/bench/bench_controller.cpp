// controller_tick/<robot>: one stride-mpc tick (newest state in → policy and status encoded and
// handed to the publisher), measured inside the closed loop with the mock robot in lock-step over
// an in-process bus, so every tick sees a real state of a robot that stands, then trots or walks.
// Only the tick is timed (manual time); the simulation between ticks is not.
#include <benchmark/benchmark.h>

#include <chrono>
#include <lcm/lcm-cpp.hpp>

#include "controller/mpc_node.hpp"
#include "sim/sim_node.hpp"

namespace stride::bench {
namespace {

void controllerTick(benchmark::State& state, const char* robot, double warmup) {
  ControllerConfig config =
      loadControllerConfig(std::string(STRIDE_CONFIG_DIR) + "/controller/" + robot + ".yaml");
  config.gait.stand = 0.5;  // into the gait quickly: the hard ticks are the stepping ones
  config.gait.step_after = 1.0;
  config.locomotion.step_after = 1.0;
  lcm::LCM lcm("memq://");
  LcmPublisher publisher(lcm);
  MpcNode mpc(config, publisher, TimeSource::Stamps);
  mpc.subscribe(lcm);
  const Robot& r = mpc.mpc().robot();
  sim::SimNodeOptions o;
  o.state_rate_hz = config.rate_hz;
  sim::SimNode sim(r, sim::SimOptions{}, o, publisher);
  sim.subscribe(lcm);
  sim.reset(r.default_q, Eigen::VectorXd::Zero(r.model.nv));
  auto one = [&](bool timed) {
    sim.publishState();
    while (lcm.handleTimeout(0) > 0) {
    }
    const auto t0 = std::chrono::steady_clock::now();
    mpc.tick(Mpc::Clock::time_point::max());
    const auto t1 = std::chrono::steady_clock::now();
    while (lcm.handleTimeout(0) > 0) {
    }
    if (!sim.advance(sim.stepsPerState()))  // fell: start again, the timing is what matters here
      sim.reset(r.default_q, Eigen::VectorXd::Zero(r.model.nv));
    if (timed) state.SetIterationTime(std::chrono::duration<double>(t1 - t0).count());
  };
  while (sim.simulator().time() < warmup) one(false);
  for (auto _ : state) one(true);
  state.counters["fell"] = sim.stats().fell;
}

// The parts of one tick's FDDP iteration on the problem the controller has 3 s into the gait
// (stepping): derivatives of all knots, the backward pass, one rollout of the line search.
void tickParts(benchmark::State& state, const char* robot, int part) {
  ControllerConfig config =
      loadControllerConfig(std::string(STRIDE_CONFIG_DIR) + "/controller/" + robot + ".yaml");
  config.gait.stand = 0.5;
  config.gait.step_after = 1.0;
  config.locomotion.step_after = 1.0;
  lcm::LCM lcm("memq://");
  LcmPublisher publisher(lcm);
  MpcNode mpc(config, publisher, TimeSource::Stamps);
  mpc.subscribe(lcm);
  const Robot& r = mpc.mpc().robot();
  sim::SimNodeOptions o;
  o.state_rate_hz = config.rate_hz;
  sim::SimNode sim(r, sim::SimOptions{}, o, publisher);
  sim.subscribe(lcm);
  sim.reset(r.default_q, Eigen::VectorXd::Zero(r.model.nv));
  while (sim.simulator().time() < 3.0) {
    sim.publishState();
    while (lcm.handleTimeout(0) > 0) {
    }
    mpc.tick(Mpc::Clock::time_point::max());
    while (lcm.handleTimeout(0) > 0) {
    }
    if (!sim.advance(sim.stepsPerState())) {
      state.SkipWithError("the robot fell during the warm-up");
      return;
    }
  }
  Solver& solver = *mpc.mpc().solver();
  solver.computeDerivatives();
  solver.backwardPass();
  for (auto _ : state) {
    if (part == 0) benchmark::DoNotOptimize(solver.computeDerivatives());
    if (part == 1) benchmark::DoNotOptimize(solver.backwardPass());
    if (part == 2) benchmark::DoNotOptimize(solver.forwardPass(0.5));
  }
}

BENCHMARK_CAPTURE(tickParts, quad_derivatives, "stride_quad", 0)
    ->Name("tick_parts/stride_quad/derivatives")
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(tickParts, quad_backward, "stride_quad", 1)
    ->Name("tick_parts/stride_quad/backward")
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(tickParts, quad_forward, "stride_quad", 2)
    ->Name("tick_parts/stride_quad/forward")
    ->Unit(benchmark::kMillisecond);

BENCHMARK_CAPTURE(controllerTick, stride_quad, "stride_quad", 1.5)
    ->Name("controller_tick/stride_quad")
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond)
    ->Iterations(400);
BENCHMARK_CAPTURE(controllerTick, stride_humanoid, "stride_humanoid", 1.5)
    ->Name("controller_tick/stride_humanoid")
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond)
    ->Iterations(100);

}  // namespace
}  // namespace stride::bench
