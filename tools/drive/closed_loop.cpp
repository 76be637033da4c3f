#include "tools/drive/closed_loop.hpp"

#include <algorithm>
#include <cmath>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <stdexcept>

namespace stride::drive {

namespace {
// Writes every message on the bus to an LCM log, stamped with the robot's clock.
class Recorder {
 public:
  Recorder(lcm::LCM& bus, const std::string& path, const std::int64_t* clock)
      : log_(path, "w"), clock_(clock) {
    if (!log_.good()) throw std::runtime_error("cannot write the log '" + path + "'");
    bus.subscribe(".*", &Recorder::onMessage, this)->setQueueCapacity(10000);
  }
  void onMessage(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    lcm::LogEvent e;
    e.eventnum = n_++;
    e.timestamp = *clock_;
    e.channel = channel;
    e.datalen = static_cast<std::int32_t>(rbuf->data_size);
    e.data = rbuf->data;
    log_.writeEvent(&e);
  }

 private:
  lcm::LogFile log_;
  const std::int64_t* clock_;
  std::int64_t n_ = 0;
};

// Delivers everything queued on the in-process bus.
void drain(lcm::LCM& bus) {
  while (bus.handleTimeout(0) > 0) {
  }
}
}  // namespace

double tiltDeg(const Eigen::VectorXd& q) {
  const double qx = q[3], qy = q[4];
  return std::acos(std::clamp(1.0 - 2.0 * (qx * qx + qy * qy), -1.0, 1.0)) * 180.0 / M_PI;
}

Run run(const ControllerConfig& config, const Options& options) {
  lcm::LCM lcm("memq://");
  LcmPublisher publisher(lcm);
  MpcNode mpc(config, publisher, TimeSource::Stamps);
  mpc.subscribe(lcm);
  const Robot& robot = mpc.mpc().robot();
  sim::SimNodeOptions o = options.sim;
  o.state_rate_hz = config.rate_hz;
  sim::SimNode sim(robot, sim::SimOptions{}, o, publisher);
  sim.subscribe(lcm);
  sim.reset(robot.default_q, Eigen::VectorXd::Zero(robot.model.nv));
  std::int64_t clock = sim.utime();
  std::unique_ptr<MpcNode> rival;
  if (options.rival != nullptr) {
    rival = std::make_unique<MpcNode>(*options.rival, publisher, TimeSource::Stamps);
    rival->subscribe(lcm);
  }
  std::unique_ptr<Recorder> recorder;
  if (!options.log.empty()) recorder = std::make_unique<Recorder>(lcm, options.log, &clock);

  Run r;
  command_t command;
  while (sim.simulator().time() < options.duration - 1e-9) {
    const double t = sim.simulator().time();
    clock = sim.utime();
    const std::int64_t stamp = sim.publishState();
    if (!options.script.empty() && t + 1e-9 < options.commands_until) {
      // The sim's time is a sum of steps (3.9999999999997 for 4): an entry at 4 s applies at 4 s.
      const ScriptedCommand& c = options.script[commandAt(options.script, t + 1e-9)];
      command.utime = sim.utime();
      command.vx = c.vx;
      command.vy = c.vy;
      command.yaw_rate = c.yaw_rate;
      command.gait = c.gait;
      command.body_height = c.body_height;
      lcm.publish(config.command_channel, &command);
      r.commands.push_back({t, c.vx, c.vy, c.yaw_rate, c.gait, c.body_height});
    }
    drain(lcm);
    if (mpc.tickDue()) {
      mpc.tick(Mpc::Clock::time_point::max());
      mpc.prepare(Mpc::Clock::time_point::max());
    }
    if (rival && rival->tickDue()) {  // after the robot's own: its first policy comes second
      rival->tick(Mpc::Clock::time_point::max());
      rival->prepare(Mpc::Clock::time_point::max());
    }
    drain(lcm);
    if (stamp >= 0 && !sim.answered(stamp)) sim.countLockstepTimeout();
    double k_max = 0.0;
    for (double k : mpc.mpc().policy().K[0]) k_max = std::max(k_max, std::abs(k));
    const mpc_status_t& status = mpc.mpc().status();
    Sample s{t,
             sim.simulator().q(),
             sim.simulator().v(),
             status.cost,
             status.gap,
             status.policy_status,
             k_max,
             status.step,
             status.regularization,
             0};
    for (int c = 0; c < static_cast<int>(robot.contacts.size()); ++c)
      s.feet_down += sim.simulator().normalForce(c) > 0.0;
    if (const Solver* solver = mpc.mpc().solver()) {
      s.backward_passes = solver->backwardPasses();
      s.forward_passes = solver->forwardPasses();
    }
    s.solve_ms = status.solve_ms;
    if (options.each) options.each(s);
    r.samples.push_back(std::move(s));
    if (!sim.advance(sim.stepsPerState())) break;  // fell or diverged
  }
  clock = sim.utime();
  if (sim.stats().fell) {
    // The fallen pose goes into the samples (its segment is marked fallen) and the log too.
    sim.publishState();
    Sample fallen = r.samples.empty() ? Sample{} : r.samples.back();
    fallen.t = sim.simulator().time();
    fallen.q = sim.simulator().q();
    fallen.v = sim.simulator().v();
    r.samples.push_back(std::move(fallen));
  }
  drain(lcm);
  r.sim = sim.stats();
  r.mpc = mpc.mpc().counters();
  r.command_counters = mpc.commands().counters();
  r.rejected = mpc.rejected();
  r.rival_policies = mpc.rivalPolicies();
  r.q_end = sim.simulator().q();
  return r;
}

std::vector<logs::BaseSample> Run::baseSamples() const {
  std::vector<logs::BaseSample> out;
  out.reserve(samples.size());
  for (const Sample& s : samples) {
    logs::BaseSample b;
    b.t = s.t;
    for (int i = 0; i < 7; ++i) b.q[i] = s.q[i];
    for (int i = 0; i < 6; ++i) b.v[i] = s.v[i];
    out.push_back(b);
  }
  return out;
}

std::vector<logs::Segment> Run::segments(const logs::SegmentOptions& options) const {
  return logs::segmentCommands(commands, baseSamples(), options);
}

}  // namespace stride::drive
