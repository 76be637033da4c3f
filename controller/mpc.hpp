#pragma once
// The receding-horizon controller, free of I/O: one tick turns the newest state estimate into a
// policy message and a status message (ARCHITECTURE.md §1, steps 2-6). The LCM side (mpc_node)
// feeds it validated states and publishes what it fills.
//
// A tick, after start-up:
//   1. plan time t of the state (its stamp minus the plan's start);
//   2. shift the horizon by the whole short knots elapsed since the last solve (the remainder,
//      under half a knot, stays as an FDDP gap), set x0 = the state;
//   3. re-plan the references from the state and the command (GaitGenerator::plan: contact timing
//      with gait switches, footholds, swing arcs, base pose and twist), rewrite every knot's
//      contacts and references for them (LocomotionProblem::update) and move the warm start onto
//      the knots' new times (Solver::retimeWarmStart; controller/README.md, "Time grid");
//   4. at most max_iterations of (box-)FDDP, stopped at the deadline;
//   5. the policy: u_ff, K, x_ref of the first contact knots (impulse knots take no time and have
//      no control, so they are skipped);
//   6. on a stale state or a failed solve, a fallback (the previous policy advanced in time, or a
//      joint hold policy), flagged in both messages and counted; in real time, a tick whose
//      preparation did not finish re-sends the previous policy (controller/README.md, "Overload").
// Steps 2-3 and the first half of step 4 do not need the state (Solver::prepare: derivatives and
// backward pass never read x0), so prepare() runs them after the policy went out, for the time
// the next state is expected at; the next tick, when its state is less than a knot from the
// prepared knot 0, only sets x0 and runs the line search. The state-to-policy latency is then one
// or a few rollouts instead of a whole iteration (controller/README.md, "Real-time iteration").
// After start-up nothing here allocates or throws (tested). Start-up (the first valid state) builds
// the problem around the robot's measured position and solves it to convergence before the first
// policy goes out.

#include <algorithm>
#include <chrono>
#include <memory>

#include "controller/controller_config.hpp"
#include "controller/slow_host.hpp"
#include "locomotion/locomotion_problem.hpp"
#include "messages/validate.hpp"
#include "solver/ddp/solver.hpp"
#include "terrain/elevation_map.hpp"
#include "terrain/steppability.hpp"

namespace stride {

enum PolicyStatus : std::int8_t {
  kPolicySolved = 0,
  kPolicyDeadline = 1,
  kPolicyPrevious = 2,
  kPolicyHold = 3,
  kPolicyNone = -1,
};

struct MpcCounters {
  std::int64_t ticks = 0;
  std::int64_t deadline_misses = 0;
  std::int64_t fallbacks = 0;
  std::int64_t stale_states = 0;
  std::int64_t ticks_without_state = 0;
  std::int64_t failed_solves = 0;
  std::int64_t unprepared_solves = 0;  // ticks after start-up that solved without a preparation
  std::int64_t late_ticks = 0;         // started after their time (the last period's work ran over)
  std::int64_t stall_restarts = 0;     // warm starts made again after line searches stalled
  // Start-up solves made again on a newer state, their own answer too old when it came (real
  // time: a start-up solve that took longer than a period).
  std::int64_t startup_resolves = 0;
  // Overload (a period's work ran past the next tick's start; controller/README.md, "Overload"):
  std::int64_t shed_line_searches = 0;   // late ticks whose line search tried the full step only
  std::int64_t shed_ticks = 0;           // ticks without preparation: the previous policy re-sent
  std::int64_t max_misses_in_a_row = 0;  // the longest run of periods with a deadline miss
  // Periods in which the host kept the controller off its core for more than kHostStallMs while
  // it had work (its wall time exceeded its CPU time by that much, or it woke that late from its
  // sleep), and the longest run of missed periods with no such stall in it: the misses the
  // controller's own work made (a stall longer than a period makes two in a row whatever it does).
  std::int64_t host_stalls = 0;
  std::int64_t max_own_misses_in_a_row = 0;
  // Elevation maps (controller/README.md, "Terrain"): taken, refused (larger than
  // terrain.max_cells or not well formed), and the ticks planned on a map, or blind because the
  // newest map was older than terrain.max_map_age (or from the future) when maps had come before.
  std::int64_t maps = 0;
  std::int64_t maps_refused = 0;
  std::int64_t map_ticks = 0;
  std::int64_t stale_map_ticks = 0;
};

class Mpc {
 public:
  using Clock = Solver::Clock;

  // Loads the robot and the gait plan; throws ConfigError / UrdfError / std::invalid_argument.
  explicit Mpc(const ControllerConfig& config);
  ~Mpc();

  const ControllerConfig& config() const { return config_; }
  const Robot& robot() const { return robot_; }
  // The robot's identity on the wire (config/model_hash.hpp), carried by every policy.
  std::int64_t modelHash() const { return policy_.model_hash; }
  // The controller's identity on the policy channel (policy_t.source_id; MpcNode draws it).
  void setSourceId(std::int64_t id) { policy_.source_id = previous_.source_id = id; }
  // The robot run its policies answer (policy_t.session: robot_state_t.session of the newest
  // state; MpcNode sets it before each tick).
  void setSession(std::int64_t session) { policy_.session = previous_.session = session; }
  int nu() const { return nu_; }
  bool started() const { return loco_ != nullptr; }

  // Replaces the gaits by a planner's contact plan, starting at start_utime on the robot's clock
  // (the command still sets the velocity). Call between ticks; the next tick rebuilds the problem
  // and solves it to convergence, as at start-up (allocating then). Throws std::invalid_argument.
  void setPlan(const ContactPlan& plan, std::int64_t start_utime);
  // The robot's clock moved by offset_us and stays there (MpcNode: a clock offset or a new
  // robot): every time kept on that clock moves with it, so the plan time goes on where it was.
  void shiftClock(std::int64_t offset_us);
  // The body command in force (the node's CommandFilter smooths it toward the one received), and
  // the gait asked for (an index into gaits()). Takes effect at the next tick's re-planning.
  void setCommand(const BodyCommand& command, int gait);
  // An elevation map (validated: messages/validate.hpp checkTerrain), measured at map.utime on the
  // robot's clock: its steppability is computed now (bounded by terrain.max_cells; no allocation
  // after construction) and the ticks plan on it while it is fresh. False, and counted, for a map
  // larger than terrain.max_cells or older than the one in use.
  bool setTerrain(const terrain_t& map);
  // The map the ticks plan on (valid() false before the first).
  const terrain::Steppability& terrain() const { return steppability_; }
  // Whether the last tick planned on the map.
  bool plannedOnMap() const { return on_map_; }

  // The gaits the robot walks with ("stand" first).
  const std::vector<std::string>& gaits() const { return gaits_; }

  // One tick. state: the newest valid estimate (null: none yet); age: seconds since it arrived;
  // deadline: for the solve (Clock::time_point::max() when replaying a log). Fills policy() and
  // status(); true when policy() is to be published.
  bool tick(const robot_state_t* state, double age, Clock::time_point deadline);
  // After a tick that solved: shift, update and linearize for the next state, expected one tick
  // period after this one's, stopping at the deadline (the next tick's start). Allocation-free.
  void prepare(Clock::time_point deadline);

  const policy_t& policy() const { return policy_; }
  const mpc_status_t& status() const { return status_; }
  mpc_status_t& status() { return status_; }
  const MpcCounters& counters() const { return counters_; }
  // Counted by the real-time loop, which knows the period: a tick it skipped because its deadline
  // had passed before it could start (a deadline miss), and a tick that started late but ran.
  void countSkippedTick() { ++counters_.deadline_misses; }
  // A late tick sheds work: its line search tries the full step only.
  void countLateTick() {
    ++counters_.late_ticks;
    late_ = true;
  }
  // After each period: whether it had a deadline miss, and whether the host stalled the
  // controller since the last period was counted (for the counters above).
  static constexpr double kHostStallMs = 1.0;
  void countPeriod(bool missed, bool stalled) {
    counters_.host_stalls += stalled ? 1 : 0;
    misses_in_a_row_ = missed ? misses_in_a_row_ + 1 : 0;
    run_stalled_ = missed && (run_stalled_ || stalled);
    counters_.max_misses_in_a_row = std::max(counters_.max_misses_in_a_row, misses_in_a_row_);
    if (!run_stalled_)
      counters_.max_own_misses_in_a_row =
          std::max(counters_.max_own_misses_in_a_row, misses_in_a_row_);
  }
  // The last tick made the first solve of a (re)built problem, which runs without deadline.
  bool startupTick() const { return startup_tick_; }
  // Start-up solves made again on a newer state before one answer went out (real time).
  static constexpr int kMaxStartupResolves = 3;

  // After a tick that solved (a fresh policy, not a fallback): the whole predicted horizon into a
  // horizon_t shaped by msg::shape(h, horizonKnots(), nq, contacts, horizonFootholds()), with the
  // footholds the gait generator chose for it: each contact's touch-downs after the state and no
  // later than the last knot (at most msg::kHorizonFootholdsPerContact each, and the capacity h
  // was shaped with), by contact then time, their times after the state. Allocation-free. False
  // when the last tick did not solve.
  bool writeHorizon(horizon_t& h) const;
  int horizonKnots() const { return config_.locomotion.knots; }
  int horizonFootholds() const {
    return msg::kHorizonFootholdsPerContact * static_cast<int>(robot_.contacts.size());
  }

  // After a tick: the solver and the problem, for tests and tools.
  const Solver* solver() const { return solver_.get(); }
  Solver* solver() { return solver_.get(); }  // tools/bench times the solver's parts
  const LocomotionProblem* problem() const { return loco_.get(); }
  const GaitGenerator* reference() const { return gen_.get(); }
  double planTime(std::int64_t utime) const { return (utime - plan_start_utime_) * 1e-6; }

 private:
  void start(std::int64_t utime);  // builds the problem and the gaits (allocates)
  // writeHorizon's footholds: the gait generator's touch-downs after the state up to t_end (plan
  // time).
  void writeFootholds(horizon_t& h, double t_end) const;
  // Re-plans the references from the state x_ at plan time t for the horizon from t_warm_, and
  // rewrites the knots for them. False when either refuses (non-finite time or state).
  bool replan(double t);
  // Shifts the horizon and the warm start by the whole knots from the warm start's knot 0 to t
  // (the remainder, under half a knot, is left to FDDP as a gap at x0). False, and nothing
  // shifted, when t is past the horizon: the warm start is used up.
  bool shiftTo(double t);
  // shed: when not null, a real-time tick without its preparation solves nothing and sets it.
  bool solveTick(double t, Clock::time_point deadline, bool late, SolveStatus& status, bool* shed);
  // The warm start made again from the references planned on the state x_ (at plan time t), with
  // its knot 0 at t_knot0; for a start-up solve (allocating), the measured state held instead
  // (LocomotionProblem::measuredWarmStart).
  void restartWarmStart(double t, double t_knot0, bool startup);
  void writePolicy(std::int64_t utime, double t, std::int8_t status);
  bool previousPolicy(std::int64_t utime);
  void holdPolicy(std::int64_t utime, double t);
  void countAnswer(Clock::time_point deadline);  // a miss when the policy is out after it
  void finishStatus(Clock::time_point tick_start, std::int8_t policy_status);
  // Before a tick's plan: the map if it is fresh at the state's stamp, else blind (counted).
  void chooseMap(std::int64_t utime);

  ControllerConfig config_;
  Robot robot_;
  ContactSet contacts_;
  ContactPlan plan_;
  bool have_plan_ = false;  // a plan file or a planner's plan replaces the gaits
  std::vector<std::string> gaits_;
  std::int64_t plan_start_utime_ = 0;
  bool plan_start_set_ = false;
  bool rebuild_ = false;
  int nq_, nv_, nu_;

  std::unique_ptr<LocomotionProblem> loco_;
  std::unique_ptr<GaitGenerator> gen_;
  std::vector<int> gait_pattern_;  // timeline pattern of each gait
  BodyCommand command_;
  int gait_ = 0;
  std::unique_ptr<SlowHost> slow_host_;  // --emulate-slow-host: the solver's work hook
  std::unique_ptr<Solver> solver_;
  std::vector<Eigen::VectorXd> xs_warm_, us_warm_;  // warm start on the references (restarts)
  double t_warm_ = 0.0;                             // plan time of the warm start's knot 0
  std::vector<double> knot_times_;                  // replan's copy of the knots' times
  std::vector<unsigned> knot_masks_;                // and of their contacts (bit c: closed)
  bool need_restart_ = false;  // the last solve failed: start again from standing
  bool have_solved_ = false;   // a solve of this problem succeeded (else the next is the first)
  // The last start-up solve's answer came too late to send: the next tick solves as a start-up
  // again, from that solution on the newer state (bounded by kMaxStartupResolves).
  bool startup_again_ = false;
  int startup_resolves_ = 0;  // since start()
  bool startup_tick_ = false;
  bool solved_ = false;        // the last tick solved (prepare() may follow)
  bool fresh_policy_ = false;  // the last tick's policy came from its solve
  bool tried_ = false;       // the last tick had a fresh state to solve for (a restart may follow)
  double t_last_ = 0.0;      // plan time of the last tick's state (x_ holds it)
  double prepare_ms_ = 0.0;  // its duration
  double trial_ms_ = 0.0;    // a prepared tick's solve per rollout, averaged, with a margin
  int previous_ticks_ = 0;   // consecutive ticks on the previous policy
  bool late_ = false;        // the coming tick started late (countLateTick)
  std::int64_t misses_in_a_row_ = 0;
  bool run_stalled_ = false;  // the host stalled the controller in the current run of misses

  terrain::ElevationMap map_in_;  // the incoming map, sized for terrain.max_cells
  terrain::Steppability steppability_;
  std::int64_t map_utime_ = 0;
  bool on_map_ = false;

  Eigen::VectorXd x_;  // the state as a solver vector
  policy_t policy_, previous_;
  bool have_previous_ = false;
  mpc_status_t status_{};
  MpcCounters counters_;
};

}  // namespace stride
