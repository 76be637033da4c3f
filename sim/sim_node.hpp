#pragma once
// stride-sim's LCM side: publishes the mock robot's state estimates (with the configured noise,
// delay and drops) and applies the newest valid policy at every physics step (ARCHITECTURE.md §1,
// §6). Until the first policy arrives a joint PD holds the default posture; when the controller
// goes silent (past a policy's end) the robot stands down (StandDown,
// sim/README.md "Controller loss"); both counted. States carry the robot's model hash; a policy of
// another model (hash, nq or nv: another robot's controller) is refused, counted, and each distinct
// cause written to stderr once (controller/README.md, "Wire contract").
//
// Time: the robot's clock is utime = utime_base + sim time, in µs. In lock-step the base is fixed
// (deterministic stamps); in real time it is CLOCK_MONOTONIC at start and the loop keeps sim time
// on the wall clock. A policy's knot 0 sits at its utime on that clock.

#include <array>
#include <functional>
#include <lcm/lcm-cpp.hpp>
#include <optional>
#include <string>

#include "config/robot_config.hpp"
#include "messages/policy_interpolation.hpp"
#include "messages/publisher.hpp"
#include "messages/validate.hpp"
#include "messages/wire_auth.hpp"
#include "sim/actuators.hpp"
#include "sim/disturbances.hpp"
#include "sim/fall.hpp"
#include "sim/plant.hpp"
#include "sim/policy.hpp"
#include "sim/sensing.hpp"
#include "sim/simulator.hpp"
#include "sim/terrain_map.hpp"

namespace stride::sim {

struct SimNodeOptions {
  double state_rate_hz = 1000.0;  // estimates published per second of sim time
  // What the robot senses: the estimate its low-level loop uses and publishes (sim/sensing.hpp).
  SensingOptions sensing;
  ActuatorOptions actuators;  // between the commanded and the applied torque (sim/actuators.hpp)
  PlantOptions plant;         // the robot as it really is (sim/plant.hpp)
  int delay = 0;              // estimates published this many publications late
  double drop = 0.0;          // probability of dropping an estimate on its way to the controller
  std::uint64_t seed = 1;
  PushSchedule pushes;
  // The joint PD before the first policy and when standing down; negative: the robot YAML's
  // `joint_pd` (kp 5, kd 0.1 without one: msg::kDefaultHoldKp/Kd, messages/hold_pd.hpp).
  double hold_kp = -1.0, hold_kd = -1.0;
  std::string state_channel = "STRIDE_STATE", policy_channel = "STRIDE_POLICY";
  std::int64_t utime_base = 1000000;
  int max_policy_knots = 64;
  // The robot follows one controller (policy_t.source_id): another source is refused as a rival
  // while the followed one has published within this many seconds of robot time; after such a
  // silence (a controller restarted) the new source is followed.
  double source_timeout = 0.2;
  // When the controller goes silent (sim/README.md, "Controller loss").
  StandDownOptions stand_down;
  // Fallen: the base's height above the terrain under it below this fraction of its height above
  // the terrain at the start, or tilted more than this (sim/fall.hpp, the log summary's too).
  FallLimits fall;
  // The elevation map the robot publishes (its perception's stand-in).
  TerrainMapOptions map;
  // The shared key (stride-sim --key-file): the robot signs its states and maps and takes only
  // policies signed with it (messages/README.md, "Signing"). None: unauthenticated.
  std::optional<msg::Key> key;
  // The freshness window of signed policies [s] (messages/README.md, "Freshness"): a policy whose
  // signature's timestamp is further than this from the robot's CLOCK_REALTIME is refused.
  double signature_window = static_cast<double>(msg::kFreshnessWindowMicros) * 1e-6;
};

// The robot's default posture standing on the terrain at its default place: the base raised by the
// terrain's height under its contact points (the highest of them, so that no foot starts inside a
// step), plus drop_height. Fixed-base robots: the default posture as it is.
Eigen::VectorXd startingPose(const Robot& robot, const terrain::Terrain& terrain,
                             double drop_height = 0.0);

struct SimNodeStats {
  std::int64_t states_published = 0, states_dropped = 0;
  std::int64_t last_state_utime = -1;  // the stamp of the last state published
  std::int64_t policies = 0, policies_rejected = 0;
  std::int64_t policies_wrong_model = 0;  // of policies_rejected: another model's
  std::int64_t policies_rival = 0;        // of policies_rejected: a rival controller's
  // Of policies_rejected: not signed with the robot's key (unsigned, forged, replayed, another
  // key's): never read.
  std::int64_t policies_unauthenticated = 0;
  // Of policies_rejected: made for another run of the robot (policy_t.session not this run's).
  std::int64_t policies_other_session = 0;
  std::int64_t source_switches = 0;  // a new controller followed after a silence
  // On the hold PD: before the first policy came (waiting, e.g. the controller's start-up solve
  // in real time), and after (a policy that did not apply: a fallback of the robot).
  std::int64_t waiting_steps = 0, hold_steps = 0, exhausted_steps = 0, steps = 0;
  // Past a policy's end by more than the grace: the controller is lost, the robot stands down.
  std::int64_t stand_downs = 0, stand_down_steps = 0;
  std::int64_t lockstep_timeouts = 0;
  // Policies that arrived at or after their end (the state they answered was as old on arrival
  // as the span they cover, or older: the estimates' latency and the controller's answer together
  // took as long as a policy lasts), by how much at most [s], and the last policy's span [s];
  // steps driven by a policy in force.
  std::int64_t policies_expired = 0;
  double expired_by_max = 0.0, policy_span = 0.0;
  std::int64_t policy_steps = 0;
  // Sensor samples lost (the low-level loop kept the previous estimate), steps where the
  // actuators' torque-speed envelope cut a command.
  std::int64_t sensor_drops = 0, envelope_steps = 0;
  double x0 = 0, y0 = 0, z0 = 0, z_min = 1e300, z_max = -1e300, max_tilt_deg = 0.0;
  // The base's height above the terrain under it: at the start, lowest, at the end.
  double above0 = 0.0, above_min = 1e300, above = 0.0;
  double peak_normal_force = 0.0;
  bool fell = false;
  bool diverged = false;  // the physics could not go on (singular M, non-finite state)
};

// Why the robot did not follow its controller, in words, when the counters show it: policies that
// arrived already expired, a robot that never had a policy in force. Empty when there is nothing
// to say. For the summaries of stride-sim, stride-drive and stride-log-summary.
std::string whyText(const SimNodeStats& stats);

class SimNode {
 public:
  SimNode(const Robot& robot, const SimOptions& sim, const SimNodeOptions& options, Publisher& out);
  // Unsubscribes: a node may die before its bus (the mock robot restarted in a closed-loop test).
  ~SimNode();
  SimNode(const SimNode&) = delete;
  SimNode& operator=(const SimNode&) = delete;

  void subscribe(lcm::LCM& in);
  void onPolicy(const lcm::ReceiveBuffer* rbuf, const std::string& channel);

  // A fault injector for tests and stride-drive: called with each estimate (and its sim time)
  // just before it is encoded; it may change it (a NaN, an old stamp) or return false to drop it
  // (a gap in the stream). It must not allocate.
  using StateFault = std::function<bool(robot_state_t&, double)>;
  void setStateFault(StateFault fault) { state_fault_ = std::move(fault); }

  // Puts the robot at (q, v) at sim time 0.
  void reset(const Eigen::VectorXd& q, const Eigen::VectorXd& v);
  // Publishes the current estimate (through delay, noise and drops); returns the stamp the
  // controller will answer, or -1 when nothing went out.
  std::int64_t publishState();
  // True once a policy answering a state stamped `utime` (or later) has arrived.
  bool answered(std::int64_t utime) const { return have_policy_ && last_answer_ >= utime; }
  // Advances `steps` physics steps, each with the policy evaluated at its start. False when the
  // run cannot go on: the robot fell, or the physics diverged (stats() says which).
  bool advance(int steps);

  Simulator& simulator() { return sim_; }
  const Simulator& simulator() const { return sim_; }
  std::int64_t utime() const;
  const SimNodeStats& stats() const { return stats_; }
  void countLockstepTimeout() { ++stats_.lockstep_timeouts; }
  const TerrainMapper& mapper() const { return mapper_; }
  // This run of the robot (robot_state_t.session): drawn at construction and at each reset().
  std::int64_t session() const { return session_; }
  // The policies' signatures: refusals by reason (messages/README.md, "Signing").
  const msg::WireAuth& auth() const { return auth_; }
  // Replaces the random session (tests and the fuzzer's replay: the same bits on every run).
  void setSession(std::int64_t session) { session_ = state_msg_.session = session; }
  int stepsPerState() const { return steps_per_state_; }

  // A human summary on stdout and, when path is not empty, JSON.
  void writeSummary(const std::string& path) const;

 private:
  void track();
  // The terrain's height under the base (the ground's for a fixed base).
  double baseTerrainHeight(const Eigen::VectorXd& q) const;
  void noteWrongModel(const void* buf, int size, const std::string& channel);
  void newSession();
  // False (and counted) for a rival controller's policy; follows a new source after a silence.
  bool followSource(std::int64_t source, const std::string& channel);

  // The estimate of the current physics step (sampled once per step), and the state the
  // robot's low-level loop sees: the estimate, or the truth when sensing is off.
  void sense();
  const Eigen::VectorXd& qSensed() const { return sensing_.enabled() ? sensing_.q() : sim_.q(); }
  const Eigen::VectorXd& vSensed() const { return sensing_.enabled() ? sensing_.v() : sim_.v(); }

  const Robot& robot_;
  SimNodeOptions options_;
  Robot plant_;  // what the physics integrates (options_.plant); robot_ is what the loop knows
  Simulator sim_;
  msg::WireAuth auth_;  // options.key: policies checked, states and maps signed
  msg::SigningPublisher signed_out_;
  Publisher& out_;  // signed_out_
  msg::PolicyEvaluator evaluator_;
  HoldPolicy hold_;
  StandDown stand_down_;
  bool standing_down_ = false;
  TerrainMapper mapper_;
  Sensing sensing_;
  std::int64_t sensed_at_ = -1;  // the step the estimate was sampled at
  Actuators actuators_;
  StateDelay delay_;
  MessageDropper dropper_;
  int steps_per_state_;
  policy_t incoming_;
  msg::Policy policy_;
  bool have_policy_ = false;
  std::int64_t last_answer_ = -1;
  robot_state_t state_msg_;
  StateFault state_fault_;
  msg::WireModel wire_;
  std::array<msg::WireClaim, 4> mismatches_{};  // the causes already written to stderr
  int n_mismatches_ = 0;
  std::int64_t session_ = 0;  // this run (robot_state_t.session)
  std::int64_t source_ = 0;   // the controller followed (policy_t.source_id)
  bool have_source_ = false;
  double source_seen_ = 0.0;              // sim time of its newest policy
  std::array<std::int64_t, 4> rivals_{};  // the rival sources already reported
  int n_rivals_ = 0;
  lcm::LCM* bus_ = nullptr;
  lcm::Subscription* subscription_ = nullptr;
  std::vector<unsigned char> buffer_;
  Eigen::VectorXd q_pub_, v_pub_, tau_cmd_, tau_;
  SimNodeStats stats_;
};

}  // namespace stride::sim
