#pragma once
// The inputs of the message fuzzer (tests/fuzz/fuzz_messages.cpp) and of its seed corpus
// (corpus.cpp): the first byte of an input picks the handler, modulo kFuzzChannels, and the rest
// is the LCM payload that handler receives, exactly as it comes off the bus.

#include <cstdint>
#include <string>

namespace stride::fuzz {

enum class Channel : std::uint8_t {
  MpcState,    // MpcNode::onState (stride-mpc)
  MpcPlan,     // MpcNode::onPlan, then applyPendingPlan
  MpcCommand,  // MpcNode::onCommand
  MpcPolicy,   // MpcNode::onPolicy (a rival controller on the policy channel)
  SimPolicy,   // SimNode::onPolicy (stride-sim), then one physics step
  VizModel,    // viz::Feed::take on each of stride-viz's seven channels, then its frames
  VizState,
  VizPolicy,
  VizHorizon,
  VizStatus,
  VizCommand,
  VizTerrain,
  MpcTerrain,  // MpcNode::onTerrain; last: the corpus's channel bytes of the others stay as they
               // were
};
constexpr int kFuzzChannels = static_cast<int>(Channel::MpcTerrain) + 1;

// The robot run (robot_state_t.session) of the corpus's states and of the mock robot the harness
// feeds policies to (SimNode::setSession): its valid policies answer it and reach the decoder.
constexpr std::int64_t kSession = 0x5e5510;

// The corpus files' names start with it ("mpc_state-standing").
inline const char* name(Channel c) {
  constexpr const char* kNames[kFuzzChannels] = {
      "mpc_state",   "mpc_plan",    "mpc_command", "mpc_policy",  "sim_policy",
      "viz_model",   "viz_state",   "viz_policy",  "viz_horizon", "viz_status",
      "viz_command", "viz_terrain", "mpc_terrain"};
  return kNames[static_cast<int>(c)];
}

// What the handlers made of the inputs so far: accepted and refused, per program and channel
// (fuzz_messages.cpp; stride-fuzz-replay prints it).
std::string handledSummary();

}  // namespace stride::fuzz
