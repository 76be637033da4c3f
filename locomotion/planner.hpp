#pragma once
// The planner the controller drives (issue 43): what plans the robot's locomotion, behind the few
// calls a tick makes. It owns the gaits on the contact timeline (or a planner's contact plan that
// replaces them), the gait and the body command in force, the elevation map the feet are placed
// on and the rule that judges its age, the gait generator and the locomotion problem it
// configures. The controller (controller/mpc.hpp) keeps the solver, the warm start, the tick's
// clock, the fallbacks and the messages; per tick it calls
//   beginTick(t, utime, contacts)   the gait asked for, the command, the map or blind, the feet;
//   replan(t, x, t_warm, solver)    references, knots, and the warm start carried onto them;
// and reads the problem, the contact mask, the gait and the footholds back for its messages.
// Why each piece plans the way it does: README.md in this folder.
//
// After build() nothing here allocates or throws (tests/locomotion/test_locomotion_no_alloc.cpp):
// build() and setPlan() allocate, and are called between ticks or by a tick that starts up.

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "config/robot_config.hpp"
#include "locomotion/contact_plan.hpp"
#include "locomotion/gait.hpp"
#include "locomotion/gait_generator.hpp"
#include "locomotion/locomotion_problem.hpp"
#include "terrain/elevation_map.hpp"
#include "terrain/steppability.hpp"

namespace stride {

class Solver;  // solver/ddp/solver.hpp: replan() carries its warm start onto the new knots

// How the robot steps: the timing of each gait (locomotion/gait.hpp), or a planner's plan file.
// Times in s.
struct GaitConfig {
  std::map<std::string, GaitTiming> timing;  // by gait name: trot, walk, pace, pronk, ...
  std::string plan_file;  // a contact plan file instead of the gaits (resolved path)
};

// Planning on an elevation map (controller/README.md, "Terrain"): where a foot may stand
// (steppability) and how a map's age is judged. The foothold shift, swing clearance and apex cap
// are the generator's (GaitGeneratorOptions).
struct TerrainConfig {
  terrain::SteppabilityOptions steppability;
  // A map measured longer ago than this (robot clock: the state's stamp minus the map's) is stale:
  // the planner plans blind until a fresh one comes.
  double max_map_age = 0.5;  // [s]
  // The largest map taken (cells); a larger one is refused.
  int max_cells = 256 * 256;
};

// The planner's part of the controller's configuration (controller/controller_config.hpp).
struct PlannerOptions {
  LocomotionOptions locomotion;
  GaitGeneratorOptions generator;
  GaitConfig gait;
  TerrainConfig terrain;
  JumpLimits jump;  // what the robot can jump (none: it does not)
  int threads = 1;  // the problem's per-knot work (ShootingProblem::setThreads)
};

// What became of the last jump asked for (mpc_status_t's jump fields).
enum class JumpState : std::int8_t { None = 0, Accepted = 1, InAir = 2, Landed = 3, Refused = 4 };
struct JumpStatus {
  int id = 0;  // the last jump asked for (0: none)
  JumpState state = JumpState::None;
  char refusal[192] = "";  // why it was refused
  std::int64_t made = 0, refused = 0;
};

// What a tick plans on (beginTick): no map has come yet; the newest map, measured at most
// terrain.max_map_age from the state; or blind, the newest map being older than that.
enum class MapChoice { None, Fresh, Stale };

class Planner {
 public:
  // Compiles the gaits of the robot's contacts and reads options.gait.plan_file, if any; checks
  // what build() will construct (the gaits' timings, the plan against the contacts, the body
  // height postures) so that a tick's build cannot fail. Throws ConfigError, naming config_path.
  // The robot must outlive the planner.
  Planner(const Robot& robot, const PlannerOptions& options, const std::string& config_path);
  ~Planner();
  Planner(const Planner&) = delete;
  Planner& operator=(const Planner&) = delete;

  // The gaits the robot walks with ("stand" first).
  const std::vector<std::string>& gaits() const { return gaits_; }
  // The contacts the problem and the generator are built on (the robot's, in YAML order).
  const ContactSet& contacts() const { return contacts_; }

  // ---- Between ticks (the controller's handlers) ----
  // Replaces the gaits by a planner's contact plan, starting at start_utime on the robot's clock
  // (the command still sets the velocity): needsBuild() until the next build(). Throws
  // std::invalid_argument for a plan that does not fit the contacts (nothing changed then).
  void setPlan(const ContactPlan& plan, std::int64_t start_utime);
  // The body command in force, and the gait asked for (an index into gaits(); others ignored).
  void setCommand(const BodyCommand& command, int gait);
  const BodyCommand& command() const { return command_; }
  // An elevation map measured at `utime` on the robot's clock: its steppability is computed now.
  // False for a map larger than terrain.max_cells, older than the one in use (maps come in stamp
  // order; one more than a second older is a restarted robot's clock, and taken), or not well
  // formed (then no map is in use until the next). Allocates nothing.
  bool setMap(const terrain::ElevationMap& map, std::int64_t utime);
  // The robot's clock moved by offset_us and stays there: the plan's start and the map's stamp
  // move with it, so the plan time goes on where it was.
  void shiftClock(std::int64_t offset_us);
  // Another run of the robot (restarted, elsewhere, standing): nothing planned for the one before
  // holds for it (its footholds, its gait's phase), so the next tick builds again, as at the start:
  // needsBuild() until the next build(). A plan goes on at its plan time.
  void newRobotRun() { plan_pending_ = true; }
  // A jump asked for at plan time t (a command with a new jump id; locomotion/jump.hpp): refused,
  // the reason in jumpStatus(), when the robot cannot make it, a plan replaces the gaits, the
  // planner is not built yet, or another jump is under way; else made from the timeline's next
  // switch instant (the gait's next phase with every foot down): a push on every foot
  // (jump.push), the flight, a landing on every foot (jump.landing), then the gait asked for
  // again. The velocity command waits meanwhile. Allocation-free.
  bool requestJump(int id, const JumpTarget& target, double t);
  const JumpStatus& jumpStatus() const { return jump_status_; }
  // Flights whose touch-down the measured contacts moved (landing as it happens, beginTick):
  // landed before the clock had it, and after (the flight held a step at a time).
  std::int64_t earlyLandings() const { return early_landings_; }
  std::int64_t lateLandings() const { return late_landings_; }

  // ---- Build (allocates: the first state, or the first after setPlan) ----
  // Before the first build, and after a new plan.
  bool needsBuild() const { return loco_ == nullptr || plan_pending_; }
  bool built() const { return loco_ != nullptr; }
  // Builds the problem, the generator and the timeline's patterns around the nominal posture
  // (the references anchor on the measured state at every tick, so where the robot stands needs
  // no rebuild). The plan's start is utime unless a plan set it. The gaits start standing; a plan
  // at its plan time 0.
  void build(std::int64_t utime);

  // ---- A tick (allocation-free) ----
  // Plan time of a stamp on the robot's clock [s].
  double planTime(std::int64_t utime) const { return (utime - plan_start_utime_) * 1e-6; }
  // A new state at plan time t (stamp utime): the gait asked for is scheduled (at the timeline's
  // next instant every foot is down), the command taken, the map chosen (fresh at utime, else
  // blind), and the estimator's loaded contacts (bit c: contact c; none: not reported). With them
  // a flight lands as it happens: a foot loaded in the second half of a flight ends it now (the
  // pattern goes on from its touch-down), and a flight the clock ends with no foot loaded goes on
  // by 20 ms at a time, at most 0.15 s (ContactTimeline::retimeFrom).
  MapChoice beginTick(double t, std::int64_t utime, std::optional<unsigned> loaded);
  // Re-plans the references from the state x at plan time t for the horizon from t_warm (the warm
  // start's knot 0, on the knot grid), rewrites every knot for them, and carries the solver's
  // warm start onto the knots' new times (Solver::retimeWarmStart); a knot that now lifts a foot
  // the warm start had down starts from the torques that hold the posture on its contacts. False
  // (nothing changed) when the generator or the problem refuses (a non-finite time or state).
  bool replan(double t, const Eigen::VectorXd& x, double t_warm, Solver& solver);
  // Warm starts for a solver (after replan): the references (each knot's state reference and
  // holding torques), or the measured state x held still on each knot's contacts (allocates: for
  // a start-up solve).
  void referenceWarmStart(std::vector<Eigen::VectorXd>& xs, std::vector<Eigen::VectorXd>& us) const;
  void measuredWarmStart(const Eigen::VectorXd& x, std::vector<Eigen::VectorXd>& xs,
                         std::vector<Eigen::VectorXd>& us) const;

  // After build(): the problem the solver solves, the generator that plans its references.
  LocomotionProblem& problem() { return *loco_; }
  const LocomotionProblem& problem() const { return *loco_; }
  const GaitGenerator& generator() const { return *gen_; }
  // The contacts closed at plan time t (bit c: contact c) and the gait in force then ("plan" while
  // a contact plan replaces the gaits).
  unsigned mask(double t) const { return gen_->mask(t); }
  const std::string& gaitAt(double t) const;

  // The touch-downs the generator planned after plan time t and no later than t_end, by contact
  // then time, at most max_per_contact each, of the first `contacts` contacts: visit(c, stance)
  // for each, until it returns false (no room for more). Allocation-free.
  template <class Visit>
  void touchDowns(double t, double t_end, int contacts, int max_per_contact, Visit&& visit) const {
    for (int c = 0; c < gen_->timeline().contacts() && c < contacts; ++c) {
      int of_contact = 0;
      for (int i = 0; i < gen_->stances(c) && of_contact < max_per_contact; ++i) {
        const GaitGenerator::Stance& s = gen_->stance(c, i);
        if (!(s.touch_down > t && s.touch_down <= t_end)) continue;
        if (!visit(c, s)) return;
        ++of_contact;
      }
    }
  }

  // The map: the newest taken (valid() false before the first, or after one not well formed), its
  // stamp on the robot's clock, and whether the last beginTick chose it.
  const terrain::Steppability& map() const { return steppability_; }
  std::int64_t mapUtime() const { return map_utime_; }
  bool onMap() const { return on_map_; }

 private:
  const Robot& robot_;
  PlannerOptions options_;
  std::string config_path_;
  ContactSet contacts_;
  std::vector<std::string> gaits_;
  ContactPlan plan_;
  bool have_plan_ = false;     // a plan file or a planner's plan replaces the gaits
  bool plan_pending_ = false;  // setPlan since the last build
  std::int64_t plan_start_utime_ = 0;
  bool plan_start_set_ = false;  // by a plan; else the first build sets it

  std::unique_ptr<LocomotionProblem> loco_;
  std::unique_ptr<GaitGenerator> gen_;
  std::vector<int> gait_pattern_;  // the timeline's pattern of each gait
  BodyCommand command_;
  int gait_ = 0;
  std::vector<double> knot_times_;    // replan's copy of the knots' times before the update
  std::vector<unsigned> knot_masks_;  // and of their contacts (bit c: closed)

  terrain::Steppability steppability_;
  std::int64_t map_utime_ = 0;
  bool on_map_ = false;

  // Jumps: a pattern per flight time (jump.min_flight, + jump.flight_step, ...), the jump under
  // way (its take-off, touch-down and end on the plan clock) and what became of the last one.
  // Landing as it happens (beginTick): a flight's touch-down moved to the measured one.
  void landOnMeasuredContacts(double t, unsigned loaded);
  std::int64_t early_landings_ = 0, late_landings_ = 0;
  double late_since_ = -1.0;  // the clock's touch-down of the flight held late (< 0: none)
  std::vector<int> jump_pattern_;
  bool jump_active_ = false;
  int jump_active_id_ = 0;
  JumpState jump_phase_ = JumpState::None;  // of the jump under way
  double jump_lift_off_ = 0.0, jump_touch_down_ = 0.0, jump_end_ = 0.0;
  JumpTarget jump_target_;
  JumpStatus jump_status_;
};

}  // namespace stride
