#pragma once
// The closed loop in one process: stride-sim's node and stride-mpc's node on one in-process LCM
// bus (memq://), in lock-step: the sim publishes a state every controller period, a command
// script (if any) publishes the command in force at that state's time, stamped with it, the
// controller ticks on them, the sim applies the answer for one period. Deterministic and
// network-free.

#include <functional>
#include <lcm/lcm-cpp.hpp>

#include "controller/command_script.hpp"
#include "controller/mpc_node.hpp"
#include "sim/sim_node.hpp"

namespace stride::closed_loop {

struct Sample {
  double t;
  Eigen::VectorXd q, v;
  double cost, gap;
  int policy_status;
  double k_max;  // largest |K| entry of the policy's first knot
  double step, reg;
  int feet_down;                                // robot contacts carrying load (sim)
  int backward_passes = 0, forward_passes = 0;  // of the tick's solve
  double solve_ms = 0.0;
};

struct Run {
  std::vector<Sample> samples;  // one per tick
  sim::SimNodeStats sim;
  MpcCounters mpc;
  std::int64_t rejected = 0;
  Eigen::VectorXd q_end;
};

inline double tiltDeg(const Eigen::VectorXd& q) {
  const double qx = q[3], qy = q[4];
  return std::acos(std::clamp(1.0 - 2.0 * (qx * qx + qy * qy), -1.0, 1.0)) * 180.0 / M_PI;
}

inline Run run(const ControllerConfig& config, const sim::SimNodeOptions& sim_options,
               double duration, const std::vector<ScriptedCommand>& script = {},
               const std::function<void(const Sample&)>& each = nullptr) {
  lcm::LCM lcm("memq://");
  LcmPublisher publisher(lcm);
  MpcNode mpc(config, publisher, TimeSource::Stamps);
  mpc.subscribe(lcm);
  const Robot& robot = mpc.mpc().robot();
  sim::SimOptions sim_physics;
  sim::SimNodeOptions o = sim_options;
  o.state_rate_hz = config.rate_hz;
  sim::SimNode sim(robot, sim_physics, o, publisher);
  sim.subscribe(lcm);
  sim.reset(robot.default_q, Eigen::VectorXd::Zero(robot.model.nv));
  Run r;
  command_t command;
  while (sim.simulator().time() < duration - 1e-9) {
    const std::int64_t stamp = sim.publishState();
    if (!script.empty()) {
      const ScriptedCommand& c = script[commandAt(script, sim.simulator().time())];
      command.utime = sim.utime();
      command.vx = c.vx;
      command.vy = c.vy;
      command.yaw_rate = c.yaw_rate;
      command.gait = c.gait;
      command.body_height = c.body_height;
      lcm.publish(config.command_channel, &command);
    }
    while (lcm.handleTimeout(0) > 0) {
    }
    if (mpc.tickDue()) {
      mpc.tick(Mpc::Clock::time_point::max());
      mpc.prepare(Mpc::Clock::time_point::max());
    }
    while (lcm.handleTimeout(0) > 0) {
    }
    if (stamp >= 0 && !sim.answered(stamp)) sim.countLockstepTimeout();
    double k_max = 0.0;
    for (double k : mpc.mpc().policy().K[0]) k_max = std::max(k_max, std::abs(k));
    Sample s{sim.simulator().time(),
             sim.simulator().q(),
             sim.simulator().v(),
             mpc.mpc().status().cost,
             mpc.mpc().status().gap,
             mpc.mpc().status().policy_status,
             k_max,
             mpc.mpc().status().step,
             mpc.mpc().status().regularization,
             0};
    for (int c = 0; c < static_cast<int>(robot.contacts.size()); ++c)
      s.feet_down += sim.simulator().normalForce(c) > 0.0;
    if (const Solver* solver = mpc.mpc().solver()) {
      s.backward_passes = solver->backwardPasses();
      s.forward_passes = solver->forwardPasses();
    }
    s.solve_ms = mpc.mpc().status().solve_ms;
    if (each) each(s);
    r.samples.push_back(std::move(s));
    if (!sim.advance(sim.stepsPerState())) break;  // fell or diverged
  }
  r.sim = sim.stats();
  r.mpc = mpc.mpc().counters();
  r.rejected = mpc.rejected();
  r.q_end = sim.simulator().q();
  return r;
}

}  // namespace stride::closed_loop
