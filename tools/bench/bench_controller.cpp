// controller_tick/<robot>: one stride-mpc tick (newest state in → policy and status encoded and
// handed to the publisher), measured inside the closed loop with the mock robot in lock-step over
// an in-process bus, so every tick sees a real state of a robot that stands, then trots or walks.
// Only the tick is timed (manual time): the latency. The preparation that follows it (the
// derivatives and backward pass of the next tick's iteration, Mpc::prepare) is reported as the
// counter prepare_ms; tick + prepare_ms is the controller's work per period. The simulation
// between ticks is not timed. The counter reused is the share of knots whose calcDiff in the
// preparation took the contact solve of the rollout before it (KeptSolve, solver/ocp/README.md).
// period_share and period_share_p99: a period's work (tick + preparation) over the period, median
// and 99th percentile over the iterations (the budget: at most 0.5 and 0.8 on one core); a
// period's work includes the handling of its messages (state, command and, at 10 Hz, an elevation
// map: decoded, checked, its steppability computed).
// controller_tick/anymal_c_stairs: the same on the shipped stairs (config/terrain/
// stairs_anymal_c.yaml) with the mock robot's maps, from 5.5 s of robot time (at the first stair)
// over the 2 s of climbing that follow.
// controller_tick/<robot>_jump/{push,flight,landing} (issue 45): the same, the robot standing and
// jumping 20 cm forward every 1.5 s (the first at 1 s), each benchmark timing only the ticks of its
// phase of the jump (mpc_status_t.jump_state: accepted and pushing, in the air, landed): the
// period's work in every phase of a flight.
// The public robots are read from the package view of ../shared (build/robot_packages); without
// it they are skipped with a message.
// controller_tick/config:NAME and tick_parts/config:NAME/*: the same on any configuration,
// stride-bench --config FILE (main.cpp; NAME is FILE's name without .yaml).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "controller/mpc_node.hpp"
#include "controller/statistics.hpp"
#include "sim/sim_node.hpp"
#include "solver/ocp/knot.hpp"
#include "terrain/terrain_file.hpp"
#include "tools/bench/controller_source.hpp"

namespace stride::bench {
namespace {

// stride-mpc's node and stride-sim's node on one in-process bus, the robot commanded into its gait
// at once, walking forward (the hard ticks are the stepping ones).
struct ClosedLoop {
  // terrain: a name in config/terrain/ (the mock robot publishes its maps), or null: flat ground.
  // jumping: standing, a 20 cm jump every 1.5 s from 1 s on, instead of the gait.
  explicit ClosedLoop(const ControllerSource& source, const char* terrain = nullptr,
                      bool jumping = false)
      : jumping(jumping),
        config(loadController(source)),
        lcm("memq://"),
        publisher(lcm),
        mpc(config, publisher, TimeSource::Stamps),
        sim(mpc.mpc().robot(), worldOf(terrain), simOptions(config, terrain), publisher) {
    mpc.subscribe(lcm);
    sim.subscribe(lcm);
    reset();
  }
  static sim::SimOptions worldOf(const char* terrain) {
    sim::SimOptions o;
    if (terrain)
      o.terrain = std::make_shared<const terrain::Terrain>(terrain::loadTerrainFile(
          std::string(STRIDE_CONFIG_DIR) + "/terrain/" + terrain + ".yaml"));
    return o;
  }
  // As stride-sim: maps at 10 Hz on a terrain, none on the default flat ground.
  static sim::SimNodeOptions simOptions(const ControllerConfig& c, const char* terrain) {
    sim::SimNodeOptions o;
    o.state_rate_hz = c.rate_hz;
    if (!terrain) o.map.rate_hz = 0.0;
    return o;
  }
  void reset() {
    const Robot& r = mpc.mpc().robot();
    sim.reset(sim::startingPose(r, sim.simulator().terrain()), Eigen::VectorXd::Zero(r.model.nv));
  }
  // One period: a state out, its messages handled (their duration in handle_seconds), the tick
  // (state in → policy out: its duration returned), the preparation for the next state (its
  // duration in prepare_seconds), the answer applied. False when the robot fell.
  bool period(double& tick_seconds, double& prepare_seconds, double& handle_seconds) {
    sim.publishState();
    command.utime = sim.utime();
    if (jumping) {
      command.gait = "stand";
      const double t = sim.simulator().time();
      command.jump_id = t >= 1.0 ? 1 + static_cast<int>((t - 1.0) / 1.5) : 0;
      command.jump[0] = 0.2;
    } else {
      command.gait = mpc.mpc().gaits().size() > 2 ? "trot" : "walk";
      command.vx = sim.simulator().time() > 0.5 ? 0.3 : 0.0;
    }
    lcm.publish(config.command_channel, &command);
    const auto t_in = std::chrono::steady_clock::now();
    while (lcm.handleTimeout(0) > 0) {
    }
    const auto t0 = std::chrono::steady_clock::now();
    handle_seconds = std::chrono::duration<double>(t0 - t_in).count();
    mpc.tick(Mpc::Clock::time_point::max());
    const auto t1 = std::chrono::steady_clock::now();
    mpc.prepare(Mpc::Clock::time_point::max());
    tick_seconds = std::chrono::duration<double>(t1 - t0).count();
    prepare_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
    while (lcm.handleTimeout(0) > 0) {
    }
    return sim.advance(sim.stepsPerState());
  }
  bool period() {
    double a = 0.0, b = 0.0, c = 0.0;
    return period(a, b, c);
  }

  bool jumping = false;
  ControllerConfig config;
  command_t command{};
  lcm::LCM lcm;
  LcmPublisher publisher;
  MpcNode mpc;
  sim::SimNode sim;
};

// jump_phase: time only the ticks whose status says this jump_state (jumping: every 1.5 s), or
// -1: every tick (walking).
void controllerTick(benchmark::State& state, const ControllerSource& source, double warmup,
                    const char* terrain, int jump_phase) {
  std::unique_ptr<ClosedLoop> made;
  try {
    made = std::make_unique<ClosedLoop>(source, terrain, jump_phase >= 0);
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());  // a public robot whose description is not here
    return;
  }
  ClosedLoop& loop = *made;
  while (loop.sim.simulator().time() < warmup)
    if (!loop.period()) loop.reset();
  double seconds = 0.0, prepare = 0.0, prepare_total = 0.0, handle = 0.0;
  long backward = 0, forward = 0;
  double reused = 0.0, knots = 0.0;  // knots whose preparation took the rollout's contact solve
  std::vector<double> work;          // tick + preparation of each period [s]
  work.reserve(state.max_iterations);
  const Solver& solver = *loop.mpc.mpc().solver();
  for (auto _ : state) {
    // (jumping: the periods of the other phases run, untimed)
    for (int guard = 0; guard < 100000; ++guard) {
      if (!loop.period(seconds, prepare, handle))
        loop.reset();  // fell: start again, the timing is what matters
      if (jump_phase < 0 || loop.mpc.mpc().status().jump_state == jump_phase) break;
    }
    state.SetIterationTime(seconds);
    prepare_total += prepare;
    work.push_back(handle + seconds + prepare);
    forward += solver.forwardPasses();
    backward += solver.backwardPasses();
    // Outside the timed part (manual time): did calcDiff reuse calc's solve (KeptSolve)?
    const ShootingProblem& problem = loop.mpc.mpc().problem()->problem();
    for (int k = 0; k < problem.horizon(); ++k) {
      if (const auto* d = dynamic_cast<const KnotActionData*>(&problem.data(k))) {
        reused += d->solve_reused ? 1.0 : 0.0;
        knots += 1.0;
      }
    }
  }
  state.counters["reused"] = reused / std::max(1.0, knots);  // share of the knots
  const auto per_tick = [&](double x) { return x / static_cast<double>(state.iterations()); };
  state.counters["rollouts"] = per_tick(static_cast<double>(forward));
  state.counters["backward"] = per_tick(static_cast<double>(backward));
  state.counters["fell"] = loop.sim.stats().fell;
  state.counters["maps"] = static_cast<double>(loop.mpc.mpc().counters().maps);
  // The other half of each iteration, run after the policy went out (ms per tick).
  state.counters["prepare_ms"] = 1e3 * per_tick(prepare_total);
  state.counters["unprepared"] = static_cast<double>(loop.mpc.mpc().counters().unprepared_solves);
  // The period's work against the period: what real time needs (ARCHITECTURE.md, real-time rules).
  // Nearest-rank percentiles, as stride-mpc's and stride-log-summary's summaries (NaN: no period).
  const double period = 1.0 / loop.config.rate_hz;
  const Percentiles share = percentiles(work);
  state.counters["period_share"] = share.p50.value_or(NAN) / period;
  state.counters["period_share_p99"] = share.p99.value_or(NAN) / period;
}

// The parts of one tick's FDDP iteration on the problem the controller has 3 s into the gait
// (stepping): derivatives of all knots, the backward pass, one rollout of the line search.
void tickParts(benchmark::State& state, const ControllerSource& source, int part) {
  std::unique_ptr<ClosedLoop> made;
  try {
    made = std::make_unique<ClosedLoop>(source);
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  ClosedLoop& loop = *made;
  while (loop.sim.simulator().time() < 3.0) {
    if (!loop.period()) {
      state.SkipWithError("the robot fell during the warm-up");
      return;
    }
  }
  Solver& solver = *loop.mpc.mpc().solver();
  solver.discardPreparation();  // the parts below change what it linearized
  solver.computeDerivatives();
  solver.backwardPass();
  solver.predictChange();
  for (auto _ : state) {
    if (part == 0) benchmark::DoNotOptimize(solver.computeDerivatives());
    if (part == 1) benchmark::DoNotOptimize(solver.backwardPass());
    if (part == 2) benchmark::DoNotOptimize(solver.forwardPass(0.5));
  }
}

BENCHMARK_CAPTURE(tickParts, quad_derivatives, shippedController("stride_quad"), 0)
    ->Name("tick_parts/stride_quad/derivatives")
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(tickParts, quad_backward, shippedController("stride_quad"), 1)
    ->Name("tick_parts/stride_quad/backward")
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(tickParts, quad_forward, shippedController("stride_quad"), 2)
    ->Name("tick_parts/stride_quad/forward")
    ->Unit(benchmark::kMillisecond);

// Every shipped controller configuration; the 200 Hz quadrupeds over 2 s of trotting, the 50 Hz
// humanoids over 2 s of walking (after 1.5 s: standing, then the first steps).
const bool registered = [] {
  // The 200 Hz robots tick 400 times (2 s), the 50 Hz ones 100 times (2 s).
  const std::pair<const char*, int> configs[] = {{"stride_quad", 400},
                                                 {"solo12", 400},
                                                 {"anymal_c", 400},
                                                 {"stride_humanoid", 100},
                                                 {"talos_reduced", 100}};
  for (const auto& [robot, ticks] : configs)
    benchmark::RegisterBenchmark((std::string("controller_tick/") + robot).c_str(), controllerTick,
                                 shippedController(robot), 1.5, nullptr, -1)
        ->UseManualTime()
        ->Unit(benchmark::kMillisecond)
        ->Iterations(ticks);
  benchmark::RegisterBenchmark("controller_tick/anymal_c_stairs", controllerTick,
                               shippedController("anymal_c"), 5.5, "stairs_anymal_c", -1)
      ->UseManualTime()
      ->Unit(benchmark::kMillisecond)
      ->Iterations(400);
  // The robots that jump, per phase of their jumps (jump_state 1, 2, 3).
  const std::pair<const char*, int> phases[] = {{"push", 1}, {"flight", 2}, {"landing", 3}};
  for (const char* robot : {"stride_quad", "solo12", "anymal_c"})
    for (const auto& [phase, state] : phases)
      benchmark::RegisterBenchmark(
          (std::string("controller_tick/") + robot + "_jump/" + phase).c_str(), controllerTick,
          shippedController(robot), 0.5, nullptr, state)
          ->UseManualTime()
          ->Unit(benchmark::kMillisecond)
          ->Iterations(200);
  return true;
}();

}  // namespace

// Any configuration (stride-bench --config FILE): as the shipped ones, 2 s of its periods after
// 1.5 s (standing, then the first steps); the parts 3 s into the gait.
void registerControllerBenchmarks(const ControllerSource& source, const std::string& name,
                                  const ControllerConfig& config) {
  const auto ticks = std::max<benchmark::IterationCount>(
      1, static_cast<benchmark::IterationCount>(std::lround(2.0 * config.rate_hz)));
  benchmark::RegisterBenchmark(("controller_tick/" + name).c_str(), controllerTick, source, 1.5,
                               nullptr, -1)
      ->UseManualTime()
      ->Unit(benchmark::kMillisecond)
      ->Iterations(ticks);
  const char* parts[] = {"derivatives", "backward", "forward"};
  for (int part = 0; part < 3; ++part)
    benchmark::RegisterBenchmark(("tick_parts/" + name + "/" + parts[part]).c_str(), tickParts,
                                 source, part)
        ->Unit(benchmark::kMillisecond);
}

}  // namespace stride::bench
