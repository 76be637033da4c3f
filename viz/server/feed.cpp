#include "viz/server/feed.hpp"

#include <algorithm>
#include <cstdio>
#include <exception>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>
#include <utility>

#include "config/model_hash.hpp"
#include "messages/signing.hpp"
#include "solver/multibody/model.hpp"
#include "stride/command_t.hpp"
#include "viz/server/frames.hpp"
#include "viz/server/wire.hpp"

namespace stride::viz {

namespace {

// A stamp this far behind the newest accepted state is a new session (a restarted robot or
// simulator), not a late message: the viewer follows it rather than refuse it for good.
constexpr std::int64_t kRestartUtime = 1000000;
// Plans come from horizon_t while one came within this long of a policy [us], else from the
// policies' x_ref (a controller that does not publish its horizon).
constexpr std::int64_t kHorizonFreshUtime = 1000000;

const char* const kBeforeRobot = "before the robot was known";

}  // namespace

struct Feed::Messages {
  robot_model_t model, model_in;
  bool have_model = false;
  // The state to frame (`state`, when state_pending) and the newest one (`waiting`), which waits
  // for the policy answering it: a robot in lock-step applies that answer from the state on, a
  // robot in real time the policy it held when it published the state. Each goes with the serial
  // of its policy in the FrameBuilder.
  robot_state_t state, waiting, state_in;
  bool state_pending = false, have_waiting = false;
  std::uint64_t state_policy = 0, waiting_policy = 0;
  std::int64_t last_state_utime = -1;
  policy_t policy, policy_in;
  horizon_t horizon, horizon_in;
  std::int64_t last_horizon_utime = std::numeric_limits<std::int64_t>::min() / 2;
  enum class PlanFrom : std::uint8_t { None, Horizon, Policy } plan = PlanFrom::None;
  mpc_status_t status, status_in;
  bool status_pending = false;
  command_t command{}, command_in{};
  bool have_command = false;
  terrain_t terrain, terrain_in;
  bool terrain_pending = false;
  std::int64_t last_terrain_utime = -1;
  std::set<std::string> refused_claims;  // each wrong-model cause is said once
  std::string model_warning;
};

Feed::Feed(Channels channels, RobotSource source)
    : channels_(std::move(channels)), source_(std::move(source)), m_(std::make_unique<Messages>()) {
  for (const std::string& c : channels_.all()) counts_[c];
  if (!source_.yaml.empty()) loadRobot(source_.yaml);
}

Feed::~Feed() = default;

void Feed::warn(const std::string& text) {
  // Each cause is said once, but a bus can carry any number of causes (every message of another
  // model hash, every robot name): the list and what it takes to remember the causes are bounded.
  if (!canWarn()) return;
  const std::string& said =
      warnings_.size() + 1 < kMaxWarnings
          ? text
          : "more than " + std::to_string(kMaxWarnings - 1) +
                " warnings: the later ones are not kept (the messages are still counted)";
  std::fprintf(stderr, "stride-viz: %s\n", said.c_str());
  warnings_.push_back(said);
}

void Feed::reject(const std::string& channel, const char* reason) {
  ++counts_[channel].rejected[reason];
}

long Feed::accepted(const std::string& channel) const {
  const auto it = counts_.find(channel);
  return it == counts_.end() ? 0 : it->second.accepted;
}

long Feed::rejected(const std::string& channel) const {
  long n = 0;
  const auto it = counts_.find(channel);
  if (it != counts_.end())
    for (const auto& [reason, count] : it->second.rejected) n += count;
  return n;
}

void Feed::loadRobot(const std::string& yaml) {
  auto robot = std::make_unique<Robot>(stride::loadRobot(yaml, source_.robots_dirs));
  auto files = std::make_shared<RobotFiles>(rewriteUrdf(robot->urdf_path, source_.robots_dirs));
  if (!files->missing.empty())
    warn(std::to_string(files->missing.size()) + " of the " + std::to_string(files->files.size()) +
         " files the URDF names were not found (the page draws without them); the first: " +
         files->missing.front());
  robot_ = std::move(robot);
  files_ = std::move(files);
  builder_ = std::make_unique<FrameBuilder>(*robot_);
  robot_hash_ = modelHash(*robot_);
  wire_ = {robot_hash_, robot_->model.nq, robot_->model.nv, actuatedDimension(robot_->model),
           robot_->name.c_str()};
  ++model_version_;
}

Feed::Took Feed::take(const std::string& channel, const void* data, int size) {
  Took took = Took::None;
  // The viewer only reads: a signed message is read as the plain one it carries, unverified
  // (messages/README.md, "Signing").
  size = static_cast<int>(msg::unsignedPayloadSize(static_cast<const std::uint8_t*>(data), size));
  // A channel may be configured twice (e.g. one name for everything in a test): first match wins.
  if (channel == channels_.model)
    took = takeModel(data, size);
  else if (channel == channels_.state)
    took = takeState(data, size);
  else if (channel == channels_.policy)
    took = takePolicy(data, size);
  else if (channel == channels_.horizon)
    took = takeHorizon(data, size);
  else if (channel == channels_.status)
    took = takeStatus(data, size);
  else if (channel == channels_.command)
    took = takeCommand(data, size);
  else if (channel == channels_.terrain)
    took = takeTerrain(data, size);
  else
    return Took::None;
  if (took != Took::None) ++counts_[channel].accepted;
  return took;
}

Feed::Took Feed::takeModel(const void* data, int size) {
  const std::string& channel = channels_.model;
  robot_model_t& in = m_->model_in;
  if (const msg::Reject r = decodeModel(data, size, in); r != msg::Reject::None) {
    reject(channel, msg::describe(r));
    return Took::None;
  }
  if (m_->have_model) {
    if (in.model_hash == m_->model.model_hash && in.robot == m_->model.robot) return Took::Model;
    const std::string cause = "another model on '" + channel + "' (" + in.robot + ", hash " +
                              hashText(in.model_hash) + ") after " + m_->model.robot + "'s";
    if (canWarn() && m_->refused_claims.insert(cause).second)
      warn(cause + ": stride-viz keeps the first model; restart it to follow the new one");
    reject(channel, "another model than the first");
    return Took::None;
  }
  if (!robot_) {
    std::vector<std::string> tried;
    const std::string yaml = findRobotYaml(in.robot, source_.config_dirs, &tried);
    const bool first_try =
        std::find(tried_names_.begin(), tried_names_.end(), in.robot) == tried_names_.end();
    if (first_try && canWarn()) tried_names_.push_back(in.robot);
    if (yaml.empty()) {
      if (first_try) {
        std::string text = "the bus's robot '" + in.robot + "' has no YAML; give it with --robot";
        for (const std::string& t : tried) text += "; not at " + t;
        warn(text);
      }
      reject(channel, "robot not found");
      return Took::None;
    }
    try {
      loadRobot(yaml);
    } catch (const std::exception& e) {
      if (first_try) warn("cannot load the robot '" + in.robot + "' (" + yaml + "): " + e.what());
      reject(channel, "robot not loadable");
      return Took::None;
    }
  }
  std::swap(m_->model, in);
  m_->have_model = true;
  const robot_model_t& model = m_->model;
  const Model& ours = robot_->model;
  if (model.nq != ours.nq || model.nv != ours.nv) {
    m_->model_warning = "the controller's robot " + model.robot + " (nq " +
                        std::to_string(model.nq) + ", nv " + std::to_string(model.nv) +
                        ") is not the loaded robot " + robot_->name + " (nq " +
                        std::to_string(ours.nq) + ", nv " + std::to_string(ours.nv) +
                        "): its states and policies are refused";
    warn(m_->model_warning);
  } else if (model.model_hash != robot_hash_) {
    m_->model_warning = "the controller's model hash " + hashText(model.model_hash) + " (" +
                        model.robot + ") is not the loaded robot's " + hashText(robot_hash_) +
                        " (" + robot_->name + "): joints or contacts may be in another order; " +
                        "drawn with the loaded robot";
    warn(m_->model_warning);
  }
  wire_.hash = model.model_hash;  // the bus's messages carry the bus's hash
  ++model_version_;
  return Took::Model;
}

Feed::Took Feed::takeState(const void* data, int size) {
  const std::string& channel = channels_.state;
  if (!robot_) {
    reject(channel, kBeforeRobot);
    return Took::None;
  }
  const int nc = static_cast<int>(robot_->contacts.size());
  robot_state_t& in = m_->state_in;
  msg::Reject r = msg::checkStateWire(data, size, wire_, nc);
  if (r == msg::Reject::WrongModel) {
    msg::WireClaim claim;
    char text[256];
    if (canWarn() && msg::readStateClaim(data, size, claim) &&
        m_->refused_claims
            .insert("state " + std::to_string(claim.hash) + " " + std::to_string(claim.nq) + " " +
                    std::to_string(claim.nv))
            .second)
      warn("refused a state on '" + channel +
           "': " + msg::describeMismatch(wire_, claim, text, sizeof text));
  }
  if (r == msg::Reject::None && !msg::decode(data, size, in)) r = msg::Reject::Undecodable;
  if (r == msg::Reject::None) r = msg::checkState(in, robot_->model.hasFreeFlyer());
  if (r == msg::Reject::None && in.ncontacts != 0 && in.ncontacts != nc) r = msg::Reject::WrongSize;
  if (r == msg::Reject::None && in.utime <= m_->last_state_utime &&
      in.utime > m_->last_state_utime - kRestartUtime)
    r = msg::Reject::OutOfOrder;
  if (r != msg::Reject::None) {
    reject(channel, msg::describe(r));
    return Took::None;
  }
  m_->last_state_utime = in.utime;
  if (!builder_->hasPolicy()) {
    // No policy to wait for: framed as it is (forces []).
    std::swap(m_->state, in);
    m_->state_pending = true;
    m_->have_waiting = false;
    return Took::State;
  }
  // A newer state: the robot did not wait for an answer to the previous one (real time), which is
  // then framed with the policy held when it came.
  if (m_->have_waiting) readyWaitingState(m_->waiting_policy);
  std::swap(m_->waiting, in);
  m_->waiting_policy = builder_->policySerial();
  m_->have_waiting = true;
  return Took::State;
}

Feed::Took Feed::takePolicy(const void* data, int size) {
  const std::string& channel = channels_.policy;
  if (!robot_) {
    reject(channel, kBeforeRobot);
    return Took::None;
  }
  policy_t& in = m_->policy_in;
  msg::Reject r = msg::checkPolicyWire(data, size, wire_, kMaxKnots);
  if (r == msg::Reject::None && in.decode(data, 0, size) != size) r = msg::Reject::Undecodable;
  if (r == msg::Reject::None) r = msg::checkPolicy(in, robot_->model.hasFreeFlyer());
  if (r != msg::Reject::None) {
    reject(channel, msg::describe(r));
    return Took::None;
  }
  std::swap(m_->policy, in);
  const std::uint64_t serial = builder_->setPolicy(m_->policy);
  // The answer to the waiting state (policy_t.utime: the state it answers): in lock-step the robot
  // waited for it and applies it from that state on.
  if (m_->have_waiting && m_->policy.utime >= m_->waiting.utime) readyWaitingState(serial);
  // Compared without a difference, which overflowed for a policy stamped near ±2^63 (a horizon's
  // stamp is >= 0, or the initial -2^62: the sum cannot overflow).
  if (m_->policy.utime > m_->last_horizon_utime + kHorizonFreshUtime)
    m_->plan = Messages::PlanFrom::Policy;
  return Took::Policy;
}

Feed::Took Feed::takeHorizon(const void* data, int size) {
  const std::string& channel = channels_.horizon;
  if (!robot_) {
    reject(channel, kBeforeRobot);
    return Took::None;
  }
  const msg::Reject r = decodeHorizon(data, size, wire_, static_cast<int>(robot_->contacts.size()),
                                      kMaxKnots, robot_->model.hasFreeFlyer(), m_->horizon_in);
  if (r != msg::Reject::None) {
    reject(channel, msg::describe(r));
    return Took::None;
  }
  std::swap(m_->horizon, m_->horizon_in);
  m_->last_horizon_utime = m_->horizon.utime;
  m_->plan = Messages::PlanFrom::Horizon;
  return Took::Horizon;
}

Feed::Took Feed::takeStatus(const void* data, int size) {
  if (const msg::Reject r = decodeStatus(data, size, m_->status_in); r != msg::Reject::None) {
    reject(channels_.status, msg::describe(r));
    return Took::None;
  }
  std::swap(m_->status, m_->status_in);
  m_->status_pending = true;
  return Took::Status;
}

Feed::Took Feed::takeCommand(const void* data, int size) {
  command_t& in = m_->command_in;
  msg::Reject r = msg::checkCommandWire(data, size);
  if (r == msg::Reject::None && in.decode(data, 0, size) != size) r = msg::Reject::Undecodable;
  if (r == msg::Reject::None) r = msg::checkCommand(in);
  if (r != msg::Reject::None) {
    reject(channels_.command, msg::describe(r));
    return Took::None;
  }
  std::swap(m_->command, in);
  m_->have_command = true;
  return Took::Command;
}

Feed::Took Feed::takeTerrain(const void* data, int size) {
  terrain_t& in = m_->terrain_in;
  msg::Reject r = msg::checkTerrainWire(data, size, kMaxTerrainCells);
  if (r == msg::Reject::None && in.decode(data, 0, size) != size) r = msg::Reject::Undecodable;
  if (r == msg::Reject::None) r = msg::checkTerrain(in);
  // Maps come in stamp order (terrain_t.lcm: non-decreasing); one far behind is a restarted robot.
  if (r == msg::Reject::None && in.utime < m_->last_terrain_utime &&
      in.utime > m_->last_terrain_utime - kRestartUtime)
    r = msg::Reject::OutOfOrder;
  if (r != msg::Reject::None) {
    reject(channels_.terrain, msg::describe(r));
    return Took::None;
  }
  m_->last_terrain_utime = in.utime;
  std::swap(m_->terrain, in);
  m_->terrain_pending = true;
  return Took::Terrain;
}

void Feed::readyWaitingState(std::uint64_t policy) {
  std::swap(m_->state, m_->waiting);
  m_->state_policy = policy;
  m_->state_pending = true;
  m_->have_waiting = false;
}

std::int64_t Feed::pendingUtime(FrameKind kind) const {
  switch (kind) {
    case FrameKind::State:
      return m_->state_pending ? m_->state.utime : -1;
    case FrameKind::Plan:
      if (m_->plan == Messages::PlanFrom::Horizon) return m_->horizon.utime;
      if (m_->plan == Messages::PlanFrom::Policy) return m_->policy.knot0_utime;
      return -1;
    case FrameKind::Status:
      return m_->status_pending ? m_->status.utime : -1;
    case FrameKind::Terrain:
      return m_->terrain_pending ? m_->terrain.utime : -1;
    default:
      return -1;
  }
}

Json Feed::frame(FrameKind kind) {
  switch (kind) {
    case FrameKind::State:
      if (!m_->state_pending) return nullptr;
      m_->state_pending = false;
      return builder_->state(m_->state, m_->state_policy);
    case FrameKind::Plan: {
      const auto from = m_->plan;
      m_->plan = Messages::PlanFrom::None;
      if (from == Messages::PlanFrom::Horizon) return builder_->plan(m_->horizon);
      if (from == Messages::PlanFrom::Policy) return builder_->plan(m_->policy);
      return nullptr;
    }
    case FrameKind::Status:
      if (!m_->status_pending) return nullptr;
      m_->status_pending = false;
      return FrameBuilder::status(m_->status, m_->have_command ? &m_->command : nullptr);
    case FrameKind::Terrain:
      if (!m_->terrain_pending) return nullptr;
      m_->terrain_pending = false;
      return FrameBuilder::terrain(m_->terrain);
    default:
      return nullptr;
  }
}

Json Feed::modelFrame() const {
  if (!robot_) return nullptr;
  Json frame = builder_->model(m_->have_model ? &m_->model : nullptr);
  if (!m_->model_warning.empty()) frame["warning"] = m_->model_warning;
  return frame;
}

Json Feed::counters() const {
  Json out = Json::object();
  for (const auto& [channel, count] : counts_) {
    Json rejected = Json::object();
    for (const auto& [reason, n] : count.rejected) rejected[reason] = n;
    out["channels"][channel] = {{"accepted", count.accepted}, {"rejected", std::move(rejected)}};
  }
  if (builder_) {
    const ForceCounts& f = builder_->forceCounts();
    out["forces"] = {{"estimated", f.estimated},
                     {"no_policy", f.no_policy},
                     {"no_contact_flags", f.no_contact_flags},
                     {"failed", f.failed}};
  }
  return out;
}

}  // namespace stride::viz
