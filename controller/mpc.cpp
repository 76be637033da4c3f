#include "controller/mpc.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

namespace stride {

namespace {
// μ at which a line search that takes no step counts as stuck (the solve fails at 1e9).
constexpr double kStalledRegularization = 1e4;
// A tick's rollout may take this much longer than the average before its answer is late.
constexpr double kTrialMargin = 1.5;
// Each tick shed for the rollout's time scales the estimate by this (Mpc::solveTick).
constexpr double kTrialForget = 0.9;

double millisSince(Solver::Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Solver::Clock::now() - t0).count();
}
Solver::Clock::time_point millisFromNow(double ms) {
  return Solver::Clock::now() + std::chrono::duration_cast<Solver::Clock::duration>(
                                    std::chrono::duration<double, std::milli>(ms));
}
// The controller walks legged robots: checked before the planner reads the robot.
const Robot& legged(const Robot& robot, const std::string& config_path) {
  if (!robot.model.hasFreeFlyer())
    throw ConfigError(config_path + ": the robot '" + robot.name +
                      "' has a fixed base: stride-mpc walks legged robots");
  return robot;
}
PlannerOptions plannerOptions(const ControllerConfig& c) {
  PlannerOptions o;
  o.locomotion = c.locomotion;
  o.generator = c.generator;
  o.gait = c.gait;
  o.terrain = c.terrain;
  o.jump = c.jump;
  o.threads = c.threads;
  return o;
}
}  // namespace

const char* toString(MpcMode mode) {
  switch (mode) {
    case MpcMode::NotStarted:
      return "not started";
    case MpcMode::StartingUp:
      return "starting up";
    case MpcMode::ResolvingStartUp:
      return "resolving the start-up";
    case MpcMode::Solving:
      return "solving";
    case MpcMode::Restarting:
      return "restarting";
  }
  return "?";
}

Mpc::Mpc(const ControllerConfig& config)
    : config_(config),
      robot_(loadRobot(config.robot_yaml, config.robots_dirs)),
      nq_(robot_.model.nq),
      nv_(robot_.model.nv),
      nu_(actuatedDimension(robot_.model)),
      planner_(legged(robot_, config_.path), plannerOptions(config_), config_.path),
      out_(robot_, config_.policy_knots, config_.locomotion.dt, config_.hold_kp, config_.hold_kd) {
  x_ = Eigen::VectorXd::Zero(nq_ + nv_);
  map_in_.height.reserve(config_.terrain.max_cells);
  status_.policy_status = kPolicyNone;
  status_.solver_status = -1;
}

Mpc::~Mpc() = default;

void Mpc::on(MpcEvent event) {
  switch (event) {
    case MpcEvent::Built:
      mode_ = MpcMode::StartingUp;
      break;
    case MpcEvent::WarmStartMade:  // a restart's warm start serves as a regular tick's
      if (mode_ == MpcMode::Restarting) mode_ = MpcMode::Solving;
      break;
    case MpcEvent::ResolveBegun:  // under way: what follows is a regular tick's
      if (mode_ == MpcMode::ResolvingStartUp) mode_ = MpcMode::Solving;
      break;
    case MpcEvent::Solved:
      mode_ = MpcMode::Solving;
      break;
    case MpcEvent::AnswerTooLate:
      mode_ = MpcMode::ResolvingStartUp;
      break;
    case MpcEvent::Failed:  // before any solve succeeded, the next is still the start-up solve
      if (mode_ != MpcMode::StartingUp) mode_ = MpcMode::Restarting;
      break;
  }
}

void Mpc::shiftClock(std::int64_t offset_us) {
  planner_.shiftClock(offset_us);
  out_.shiftClock(offset_us);
}

bool Mpc::setTerrain(const terrain_t& m) {
  // Off the wire into the map buffer (its room reserved for terrain.max_cells: no allocation).
  const long cells = static_cast<long>(m.rows) * m.cols;
  bool taken = m.rows >= 1 && m.cols >= 1 && cells <= config_.terrain.max_cells &&
               static_cast<long>(m.height.size()) == m.rows;
  if (taken) {
    map_in_.origin_x = m.origin_x;
    map_in_.origin_y = m.origin_y;
    map_in_.resolution = m.resolution;
    map_in_.rows = m.rows;
    map_in_.cols = m.cols;
    map_in_.height.resize(cells);  // within the reserved capacity: no allocation
    for (int r = 0; r < m.rows && taken; ++r) {
      taken = static_cast<int>(m.height[r].size()) == m.cols;
      if (taken)
        std::copy(m.height[r].begin(), m.height[r].end(),
                  map_in_.height.begin() + static_cast<long>(r) * m.cols);
    }
  }
  taken = taken && planner_.setMap(map_in_, m.utime);
  ++(taken ? counters_.maps : counters_.maps_refused);
  return taken;
}

void Mpc::start(std::int64_t utime) {
  solver_.reset();  // it solves the problem the planner replaces
  planner_.build(utime);
  LocomotionProblem& loco = planner_.problem();
  SolverOptions options;
  options.line_search_steps = config_.line_search_steps;
  if (config_.emulated_slowdown > 1.0) {
    slow_host_ = std::make_unique<SlowHost>(config_.emulated_slowdown);
    options.work_hook = slow_host_.get();
  }
  solver_ = std::make_unique<Solver>(loco.problem(), config_.solver, options);
  if (config_.solver == SolverKind::BoxFddp)
    solver_->setControlBounds(loco.controlLower(), loco.controlUpper());
  xs_warm_.assign(config_.locomotion.knots + 1, loco.nominal());
  us_warm_.assign(config_.locomotion.knots, Eigen::VectorXd::Zero(nu_));
  out_.forgetPrevious();
  startup_resolves_ = 0;
  on(MpcEvent::Built);
}

bool Mpc::restartWarmStart(double t, double t_knot0, bool startup) {
  t_warm_ = t_knot0;
  if (!planner_.replan(t, x_, t_warm_, *solver_)) return false;
  // The first solve starts where the robot is, held still: a controller started (or restarted)
  // on a robot that stands anywhere but in the nominal posture -- feet where a stand-down left
  // them, turned, at another height -- would otherwise start from the references' default joint
  // angles, far from every state its contacts allow, and its first iterations must close those
  // gaps (from a quadruped stood down on legs folded the wrong way, the references' warm start
  // failed 19 solves in a row; this one converged). Later restarts, in the tick, allocate nothing
  // and take the references.
  if (startup)
    planner_.measuredWarmStart(x_, xs_warm_, us_warm_);
  else
    planner_.referenceWarmStart(xs_warm_, us_warm_);
  solver_->setWarmStart(xs_warm_, us_warm_);
  // After the start-up solve μ starts again at the ticks' trust region, not below it: from 1e-9 a
  // restart spent 14 ticks of line searches that took no step climbing back, and the quadruped
  // fell at a sidestep's start in real time.
  solver_->setRegularization(mode_ != MpcMode::StartingUp ? config_.min_regularization
                                                          : solver_->options.reg_initial);
  on(MpcEvent::WarmStartMade);
  return true;
}

bool Mpc::shiftTo(double t) {
  // In whole knots of the grid's first (shortest) duration; the trajectory itself moves in
  // Planner::replan (Solver::retimeWarmStart), the knot models with it here, so that the short
  // knots' kept solves stay with their states (KeptSolve).
  LocomotionProblem& loco = planner_.problem();
  const double dt = config_.locomotion.dt;
  const double shift = std::floor((t - t_warm_) / dt + 0.5);
  if (t_warm_ + shift * dt >= loco.knotTime(loco.problem().horizon())) return false;
  if (shift >= 1.0) {
    const int n = static_cast<int>(shift);
    loco.problem().shift(n);
    t_warm_ += n * dt;
  }
  return true;
}

bool Mpc::solveTick(double t, Clock::time_point deadline, bool late, SolveStatus& result,
                    bool* shed) {
  if (shed != nullptr) *shed = false;
  ShootingProblem& problem = planner_.problem().problem();
  const double dt = config_.locomotion.dt;
  // The first solve, before any policy went out, runs to convergence (no deadline); a restart
  // after a failure gets the normal budget and converges over the following ticks. So does a
  // start-up solve made again on a newer state (ResolvingStartUp), from the last one's solution.
  const bool first = startingUp();
  on(MpcEvent::ResolveBegun);
  // The preparation serves while the state is less than a knot from the prepared knot 0: only
  // x0 changes, and the time between them stays a gap at x0 as after a shift. (Within half a knot
  // when ticks come on time; up to a period more after a late tick, when the loop skipped one.)
  const bool use_prepared = !warmStartLost() && solver_->prepared() && std::abs(t - t_warm_) < dt;
  status_.prepared = use_prepared ? 1 : 0;
  status_.prepare_ms = use_prepared ? prepare_ms_ : 0.0;
  problem.setX0(x_);
  // Overload, last resort: in real time a tick without its preparation (cut by the period's end,
  // made for another time, or a restart after a failed solve) would run a whole iteration before
  // its answer and make the next period late too. It re-sends the previous policy instead, and
  // the period prepares again (a restart included: prepare()).
  // So does a tick that starts too late for even one rollout before its deadline (a late answer
  // would make two misses in a row: the one that made it late, and its own); its preparation
  // stays for the next tick.
  const bool real_time = deadline != Clock::time_point::max();
  if (shed != nullptr && !first && real_time &&
      (!use_prepared || millisFromNow(trial_ms_) > deadline)) {
    // A tick shed for the rollout's time measures no rollout: an estimate too high to allow one
    // would never be measured again, and every tick would shed for good. It forgets itself.
    if (use_prepared) trial_ms_ *= kTrialForget;
    *shed = true;
    return false;
  }
  if (!use_prepared) {
    solver_->discardPreparation();  // made for another time, or left over from before a restart
    if (!first) ++counters_.unprepared_solves;
    // The knots' phases and references on the warm start's own time grid: its knot 0 is at
    // t_warm_. Updated for t instead, a touch-down half a knot away would land on the next knot
    // while the shifted trajectory has its velocity jump on this one: a gap of tens of rad/s at
    // every impulse knot after each shift, and line searches that stall. (A restart re-plans for
    // its own warm start, at t.)
    if (warmStartLost() || !shiftTo(t)) {
      if (!restartWarmStart(t, t, first)) {  // the references could not be planned
        on(MpcEvent::Failed);
        return false;
      }
    } else if (!planner_.replan(t, x_, t_warm_, *solver_)) {
      return false;
    }
  }
  last_.startup_solve = first;
  // The start-up solve may backtrack as far as it needs; the ticks' line search is bounded.
  // A late tick (the last period ran over) tries the full step only: one rollout.
  solver_->options.line_search_steps = first ? 10 : late ? 1 : config_.line_search_steps;
  if (late && !first) ++counters_.shed_line_searches;
  solver_->options.reg_min = first ? SolverOptions().reg_min : config_.min_regularization;
  const Clock::time_point solve_start = Clock::now();
  result = first ? solver_->solve(config_.initial_iterations)
                 : solver_->solve(config_.max_iterations, deadline);
  // What one rollout of a prepared tick takes on this host (with the rest of the solve, and a
  // margin): the least time a tick needs before its deadline. Slowly averaged, so that one
  // interrupted solve does not shed the next ticks.
  if (use_prepared && !first && solver_->forwardPasses() > 0) {
    // At most a period: a host stall inside the solve (SIGSTOP, swapping: issue 33's pause made
    // one rollout "take" 1.5 s) is not what a rollout costs.
    const double need = std::min(kTrialMargin * millisSince(solve_start) / solver_->forwardPasses(),
                                 1e3 / config_.rate_hz);
    trial_ms_ = trial_ms_ == 0.0 ? need : 0.9 * trial_ms_ + 0.1 * need;
  }
  if (result == SolveStatus::NonFinite || result == SolveStatus::NoDescent) {
    ++counters_.failed_solves;
    on(MpcEvent::Failed);
    return false;
  }
  on(MpcEvent::Solved);
  return true;
}

bool Mpc::tick(const robot_state_t* state, double age, Clock::time_point deadline) {
  const Clock::time_point tick_start = Clock::now();
  ++counters_.ticks;
  status_.tick = counters_.ticks;
  status_.solve_ms = 0.0;
  status_.iterations = 0;
  status_.solver_status = -1;
  last_ = LastTick{};
  const bool late = late_;  // countLateTick() before this tick
  late_ = false;
  status_.prepared = 0;
  status_.prepare_ms = 0.0;

  if (state == nullptr) {  // nothing to control yet: publish no policy
    ++counters_.ticks_without_state;
    status_.utime = 0;
    finishStatus(tick_start, kPolicyNone);
    return false;
  }
  status_.utime = state->utime;
  for (int i = 0; i < nq_; ++i) x_[i] = state->q[i];
  for (int i = 0; i < nv_; ++i) x_[nq_ + i] = state->v[i];
  if (robot_.model.hasFreeFlyer()) x_.segment<4>(3).normalize();  // within 1e-4 of unit already

  if (planner_.needsBuild()) start(state->utime);
  const double t = planner_.planTime(state->utime);
  status_.plan_time = t;
  // The estimator's contacts, when it reports them (robot YAML order).
  std::optional<unsigned> loaded;
  if (state->ncontacts == static_cast<std::int32_t>(robot_.contacts.size())) {
    loaded = 0u;
    for (int c = 0; c < state->ncontacts; ++c) *loaded |= (state->contact[c] != 0 ? 1u : 0u) << c;
  }
  switch (planner_.beginTick(t, state->utime, loaded)) {
    case MapChoice::Fresh:
      ++counters_.map_ticks;
      break;
    case MapChoice::Stale:
      ++counters_.stale_map_ticks;
      break;
    case MapChoice::None:
      break;
  }
  if (jump_pending_) {
    planner_.requestJump(jump_id_, jump_target_, t);
    jump_pending_ = false;
  }
  const JumpStatus& jump = planner_.jumpStatus();
  status_.jump_id = jump.id;
  status_.jump_state = static_cast<std::int8_t>(jump.state);
  status_.jump_refusal.assign(jump.refusal);  // within the capacity reserved at start
  status_.jumps_made = jump.made;
  status_.jumps_refused = jump.refused;
  status_.phase = static_cast<std::int32_t>(planner_.mask(t));
  status_.gait = planner_.gaitAt(t);
  const BodyCommand& command = planner_.command();
  status_.command[0] = command.vx;
  status_.command[1] = command.vy;
  status_.command[2] = command.yaw_rate;
  status_.command[3] = command.height;

  if (age > config_.max_state_age) {
    ++counters_.stale_states;
  } else {
    const Clock::time_point solve_start = Clock::now();
    t_last_ = t;
    SolveStatus result = SolveStatus::NonFinite;
    bool shed = false;
    bool ok = solveTick(t, deadline, late, result, &shed);
    if (shed) {
      // The period prepares for the next tick (or restarts).
      last_.prepare = true;
      if (out_.previous(state->utime, counters_.ticks)) {
        ++counters_.shed_ticks;
        countAnswer(deadline);
        finishStatus(tick_start, out_.policy().status);
        return true;
      }
      // Nothing left to re-send (no policy solved for a whole policy's length): a whole iteration
      // now when the last ones say it ends before the deadline; else the fallback below, and
      // the period prepares (an iteration past the deadline made several misses in a row at 3x
      // slowdown).
      if (millisFromNow(kTrialMargin * (prepare_ms_ + trial_ms_)) < deadline) {
        last_.prepare = false;
        ok = solveTick(t, deadline, late, result, nullptr);
      } else {
        ++counters_.fallbacks;
        holdPolicy(state->utime, t);
        countAnswer(deadline);
        finishStatus(tick_start, out_.policy().status);
        return true;
      }
    }
    status_.solve_ms = millisSince(solve_start);
    status_.solver_status = static_cast<std::int32_t>(result);
    status_.iterations = solver_->iterations();
    status_.cost = solver_->cost();
    status_.gap = solver_->gap();
    status_.regularization = solver_->regularization();
    const int n_stats = solver_->statsCount();
    status_.step = n_stats > 0 ? solver_->stats()[n_stats - 1].step : 0.0;
    // In real time a start-up solve that took longer than a period answers for a state that old
    // (the humanoid's: 0.1-0.8 s): the robot has moved on (a stand-down, a push) and the
    // policy's knots are behind its clock. It is not sent; the next tick solves again, to
    // convergence, from this solution on the state then, which takes a few iterations.
    const bool real_time = deadline != Clock::time_point::max();
    if (ok && last_.startup_solve && real_time && startup_resolves_ < kMaxStartupResolves &&
        status_.solve_ms > 1e3 / config_.rate_hz) {
      ++startup_resolves_;
      ++counters_.startup_resolves;
      on(MpcEvent::AnswerTooLate);
      finishStatus(tick_start, kPolicyNone);
      return false;
    }
    // Past the re-solves, a start-up solve that took more than half a policy's span is not sent
    // either: its policy would reach the robot at or past its end (issue 33: 4 of 10 real-time
    // restarts of the humanoid sent one 0.2 s old, and one of those robots fell). The next tick
    // is a regular one from this solution, bounded by its deadline.
    const double policy_ms = 1e3 * (out_.policy().knots - 1) * config_.locomotion.dt;
    if (ok && last_.startup_solve && real_time && status_.solve_ms > 0.5 * policy_ms) {
      ++counters_.startup_resolves;
      finishStatus(tick_start, kPolicyNone);
      return false;
    }
    if (ok) {
      // A line search that takes no step, tick after tick, while μ climbs to its limit is stuck
      // on a warm start the new references broke (a sudden stand on a frozen robot lifted the
      // rollouts of 30 ms knots into singular postures for 8 ticks until the solve failed): start
      // again from the references at the next tick (counted). Not sooner: a few rejected steps
      // are part of a hard turn, and a restart then made ANYmal fall.
      const bool stalled = result == SolveStatus::MaxIterations && status_.step == 0.0 &&
                           solver_->regularization() >= kStalledRegularization;
      if (stalled && !last_.startup_solve) {
        on(MpcEvent::Failed);
        ++counters_.stall_restarts;
      }
      last_.prepare = true;
      // Cut: the line search stopped for the deadline (before it, when its next trial would have
      // ended after it: then on time, not a miss).
      const bool cut = result == SolveStatus::Deadline;
      out_.solved({state->utime, t, counters_.ticks}, status_.phase,
                  cut ? kPolicyDeadline : kPolicySolved, planner_.problem().problem(), *solver_);
      last_.fresh_policy = true;
      previous_ticks_ = 0;
      countAnswer(deadline);
      finishStatus(tick_start, out_.policy().status);
      return true;
    }
    // Failed: the period after a failure that needs a restart makes it (prepare()).
    last_.prepare = mode_ == MpcMode::Restarting;
  }
  // Fallback: the previous policy advanced to now, for a while; then hold the posture.
  ++counters_.fallbacks;
  if (config_.fallback == Fallback::Previous && previous_ticks_ < config_.max_previous_ticks &&
      out_.previous(state->utime, counters_.ticks)) {
    ++previous_ticks_;
  } else {
    holdPolicy(state->utime, t);
  }
  countAnswer(deadline);
  finishStatus(tick_start, out_.policy().status);
  return true;
}

bool Mpc::writeHorizon(horizon_t& h) const {
  if (!last_.fresh_policy || !planner_.built()) return false;
  return out_.horizon(h, planner_, *solver_, t_last_);
}

void Mpc::countAnswer(Clock::time_point deadline) {
  // A deadline is on the answer: whatever policy goes out after it (solved, cut, re-sent, hold)
  // is a miss; the start-up solve has none.
  if (!last_.startup_solve && deadline != Clock::time_point::max() && Clock::now() > deadline)
    ++counters_.deadline_misses;
}

void Mpc::prepare(Clock::time_point deadline) {
  // After a failed or stalled solve, the warm start is made again here, from the references
  // planned on the last state, for when the next state is expected: the restart's whole
  // iteration then runs off the state-to-policy path, as every other preparation does (in the
  // tick it missed the deadline, 4 of 4 times in a 60 s real-time run).
  if (!last_.prepare) return;
  last_.prepare = false;  // one preparation per tick that solved, or tried to
  const bool restart = mode_ == MpcMode::Restarting;
  // Past its deadline already (after a missed period it ends at the next tick's start): nothing
  // to start; the next tick re-sends the previous policy and its period prepares.
  if (Clock::now() >= deadline) return;
  const double t_next = t_last_ + 1.0 / config_.rate_hz;
  // A tick shed for lack of time left its preparation unused: it still serves the next state.
  if (!restart && solver_->prepared() && std::abs(t_next - t_warm_) < config_.locomotion.dt) return;
  // A preparation the last period's deadline cut goes on where it stopped while it still serves
  // the next state (less than a knot from its knot 0, as in solveTick): its work is not redone.
  const bool resume =
      !restart && solver_->preparing() && std::abs(t_next - t_warm_) < config_.locomotion.dt;
  if (!resume) solver_->discardPreparation();
  // The next state past the warm start's horizon (the controller was stopped for longer than
  // the horizon: a host stall, SIGSTOP, a debugger): the warm start is made again from the
  // references, as after a failure. Returning unprepared instead left every later tick to shed
  // and fall back, for good (issue 33: 2461 fallbacks after a 1.5 s pause, the robot standing).
  const bool behind = !restart && !resume && !shiftTo(t_next);
  if (restart || behind) {
    // The references could not be planned: the next tick tries.
    if (!restartWarmStart(t_last_, t_next, false)) return;
  } else if (!resume) {
    // On the trajectory's grid, as in solveTick.
    if (!planner_.replan(t_last_, x_, t_warm_, *solver_)) return;
  }
  SolveStatus why = SolveStatus::MaxIterations;
  if (solver_->prepare(deadline, why)) {
    prepare_ms_ = solver_->prepareMillis();
  } else if (why == SolveStatus::NonFinite || why == SolveStatus::NoDescent) {
    // The trajectory cannot be linearized: the next tick starts again from standing.
    ++counters_.failed_solves;
    on(MpcEvent::Failed);
  }
  // At the deadline: not prepared yet; in real time the next tick re-sends the previous policy
  // and its period resumes this preparation.
}

void Mpc::holdPolicy(std::int64_t utime, double t) {
  // The torques that hold the default posture on the contacts of the current phase.
  const unsigned phase = planner_.mask(t);
  out_.hold({utime, t, counters_.ticks}, phase, x_, planner_.problem().holdingControl(phase));
}

void Mpc::finishStatus(Clock::time_point tick_start, std::int8_t policy_status) {
  status_.policy_status = policy_status;
  status_.deadline_misses = counters_.deadline_misses;
  status_.late_ticks = counters_.late_ticks;
  status_.fallbacks = counters_.fallbacks;
  status_.stale_states = counters_.stale_states;
  status_.ticks_without_state = counters_.ticks_without_state;
  status_.unprepared_solves = counters_.unprepared_solves;
  const terrain::Steppability& map = planner_.map();
  status_.terrain_mode = planner_.onMap() ? 1 : map.valid() ? 2 : 0;
  status_.map_age =
      map.valid() && status_.utime != 0 ? (status_.utime - planner_.mapUtime()) * 1e-6 : -1.0;
  status_.maps = counters_.maps;
  status_.stale_map_ticks = counters_.stale_map_ticks;
  status_.tick_ms = millisSince(tick_start);
}

}  // namespace stride
