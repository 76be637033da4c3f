// reference_update/<robot>: what the controller's tick spends on references (issue "commandable
// locomotion"): GaitGenerator::plan (base trajectory from the command, latching, every touch-down
// of the horizon placed) and LocomotionProblem::update (every knot's contacts, modes and
// references) for one tick, on the shipped controller configuration of each robot, the robot
// commanded at a walking speed in its stepping gait, the clock advancing one period per iteration
// (so gait phases, touch-downs and shifts all come by). Counter period_ms: the controller's
// period, for scale. The public robots are read from the package view of ../shared
// (build/robot_packages); without it they are skipped with a message.
// reference_update/config:NAME: the same on any configuration (stride-bench --config FILE), at
// half its max_velocity forward.
#include <benchmark/benchmark.h>

#include "controller/controller_config.hpp"
#include "locomotion/gait.hpp"
#include "locomotion/locomotion_problem.hpp"
#include "tools/bench/controller_source.hpp"

namespace stride::bench {
namespace {

void referenceUpdate(benchmark::State& state, const ControllerSource& source, double speed) {
  ControllerConfig config;
  Robot r;
  try {
    config = loadController(source);
    r = loadRobot(config.robot_yaml, config.robots_dirs);
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());  // a public robot whose description is not here
    return;
  }
  ContactSet contacts;
  for (const ContactSpec& c : r.contacts)
    contacts.add(r.model, c.frame, c.dim, ReferenceFrame::LocalWorldAligned);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(r.model.nq + r.model.nv);
  x.head(r.model.nq) = r.default_q;
  LocomotionProblem loco(r.model, contacts, x, config.locomotion);
  GaitGenerator gen(r.model, contacts, x, config.generator);
  const std::vector<std::string> gaits = gaitNames(contacts.size());
  const std::string gait = gaits.size() > 2 ? "trot" : "walk";
  const auto timing = config.gait.timing.find(gait);
  gen.timeline().reset(gen.timeline().addPattern(makeGaitPattern(gait, timing->second, r.contacts)),
                       0.0);
  BodyCommand command;
  command.vx = speed;
  command.yaw_rate = 0.2;
  gen.setCommand(command);
  const double period = 1.0 / config.rate_hz, dt = config.locomotion.dt;
  double t = 0.0;
  for (auto _ : state) {
    t += period;
    const double t_warm = dt * std::floor(t / dt + 0.5);  // on the knot grid, as the tick
    // The base moves with the command, so the references see a moving robot.
    x[0] = speed * t;
    benchmark::DoNotOptimize(gen.plan(t, x, t_warm, t_warm + loco.span()));
    benchmark::DoNotOptimize(loco.update(t_warm, gen));
  }
  state.counters["period_ms"] = 1e3 * period;
}

BENCHMARK_CAPTURE(referenceUpdate, stride_quad, shippedController("stride_quad"), 0.5)
    ->Name("reference_update/stride_quad")
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(referenceUpdate, solo12, shippedController("solo12"), 0.5)
    ->Name("reference_update/solo12")
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(referenceUpdate, anymal_c, shippedController("anymal_c"), 0.8)
    ->Name("reference_update/anymal_c")
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(referenceUpdate, stride_humanoid, shippedController("stride_humanoid"), 0.3)
    ->Name("reference_update/stride_humanoid")
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(referenceUpdate, talos_reduced, shippedController("talos_reduced"), 0.3)
    ->Name("reference_update/talos_reduced")
    ->Unit(benchmark::kMicrosecond);

}  // namespace

void registerReferenceBenchmark(const ControllerSource& source, const std::string& name,
                                const ControllerConfig& config) {
  benchmark::RegisterBenchmark(("reference_update/" + name).c_str(), referenceUpdate, source,
                               0.5 * config.command.max_vx)
      ->Unit(benchmark::kMicrosecond);
}

}  // namespace stride::bench
