#pragma once
// stride-mpc's LCM side: receives state estimates, body commands and contact plans, validates
// every message before the controller sees it, runs the controller's tick and publishes its
// policy and status.
//
// Messages arrive as raw bytes (lcm's raw subscribe), are size-checked on the wire, decoded into
// preallocated objects and content-checked (messages/validate.hpp); a rejected message is counted
// by reason and dropped, never passed on. Out-of-order stamps (not newer than the last accepted
// state) are rejected; staleness is measured on the controller's side (the state's arrival time),
// so it needs no clock shared with the robot. Commands go through a CommandFilter (limits, deadman,
// smoothing) on the same clock: their arrival time, never the sender's stamp, feeds the deadman.
// The wire contract: every state must carry this robot's model hash and sizes (config/
// model_hash.hpp); another model's state is refused (Reject::WrongModel), each distinct cause is
// written to stderr once ("expected nq 19, nv 18 (anymal_c, hash ...), got nq 29, ...") and the
// latest is carried by the status. The robot_model_t goes out on the model channel at the first
// tick and then at 1 Hz, so a robot, lcm-spy or a log can tell which layout the controller expects.
// For viewers, the whole predicted horizon (horizon_t, with the footholds the gait generator chose)
// goes out at lcm.horizon_rate_hz after ticks that solved.
// Two ways to run:
//   real time  a fixed-rate loop on CLOCK_MONOTONIC (controller/main.cpp);
//   stamps     time is the newest state's stamp: a tick is due whenever a state reaches the next
//              tick time. Lock-step with the mock robot and log replay use it, so both are
//              deterministic and need no wall clock.

#include <array>
#include <lcm/lcm-cpp.hpp>
#include <string>
#include <vector>

#include "controller/mpc.hpp"
#include "messages/publisher.hpp"
#include "messages/wire_auth.hpp"
#include "stride/robot_model_t.hpp"

namespace stride {

enum class TimeSource { RealTime, Stamps };

class MpcNode {
 public:
  using Clock = Mpc::Clock;
  MpcNode(const ControllerConfig& config, Publisher& out, TimeSource time);
  // Unsubscribes: a node may die before its bus (a controller killed in a closed-loop test).
  ~MpcNode();
  MpcNode(const MpcNode&) = delete;
  MpcNode& operator=(const MpcNode&) = delete;

  // Subscribes the raw handlers on `in`, with queues deep enough for a 1 kHz estimator. With
  // watch_policies (on a live bus, not a log) also the policy channel, to see a rival controller.
  void subscribe(lcm::LCM& in, bool watch_policies = true);
  // The raw handlers (public for tests, which feed them bytes directly).
  void onState(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  void onPlan(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  void onCommand(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  // Elevation maps (terrain_t): checked on the wire and in content, handed to Mpc::setTerrain
  // (controller/README.md, "Terrain"); a map older than the last one taken is out of order.
  void onTerrain(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  // Policies on the policy channel: this controller's own come back (LCM delivers to the sender);
  // another source is a rival controller, counted and written to stderr once per source.
  void onPolicy(const lcm::ReceiveBuffer* rbuf, const std::string& channel);

  // Stamps mode: a state has reached the next tick time.
  bool tickDue() const;
  // One tick: the newest state (if any) through the controller, then publish. Allocation-free
  // after start-up. deadline: for the solve (Clock::time_point::max() in stamps mode).
  void tick(Clock::time_point deadline);
  // After tick(): the first half of the next tick's solve (Mpc::prepare), until the deadline.
  void prepare(Clock::time_point deadline) { mpc_.prepare(deadline); }
  // Applies a plan received since the last call (allocates: call between ticks).
  void applyPendingPlan();

  Mpc& mpc() { return mpc_; }
  const Mpc& mpc() const { return mpc_; }
  std::int64_t rejected() const { return rejected_total_; }
  std::int64_t rejected(msg::Reject reason) const { return rejected_[static_cast<int>(reason)]; }
  std::int64_t acceptedStates() const { return accepted_; }
  std::int64_t planUpdates() const { return plan_updates_; }
  std::int64_t policiesPublished() const { return policies_published_; }
  bool hasState() const { return have_state_; }  // a valid state came in since the start
  const CommandFilter& commands() const { return commands_; }
  // Commands refused before the filter saw them (malformed, non-finite, out of order).
  std::int64_t commandsMalformed() const { return commands_malformed_; }
  // Tick latencies [ms] of every tick that published a policy (capacity fixed at construction;
  // the oldest are overwritten beyond it).
  const std::vector<float>& latencies() const { return latencies_; }
  long latencyCount() const { return latency_count_; }
  const msg::WireModel& wireModel() const { return wire_; }
  const ControllerConfig& config() const { return config_; }
  std::int64_t sourceId() const { return source_id_; }
  // Replaces the random source id (a replay: its output is then the same bits on every run).
  void setSourceId(std::int64_t id);
  std::int64_t rivalPolicies() const { return rival_policies_; }
  // Messages signed (with the key of lcm.key_file) or not, and the refusals by reason.
  const msg::WireAuth& auth() const { return auth_; }
  // Times the robot's clock was taken after its stamps stayed ahead of the time that passed (a
  // clock offset) or behind the newest state (a new robot): onState.
  std::int64_t clockRebasesAhead() const { return rebases_ahead_; }
  std::int64_t clockRebasesBack() const { return rebases_back_; }
  // The robot run followed (robot_state_t.session; 0 before the first state), and the times a new
  // run was followed after the previous one went silent (a robot restarted).
  std::int64_t session() const { return session_; }
  std::int64_t sessionSwitches() const { return session_switches_; }
  // States refused for another model, and the distinct causes (at most kMaxMismatches kept).
  struct ModelMismatch {
    msg::WireClaim claim;
    std::int64_t count = 0;
    std::array<char, 200> text{};
  };
  static constexpr int kMaxMismatches = 4;
  std::int64_t wrongModel() const { return rejected(msg::Reject::WrongModel); }
  int mismatchCount() const { return n_mismatches_; }
  const ModelMismatch& mismatch(int i) const { return mismatches_[i]; }

 private:
  void reject(msg::Reject reason);
  // The size to decode of a message on a slot's channel, or -1 (refused: counted).
  int authenticated(int slot, const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  void noteWrongModel(const void* buf, int size, const std::string& channel);
  void publishModelIfDue();
  void publishHorizonIfDue();
  void rebaseClock(std::int64_t offset_us);
  // True when incoming_ is of the robot run followed, or of a new one that takes over (the
  // followed one silent); false: refused as another run's (counted by the caller, said once).
  bool followSession(std::int64_t arrival_us, const std::string& channel);
  static std::int64_t monotonicMicros();
  static std::int64_t arrivalMicros(std::int64_t recv_utime);
  double now() const;  // the controller's clock [s]: monotonic, or the newest state's stamp

  ControllerConfig config_;
  Mpc mpc_;
  // Signatures (config.key_file): what comes in is checked per channel, what goes out signed.
  msg::WireAuth auth_;
  enum Slot { kStateSlot, kCommandSlot, kPlanSlot, kTerrainSlot, kPolicySlot };
  msg::SigningPublisher signed_out_;
  Publisher& out_;  // signed_out_
  TimeSource time_;
  bool floating_;
  robot_state_t incoming_, newest_;
  bool have_state_ = false, new_state_ = false;
  std::int64_t newest_arrival_us_ = 0;  // real time: CLOCK_MONOTONIC at arrival
  // The states refused on their stamps in a row (increasing among themselves): how many, since
  // when (arrival), the newest stamp; and the rebases they led to.
  int streak_ = 0;
  std::int64_t streak_since_us_ = 0, streak_utime_ = 0;
  std::int64_t rebases_ahead_ = 0, rebases_back_ = 0;
  // The robot run followed, when its last state was taken (real time: arrival), the states of
  // another run since, and the switches to a new run.
  std::int64_t session_ = 0, session_seen_us_ = 0, session_switches_ = 0;
  bool have_session_ = false;
  int other_session_states_ = 0;
  std::int64_t next_tick_utime_ = 0;
  bool tick_grid_set_ = false;
  std::int64_t accepted_ = 0, rejected_total_ = 0, plan_updates_ = 0, policies_published_ = 0;
  std::array<std::int64_t, msg::kRejectReasons> rejected_{};
  contact_plan_t plan_msg_;
  bool plan_pending_ = false;
  command_t command_msg_{};
  terrain_t terrain_msg_;
  CommandFilter commands_;
  std::int64_t last_command_utime_ = -1, commands_malformed_ = 0;
  std::vector<unsigned char> buffer_;  // encoded policy / status
  msg::WireModel wire_;
  std::vector<unsigned char> model_buffer_;  // the encoded robot_model_t, sent as is
  double model_sent_at_ = 0.0;
  bool model_sent_ = false;
  horizon_t horizon_;  // shaped at start: writing it allocates nothing
  std::vector<unsigned char> horizon_buffer_;
  double horizon_sent_at_ = -1e300;
  std::array<ModelMismatch, kMaxMismatches> mismatches_{};
  std::int64_t source_id_ = 0, rival_policies_ = 0;
  lcm::LCM* bus_ = nullptr;  // what subscribe() subscribed on
  std::vector<lcm::Subscription*> subscriptions_;
  std::array<std::int64_t, 4> rivals_{};  // the rival sources already reported
  int n_rivals_ = 0;
  int n_mismatches_ = 0, latest_mismatch_ = -1;
  std::vector<float> latencies_;
  long latency_count_ = 0;
};

// The robot_model_t of a robot (name, hash, sizes, joints in wire order, contact frames).
robot_model_t robotModelMessage(const Robot& robot, int nu);

// LCM over UDP multicast sends a message larger than one datagram (65507 bytes of payload) in
// fragments, and one lost fragment loses the whole message. The warning stride-mpc prints at start
// when its policies do not fit in one datagram: the size and the fix. Empty when they fit or when
// the URL is not udpm.
std::string policyDatagramWarning(int policy_bytes, int policy_knots, const std::string& url);

}  // namespace stride
