#pragma once
// The controller's configuration (config/controller/<name>.yaml): which robot, how fast, the
// horizon, the cost weights, the solver budget, the gaits, the command limits, LCM channels and
// URLs, safety limits and real-time settings. Loaded once at start-up; every error names the file
// and the key.

#include <map>
#include <string>
#include <vector>

#include "config/robot_config.hpp"
#include "controller/command.hpp"
#include "locomotion/gait.hpp"
#include "locomotion/locomotion_problem.hpp"
#include "locomotion/planner.hpp"
#include "messages/hold_pd.hpp"
#include "messages/signing.hpp"
#include "solver/ddp/solver.hpp"
#include "terrain/steppability.hpp"

namespace stride {

enum class Fallback { Previous, Hold };

// The planner's parts (locomotion, generator, gait, terrain, threads) are PlannerOptions' types
// (locomotion/planner.hpp): GaitConfig (the gaits' timing or a plan file), TerrainConfig (the
// steppability of a map and the age rule that judges it).

// The shortest policy, in tick periods: it must bridge kMinPolicyPeriods - 1 lost answers in a row
// (controller_config.cpp, controller/README.md "Robustness").
inline constexpr int kMinPolicyPeriods = 6;

struct ControllerConfig {
  std::string path;        // the YAML it came from
  std::string robot_yaml;  // resolved against the YAML's folder
  // Where package:// URIs of the robot YAML are looked for first (--robots-dir), before
  // ROS_PACKAGE_PATH (config/package_path.hpp).
  std::vector<std::string> robots_dirs;
  double rate_hz = 100.0;
  int policy_knots = 8;  // knots sent in each policy message (covering kMinPolicyPeriods)
  LocomotionOptions locomotion;
  GaitGeneratorOptions generator;  // horizon, accelerations and height rate follow the rest
  GaitConfig gait;
  CommandConfig command;
  TerrainConfig terrain;
  JumpLimits jump;  // the `jump:` section; none: the robot does not jump

  SolverKind solver = SolverKind::BoxFddp;
  int max_iterations = 1;          // per tick
  int initial_iterations = 100;    // the first solve, before the first policy
  double deadline_fraction = 0.8;  // of the tick period, for the solve
  int line_search_steps = 4;       // α = 1, 1/2, ...: with one iteration per tick, a step shorter
                              // than the last is not worth its rollouts (the next tick retries)
  // μ never drops below this during ticks (the start-up solve goes down to 1e-9): a trust region
  // that keeps one iteration's step within what the linearization predicts, so the first rollout
  // is usually accepted. Each rejected rollout costs a rollout's time in the tick's latency.
  double min_regularization = 1e-9;
  // Not from the YAML: stride-mpc --emulate-slow-host F (tests of the overload handling) makes
  // every piece of the solver's work take F times its duration (controller/slow_host.hpp).
  double emulated_slowdown = 1.0;
  int threads = 1;

  std::string state_channel = "STRIDE_STATE", policy_channel = "STRIDE_POLICY",
              status_channel = "STRIDE_STATUS", plan_channel = "STRIDE_PLAN",
              command_channel = "STRIDE_COMMAND", model_channel = "STRIDE_MODEL",
              horizon_channel = "STRIDE_HORIZON", terrain_channel = "STRIDE_TERRAIN";
  // horizon_t (the whole predicted horizon, for viewers) per second; 0: not published.
  double horizon_rate_hz = 10.0;
  std::string input_url, output_url;  // empty: LCM_DEFAULT_URL
  // The shared key that signs and checks messages (lcm.key_file, relative to the YAML, or
  // stride-mpc --key-file); empty: the wire is unauthenticated (messages/README.md, "Signing").
  std::string key_file;
  // The freshness window of signed messages [s] (lcm.signature_window_s): a message whose
  // signature's timestamp is further than this from this host's CLOCK_REALTIME at its arrival is
  // refused (messages/README.md, "Freshness": the hosts' clocks kept together by chrony or PTP).
  double signature_window = static_cast<double>(msg::kFreshnessWindowMicros) * 1e-6;

  double max_state_age = 0.05;  // s; an older state is stale
  Fallback fallback = Fallback::Previous;
  // Hold policy joint gains [Nm/rad, Nm s/rad]: the law and the defaults the mock robot's too
  // (messages/hold_pd.hpp; the default damping was 0.2 here, 0.1 there, for no stated reason).
  double hold_kp = msg::kDefaultHoldKp, hold_kd = msg::kDefaultHoldKd;
  int max_previous_ticks = 20;  // fallback Previous degrades to Hold after this many

  int cpu = -1;           // pin the loop to this CPU (-1: no)
  int fifo_priority = 0;  // SCHED_FIFO priority (0: normal scheduling)
};

// Throws ConfigError naming the file and the key.
ControllerConfig loadControllerConfig(const std::string& yaml_path);

const char* toString(SolverKind kind);
// "45 knots, 1.2 s: 20 x 10 ms, 10 x 20 ms, 15 x 40 ms" (or "100 knots of 10 ms").
std::string describeHorizon(const LocomotionOptions& horizon);

}  // namespace stride
