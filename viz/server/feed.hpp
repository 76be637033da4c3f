#pragma once
// What stride-viz makes of the Stride channels, the same for a live bus and a log: each message is
// checked (messages/validate.hpp, viz/server/wire.hpp) against the robot, the newest accepted one
// of each kind is kept, and frames are built from them on demand (viz/server/frames.hpp). Bad
// messages are counted by channel and reason and dropped; nothing a message holds can stop it.
//
// The robot is the one given (--robot), or the one the first robot_model_t names, found as
// <config dir>/robots/<name>/<name>.yaml. Until a robot is known, states, policies and horizons
// cannot be checked or drawn: they are counted as "before the robot" and dropped. Terrain maps
// (terrain_t) need no robot: they are taken from the first.
//
// Not thread-safe: one thread feeds it and asks for frames (the LCM thread, or the log reader).

#include <cstdint>
#include <map>
#include <memory>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "config/robot_config.hpp"
#include "messages/validate.hpp"
#include "viz/server/client_queue.hpp"
#include "viz/server/robot_files.hpp"

namespace stride::viz {

using Json = nlohmann::json;
class FrameBuilder;

struct Channels {
  std::string state = "STRIDE_STATE", policy = "STRIDE_POLICY", status = "STRIDE_STATUS",
              model = "STRIDE_MODEL", command = "STRIDE_COMMAND", horizon = "STRIDE_HORIZON",
              terrain = "STRIDE_TERRAIN";
  std::vector<std::string> all() const {
    return {state, policy, status, model, command, horizon, terrain};
  }
};

struct RobotSource {
  std::string yaml;                      // --robot; empty: by the name in the first robot_model_t
  std::vector<std::string> robots_dirs;  // --robots-dir, for package:// URIs
  std::vector<std::string> config_dirs;  // searched for robots/<name>/<name>.yaml
};

// Limits on what a message may claim (beyond them it is refused as WrongSize).
constexpr int kMaxKnots = 10000;
constexpr int kMaxTerrainCells = 512 * 512;  // messages/terrain_t.lcm: 1 MB of floats
// Terrain frames per second, at most, live (wall clock) and from a log (log time): a 100 x 100
// map is ~50 kB of JSON, and it changes slowly under a walking robot.
constexpr double kTerrainFrameRate = 2.0;

class Feed {
 public:
  // Loads source.yaml now when given (throws what loadRobot and rewriteUrdf throw).
  Feed(Channels channels, RobotSource source);
  ~Feed();
  Feed(const Feed&) = delete;
  Feed& operator=(const Feed&) = delete;

  const Channels& channels() const { return channels_; }

  // One message from the bus or a log, by channel; returns what it was taken as (None: refused,
  // unknown channel, or before the robot).
  enum class Took : std::uint8_t { None, Model, State, Policy, Horizon, Status, Command, Terrain };
  Took take(const std::string& channel, const void* data, int size);

  // The stamp [us] of the newest message not yet framed of that kind, -1 when there is none: the
  // log reader decimates on it before building anything. Once policies flow, a state is ready to
  // frame when the policy answering it comes or when the next state does, whichever is first (so
  // that its forces use the torque the robot applied there: viz/README.md, "How forces are
  // estimated").
  std::int64_t pendingUtime(FrameKind kind) const;
  // The frame of the newest message of that kind not yet framed (State, Plan, Status, Terrain),
  // then that message counts as framed; a null Json when there is none.
  Json frame(FrameKind kind);

  // The model frame (with a "warning" when the bus's model is not the loaded robot's); null until
  // a robot is loaded. Its version changes each time it does.
  Json modelFrame() const;
  int modelVersion() const { return model_version_; }
  // The robot's URDF and files for the page; null until a robot is loaded.
  std::shared_ptr<const RobotFiles> robotFiles() const { return files_; }
  const Robot* robot() const { return robot_.get(); }

  // Every warning so far (each also written once to stderr), at most kMaxWarnings (the last one
  // then says that later ones are not kept), and the counters by channel and reason:
  // {"STRIDE_STATE": {"accepted": n, "rejected": {"reason": n}}, ..., "forces": {...}}.
  static constexpr std::size_t kMaxWarnings = 32;
  const std::vector<std::string>& warnings() const { return warnings_; }
  Json counters() const;
  long accepted(const std::string& channel) const;
  long rejected(const std::string& channel) const;

 private:
  void loadRobot(const std::string& yaml);
  void warn(const std::string& text);
  bool canWarn() const { return warnings_.size() < kMaxWarnings; }
  void reject(const std::string& channel, const char* reason);
  Took takeModel(const void* data, int size);
  Took takeState(const void* data, int size);
  Took takePolicy(const void* data, int size);
  Took takeHorizon(const void* data, int size);
  Took takeStatus(const void* data, int size);
  Took takeCommand(const void* data, int size);
  Took takeTerrain(const void* data, int size);
  // The waiting state becomes the one to frame, estimated with the policy of that serial.
  void readyWaitingState(std::uint64_t policy);

  struct Messages;  // the newest of each kind and scratch messages to decode into
  struct Count {
    long accepted = 0;
    std::map<std::string, long> rejected;
  };

  Channels channels_;
  RobotSource source_;
  std::unique_ptr<Robot> robot_;
  std::unique_ptr<FrameBuilder> builder_;
  std::unique_ptr<Messages> m_;
  std::shared_ptr<const RobotFiles> files_;
  msg::WireModel wire_;  // what states and policies must claim: the bus's hash, the robot's sizes
  std::int64_t robot_hash_ = 0;
  std::vector<std::string> tried_names_;  // robot names looked for (one warning each)
  int model_version_ = 0;
  std::vector<std::string> warnings_;
  std::map<std::string, Count> counts_;
};

}  // namespace stride::viz
