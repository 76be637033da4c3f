#pragma once
// The receding-horizon controller, free of I/O: one tick turns the newest state estimate into a
// policy message and a status message (ARCHITECTURE.md §1, steps 2-6). The LCM side (mpc_node)
// feeds it validated states and publishes what it fills.
//
// A tick, after start-up:
//   1. plan time t of the state (its stamp minus the plan's start);
//   2. shift the horizon by the whole short knots elapsed since the last solve (the remainder,
//      under half a knot, stays as an FDDP gap), set x0 = the state;
//   3. the planner (locomotion/planner.hpp): Planner::beginTick (the gait asked for, the command,
//      the map or blind), then Planner::replan re-plans the references from the state (contact
//      timing with gait switches, footholds, swing arcs, base pose and twist), rewrites every
//      knot's contacts and references for them and moves the warm start onto the knots' new times
//      (controller/README.md, "Time grid");
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
// policy goes out. Which solve a tick makes is the controller's mode (MpcMode, below); how its
// answer is written on the wire, controller/policy_writer.hpp.

#include <algorithm>
#include <chrono>
#include <memory>

#include "controller/controller_config.hpp"
#include "controller/policy_writer.hpp"
#include "controller/slow_host.hpp"
#include "locomotion/planner.hpp"
#include "messages/validate.hpp"
#include "solver/ddp/solver.hpp"
#include "terrain/elevation_map.hpp"

namespace stride {

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

// What the controller is doing, between ticks (controller/README.md, "The controller's mode").
// Every change of it is Mpc::on(MpcEvent), the one place the transitions are written.
enum class MpcMode : std::int8_t {
  NotStarted,        // no state yet: no problem, no solver
  StartingUp,        // the problem was (re)built, or its start-up solve failed: the next solve is
                     // the start-up solve, from the measured state held still, to convergence
  ResolvingStartUp,  // the start-up answer came too late to send (real time): the next solve is a
                     // start-up solve again, from that solution on the newer state
  Solving,           // warm-started ticks, the next iteration prepared after each policy
  Restarting,        // a solve failed or stalled: the warm start is made again from the
                     // references (by the preparation, or by the next tick)
};
const char* toString(MpcMode mode);

// What moves the mode (Mpc::on).
enum class MpcEvent : std::int8_t {
  Built,          // the problem was (re)built: the first state, or the first after a new plan
  WarmStartMade,  // a restart's warm start was made from the references
  ResolveBegun,   // a start-up solve made again has begun (a failure after it is a regular one's)
  Solved,         // a solve ended with a usable iterate
  AnswerTooLate,  // a start-up answer too old to send, with re-solves left (kMaxStartupResolves)
  Failed,         // a solve or a preparation failed, a line search stalled, or a restart's
                  // references could not be planned
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
  std::int64_t modelHash() const { return out_.modelHash(); }
  // The controller's identity on the policy channel (policy_t.source_id; MpcNode draws it).
  void setSourceId(std::int64_t id) { out_.setSourceId(id); }
  // The robot run its policies answer (policy_t.session: robot_state_t.session of the newest
  // state; MpcNode sets it before each tick).
  void setSession(std::int64_t session) { out_.setSession(session); }
  int nu() const { return nu_; }
  bool started() const { return mode_ != MpcMode::NotStarted; }
  MpcMode mode() const { return mode_; }

  // Replaces the gaits by a planner's contact plan, starting at start_utime on the robot's clock
  // (the command still sets the velocity). Call between ticks; the next tick rebuilds the problem
  // and solves it to convergence, as at start-up (allocating then). Throws std::invalid_argument.
  void setPlan(const ContactPlan& plan, std::int64_t start_utime) {
    planner_.setPlan(plan, start_utime);
  }
  // The robot's clock moved by offset_us and stays there (MpcNode: a clock offset or a new
  // robot): every time kept on that clock moves with it, so the plan time goes on where it was.
  void shiftClock(std::int64_t offset_us);
  // The states come from another run of the robot (MpcNode: its session changed): the next tick
  // builds the problem again and makes the start-up solve from that robot as it stands
  // (Planner::newRobotRun), as a controller started on it would.
  void newRobotRun() { planner_.newRobotRun(); }
  // The body command in force (the node's CommandFilter smooths it toward the one received), and
  // the gait asked for (an index into gaits()). Takes effect at the next tick's re-planning.
  void setCommand(const BodyCommand& command, int gait) { planner_.setCommand(command, gait); }
  // A jump asked for (a command's new jump_id): planned at the next tick with a state
  // (Planner::requestJump), which says in the status what became of it.
  void requestJump(int id, const JumpTarget& target) {
    jump_pending_ = true;
    jump_id_ = id;
    jump_target_ = target;
  }
  // An elevation map (validated: messages/validate.hpp checkTerrain), measured at map.utime on the
  // robot's clock: copied off the wire and handed to the planner, which computes its steppability
  // now (bounded by terrain.max_cells; no allocation after construction) and plans on it while it
  // is fresh. False, and counted, for a map larger than terrain.max_cells or older than the one in
  // use.
  bool setTerrain(const terrain_t& map);
  // The map the ticks plan on (valid() false before the first).
  const terrain::Steppability& terrain() const { return planner_.map(); }
  // Whether the last tick planned on the map.
  bool plannedOnMap() const { return planner_.onMap(); }

  // The gaits the robot walks with ("stand" first).
  const std::vector<std::string>& gaits() const { return planner_.gaits(); }

  // One tick. state: the newest valid estimate (null: none yet); age: seconds since it arrived;
  // deadline: for the solve (Clock::time_point::max() when replaying a log). Fills policy() and
  // status(); true when policy() is to be published.
  bool tick(const robot_state_t* state, double age, Clock::time_point deadline);
  // After a tick that solved: shift, update and linearize for the next state, expected one tick
  // period after this one's, stopping at the deadline (the next tick's start). Allocation-free.
  void prepare(Clock::time_point deadline);

  const policy_t& policy() const { return out_.policy(); }
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
  bool startupTick() const { return last_.startup_solve; }
  // Start-up solves made again on a newer state before one answer went out (real time).
  static constexpr int kMaxStartupResolves = 3;

  // After a tick that solved (a fresh policy, not a fallback): the whole predicted horizon into a
  // horizon_t shaped by msg::shape(h, horizonKnots(), nq, contacts, horizonFootholds())
  // (PolicyWriter::horizon: with the footholds the planner chose for it). Allocation-free. False
  // when the last tick did not solve.
  bool writeHorizon(horizon_t& h) const;
  int horizonKnots() const { return config_.locomotion.knots; }
  int horizonFootholds() const {
    return msg::kHorizonFootholdsPerContact * static_cast<int>(robot_.contacts.size());
  }

  // After a tick: the solver, the problem and the planner, for tests and tools.
  const Solver* solver() const { return solver_.get(); }
  Solver* solver() { return solver_.get(); }  // tools/bench times the solver's parts
  const Planner& planner() const { return planner_; }
  const LocomotionProblem* problem() const {
    return planner_.built() ? &planner_.problem() : nullptr;
  }
  const GaitGenerator* reference() const {
    return planner_.built() ? &planner_.generator() : nullptr;
  }
  double planTime(std::int64_t utime) const { return planner_.planTime(utime); }

 private:
  // The one place the mode changes (MpcMode, MpcEvent; the table in controller/README.md).
  void on(MpcEvent event);
  // The next solve is a start-up solve (to convergence, no deadline).
  bool startingUp() const {
    return mode_ == MpcMode::StartingUp || mode_ == MpcMode::ResolvingStartUp;
  }
  // The warm start must be made again before the next solve.
  bool warmStartLost() const {
    return mode_ == MpcMode::StartingUp || mode_ == MpcMode::Restarting;
  }
  void start(std::int64_t utime);  // builds the planner's problem and the solver (allocates)
  // Shifts the horizon and the warm start by the whole knots from the warm start's knot 0 to t
  // (the remainder, under half a knot, is left to FDDP as a gap at x0). False, and nothing
  // shifted, when t is past the horizon: the warm start is used up.
  bool shiftTo(double t);
  // shed: when not null, a real-time tick without its preparation solves nothing and sets it.
  bool solveTick(double t, Clock::time_point deadline, bool late, SolveStatus& status, bool* shed);
  // The warm start made again from the references planned on the state x_ (at plan time t), with
  // its knot 0 at t_knot0; for a start-up solve (allocating), the measured state held instead
  // (LocomotionProblem::measuredWarmStart). False, nothing changed, when the references could not
  // be planned.
  bool restartWarmStart(double t, double t_knot0, bool startup);
  void holdPolicy(std::int64_t utime, double t);
  void countAnswer(Clock::time_point deadline);  // a miss when the policy is out after it
  void finishStatus(Clock::time_point tick_start, std::int8_t policy_status);

  ControllerConfig config_;
  Robot robot_;
  int nq_, nv_, nu_;
  Planner planner_;
  PolicyWriter out_;

  MpcMode mode_ = MpcMode::NotStarted;
  // What the last tick did, for what follows it: facts of one tick, whatever the mode.
  struct LastTick {
    bool startup_solve = false;  // it made a start-up solve (no deadline: never a miss)
    bool fresh_policy = false;   // its policy came from its solve (writeHorizon)
    // The period after it prepares (prepare()): it solved, it was shed (its preparation made for
    // another time or cut), or its solve failed into a restart.
    bool prepare = false;
  } last_;
  int startup_resolves_ = 0;  // since start()

  std::unique_ptr<SlowHost> slow_host_;  // --emulate-slow-host: the solver's work hook
  std::unique_ptr<Solver> solver_;
  std::vector<Eigen::VectorXd> xs_warm_, us_warm_;  // warm start on the references (restarts)
  double t_warm_ = 0.0;                             // plan time of the warm start's knot 0
  double t_last_ = 0.0;      // plan time of the last tick's state (x_ holds it)
  double prepare_ms_ = 0.0;  // its duration
  double trial_ms_ = 0.0;    // a prepared tick's solve per rollout, averaged, with a margin
  int previous_ticks_ = 0;   // consecutive ticks on the previous policy
  bool late_ = false;        // the coming tick started late (countLateTick)
  std::int64_t misses_in_a_row_ = 0;
  bool run_stalled_ = false;  // the host stalled the controller in the current run of misses

  terrain::ElevationMap map_in_;  // the incoming map off the wire, sized for terrain.max_cells

  Eigen::VectorXd x_;  // the state as a solver vector
  mpc_status_t status_{};
  MpcCounters counters_;
  bool jump_pending_ = false;  // requestJump, until a tick with a state plans it
  int jump_id_ = 0;
  JumpTarget jump_target_;
};

}  // namespace stride
