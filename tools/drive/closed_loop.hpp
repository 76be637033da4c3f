#pragma once
// The closed loop in one process: stride-sim's node and stride-mpc's node on one in-process LCM
// bus (memq://), in lock-step: the sim publishes a state every controller period, a command script
// (if any) publishes the command in force at that state's time, stamped with it, the controller
// ticks on them, the sim applies the answer for one period. Deterministic and network-free: the
// tests, stride-drive and the sweeps (tools/drive/README.md) all drive robots through it.

#include <functional>
#include <lcm/lcm-cpp.hpp>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "controller/command_script.hpp"
#include "controller/mpc_node.hpp"
#include "sim/sim_node.hpp"
#include "tools/log/segments.hpp"

namespace stride::drive {

struct Sample {
  double t;
  Eigen::VectorXd q, v;
  double cost, gap;
  int policy_status;
  double k_max;  // largest |K| entry of the policy's first knot
  double step, reg;
  int feet_down;                                // robot contacts carrying load (sim)
  double ground = 0.0;                          // the terrain's height under the base
  unsigned feet_mask = 0;                       // bit c: contact c carries load
  int backward_passes = 0, forward_passes = 0;  // of the tick's solve
  // The tick's figures from its status (mpc_status_t): the solve after the state came in, the
  // preparation it used (run ahead, in the previous period), the whole tick.
  double solve_ms = 0.0, prepare_ms = 0.0, tick_ms = 0.0;
  // The mock robot's 1 kHz steps so far whose torque was clamped to the effort limits, and the
  // torque applied in the last one (nu): a robot short of torque shows here first.
  std::int64_t clamped_steps = 0;
  Eigen::VectorXd tau = Eigen::VectorXd();
};

struct Options {
  sim::SimNodeOptions sim;  // pushes, sensing, actuators, mismatch (the state rate: the config's)
  sim::SimOptions physics;  // the mock robot's physics (--mu); its terrain is `terrain` below
  double duration = 10.0;   // [s] of robot time
  std::vector<ScriptedCommand> script;  // empty: no command (the robot stands)
  // Commands stop at this time [s] (a teleop that went silent: the deadman's case).
  double commands_until = std::numeric_limits<double>::infinity();
  std::string log;  // an LCM log of every message on the bus (lcm-logger's format), if not empty
  std::function<void(const Sample&)> each;  // called every period
  // A rival: a second controller on the same bus, ticking on the same states and publishing on
  // the same policy channel (the robot must keep following the first; sim/README.md).
  const ControllerConfig* rival = nullptr;
  // A controller lost and restarted: at `controller_lost_at` [s] the controller process dies (its
  // node is destroyed: no more policies), and `controller_back_after` [s] later a new one starts
  // (a fresh node: new source id, start-up solve from the robot as it is). Negative: never.
  double controller_lost_at = -1.0;
  double controller_back_after = 1.0;
  // Faults on the wire: each state estimate passes through this before it goes out (it may be
  // changed or dropped; sim::SimNode::setStateFault), and every period `flood_per_period`
  // policies of another robot's sizes are published on the policy channel before the answer.
  sim::SimNode::StateFault state_fault;
  // The mock robot restarted: at `sim_lost_at` [s] stride-sim dies; `sim_back_after` [s] later a
  // new one starts, the robot standing at the default posture at the origin. Negative: never.
  double sim_lost_at = -1.0, sim_back_after = 1.0;
  int flood_per_period = 0;
  // Called every period with the bus and the run time [s], after the robot's state and the
  // command went out and before they are delivered: an attacker on the bus (a recording replayed,
  // forged or junk messages; tests/controller/test_signed_replay.cpp).
  std::function<void(lcm::LCM& bus, double t)> on_bus;
  // False: no controller at all (the robot alone on the bus, with whatever on_bus sends it).
  bool controller = true;
  // The world (terrain/terrain.hpp): null, the flat ground at z = 0. The robot starts standing on
  // it at its default place, drop_height above (sim::startingPose).
  std::shared_ptr<const terrain::Terrain> terrain;
  double drop_height = 0.0;
};

struct Run {
  std::vector<Sample> samples;                // one per tick
  std::vector<logs::CommandSample> commands;  // as sent (t: sim time)
  sim::SimNodeStats sim;
  MpcCounters mpc;
  std::vector<logs::JumpOutcome> jumps;  // what the controller's statuses said of each jump
  CommandCounters command_counters;
  std::int64_t rejected = 0;
  std::int64_t rival_policies = 0;  // seen by the controller on its policy channel
  // Signatures (with a key): the robot's refusals in words and those stale; the controller's
  // refusals (every channel), those stale, and its states of another robot run refused.
  std::string sim_auth_text, mpc_auth_text;  // the last controller's
  std::int64_t sim_stale = 0;
  std::int64_t mpc_unauthenticated = 0, mpc_stale = 0, mpc_other_session = 0;
  int controller_starts = 1;             // 2 after a restart (Options::controller_lost_at)
  int sim_starts = 1;                    // 2 after a restart (Options::sim_lost_at)
  sim::SimNodeStats sim_before_restart;  // the first mock robot's figures, if restarted
  Eigen::VectorXd q_end;
  // The mock robot's terrain, its feet's trips on vertical faces, and the base's height above the
  // terrain under it at the end.
  std::string terrain = "flat";
  std::int64_t trips = 0;
  // Its feet's touch-downs, those closer than 2 cm to an edge of the true terrain, the nearest any
  // came to one (+infinity: none within 5 cm) and all of it in words (sim::SimCounters,
  // sim::footholdText). After a restart of the mock robot (Options::sim_lost_at), the new one's.
  std::int64_t footholds = 0, edge_footholds = 0;
  double min_edge_distance = std::numeric_limits<double>::infinity();
  // Soles down with every corner, of the time they are down (sim::soleFlatFraction; NaN: no soles).
  double sole_flat_fraction = std::numeric_limits<double>::quiet_NaN();
  std::string footholds_text;
  double base_above_terrain = 0.0;
  // A diverged simulation (sim::SimNodeStats::diverged) counts as a fall: the run is over.
  bool fell() const { return sim.fell || sim.diverged; }
  // The base states for segments (t: sim time).
  std::vector<logs::BaseSample> baseSamples() const;
  // One segment per run of identical commands (logs::segmentCommands).
  std::vector<logs::Segment> segments(const logs::SegmentOptions& options = {}) const;
  // The base's motion from t0 to t1 (logs::motion): how far a jump went, how much it turned.
  using Motion = logs::Motion;
  Motion motion(double t0, double t1) const { return logs::motion(baseSamples(), t0, t1); }
};

// Drives the robot of `config` (its robot YAML, at its default posture) for options.duration.
// Throws what the controller's construction throws (ConfigError, UrdfError), or
// std::runtime_error when the log cannot be written.
Run run(const ControllerConfig& config, const Options& options);

// Base tilt [deg]: the angle between the base's z axis and the world's.
double tiltDeg(const Eigen::VectorXd& q);

}  // namespace stride::drive
