// The message fuzzer (issue 19): bytes into the handlers the programs run on what arrives from the
// bus, never a copy of their decoding. The first byte of an input picks the handler
// (fuzz_channels.hpp), the rest is the LCM payload, handed over in an lcm::ReceiveBuffer as LCM
// does:
//   stride-mpc   MpcNode::onState, onPlan (then applyPendingPlan, which resolves the contact
//                names), onCommand, onPolicy (a rival controller on the policy channel);
//   stride-sim   SimNode::onPolicy, then one physics step, so that a policy that got through the
//                checks is applied to the robot;
//   stride-viz   viz::Feed::take on its seven channels, then every frame the feed has ready (the
//                JSON the page gets, serialized as the server does).
// The nodes are built once (stride_quad, on an in-process memq:// LCM, nothing on a network;
// stride-viz has heard the controller's model) and keep their state from one input to the next, as
// on a live bus (stamp order, the first model stride-viz saw); the mock robot is put back at its
// default posture before each policy, so that an input's physics step does not depend on the ones
// before.
//
// Besides the sanitizers' findings, an input fails (abort) when a handler neither accepts nor
// counts a message as refused: every message must end in exactly one of the two.
//
// Built as a libFuzzer binary (stride-fuzz-messages, clang with STRIDE_FUZZ) and into
// stride-fuzz-replay (any compiler: replay_main.cpp runs the corpus through this function).

#include <Eigen/Core>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <lcm/lcm-cpp.hpp>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "config/robot_config.hpp"
#include "controller/controller_config.hpp"
#include "controller/mpc_node.hpp"
#include "fuzz_channels.hpp"
#include "messages/publisher.hpp"
#include "sim/sim_node.hpp"
#include "viz/server/feed.hpp"

namespace stride::fuzz {
namespace {

std::string configDir() {
  return STRIDE_CONFIG_DIR;
}

viz::RobotSource vizSource() {
  viz::RobotSource source;
  source.yaml = configDir() + "/robots/stride_quad/stride_quad.yaml";
  source.config_dirs = {configDir()};
  return source;
}

// What the nodes publish (a policy, a horizon and a status for each state the controller takes,
// the mock robot's maps) is encoded and dropped. Published on the memq:// bus, which nothing here
// handles, each message stayed queued in LCM: 1.6 GB in 39 000 messages after 480 000 inputs,
// past libFuzzer's 2 GB limit (an out-of-memory "finding" of the harness, not of the nodes).
struct Discard : Publisher {
  void publish(const std::string&, const void*, int) override {}
};

// Everything an input goes to, built on first use.
struct Harness {
  lcm::LCM bus{"memq://"};
  Discard out;
  ControllerConfig config = loadControllerConfig(configDir() + "/controller/stride_quad.yaml");
  MpcNode mpc{config, out, TimeSource::Stamps};
  const Robot& robot = mpc.mpc().robot();
  sim::SimNode sim{robot, sim::SimOptions{}, sim::SimNodeOptions{}, out};
  Eigen::VectorXd q0 = robot.default_q, v0 = Eigen::VectorXd::Zero(robot.model.nv);
  viz::Feed feed{viz::Channels{}, vizSource()};
  std::int64_t sim_policies_applied = 0, sim_policies_refused = 0;

  Harness() {
    if (!bus.good()) fail("no memq:// LCM");
    mpc.subscribe(bus);
    sim.subscribe(bus);
    // What stride-viz hears first from a controller: its model (the programs' own message).
    const robot_model_t model = robotModelMessage(robot, mpc.mpc().nu());
    std::vector<unsigned char> bytes(static_cast<std::size_t>(model.getEncodedSize()));
    model.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
    if (feed.take(feed.channels().model, bytes.data(), static_cast<int>(bytes.size())) !=
        viz::Feed::Took::Model)
      fail("stride-viz refused stride_quad's model");
  }

  [[noreturn]] static void fail(const char* what) {
    std::fprintf(stderr, "stride-fuzz: %s\n", what);
    std::abort();
  }
};

Harness& harness() {
  static Harness h;
  return h;
}

void toMpc(Harness& h, Channel channel, const lcm::ReceiveBuffer& rbuf) {
  MpcNode& node = h.mpc;
  const std::int64_t handled = node.acceptedStates() + node.rejected() + node.planUpdates();
  switch (channel) {
    case Channel::MpcState:
      node.onState(&rbuf, node.config().state_channel);
      break;
    case Channel::MpcPlan:
      node.onPlan(&rbuf, node.config().plan_channel);
      node.applyPendingPlan();
      break;
    case Channel::MpcTerrain: {
      // Refused by the node (malformed, out of order, too large: counted by reason) or taken.
      const std::int64_t maps = node.rejected() + node.mpc().counters().maps;
      node.onTerrain(&rbuf, node.config().terrain_channel);
      if (node.rejected() + node.mpc().counters().maps != maps + 1)
        Harness::fail("MpcNode: a map neither taken nor counted as refused");
      return;
    }
    case Channel::MpcCommand: {
      // Refused by the node (malformed, out of order, an unknown gait: counted by reason) or
      // accepted by its command filter.
      const std::int64_t commands = node.rejected() + node.commands().counters().accepted;
      node.onCommand(&rbuf, node.config().command_channel);
      if (node.rejected() + node.commands().counters().accepted != commands + 1)
        Harness::fail("MpcNode: a command neither accepted nor counted as refused");
      return;
    }
    default: {
      const std::int64_t rivals = node.rivalPolicies();
      node.onPolicy(&rbuf, node.config().policy_channel);
      if (node.rivalPolicies() - rivals > 1) Harness::fail("MpcNode::onPolicy counted twice");
      return;
    }
  }
  if (node.acceptedStates() + node.rejected() + node.planUpdates() != handled + 1)
    Harness::fail("MpcNode: a state or plan neither accepted nor counted as refused");
}

void toSim(Harness& h, const lcm::ReceiveBuffer& rbuf) {
  h.sim.reset(h.q0, h.v0);
  h.sim.setSession(kSession);  // the corpus's policies answer this run
  h.sim.onPolicy(&rbuf, "STRIDE_POLICY");
  const sim::SimNodeStats& s = h.sim.stats();
  if (s.policies + s.policies_rejected != 1)
    Harness::fail("SimNode: a policy neither applied nor counted as refused");
  h.sim_policies_applied += s.policies;
  h.sim_policies_refused += s.policies_rejected;
  h.sim.advance(1);
}

void toViz(Harness& h, Channel channel, const void* data, int size) {
  viz::Feed& feed = h.feed;
  const viz::Channels& ch = feed.channels();
  const std::string* name = &ch.model;
  switch (channel) {
    case Channel::VizState:
      name = &ch.state;
      break;
    case Channel::VizPolicy:
      name = &ch.policy;
      break;
    case Channel::VizHorizon:
      name = &ch.horizon;
      break;
    case Channel::VizStatus:
      name = &ch.status;
      break;
    case Channel::VizCommand:
      name = &ch.command;
      break;
    case Channel::VizTerrain:
      name = &ch.terrain;
      break;
    default:
      break;
  }
  const long handled = feed.accepted(*name) + feed.rejected(*name);
  const viz::Feed::Took took = feed.take(*name, data, size);
  if (feed.accepted(*name) + feed.rejected(*name) != handled + 1)
    Harness::fail("viz::Feed: a message neither accepted nor counted as refused");
  // What the server then sends (viz/server/live.cpp, http_server.cpp): frames as JSON text.
  auto send = [](const viz::Json& frame) {
    if (!frame.is_null())
      (void)frame.dump(-1, ' ', false, viz::Json::error_handler_t::replace).size();
  };
  if (took == viz::Feed::Took::Model) send(feed.modelFrame());
  for (viz::FrameKind kind : {viz::FrameKind::State, viz::FrameKind::Plan, viz::FrameKind::Status,
                              viz::FrameKind::Terrain})
    send(feed.frame(kind));
}

}  // namespace

std::string handledSummary() {
  Harness& h = harness();
  const MpcNode& m = h.mpc;
  std::string text =
      "stride-mpc: " + std::to_string(m.acceptedStates()) + " states, " +
      std::to_string(m.planUpdates()) + " plans, " +
      std::to_string(m.commands().counters().accepted) + " commands accepted, " +
      std::to_string(m.rejected()) + " refused, " + std::to_string(m.rivalPolicies()) +
      " rival policies; stride-sim: " + std::to_string(h.sim_policies_applied) +
      " policies applied, " + std::to_string(h.sim_policies_refused) + " refused; stride-viz:";
  for (const std::string& c : h.feed.channels().all())
    text += " " + c + " " + std::to_string(h.feed.accepted(c)) + "/" +
            std::to_string(h.feed.accepted(c) + h.feed.rejected(c));
  return text;
}

}  // namespace stride::fuzz

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace stride::fuzz;
  if (size == 0 || size > (1u << 30)) return 0;
  Harness& h = harness();
  const auto channel = static_cast<Channel>(data[0] % kFuzzChannels);
  // The payload as LCM hands it to a raw subscriber (its end is the input's end: a read past it is
  // a read past the allocation, which AddressSanitizer sees).
  void* payload = const_cast<std::uint8_t*>(data + 1);
  const int n = static_cast<int>(size - 1);
  const lcm::ReceiveBuffer rbuf{payload, static_cast<std::uint32_t>(n), 0};
  switch (channel) {
    case Channel::MpcState:
    case Channel::MpcPlan:
    case Channel::MpcCommand:
    case Channel::MpcPolicy:
      toMpc(h, channel, rbuf);
      break;
    case Channel::SimPolicy:
      toSim(h, rbuf);
      break;
    default:
      toViz(h, channel, payload, n);
      break;
  }
  return 0;
}
