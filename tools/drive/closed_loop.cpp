#include "tools/drive/closed_loop.hpp"

#include "messages/wire_auth.hpp"
#include "sim/fall.hpp"

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
  return sim::baseTilt(q[3], q[4], q[5], q[6]) * 180.0 / M_PI;  // the fall test's (sim/fall.hpp)
}

Run run(const ControllerConfig& config, const Options& options) {
  lcm::LCM lcm("memq://");
  LcmPublisher publisher(lcm);
  auto mpc = std::make_unique<MpcNode>(config, publisher, TimeSource::Stamps);
  mpc->subscribe(lcm);
  // The sim keeps its own copy of the robot: the controller may die (options.controller_lost_at).
  const Robot robot = mpc->mpc().robot();
  if (!options.controller) mpc.reset();  // the robot alone
  sim::SimNodeOptions o = options.sim;
  o.state_rate_hz = config.rate_hz;
  // Signatures (messages/README.md, "Signing"): the controller's key (its config's key_file) is
  // the robot's and the commands' too, unless the robot was given its own.
  if (!o.key && !config.key_file.empty()) o.key = msg::loadKeyFile(config.key_file);
  msg::WireAuth teleop = o.key ? msg::WireAuth(*o.key, "stride-drive") : msg::WireAuth();
  std::vector<std::uint8_t> command_bytes;
  // The mock robot; a restart (options.sim_lost_at) is a new node, at the default posture, whose
  // clock goes on from the old one's plus the outage (as stride-sim's monotonic stamps would).
  std::unique_ptr<sim::SimNode> sim;
  auto startSim = [&](std::int64_t utime_base) {
    o.utime_base = utime_base;
    sim::SimOptions physics = options.physics;
    physics.terrain = options.terrain;
    sim = std::make_unique<sim::SimNode>(robot, physics, o, publisher);
    sim->subscribe(lcm);
    sim->reset(sim::startingPose(robot, sim->simulator().terrain(), options.drop_height),
               Eigen::VectorXd::Zero(robot.model.nv));
    if (options.state_fault) sim->setStateFault(options.state_fault);
  };
  startSim(o.utime_base);
  // The flood: a policy one entry too wide everywhere (another robot's), encoded once.
  std::vector<unsigned char> flood;
  if (options.flood_per_period > 0) {
    policy_t foreign;
    const int nu = actuatedDimension(robot.model);
    msg::shape(foreign, 8, robot.model.nq + 1, robot.model.nv + 1, nu + 1);
    foreign.model_hash = 0x5eed;
    foreign.source_id = 0xf100d;
    flood.resize(foreign.getEncodedSize());
    foreign.encode(flood.data(), 0, static_cast<int>(flood.size()));
  }
  std::int64_t clock = sim->utime();
  double t_offset = 0.0;         // run time at the current sim's time 0
  sim::SimNodeStats sim_before;  // the first sim's figures, when it was restarted
  std::unique_ptr<MpcNode> rival;
  if (options.rival != nullptr) {
    rival = std::make_unique<MpcNode>(*options.rival, publisher, TimeSource::Stamps);
    rival->subscribe(lcm);
  }
  std::unique_ptr<Recorder> recorder;
  if (!options.log.empty()) recorder = std::make_unique<Recorder>(lcm, options.log, &clock);

  Run r;
  command_t command{};
  const bool loses = options.controller_lost_at >= 0.0;
  bool lost = false;
  // The last controller's figures, kept when it dies (the run reports the one alive at the end).
  MpcCounters mpc_counters;
  CommandCounters command_counters;
  std::int64_t rejected = 0, rival_policies = 0;
  auto keepFigures = [&] {
    mpc_counters = mpc->mpc().counters();
    command_counters = mpc->commands().counters();
    rejected = mpc->rejected();
    rival_policies = mpc->rivalPolicies();
    // Summed over the controllers of the run (a restart is a new one).
    r.mpc_unauthenticated += mpc->auth().refused();
    r.mpc_stale += mpc->auth().refused(msg::Verdict::Stale);
    r.mpc_other_session += mpc->rejected(msg::Reject::OtherSession);
    r.mpc_auth_text = msg::refusedText(mpc->auth());
  };
  while (t_offset + sim->simulator().time() < options.duration - 1e-9) {
    if (options.sim_lost_at >= 0.0 && t_offset == 0.0 &&
        sim->simulator().time() + 1e-9 >= options.sim_lost_at) {
      // Killed, and back after the outage: no states meanwhile (the controller keeps ticking on
      // none), then a robot standing at the origin.
      sim_before = sim->stats();
      const std::int64_t back =
          sim->utime() + static_cast<std::int64_t>(std::llround(options.sim_back_after * 1e6));
      t_offset = sim->simulator().time() + options.sim_back_after;
      sim.reset();
      startSim(back);
      ++r.sim_starts;
    }
    const double t = t_offset + sim->simulator().time();
    if (loses && !lost && mpc && t + 1e-9 >= options.controller_lost_at) {
      keepFigures();
      mpc.reset();  // killed: its subscriptions go with it
      lost = true;
    }
    if (loses && lost && !mpc &&
        t + 1e-9 >= options.controller_lost_at + options.controller_back_after) {
      mpc = std::make_unique<MpcNode>(config, publisher, TimeSource::Stamps);
      mpc->subscribe(lcm);
      ++r.controller_starts;
    }
    clock = sim->utime();
    const std::int64_t stamp = sim->publishState();
    if (!options.script.empty() && t + 1e-9 < options.commands_until) {
      // The sim's time is a sum of steps (3.9999999999997 for 4): an entry at 4 s applies at 4 s.
      const ScriptedCommand& c = options.script[commandAt(options.script, t + 1e-9)];
      command = toCommand(c, sim->utime());
      const int size = command.getEncodedSize();
      command_bytes.resize(static_cast<std::size_t>(size) + msg::kSignatureSize);
      command.encode(command_bytes.data(), 0, size);
      const int n = teleop.send(config.command_channel.c_str(), command_bytes.data(), size,
                                static_cast<int>(command_bytes.size()));
      lcm.publish(config.command_channel, command_bytes.data(), static_cast<unsigned>(n));
      r.commands.push_back({t, c.vx, c.vy, c.yaw_rate, c.gait, c.body_height, c.jump_id});
    }
    if (options.on_bus) options.on_bus(lcm, t);
    drain(lcm);
    if (mpc && mpc->tickDue()) {
      mpc->tick(Mpc::Clock::time_point::max());
      mpc->prepare(Mpc::Clock::time_point::max());
    }
    if (rival && rival->tickDue()) {  // after the robot's own: its first policy comes second
      rival->tick(Mpc::Clock::time_point::max());
      rival->prepare(Mpc::Clock::time_point::max());
    }
    // The flood arrives with the answer, in the same queue of the robot's policy subscription.
    for (int i = 0; i < options.flood_per_period; ++i)
      lcm.publish(config.policy_channel, flood.data(), static_cast<unsigned>(flood.size()));
    drain(lcm);
    if (stamp >= 0 && !sim->answered(stamp)) sim->countLockstepTimeout();
    double k_max = 0.0;
    mpc_status_t status{};
    status.policy_status = -1;  // no controller
    if (mpc) {
      for (double k : mpc->mpc().policy().K[0]) k_max = std::max(k_max, std::abs(k));
      status = mpc->mpc().status();
      logs::noteJump(r.jumps, status.jump_id, status.jump_state, status.jump_refusal, t);
    }
    Sample s{t,
             sim->simulator().q(),
             sim->simulator().v(),
             status.cost,
             status.gap,
             status.policy_status,
             k_max,
             status.step,
             status.regularization,
             0};
    if (robot.model.hasFreeFlyer()) s.ground = sim->simulator().terrain().height(s.q[0], s.q[1]);
    for (int c = 0; c < static_cast<int>(robot.contacts.size()); ++c)
      if (sim->simulator().normalForce(c) > 0.0) {
        ++s.feet_down;
        s.feet_mask |= 1u << c;
      }
    if (const Solver* solver = mpc ? mpc->mpc().solver() : nullptr) {
      s.backward_passes = solver->backwardPasses();
      s.forward_passes = solver->forwardPasses();
    }
    s.solve_ms = status.solve_ms;
    s.prepare_ms = status.prepare_ms;
    s.tick_ms = status.tick_ms;
    s.clamped_steps = sim->simulator().counters().clamped_steps;
    s.tau = sim->simulator().appliedTorque();
    if (options.each) options.each(s);
    r.samples.push_back(std::move(s));
    if (!sim->advance(sim->stepsPerState())) break;  // fell or diverged
  }
  clock = sim->utime();
  if (sim->stats().fell) {
    // The fallen pose goes into the samples (its segment is marked fallen) and the log too.
    sim->publishState();
    Sample fallen = r.samples.empty() ? Sample{} : r.samples.back();
    fallen.t = t_offset + sim->simulator().time();
    fallen.q = sim->simulator().q();
    fallen.v = sim->simulator().v();
    fallen.ground = sim->simulator().terrain().height(fallen.q[0], fallen.q[1]);
    r.samples.push_back(std::move(fallen));
  }
  drain(lcm);
  r.sim = sim->stats();
  r.sim_auth_text = msg::refusedText(sim->auth());
  r.sim_stale = sim->auth().refused(msg::Verdict::Stale);
  r.sim_before_restart = sim_before;
  if (mpc) keepFigures();
  r.mpc = mpc_counters;
  r.command_counters = command_counters;
  r.rejected = rejected;
  r.rival_policies = rival_policies;
  r.q_end = sim->simulator().q();
  r.terrain = sim->simulator().terrain().name();
  const sim::SimCounters& counters = sim->simulator().counters();
  r.trips = counters.trips;
  r.footholds = counters.footholds;
  r.edge_footholds = counters.edge_footholds;
  r.min_edge_distance = counters.min_edge_distance;
  r.sole_flat_fraction = sim::soleFlatFraction(counters);
  r.footholds_text = sim::footholdText(counters, sim->simulator().options());
  r.base_above_terrain = sim->stats().above;
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
    b.ground = s.ground;
    out.push_back(b);
  }
  return out;
}

std::vector<logs::Segment> Run::segments(const logs::SegmentOptions& options) const {
  return logs::segmentCommands(commands, baseSamples(), options);
}

}  // namespace stride::drive
