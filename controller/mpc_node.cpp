#include "controller/mpc_node.hpp"

#include <time.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <random>

#include "config/model_hash.hpp"
#include "solver/contact/contact_set.hpp"

namespace stride {

namespace {
// A state's contact flags: at most the contact limit (solver/contact/contact_set.hpp).
constexpr int kMaxContactFlags = kMaxContacts;
constexpr int kMaxPlanPhases = 100000;
constexpr int kQueueCapacity = 1000;  // > 1 s of a 1 kHz estimator between two drains
constexpr long kLatencyCapacity = 1L << 20;
constexpr std::int64_t kMaxStampLeadUs = 1000000;  // stamps may run 1 s ahead of the arrivals
// A stream refused on its stamps for this many states (and, in real time, this long) is the
// robot's clock (MpcNode::onState).
constexpr int kRebaseStates = 20;
constexpr std::int64_t kRebaseUs = 200000;
constexpr std::int64_t kMaxRebaseWarnings = 5;
// The controller follows one robot run (robot_state_t.session): another's states take over only
// after the followed one has been silent this long (real time: its restarts take seconds), or (in
// stamps mode, with no clock but the states') after this many of them in a row with none of the
// followed run between. A recording or another run interleaved with the live robot never does.
constexpr std::int64_t kSessionSilenceUs = 200000;
constexpr int kSessionSwitchStates = 3;
// A rival controller's policies may have more knots than ours: any count up to this one.
constexpr int kMaxRivalKnots = 200;
// A command's payload: the fixed fields and a gait name of at most kMaxGaitName characters.
constexpr int kCommandFixedBytes = 8 + 8 + 3 * 8 + 4 + 1 + 8 + 4 + 4 * 8;
// What the signing publisher preallocates before the node knows its messages' sizes (reserve).
constexpr int kSignedCapacity = 1 << 12;
}  // namespace

MpcNode::MpcNode(const ControllerConfig& config, Publisher& out, TimeSource time)
    : config_(config),
      mpc_(config),
      auth_(config.key_file.empty() ? msg::WireAuth()
                                    : msg::WireAuth(msg::loadKeyFile(config.key_file), "stride-mpc",
                                                    std::llround(config.signature_window * 1e6))),
      signed_out_(out, auth_, kSignedCapacity),
      out_(signed_out_),
      time_(time),
      commands_(config.command, mpc_.gaits()) {
  const Model& model = mpc_.robot().model;
  floating_ = model.hasFreeFlyer();
  msg::shape(incoming_, model.nq, model.nv, kMaxContactFlags);
  msg::shape(newest_, model.nq, model.nv, kMaxContactFlags);
  newest_.session = incoming_.session = 0;  // no robot run yet (lcm-gen leaves fields unset)
  mpc_status_t status{};
  status.gait.assign(msg::kMaxGaitName, 'x');  // the longest a status may carry
  buffer_.resize(std::max(msg::policyWireSize(config.policy_knots, model.nq, model.nv, mpc_.nu()),
                          status.getEncodedSize()));
  latencies_.reserve(kLatencyCapacity);
  command_msg_.gait.reserve(msg::kMaxGaitName + 1);  // decoding a gait name then never allocates
  // A source id per start: the robot follows one controller and tells a rival (or this one
  // restarted) apart. Never 0, which a test or a tool may use.
  std::random_device entropy;
  std::int64_t id = 0;
  while (id == 0) id = static_cast<std::int64_t>((std::uint64_t(entropy()) << 32) | entropy());
  setSourceId(id);
  wire_.hash = mpc_.modelHash();
  wire_.nq = model.nq;
  wire_.nv = model.nv;
  wire_.nu = mpc_.nu();
  wire_.robot = mpc_.robot().name.c_str();  // the Mpc owns the robot: stable
  const robot_model_t m = robotModelMessage(mpc_.robot(), mpc_.nu());
  model_buffer_.resize(m.getEncodedSize());
  m.encode(model_buffer_.data(), 0, static_cast<int>(model_buffer_.size()));
  mpc_.status().wrong_model_cause.reserve(sizeof(ModelMismatch::text));
  mpc_.status().jump_refusal.reserve(sizeof(JumpStatus::refusal));
  // Shaped with every foothold it can carry: the buffer fits the largest horizon, and writing one
  // with fewer footholds only lowers nfootholds.
  msg::shape(horizon_, mpc_.horizonKnots(), model.nq,
             static_cast<int>(mpc_.robot().contacts.size()), mpc_.horizonFootholds());
  horizon_buffer_.resize(horizon_.getEncodedSize());
  signed_out_.reserve(
      static_cast<int>(std::max({buffer_.size(), horizon_buffer_.size(), model_buffer_.size()})));
  // The sizes each channel's type can have for this robot: any other is refused before hashing
  // (messages/README.md, "Cheap refusals").
  auth_.setSizes(kStateSlot, {msg::stateWireSize(model.nq, model.nv, 0),
                              msg::stateWireSize(model.nq, model.nv, kMaxContactFlags), 1});
  auth_.setSizes(kCommandSlot, {kCommandFixedBytes, kCommandFixedBytes + msg::kMaxGaitName, 1});
  const int one = msg::policyWireSize(1, model.nq, model.nv, mpc_.nu());
  auth_.setSizes(kPolicySlot,
                 {one, msg::policyWireSize(kMaxRivalKnots, model.nq, model.nv, mpc_.nu()),
                  msg::policyWireSize(2, model.nq, model.nv, mpc_.nu()) - one});
  auth_.setSizes(
      kTerrainSlot,
      {0, static_cast<std::int64_t>(msg::terrainWireSize(1, config.terrain.max_cells)), 1});
}

robot_model_t robotModelMessage(const Robot& robot, int nu) {
  robot_model_t m;
  m.robot = robot.name;
  m.model_hash = modelHash(robot);
  m.nq = robot.model.nq;
  m.nv = robot.model.nv;
  m.nu = nu;
  for (const WireJoint& j : wireJoints(robot.model)) {
    m.joint_names.push_back(j.name);
    m.joint_types.push_back(j.type);
    m.joint_idx_q.push_back(j.idx_q);
    m.joint_idx_v.push_back(j.idx_v);
  }
  m.njoints = static_cast<std::int32_t>(m.joint_names.size());
  for (const ContactSpec& c : robot.contacts) m.contact_frames.push_back(c.frame);
  m.ncontacts = static_cast<std::int32_t>(m.contact_frames.size());
  return m;
}

void MpcNode::noteWrongModel(const void* buf, int size, const std::string& channel) {
  msg::WireClaim claim;
  if (!msg::readStateClaim(buf, size, claim)) return;
  for (int i = 0; i < n_mismatches_; ++i)
    if (mismatches_[i].claim == claim) {
      ++mismatches_[i].count;
      latest_mismatch_ = i;
      return;
    }
  if (n_mismatches_ == kMaxMismatches) return;  // counted in rejected_; not described again
  ModelMismatch& m = mismatches_[n_mismatches_];
  m.claim = claim;
  m.count = 1;
  msg::describeMismatch(wire_, claim, m.text.data(), static_cast<int>(m.text.size()));
  latest_mismatch_ = n_mismatches_++;
  // Once per cause: a wiring error must be seen, and a flood of it must not flood the terminal.
  std::fprintf(stderr, "stride-mpc: refused a state on '%s': %s\n", channel.c_str(), m.text.data());
}

void MpcNode::publishHorizonIfDue() {
  if (config_.horizon_rate_hz <= 0.0) return;
  const double t = now();
  if (t - horizon_sent_at_ < 1.0 / config_.horizon_rate_hz - 1e-9) return;
  if (!mpc_.writeHorizon(horizon_)) return;  // not solved this tick: the next one
  const int n =
      horizon_.encode(horizon_buffer_.data(), 0, static_cast<int>(horizon_buffer_.size()));
  if (n > 0) out_.publish(config_.horizon_channel, horizon_buffer_.data(), n);
  horizon_sent_at_ = t;
}

void MpcNode::publishModelIfDue() {
  const double t = now();
  if (model_sent_ && t - model_sent_at_ < 1.0) return;
  out_.publish(config_.model_channel, model_buffer_.data(), static_cast<int>(model_buffer_.size()));
  model_sent_ = true;
  model_sent_at_ = t;
}

double MpcNode::now() const {
  return time_ == TimeSource::RealTime ? static_cast<double>(monotonicMicros()) * 1e-6
                                       : static_cast<double>(newest_.utime) * 1e-6;
}

std::int64_t MpcNode::monotonicMicros() {
  timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1000000 + ts.tv_nsec / 1000;
}

void MpcNode::setSourceId(std::int64_t id) {
  source_id_ = id;
  mpc_.setSourceId(id);
  mpc_.status().source_id = id;
}

MpcNode::~MpcNode() {
  if (bus_ != nullptr)
    for (lcm::Subscription* s : subscriptions_) bus_->unsubscribe(s);
}

void MpcNode::subscribe(lcm::LCM& in, bool watch_policies) {
  bus_ = &in;
  auto add = [&](lcm::Subscription* s, int capacity) {
    s->setQueueCapacity(capacity);
    subscriptions_.push_back(s);
  };
  add(in.subscribe(config_.state_channel, &MpcNode::onState, this), kQueueCapacity);
  if (watch_policies) add(in.subscribe(config_.policy_channel, &MpcNode::onPolicy, this), 100);
  add(in.subscribe(config_.plan_channel, &MpcNode::onPlan, this), 10);
  add(in.subscribe(config_.command_channel, &MpcNode::onCommand, this), 100);
  add(in.subscribe(config_.terrain_channel, &MpcNode::onTerrain, this), 2);
}

void MpcNode::reject(msg::Reject reason) {
  ++rejected_total_;
  ++rejected_[static_cast<int>(reason)];
}

int MpcNode::authenticated(int slot, const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
  const int size =
      auth_.receive(slot, channel.c_str(), static_cast<const std::uint8_t*>(rbuf->data),
                    static_cast<int>(rbuf->data_size), rbuf->recv_utime);
  if (size < 0) reject(msg::Reject::Unauthenticated);
  return size;
}

void MpcNode::onState(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
  const int size = authenticated(kStateSlot, rbuf, channel);
  if (size < 0) return;
  msg::Reject why = msg::checkStateWire(rbuf->data, size, wire_, kMaxContactFlags);
  if (why == msg::Reject::WrongModel) noteWrongModel(rbuf->data, size, channel);
  if (why == msg::Reject::None && !msg::decode(rbuf->data, size, incoming_))
    why = msg::Reject::Undecodable;
  if (why == msg::Reject::None) why = msg::checkState(incoming_, floating_);
  if (why != msg::Reject::None) {  // not a state at all: says nothing about the robot's clock
    reject(why);
    return;
  }
  const bool real_time = time_ == TimeSource::RealTime;
  const std::int64_t arrival_us = real_time ? arrivalMicros(rbuf->recv_utime) : incoming_.utime;
  if (!followSession(arrival_us, channel)) {
    reject(msg::Reject::OtherSession);
    return;
  }
  // The stamp checks: newer than the newest state, and (real time) not far ahead of the time that
  // really passed since it arrived, which a corrupt stamp or a clock jump would be.
  std::int64_t lead_us = 0;
  if (have_state_) {
    lead_us = incoming_.utime - newest_.utime - (real_time ? arrival_us - newest_arrival_us_ : 0);
    if (incoming_.utime <= newest_.utime)
      why = msg::Reject::OutOfOrder;
    else if (real_time && lead_us > kMaxStampLeadUs)
      why = msg::Reject::BadField;
  }
  if (why != msg::Reject::None) {
    // Refused on its stamp alone. A stream of them that goes on (stamps increasing among
    // themselves, for kRebaseStates states and kRebaseUs) is the robot's clock, not a corrupt
    // stamp: a clock offset or a new robot. Refusing it for good would lock the controller out
    // (issue 33): its clock is taken instead, and every time kept on the old one moves with it.
    if (streak_ > 0 && incoming_.utime > streak_utime_) {
      ++streak_;
    } else {
      streak_ = 1;
      streak_since_us_ = arrival_us;
    }
    streak_utime_ = incoming_.utime;
    const bool persists =
        streak_ >= kRebaseStates && (!real_time || arrival_us - streak_since_us_ >= kRebaseUs);
    if (!persists) {
      reject(why);
      return;
    }
    rebaseClock(lead_us);
  }
  streak_ = 0;
  newest_ = incoming_;  // same shapes: element copies only
  newest_arrival_us_ = arrival_us;
  have_state_ = true;
  new_state_ = true;
  ++accepted_;
  session_ = incoming_.session;
  have_session_ = true;
  session_seen_us_ = real_time ? arrival_us : 0;
  other_session_states_ = 0;
  auth_.accept(kStateSlot);  // taken: only now is its signature remembered against replay
}

bool MpcNode::followSession(std::int64_t arrival_us, const std::string& channel) {
  if (!have_session_ || incoming_.session == session_) return true;
  const bool real_time = time_ == TimeSource::RealTime;
  const bool silent = real_time ? arrival_us - session_seen_us_ >= kSessionSilenceUs
                                : ++other_session_states_ >= kSessionSwitchStates;
  char theirs[17], ours[17];
  msg::formatHash(incoming_.session, theirs);
  msg::formatHash(session_, ours);
  if (silent) {  // the robot (or its estimator) restarted: its new run is followed, from scratch
    mpc_.newRobotRun();
    if (++session_switches_ <= 4)
      std::fprintf(stderr, "stride-mpc: following the robot's run %s on '%s' (%s went silent)\n",
                   theirs, channel.c_str(), ours);
    return true;
  }
  if (rejected(msg::Reject::OtherSession) == 0)
    std::fprintf(stderr,
                 "stride-mpc: refused a state on '%s' of another run of the robot (session %s) "
                 "while the run followed (%s) is alive: a recording, or another robot on these "
                 "channels (the first such; the later ones are counted)\n",
                 channel.c_str(), theirs, ours);
  return false;
}

void MpcNode::rebaseClock(std::int64_t offset_us) {
  const bool ahead = offset_us > 0;
  std::int64_t& count = ahead ? rebases_ahead_ : rebases_back_;
  ++count;
  mpc_.shiftClock(offset_us);
  next_tick_utime_ += offset_us;
  if (count <= kMaxRebaseWarnings)
    std::fprintf(stderr,
                 "stride-mpc: warning: the robot's stamps %s %.3f s %s the time that passed and "
                 "stayed there for %d states: %s; its clock taken from here on%s\n",
                 ahead ? "jumped" : "went back", std::abs(offset_us) * 1e-6,
                 ahead ? "ahead of" : "behind", streak_,
                 ahead ? "a clock offset (its clock stepped, or its estimator restarted on "
                         "another clock)"
                       : "a new robot (a restarted robot or estimator, its clock started again)",
                 count == kMaxRebaseWarnings ? " (the later ones are only counted)" : "");
}

std::int64_t MpcNode::arrivalMicros(std::int64_t recv_utime) {
  // When LCM's receive thread got the message (recv_utime, wall clock), on CLOCK_MONOTONIC: not
  // when this tick drained the queue. A backlog (a controller started while the robot ran, or
  // stopped by the host) must not pass for fresh states, nor make the next fresh one look early.
  const std::int64_t now = monotonicMicros();
  if (recv_utime <= 0) return now;
  timespec ts;
  clock_gettime(CLOCK_REALTIME, &ts);
  const std::int64_t wall = static_cast<std::int64_t>(ts.tv_sec) * 1000000 + ts.tv_nsec / 1000;
  return now - std::clamp<std::int64_t>(wall - recv_utime, 0, 3600LL * 1000000);
}

void MpcNode::onPolicy(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
  // With a key, only a controller that has it is a rival (the robot refuses the others' policies
  // unread: they are counted as refused, not as a rival's).
  const int size = authenticated(kPolicySlot, rbuf, channel);
  std::int64_t source = 0;
  if (size < 0 || !msg::readPolicySource(rbuf->data, size, source)) return;
  if (source == source_id_) {
    // Our own, back from the bus: its signature is spent. A rival's are only watched (counted
    // each time), never remembered: a key holder's junk here must not refuse our own echoes.
    auth_.accept(kPolicySlot);
    return;
  }
  ++rival_policies_;
  for (int i = 0; i < n_rivals_; ++i)
    if (rivals_[i] == source) return;
  if (n_rivals_ == static_cast<int>(rivals_.size())) return;
  rivals_[n_rivals_++] = source;
  char theirs[17], ours[17];
  msg::formatHash(source, theirs);
  msg::formatHash(source_id_, ours);
  std::fprintf(stderr,
               "stride-mpc: warning: another controller (source %s) publishes policies on '%s', "
               "as this one (source %s) does: a robot follows one of them; stop the other\n",
               theirs, channel.c_str(), ours);
}

void MpcNode::onPlan(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
  const int size = authenticated(kPlanSlot, rbuf, channel);
  if (size < 0) return;
  msg::Reject why = msg::checkPlanWire(rbuf->data, size, kMaxContactFlags, kMaxPlanPhases);
  if (why == msg::Reject::None && plan_msg_.decode(rbuf->data, 0, size) < 0)
    why = msg::Reject::Undecodable;
  if (why == msg::Reject::None) why = msg::checkPlan(plan_msg_);
  if (why != msg::Reject::None) {
    reject(why);
    return;
  }
  auth_.accept(kPlanSlot);
  plan_pending_ = true;
}

void MpcNode::onCommand(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
  const int size = authenticated(kCommandSlot, rbuf, channel);
  if (size < 0) {
    ++commands_malformed_;
    return;
  }
  msg::Reject why = msg::checkCommandWire(rbuf->data, size);
  if (why == msg::Reject::None && command_msg_.decode(rbuf->data, 0, size) < 0)
    why = msg::Reject::Undecodable;
  if (why == msg::Reject::None) why = msg::checkCommand(command_msg_);
  // Stamps must increase while a sender speaks; after a silence the deadman acted on, any stamp
  // starts again (a restarted or another teleop, on its own clock: a stamp from the future must
  // not lock every later command out).
  if (why == msg::Reject::None && !commands_.silentAt(now()) &&
      command_msg_.utime <= last_command_utime_)
    why = msg::Reject::OutOfOrder;
  if (why != msg::Reject::None) {
    reject(why);
    ++commands_malformed_;
    return;
  }
  // An unknown gait is refused without consuming its stamp: the sender may resend it corrected.
  if (!commands_.receive(command_msg_, now())) {
    reject(msg::Reject::BadField);
    return;
  }
  last_command_utime_ = command_msg_.utime;
  auth_.accept(kCommandSlot);
}

void MpcNode::onTerrain(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
  const int size = authenticated(kTerrainSlot, rbuf, channel);
  if (size < 0) return;
  msg::Reject why = msg::checkTerrainWire(rbuf->data, size, config_.terrain.max_cells);
  if (why == msg::Reject::None && terrain_msg_.decode(rbuf->data, 0, size) != size)
    why = msg::Reject::Undecodable;
  if (why == msg::Reject::None) why = msg::checkTerrain(terrain_msg_);
  // Mpc::setTerrain refuses a map older than the one in use (out of order) or larger than
  // terrain.max_cells (the wire check has refused those already).
  if (why == msg::Reject::None && !mpc_.setTerrain(terrain_msg_)) why = msg::Reject::OutOfOrder;
  if (why != msg::Reject::None)
    reject(why);
  else
    auth_.accept(kTerrainSlot);
}

void MpcNode::applyPendingPlan() {
  if (!plan_pending_) return;
  plan_pending_ = false;
  ContactPlan plan;
  plan.cyclic = plan_msg_.cyclic != 0;
  for (int i = 0; i < plan_msg_.nphases; ++i) {
    ContactPhase phase{plan_msg_.duration[i], {}};
    for (int c = 0; c < plan_msg_.ncontacts; ++c)
      if (plan_msg_.closed[i][c]) phase.contacts.push_back(plan_msg_.contacts[c]);
    plan.phases.push_back(phase);
  }
  try {
    mpc_.setPlan(plan, plan_msg_.utime);
    ++plan_updates_;
  } catch (const std::exception&) {  // e.g. a contact this robot does not have
    reject(msg::Reject::BadField);
  }
}

bool MpcNode::tickDue() const {
  return new_state_ && (!tick_grid_set_ || newest_.utime >= next_tick_utime_);
}

void MpcNode::tick(Clock::time_point deadline) {
  const Clock::time_point start = Clock::now();
  publishModelIfDue();
  const robot_state_t* state = have_state_ ? &newest_ : nullptr;
  const double age = !have_state_ || time_ == TimeSource::Stamps
                         ? 0.0
                         : static_cast<double>(monotonicMicros() - newest_arrival_us_) * 1e-6;
  commands_.update(now());
  mpc_.setCommand(commands_.command(), commands_.gait());
  int jump_id;
  JumpTarget jump;
  if (commands_.takeJump(jump_id, jump)) mpc_.requestJump(jump_id, jump);
  mpc_.setSession(newest_.session);  // the run its policy answers (policy_t.session)
  const bool publish = mpc_.tick(state, age, deadline);
  new_state_ = false;
  if (have_state_) {
    // The tick grid of stamps mode: every period from the first state on.
    const auto period_us = static_cast<std::int64_t>(std::llround(1e6 / config_.rate_hz));
    if (!tick_grid_set_) {
      next_tick_utime_ = newest_.utime;
      tick_grid_set_ = true;
    }
    while (next_tick_utime_ <= newest_.utime) next_tick_utime_ += period_us;
  }
  if (publish) {
    const policy_t& policy = mpc_.policy();
    const int n = policy.encode(buffer_.data(), 0, static_cast<int>(buffer_.size()));
    if (n > 0) {
      out_.publish(config_.policy_channel, buffer_.data(), n);
      ++policies_published_;
    }
  }
  if (publish && !mpc_.startupTick()) {  // the first solve has no deadline: not a latency
    const float ms = std::chrono::duration<float, std::milli>(Clock::now() - start).count();
    if (static_cast<long>(latencies_.size()) < kLatencyCapacity)
      latencies_.push_back(ms);  // within the reserved capacity: no allocation
    else
      latencies_[latency_count_ % kLatencyCapacity] = ms;
    ++latency_count_;
  }
  if (publish) publishHorizonIfDue();  // after the policy and its latency: never delays it
  mpc_status_t& status = mpc_.status();
  status.rejected_messages = rejected_total_;
  status.wrong_model = wrongModel();
  status.rival_policies = rival_policies_;
  if (latest_mismatch_ >= 0)  // within the capacity reserved at start: no allocation
    status.wrong_model_cause.assign(mismatches_[latest_mismatch_].text.data());
  const CommandCounters& cc = commands_.counters();
  status.commands_accepted = cc.accepted;
  status.commands_rejected = cc.rejected + commands_malformed_;
  status.commands_clamped = cc.clamped;
  status.command_timeouts = cc.timeouts;
  status.tick_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
  const int n = status.encode(buffer_.data(), 0, static_cast<int>(buffer_.size()));
  if (n > 0) out_.publish(config_.status_channel, buffer_.data(), n);
}

std::string policyDatagramWarning(int policy_bytes, int policy_knots, const std::string& url) {
  constexpr int kDatagram = 65507;  // the largest UDP payload over IPv4
  if (policy_bytes <= kDatagram || url.rfind("udpm://", 0) != 0) return "";
  // The knots are most of a policy: the count that fits, leaving the header's share.
  const int per_knot = policy_bytes / policy_knots;
  const int fits = std::max(1, (kDatagram - (policy_bytes - per_knot * policy_knots)) / per_knot);
  return "a policy is " + std::to_string(policy_bytes) + " bytes (" + std::to_string(policy_knots) +
         " knots), more than one UDP datagram (" + std::to_string(kDatagram) +
         "): LCM sends it in fragments and a lost fragment loses the policy; policy_knots: " +
         std::to_string(fits) +
         " fits in one, or make sure the network and the receive buffers carry the fragments";
}

}  // namespace stride
