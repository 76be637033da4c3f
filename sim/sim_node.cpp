#include "sim/sim_node.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <random>

#include "config/model_hash.hpp"
#include "messages/hold_pd.hpp"
#include "sim/ground_contact.hpp"
#include "solver/multibody/frames.hpp"
#include "solver/multibody/kinematics.hpp"
#include "solver/multibody/model.hpp"

namespace stride::sim {

namespace {
// The option when given, else the robot's own, else a fallback.
double holdGain(double option, double robot, double fallback) {
  return option >= 0.0 ? option : robot > 0.0 ? robot : fallback;
}

std::vector<StandDownContact> standDownContacts(const Robot& robot) {
  std::vector<StandDownContact> contacts;
  for (const ContactSpec& c : robot.contacts)
    contacts.push_back({robot.model.getFrameId(c.frame), c.dim});
  return contacts;
}
}  // namespace

Eigen::VectorXd startingPose(const Robot& robot, const terrain::Terrain& terrain,
                             double drop_height) {
  Eigen::VectorXd q = robot.default_q;
  if (!robot.model.hasFreeFlyer()) return q;
  // The default posture stands on z = 0: each contact point's lift is the terrain's height under
  // it; the highest lift puts every point on or above the surface.
  Data data(robot.model);
  forwardKinematics(robot.model, data, q);
  double lift = -std::numeric_limits<double>::infinity();
  for (const ContactPoint& pt : contactPointsFromRobot(robot)) {
    const Frame& frame = robot.model.frames[pt.frame];
    const SE3& oMj = data.oMi[frame.parentJoint];
    const Eigen::Vector3d p = oMj.R * (frame.placement.R * pt.offset + frame.placement.p) + oMj.p;
    lift = std::max(lift, terrain.height(p.x(), p.y()));
  }
  if (!std::isfinite(lift)) lift = terrain.height(q[0], q[1]);  // no contacts: under the base
  q[2] += lift + drop_height;
  return q;
}

SimNode::SimNode(const Robot& robot, const SimOptions& sim, const SimNodeOptions& options,
                 Publisher& out)
    : robot_(robot),
      options_(options),
      plant_(options.plant.enabled() ? plantOf(robot, options.plant) : robot),
      sim_(plant_, sim),
      auth_(options.key ? msg::WireAuth(*options.key, "stride-sim",
                                        std::llround(options.signature_window * 1e6))
                        : msg::WireAuth()),
      signed_out_(out, auth_, 1 << 12),
      out_(signed_out_),
      evaluator_(robot.model, actuatedDimension(robot.model)),
      hold_(robot.model, robot.default_q,
            holdGain(options.hold_kp, robot.joint_kp, msg::kDefaultHoldKp),
            holdGain(options.hold_kd, robot.joint_kd, msg::kDefaultHoldKd), sim.dt),
      stand_down_(robot.model, hold_, standDownContacts(robot), options.stand_down),
      mapper_(sim_.terrain(), options.map, sim.dt),
      sensing_(robot.model, options.sensing, sim.dt, options.seed + 3),
      actuators_(plant_.model, robot.default_q, options.actuators, sim.dt),
      delay_(robot.model.nq, robot.model.nv, options.delay),
      dropper_(options.drop, options.seed + 1) {
  const Model& model = robot.model;
  steps_per_state_ =
      std::max(1, static_cast<int>(std::lround(1.0 / (options.state_rate_hz * sim.dt))));
  msg::shape(state_msg_, model.nq, model.nv, static_cast<int>(robot.contacts.size()));
  state_msg_.model_hash = modelHash(robot);
  wire_ = {state_msg_.model_hash, model.nq, model.nv, sim_.nu(), robot_.name.c_str()};
  newSession();
  // The policies' sizes, one per knot count: a frame of any other size is refused before hashing.
  const int one = msg::policyWireSize(1, model.nq, model.nv, sim_.nu());
  auth_.setSizes(0,
                 {one, msg::policyWireSize(options.max_policy_knots, model.nq, model.nv, sim_.nu()),
                  msg::policyWireSize(2, model.nq, model.nv, sim_.nu()) - one});
  buffer_.resize(state_msg_.getEncodedSize());
  signed_out_.reserve(std::max(static_cast<int>(buffer_.size()), mapper_.messageSize()));
  q_pub_ = Eigen::VectorXd::Zero(model.nq);
  v_pub_ = Eigen::VectorXd::Zero(model.nv);
  tau_cmd_ = Eigen::VectorXd::Zero(sim_.nu());
  tau_ = Eigen::VectorXd::Zero(sim_.nu());
}

SimNode::~SimNode() {
  if (bus_ != nullptr && subscription_ != nullptr) bus_->unsubscribe(subscription_);
}

void SimNode::subscribe(lcm::LCM& in) {
  bus_ = &in;
  subscription_ = in.subscribe(options_.policy_channel, &SimNode::onPolicy, this);
  subscription_->setQueueCapacity(100);
}

std::int64_t SimNode::utime() const {
  return options_.utime_base + static_cast<std::int64_t>(std::llround(sim_.time() * 1e6));
}

void SimNode::newSession() {
  // Random and nonzero: two runs (two days, two lock-step runs whose clocks both start at 0) never
  // share one, and no policy answers a run it was not made for.
  std::random_device entropy;
  std::int64_t id = 0;
  while (id == 0) id = static_cast<std::int64_t>((std::uint64_t(entropy()) << 32) | entropy());
  session_ = id;
  state_msg_.session = id;
}

void SimNode::reset(const Eigen::VectorXd& q, const Eigen::VectorXd& v) {
  newSession();  // the robot's clock starts again: another run
  sim_.reset(q, v, 0.0);
  sensing_.reset(q, v);
  sensed_at_ = -1;
  actuators_.reset();
  delay_.clear();
  have_policy_ = false;
  standing_down_ = false;
  last_answer_ = -1;
  have_source_ = false;
  n_rivals_ = 0;
  stats_ = SimNodeStats{};
  stats_.x0 = q[0];
  stats_.y0 = q[1];
  stats_.z0 = q[2];
  stats_.above0 = q[2] - baseTerrainHeight(q);
  mapper_.reset();
  track();
}

void SimNode::onPolicy(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
  const Model& model = robot_.model;
  // With a key, a policy not signed with it is never read (a rival or a forger without the key
  // changes nothing on the robot).
  const int size = auth_.receive(0, channel.c_str(), static_cast<const std::uint8_t*>(rbuf->data),
                                 static_cast<int>(rbuf->data_size), rbuf->recv_utime);
  if (size < 0) {
    ++stats_.policies_unauthenticated;
    ++stats_.policies_rejected;
    return;
  }
  // Cheap checks on the raw bytes first (model, sizes, session, source): a flood of foreign
  // policies costs no decoding.
  const msg::Reject wire = msg::checkPolicyWire(rbuf->data, size, wire_, options_.max_policy_knots);
  if (wire == msg::Reject::WrongModel) noteWrongModel(rbuf->data, size, channel);
  // A policy made for another run of this robot (a recording of an earlier run, or of a run
  // whose clock also started at 0) is refused whatever its stamps, before it can take the
  // robot from its controller (messages/README.md, "Sessions").
  std::int64_t session = 0;
  if (wire == msg::Reject::None && msg::readPolicySession(rbuf->data, size, session) &&
      session != session_) {
    ++stats_.policies_rejected;
    if (++stats_.policies_other_session == 1) {
      char theirs[17], ours[17];
      msg::formatHash(session, theirs);
      msg::formatHash(session_, ours);
      std::fprintf(stderr,
                   "stride-sim: refused a policy on '%s' made for another run of the robot "
                   "(session %s; this run is %s): a recording, or another run's controller (the "
                   "first such; the later ones are counted)\n",
                   channel.c_str(), theirs, ours);
    }
    return;
  }
  std::int64_t source = 0;
  if (wire == msg::Reject::None && msg::readPolicySource(rbuf->data, size, source) &&
      !followSource(source, channel)) {
    ++stats_.policies_rejected;
    return;
  }
  const bool ok = wire == msg::Reject::None && incoming_.decode(rbuf->data, 0, size) >= 0 &&
                  msg::checkPolicy(incoming_, model.hasFreeFlyer()) == msg::Reject::None;
  if (!ok) {
    ++stats_.policies_rejected;
    return;
  }
  auth_.accept(0);  // taken: only now is its signature's timestamp remembered against replay
  source_ = source;
  have_source_ = true;
  source_seen_ = sim_.time();
  if (policy_.knots != incoming_.knots)
    policy_.resize(incoming_.knots, model.nq, model.nv, sim_.nu());
  // In double: a stamp near -2^63 minus the base would overflow int64 (undefined behaviour; found
  // by the message fuzzer).
  policy_.t0 =
      (static_cast<double>(incoming_.knot0_utime) - static_cast<double>(options_.utime_base)) *
      1e-6;
  policy_.dt = incoming_.dt;
  for (int k = 0; k < incoming_.knots; ++k) {
    std::copy(incoming_.x_ref[k].begin(), incoming_.x_ref[k].end(), policy_.xRef(k));
    std::copy(incoming_.u_ff[k].begin(), incoming_.u_ff[k].end(), policy_.uFf(k));
    std::copy(incoming_.K[k].begin(), incoming_.K[k].end(), policy_.gain(k));
  }
  have_policy_ = true;
  last_answer_ = std::max(last_answer_, incoming_.utime);
  ++stats_.policies;
  // At or past its end on arrival (to the stamps' microsecond): the robot cannot follow it, and
  // stands down past the grace. Said for the first two; the summaries say how many (whyText).
  const double now = sim_.time(), end = policy_.t0 + (policy_.knots - 1) * policy_.dt;
  stats_.policy_span = end - policy_.t0;
  if (now > end - 1e-6) {
    stats_.expired_by_max = std::max(stats_.expired_by_max, now - end);
    if (++stats_.policies_expired <= 2)
      std::fprintf(stderr,
                   "stride-sim: a policy arrived %.3f s after its end: it covers %.3f s from a "
                   "state %.3f s old; the estimates' latency and the controller's answer together "
                   "take as long as a policy lasts or longer, and the robot cannot follow it\n",
                   std::max(0.0, now - end), stats_.policy_span, now - policy_.t0);
  }
}

std::string whyText(const SimNodeStats& s) {
  std::string why;
  char text[320];
  if (s.policies_expired > 0) {
    std::snprintf(text, sizeof text,
                  "%lld of %lld policies arrived at or after their end (up to %.3f s after; a "
                  "policy covers %.3f s): the estimates' latency and the controller's answer "
                  "together took as long as a policy lasts or longer",
                  static_cast<long long>(s.policies_expired), static_cast<long long>(s.policies),
                  s.expired_by_max, s.policy_span);
    why += text;
    if (s.stand_downs > 0) {
      std::snprintf(text, sizeof text, "; past a policy's end the robot stood down (%lld times)",
                    static_cast<long long>(s.stand_downs));
      why += text;
    }
  }
  if (s.steps > 0 && s.policy_steps == 0) {
    if (!why.empty()) why += "; ";
    why += s.policies == 0 ? "no policy came: the robot stood on its hold PD for the whole run"
                           : "no policy was ever in force: the robot stood for the whole run";
  }
  return why;
}

bool SimNode::followSource(std::int64_t source, const std::string& channel) {
  if (!have_source_ || source == source_) return true;
  const double silent = sim_.time() - source_seen_;
  char theirs[17], ours[17];
  msg::formatHash(source, theirs);
  msg::formatHash(source_, ours);
  if (silent >= options_.source_timeout) {  // the followed controller stopped: a restart, say
    // Said for the first switches (a restart or two); a run that switches all the time says so
    // in its summary's count.
    if (++stats_.source_switches <= 4)
      std::fprintf(stderr,
                   "stride-sim: following the controller %s on '%s' (%s silent for %.3f s)\n",
                   theirs, channel.c_str(), ours, silent);
    return true;
  }
  ++stats_.policies_rival;
  for (int i = 0; i < n_rivals_; ++i)
    if (rivals_[i] == source) return false;
  if (n_rivals_ < static_cast<int>(rivals_.size())) {
    rivals_[n_rivals_++] = source;
    std::fprintf(stderr,
                 "stride-sim: refused the policies of a rival controller %s on '%s': following "
                 "%s, which is alive\n",
                 theirs, channel.c_str(), ours);
  }
  return false;
}

void SimNode::noteWrongModel(const void* buf, int size, const std::string& channel) {
  ++stats_.policies_wrong_model;
  msg::WireClaim claim;
  if (!msg::readPolicyClaim(buf, size, claim)) return;
  for (int i = 0; i < n_mismatches_; ++i)
    if (mismatches_[i] == claim) return;
  if (n_mismatches_ == static_cast<int>(mismatches_.size())) return;
  mismatches_[n_mismatches_++] = claim;
  char text[200];
  std::fprintf(stderr, "stride-sim: refused a policy on '%s': %s\n", channel.c_str(),
               msg::describeMismatch(wire_, claim, text, sizeof text));
}

void SimNode::sense() {
  if (sensed_at_ == stats_.steps) return;
  sensing_.sample(sim_.q(), sim_.v());
  sensed_at_ = stats_.steps;
  stats_.sensor_drops = sensing_.dropped();
}

std::int64_t SimNode::publishState() {
  const Model& model = robot_.model;
  sense();
  // The estimate is of the state `latency` steps ago, and says so in its stamp.
  double t = std::max(0.0, sim_.time() - sensing_.latency() * sim_.options().dt);
  q_pub_ = qSensed();
  v_pub_ = vSensed();
  if (delay_.delay() > 0) {
    delay_.push(t, q_pub_, v_pub_);
    if (!delay_.delayed(t, q_pub_, v_pub_)) return -1;  // not enough history yet
  }
  if (dropper_.drop()) {
    ++stats_.states_dropped;
    return -1;
  }
  state_msg_.utime = options_.utime_base + static_cast<std::int64_t>(std::llround(t * 1e6));
  std::copy(q_pub_.data(), q_pub_.data() + model.nq, state_msg_.q.begin());
  std::copy(v_pub_.data(), v_pub_.data() + model.nv, state_msg_.v.begin());
  for (int c = 0; c < state_msg_.ncontacts; ++c)
    state_msg_.contact[c] = sim_.normalForce(c) > 0.0 ? 1 : 0;
  if (state_fault_ && !state_fault_(state_msg_, t)) {
    ++stats_.states_dropped;
    return -1;
  }
  const int n = state_msg_.encode(buffer_.data(), 0, static_cast<int>(buffer_.size()));
  if (n > 0) out_.publish(options_.state_channel, buffer_.data(), n);
  ++stats_.states_published;
  stats_.last_state_utime = state_msg_.utime;
  return state_msg_.utime;
}

bool SimNode::advance(int steps) {
  for (int i = 0; i < steps; ++i) {
    const double t = sim_.time();
    const Vector6d push = options_.pushes.wrenchAt(t);
    if (!push.isZero()) sim_.applyExternalWrench(push, options_.pushes.activeUntil(t));
    // The low-level loop has only what the robot senses (sim/sensing.hpp).
    sense();
    const Eigen::VectorXd& q_hat = qSensed();
    const Eigen::VectorXd& v_hat = vSensed();
    msg::PolicyStatus status = msg::PolicyStatus::Invalid;
    if (have_policy_) status = evaluator_.evaluate(policy_, t, q_hat, v_hat, tau_cmd_);
    if (status == msg::PolicyStatus::Exhausted) {
      // Past the policy's end (by the grace, 0 by default: sim/README.md) the controller is lost.
      const double end = policy_.t0 + (policy_.knots - 1) * policy_.dt;
      if (!standing_down_ && t - end > options_.stand_down.grace) {
        const int last = policy_.knots - 1;
        stand_down_.begin(t, q_hat,
                          Eigen::Map<const Eigen::VectorXd>(policy_.uFf(last), sim_.nu()));
        standing_down_ = true;
        if (++stats_.stand_downs <= 4)
          std::fprintf(stderr,
                       "stride-sim: no policy for %.3f s past the last one's end: standing down "
                       "(sim/README.md, \"Controller loss\")\n",
                       t - end);
      }
      if (standing_down_) {
        unsigned on_ground = 0;  // the robot's contact sensing
        for (int c = 0; c < static_cast<int>(robot_.contacts.size()) && c < 32; ++c)
          if (sim_.normalForce(c) > 0.0) on_ground |= 1u << c;
        stand_down_.torque(t, q_hat, v_hat, on_ground, tau_cmd_);
        ++stats_.stand_down_steps;
      } else {
        ++stats_.exhausted_steps;
      }
    } else if (status != msg::PolicyStatus::Invalid) {
      standing_down_ = false;  // a policy in force again: the controller is back
      ++stats_.policy_steps;
    }
    if (status == msg::PolicyStatus::Invalid) {
      hold_.torque(robot_.model, q_hat, v_hat, tau_cmd_);
      ++(have_policy_ ? stats_.hold_steps : stats_.waiting_steps);
    }
    actuators_.apply(tau_cmd_, sim_.v(), tau_);
    stats_.envelope_steps = actuators_.envelopeSteps();
    const StepStatus step = sim_.step(tau_);
    ++stats_.steps;
    if (step == StepStatus::NonFiniteState || step == StepStatus::SingularMassMatrix) {
      stats_.diverged = true;
      return false;
    }
    track();
    const Eigen::VectorXd& q = sim_.q();
    if (robot_.model.hasFreeFlyer())
      mapper_.step(sim_.time(), options_.utime_base, q[0], q[1], out_);
    else
      mapper_.step(sim_.time(), options_.utime_base, 0.0, 0.0, out_);
    if (stats_.fell) return false;
  }
  return true;
}

double SimNode::baseTerrainHeight(const Eigen::VectorXd& q) const {
  return robot_.model.hasFreeFlyer() ? sim_.terrain().height(q[0], q[1]) : sim_.terrain().ground();
}

void SimNode::track() {
  const Eigen::VectorXd& q = sim_.q();
  stats_.z_min = std::min(stats_.z_min, q[2]);
  stats_.z_max = std::max(stats_.z_max, q[2]);
  // Fallen is low over the ground under the base, not low in the world (sim/fall.hpp: the one
  // criterion, the log summary's too).
  stats_.above = q[2] - baseTerrainHeight(q);
  stats_.above_min = std::min(stats_.above_min, stats_.above);
  const double tilt = baseTilt(q[3], q[4], q[5], q[6]);
  stats_.max_tilt_deg = std::max(stats_.max_tilt_deg, tilt * 180.0 / M_PI);
  for (int c = 0; c < static_cast<int>(robot_.contacts.size()); ++c)
    stats_.peak_normal_force = std::max(stats_.peak_normal_force, sim_.normalForce(c));
  if (fallen(stats_.above, stats_.above0, tilt, options_.fall)) stats_.fell = true;
}

void SimNode::writeSummary(const std::string& path) const {
  const SimNodeStats& s = stats_;
  const Eigen::VectorXd& q = sim_.q();
  const double distance = std::hypot(q[0] - s.x0, q[1] - s.y0);
  std::printf(
      "stride-sim: %.2f s simulated, walked %.3f m (x %+.3f), base height %.3f .. %.3f m, max "
      "tilt %.1f deg, %s; %lld states published (%lld dropped), %lld policies (%lld rejected, "
      "%lld of another model, %lld of a rival controller; %lld controller switches), %lld steps on "
      "the hold PD before the first policy and %lld after, %lld past a policy's end, %lld "
      "standing down (%lld stand-downs), %lld lock-step timeouts\n",
      sim_.time(), distance, q[0] - s.x0, s.z_min, s.z_max, s.max_tilt_deg,
      s.diverged ? "DIVERGED" : (s.fell ? "FELL" : "did not fall"),
      static_cast<long long>(s.states_published), static_cast<long long>(s.states_dropped),
      static_cast<long long>(s.policies), static_cast<long long>(s.policies_rejected),
      static_cast<long long>(s.policies_wrong_model), static_cast<long long>(s.policies_rival),
      static_cast<long long>(s.source_switches), static_cast<long long>(s.waiting_steps),
      static_cast<long long>(s.hold_steps), static_cast<long long>(s.exhausted_steps),
      static_cast<long long>(s.stand_down_steps), static_cast<long long>(s.stand_downs),
      static_cast<long long>(s.lockstep_timeouts));
  if (auth_.keyed())
    std::printf(
        "stride-sim: signed with key %08x; %lld policies not signed with it (or not fresh) "
        "refused%s%s%s\n",
        auth_.keyId(), static_cast<long long>(s.policies_unauthenticated),
        auth_.refused() > 0 ? " (" : "", msg::refusedText(auth_).c_str(),
        auth_.refused() > 0 ? ")" : "");
  const terrain::Terrain& terrain = sim_.terrain();
  const SimCounters& counters = sim_.counters();
  std::printf(
      "stride-sim: terrain '%s'; final base (%.3f, %.3f, %.3f) m, %.3f m above the terrain under "
      "it (lowest %.3f, start %.3f); %lld trips (a foot pushing on a vertical face); %lld terrain "
      "maps published\n",
      terrain.name().c_str(), q[0], q[1], q[2], s.above, s.above_min, s.above0,
      static_cast<long long>(counters.trips), static_cast<long long>(mapper_.published()));
  std::printf("stride-sim: %s\n", footholdText(counters, sim_.options()).c_str());
  const std::string why = whyText(s);
  if (!why.empty()) std::printf("stride-sim: why: %s\n", why.c_str());
  if (path.empty()) return;
  nlohmann::ordered_json j;
  j["sim_time_s"] = sim_.time();
  j["distance_m"] = distance;
  j["base_height_min_m"] = s.z_min;
  j["base_height_max_m"] = s.z_max;
  j["max_tilt_deg"] = s.max_tilt_deg;
  j["fell"] = s.fell || s.diverged;
  j["diverged"] = s.diverged;
  j["peak_normal_force_N"] = s.peak_normal_force;
  j["states_published"] = s.states_published;
  // A log's reader tells from it whether the logger had every state (stride-log-summary).
  j["last_state_utime"] = s.last_state_utime;
  j["policies"] = s.policies;
  j["policies_rejected"] = s.policies_rejected;
  j["policies_wrong_model"] = s.policies_wrong_model;
  j["policies_rival"] = s.policies_rival;
  j["policies_unauthenticated"] = s.policies_unauthenticated;
  j["policies_other_session"] = s.policies_other_session;
  j["source_switches"] = s.source_switches;
  j["waiting_steps"] = s.waiting_steps;
  j["hold_steps"] = s.hold_steps;
  j["exhausted_steps"] = s.exhausted_steps;
  j["stand_downs"] = s.stand_downs;
  j["stand_down_steps"] = s.stand_down_steps;
  j["lockstep_timeouts"] = s.lockstep_timeouts;
  j["policies_expired"] = s.policies_expired;
  j["policy_steps"] = s.policy_steps;
  j["sensor_drops"] = s.sensor_drops;
  j["envelope_steps"] = s.envelope_steps;
  j["why"] = why.empty() ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(why);
  j["terrain"] = terrain.name();
  // A fixed-base robot has no base: its q starts with joints.
  j["final_base"] = robot_.model.hasFreeFlyer() ? nlohmann::ordered_json({q[0], q[1], q[2]})
                                                : nlohmann::ordered_json(nullptr);
  j["base_height_above_terrain_m"] = s.above;
  j["base_height_above_terrain_min_m"] = s.above_min;
  j["trips"] = counters.trips;
  j["footholds"] = counters.footholds;
  j["edge_footholds"] = counters.edge_footholds;
  // No touch-down had an edge within the search radius: null, not infinity (not JSON).
  j["min_edge_distance_m"] = std::isfinite(counters.min_edge_distance)
                                 ? nlohmann::ordered_json(counters.min_edge_distance)
                                 : nlohmann::ordered_json(nullptr);
  const double flat = sim::soleFlatFraction(counters);
  j["sole_flat_fraction"] =
      std::isfinite(flat) ? nlohmann::ordered_json(flat) : nlohmann::ordered_json(nullptr);
  j["terrain_maps"] = mapper_.published();
  std::ofstream f(path);
  f << j.dump(2) << "\n";
  if (!f) std::fprintf(stderr, "stride-sim: cannot write the summary to '%s'\n", path.c_str());
}

}  // namespace stride::sim
