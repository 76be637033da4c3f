#include "controller/mpc.hpp"

#include <algorithm>
#include <cmath>

#include "config/model_hash.hpp"
#include "locomotion/gait.hpp"
#include "messages/hold_pd.hpp"
#include "solver/contact/knot_dynamics.hpp"
#include "solver/multibody/frames.hpp"

namespace stride {

// The contact limit is one number (solver/contact/contact_set.hpp): the wire's int32 masks carry
// it.
static_assert(kMaxContacts <= msg::kContactMaskBits,
              "policy_t.phase, mpc_status_t.phase, horizon_t.contact_mask: bit c for contact c");

namespace {
// The gait reported while a planner's plan replaces the gaits.
const std::string kPlanGait = "plan";
// Velocity-level Baumgarte term of the controller's contact model (a + kd v = 0 at the foot): a
// foot's drift velocity decays in 1/kd = 20 ms instead of growing over the 1 s horizon.
constexpr double kContactDamping = 50.0;
// The planned centre of pressure stays in this fraction of the sole: at the edge, the slightest
// disturbance tips the foot.
constexpr double kSoleMargin = 0.8;
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
}  // namespace

Mpc::Mpc(const ControllerConfig& config)
    : config_(config), robot_(loadRobot(config.robot_yaml, config.robots_dirs)) {
  const Model& model = robot_.model;
  nq_ = model.nq;
  nv_ = model.nv;
  nu_ = actuatedDimension(model);
  for (const ContactSpec& c : robot_.contacts)
    contacts_.add(model, c.frame, c.dim, ReferenceFrame::LocalWorldAligned, 0.0, kContactDamping);
  config_.locomotion.sole_half_extents = kSoleMargin * robot_.sole_half_extents;
  config_.generator.sole_half_length = robot_.sole_half_extents.x();
  gaits_ = gaitNames(static_cast<int>(robot_.contacts.size()));
  for (const std::string& g : gaits_) {  // a bad timing fails here, not at the first state
    const auto timing = config_.gait.timing.find(g);
    makeGaitPattern(g, timing == config_.gait.timing.end() ? GaitTiming{} : timing->second,
                    robot_.contacts);
  }
  if (!config_.gait.plan_file.empty()) {
    plan_ = loadContactPlan(config_.gait.plan_file);
    have_plan_ = true;
    try {
      plan_.validate(contacts_);
    } catch (const std::invalid_argument& e) {
      throw ConfigError(config_.path + ": the contact plan does not fit the robot: " + e.what());
    }
  }
  if (!robot_.model.hasFreeFlyer())
    throw ConfigError(config_.path + ": the robot '" + robot_.name +
                      "' has a fixed base: stride-mpc walks legged robots");
  // What the first state builds (start()) must not fail then: the references' checks (contacts,
  // the body-height postures) run here, once.
  try {
    Eigen::VectorXd x = Eigen::VectorXd::Zero(nq_ + nv_);
    x.head(nq_) = robot_.default_q;
    GaitGenerator check(robot_.model, contacts_, x, config_.generator);
  } catch (const std::invalid_argument& e) {
    throw ConfigError(config_.path + ": " + e.what());
  }
  x_ = Eigen::VectorXd::Zero(nq_ + nv_);
  steppability_ = terrain::Steppability(config_.terrain.steppability, config_.terrain.max_cells);
  map_in_.height.reserve(config_.terrain.max_cells);
  msg::shape(policy_, config_.policy_knots, nq_, nv_, nu_);
  msg::shape(previous_, config_.policy_knots, nq_, nv_, nu_);
  policy_.model_hash = previous_.model_hash = stride::modelHash(robot_);
  policy_.source_id = previous_.source_id = 0;
  status_.policy_status = kPolicyNone;
  status_.solver_status = -1;
}

Mpc::~Mpc() = default;

void Mpc::setPlan(const ContactPlan& plan, std::int64_t start_utime) {
  plan.validate(contacts_);
  plan_ = plan;
  have_plan_ = true;
  plan_start_utime_ = start_utime;
  plan_start_set_ = true;
  rebuild_ = true;
}

void Mpc::shiftClock(std::int64_t offset_us) {
  plan_start_utime_ += offset_us;
  if (steppability_.valid()) map_utime_ += offset_us;
  previous_.utime += offset_us;
  previous_.knot0_utime += offset_us;
}

bool Mpc::setTerrain(const terrain_t& m) {
  const long cells = static_cast<long>(m.rows) * m.cols;
  if (m.rows < 1 || m.cols < 1 || cells > config_.terrain.max_cells ||
      static_cast<long>(m.height.size()) != m.rows ||
      // Maps come in stamp order; one more than a second behind is a restarted robot's clock.
      (steppability_.valid() && m.utime < map_utime_ && m.utime > map_utime_ - 1000000)) {
    ++counters_.maps_refused;
    return false;
  }
  map_in_.origin_x = m.origin_x;
  map_in_.origin_y = m.origin_y;
  map_in_.resolution = m.resolution;
  map_in_.rows = m.rows;
  map_in_.cols = m.cols;
  map_in_.height.resize(cells);  // within the reserved capacity: no allocation
  for (int r = 0; r < m.rows; ++r) {
    if (static_cast<int>(m.height[r].size()) != m.cols) {
      ++counters_.maps_refused;
      return false;
    }
    std::copy(m.height[r].begin(), m.height[r].end(),
              map_in_.height.begin() + static_cast<long>(r) * m.cols);
  }
  if (!steppability_.update(map_in_)) {
    ++counters_.maps_refused;
    return false;
  }
  map_utime_ = m.utime;
  ++counters_.maps;
  return true;
}

void Mpc::chooseMap(std::int64_t utime) {
  on_map_ = false;
  if (steppability_.valid()) {
    const double age = (utime - map_utime_) * 1e-6;
    on_map_ = age >= -config_.terrain.max_map_age && age <= config_.terrain.max_map_age;
    ++(on_map_ ? counters_.map_ticks : counters_.stale_map_ticks);
  }
  gen_->setMap(on_map_ ? &steppability_ : nullptr);
}

void Mpc::setCommand(const BodyCommand& command, int gait) {
  command_ = command;
  if (gait >= 0 && gait < static_cast<int>(gaits_.size())) gait_ = gait;
}

void Mpc::start(std::int64_t utime) {
  if (!plan_start_set_) {
    plan_start_utime_ = utime;
    plan_start_set_ = true;
  }
  // The nominal posture at the origin: the references are anchored on the measured state at
  // every tick (GaitGenerator::plan), so where the robot stands now needs no rebuild.
  Eigen::VectorXd x_nominal = Eigen::VectorXd::Zero(nq_ + nv_);
  x_nominal.head(nq_) = robot_.default_q;
  solver_.reset();
  loco_ =
      std::make_unique<LocomotionProblem>(robot_.model, contacts_, x_nominal, config_.locomotion);
  loco_->problem().setThreads(config_.threads);
  gen_ = std::make_unique<GaitGenerator>(robot_.model, contacts_, x_nominal, config_.generator);
  loco_->setPostures(gen_->crouchPostures(), config_.generator.max_height);
  ContactTimeline& timeline = gen_->timeline();
  gait_pattern_.clear();
  for (const std::string& g : gaits_) {
    const auto timing = config_.gait.timing.find(g);
    gait_pattern_.push_back(timeline.addPattern(makeGaitPattern(
        g, timing == config_.gait.timing.end() ? GaitTiming{} : timing->second, robot_.contacts)));
  }
  // A plan starts at plan time 0 (the plan's start); the gaits start standing.
  timeline.reset(have_plan_ ? timeline.addPattern(plan_) : gait_pattern_[0], 0.0);
  SolverOptions options;
  options.line_search_steps = config_.line_search_steps;
  if (config_.emulated_slowdown > 1.0) {
    slow_host_ = std::make_unique<SlowHost>(config_.emulated_slowdown);
    options.work_hook = slow_host_.get();
  }
  solver_ = std::make_unique<Solver>(loco_->problem(), config_.solver, options);
  if (config_.solver == SolverKind::BoxFddp)
    solver_->setControlBounds(loco_->controlLower(), loco_->controlUpper());
  knot_times_ = loco_->knotTimes();
  knot_masks_.assign(config_.locomotion.knots, 0u);
  xs_warm_.assign(config_.locomotion.knots + 1, x_nominal);
  us_warm_.assign(config_.locomotion.knots, Eigen::VectorXd::Zero(nu_));
  rebuild_ = false;
  need_restart_ = true;
  have_previous_ = false;
  have_solved_ = false;
  startup_again_ = false;
  startup_resolves_ = 0;
}

bool Mpc::replan(double t) {
  // The knots' times before the update: where the warm start's states are (knot_masks_: on which
  // feet, kept from the last update, as the knot models have moved with the shift since).
  const int T = loco_->problem().horizon();
  knot_times_ = loco_->knotTimes();
  if (!gen_->plan(t, x_, t_warm_, t_warm_ + loco_->span()) || !loco_->update(t_warm_, *gen_))
    return false;
  // On the new grid (shifted by whole short knots, or moved by an impulse knot coming in), the
  // warm start at the knots' new times: the short knots near now only change places, the long
  // ones of the tail are interpolated.
  const std::vector<double>& times = loco_->knotTimes();
  solver_->retimeWarmStart(knot_times_, times);
  // A knot that lifts a foot the warm start had down (a new gait coming in, a step entering the
  // horizon) starts from the torques that hold the posture on its contacts: the stance torques
  // on a lifted leg would swing it at thousands of rad/s² (gaps that blew up the first rollouts
  // of every trot start on a grid of 20-30 ms knots).
  int j = 0;  // the last old knot at or before knot k's time
  for (int k = 0; k < T; ++k) {
    while (j + 1 < T && knot_times_[j + 1] <= times[k] + kPlanTimeEpsilon) ++j;
    const unsigned mask = loco_->contactMask(k);
    if (knot_masks_[j] & ~mask) solver_->setControl(k, loco_->holdingControl(mask));
  }
  for (int k = 0; k < T; ++k) knot_masks_[k] = loco_->contactMask(k);
  return true;
}

void Mpc::restartWarmStart(double t, double t_knot0, bool startup) {
  t_warm_ = t_knot0;
  if (!replan(t)) return;
  // The first solve starts where the robot is, held still: a controller started (or restarted)
  // on a robot that stands anywhere but in the nominal posture -- feet where a stand-down left
  // them, turned, at another height -- would otherwise start from the references' default joint
  // angles, far from every state its contacts allow, and its first iterations must close those
  // gaps (from a quadruped stood down on legs folded the wrong way, the references' warm start
  // failed 19 solves in a row; this one converged). Later restarts, in the tick, allocate nothing
  // and take the references.
  if (startup)
    loco_->measuredWarmStart(x_, xs_warm_, us_warm_);
  else
    loco_->referenceWarmStart(*gen_, xs_warm_, us_warm_);
  solver_->setWarmStart(xs_warm_, us_warm_);
  // After the start-up solve μ starts again at the ticks' trust region, not below it: from 1e-9 a
  // restart spent 14 ticks of line searches that took no step climbing back, and the quadruped
  // fell at a sidestep's start in real time.
  solver_->setRegularization(have_solved_ ? config_.min_regularization
                                          : solver_->options.reg_initial);
  need_restart_ = false;
}

bool Mpc::shiftTo(double t) {
  // In whole knots of the grid's first (shortest) duration; the trajectory itself moves in
  // replan() (Solver::retimeWarmStart), the knot models with it here, so that the short knots'
  // kept solves stay with their states (KeptSolve).
  const double dt = config_.locomotion.dt;
  const double shift = std::floor((t - t_warm_) / dt + 0.5);
  if (t_warm_ + shift * dt >= loco_->knotTime(loco_->problem().horizon())) return false;
  if (shift >= 1.0) {
    const int n = static_cast<int>(shift);
    loco_->problem().shift(n);
    t_warm_ += n * dt;
  }
  return true;
}

bool Mpc::solveTick(double t, Clock::time_point deadline, bool late, SolveStatus& result,
                    bool* shed) {
  if (shed != nullptr) *shed = false;
  ShootingProblem& problem = loco_->problem();
  const double dt = config_.locomotion.dt;
  // The first solve, before any policy went out, runs to convergence (no deadline); a restart
  // after a failure gets the normal budget and converges over the following ticks. So does a
  // start-up solve made again on a newer state (startup_again_), from the last one's solution.
  const bool first = !have_solved_ || startup_again_;
  startup_again_ = false;
  // The preparation serves while the state is less than a knot from the prepared knot 0: only
  // x0 changes, and the time between them stays a gap at x0 as after a shift. (Within half a knot
  // when ticks come on time; up to a period more after a late tick, when the loop skipped one.)
  const bool use_prepared = !need_restart_ && solver_->prepared() && std::abs(t - t_warm_) < dt;
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
    if (need_restart_ || !shiftTo(t)) {
      restartWarmStart(t, t, first);
      if (need_restart_) return false;  // the references could not be planned
    } else if (!replan(t)) {
      return false;
    }
  }
  startup_tick_ = first;
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
    need_restart_ = true;
    return false;
  }
  have_solved_ = true;
  return true;
}

bool Mpc::tick(const robot_state_t* state, double age, Clock::time_point deadline) {
  const Clock::time_point tick_start = Clock::now();
  ++counters_.ticks;
  status_.tick = counters_.ticks;
  status_.solve_ms = 0.0;
  status_.iterations = 0;
  status_.solver_status = -1;
  startup_tick_ = false;
  solved_ = false;
  fresh_policy_ = false;
  tried_ = false;
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

  if (!started() || rebuild_) start(state->utime);
  const double t = planTime(state->utime);
  status_.plan_time = t;
  // The gait asked for: a switch at the next instant every foot is down (ContactTimeline).
  ContactTimeline& timeline = gen_->timeline();
  if (!have_plan_ && timeline.lastPattern() != gait_pattern_[gait_])
    timeline.switchTo(gait_pattern_[gait_], t);
  gen_->setCommand(command_);
  chooseMap(state->utime);
  // The estimator's contacts, when it reports them (robot YAML order).
  if (state->ncontacts == static_cast<std::int32_t>(robot_.contacts.size())) {
    unsigned loaded = 0;
    for (int c = 0; c < state->ncontacts; ++c) loaded |= (state->contact[c] != 0 ? 1u : 0u) << c;
    gen_->setMeasuredContacts(loaded);
  } else {
    gen_->clearMeasuredContacts();
  }
  status_.phase = static_cast<std::int32_t>(timeline.mask(t));
  const int in_force = timeline.patternAt(t);
  status_.gait = have_plan_ ? kPlanGait : gaits_[std::min<int>(in_force, gaits_.size() - 1)];
  status_.command[0] = command_.vx;
  status_.command[1] = command_.vy;
  status_.command[2] = command_.yaw_rate;
  status_.command[3] = command_.height;

  if (age > config_.max_state_age) {
    ++counters_.stale_states;
  } else {
    const Clock::time_point solve_start = Clock::now();
    t_last_ = t;
    tried_ = true;
    SolveStatus result = SolveStatus::NonFinite;
    bool shed = false;
    bool ok = solveTick(t, deadline, late, result, &shed);
    if (shed) {
      if (have_previous_ && previousPolicy(state->utime)) {
        ++counters_.shed_ticks;
        solved_ = !need_restart_;  // the period prepares for the next tick (or restarts)
        countAnswer(deadline);
        finishStatus(tick_start, policy_.status);
        return true;
      }
      // Nothing left to re-send (no policy solved for a whole policy's length): a whole iteration
      // now when the last ones say it ends before the deadline; else the fallback below, and
      // the period prepares (an iteration past the deadline made several misses in a row at 3x
      // slowdown).
      if (millisFromNow(kTrialMargin * (prepare_ms_ + trial_ms_)) < deadline) {
        ok = solveTick(t, deadline, late, result, nullptr);
      } else {
        solved_ = !need_restart_;
        ++counters_.fallbacks;
        holdPolicy(state->utime, t);
        countAnswer(deadline);
        finishStatus(tick_start, policy_.status);
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
    if (ok && startup_tick_ && real_time && startup_resolves_ < kMaxStartupResolves &&
        status_.solve_ms > 1e3 / config_.rate_hz) {
      ++startup_resolves_;
      ++counters_.startup_resolves;
      startup_again_ = true;
      finishStatus(tick_start, kPolicyNone);
      return false;
    }
    // Past the re-solves, a start-up solve that took more than half a policy's span is not sent
    // either: its policy would reach the robot at or past its end (issue 33: 4 of 10 real-time
    // restarts of the humanoid sent one 0.2 s old, and one of those robots fell). The next tick
    // is a regular one from this solution, bounded by its deadline.
    const double policy_ms = 1e3 * (policy_.knots - 1) * config_.locomotion.dt;
    if (ok && startup_tick_ && real_time && status_.solve_ms > 0.5 * policy_ms) {
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
      if (stalled && !startup_tick_) {
        need_restart_ = true;
        ++counters_.stall_restarts;
      }
      solved_ = true;
      // Cut: the line search stopped for the deadline (before it, when its next trial would have
      // ended after it: then on time, not a miss).
      const bool cut = result == SolveStatus::Deadline;
      writePolicy(state->utime, t, cut ? kPolicyDeadline : kPolicySolved);
      fresh_policy_ = true;
      previous_ticks_ = 0;
      countAnswer(deadline);
      finishStatus(tick_start, policy_.status);
      return true;
    }
  }
  // Fallback: the previous policy advanced to now, for a while; then hold the posture.
  ++counters_.fallbacks;
  if (config_.fallback == Fallback::Previous && previous_ticks_ < config_.max_previous_ticks &&
      previousPolicy(state->utime)) {
    ++previous_ticks_;
  } else {
    holdPolicy(state->utime, t);
  }
  countAnswer(deadline);
  finishStatus(tick_start, policy_.status);
  return true;
}

bool Mpc::writeHorizon(horizon_t& h) const {
  // The knots' forces are those of the solver's last computation, which may be a rejected trial's
  // rollout: then nothing is written (Solver::dataAtSolution).
  if (!fresh_policy_ || loco_ == nullptr || !solver_->dataAtSolution()) return false;
  const ShootingProblem& problem = loco_->problem();
  const int T = std::min(problem.horizon(), h.knots);
  const std::vector<double>& times = loco_->knotTimes();
  h.utime = policy_.utime;
  h.model_hash = policy_.model_hash;
  for (int k = 0; k < T; ++k) {
    const auto& knot = static_cast<const KnotModel&>(problem.knot(k));
    const auto& data = static_cast<const KnotActionData&>(problem.data(k));
    const ContactSet& contacts = knot.contacts();
    h.t[k] = times[k] - times[0];  // knot 0 is the state, as in the policy (knot0_utime = utime)
    std::copy(solver_->xs()[k].data(), solver_->xs()[k].data() + nq_, h.q[k].begin());
    h.impulse[k] = knot.mode() == KnotMode::Impulse ? 1 : 0;
    h.contact_mask[k] = static_cast<std::int32_t>(loco_->contactMask(k));
    // forces(): the active contacts stacked in the set's order, each its dim (force part first).
    int row = 0;
    for (int c = 0; c < contacts.size() && c < h.ncontacts; ++c) {
      double* f = h.force[k].data() + 3 * c;
      if (!contacts.isActive(c)) {
        f[0] = f[1] = f[2] = 0.0;
        continue;
      }
      for (int i = 0; i < 3; ++i) f[i] = row + i < data.nc() ? data.forces()[row + i] : 0.0;
      row += contacts[c].dim;
    }
  }
  writeFootholds(h, times[T - 1]);
  return true;
}

void Mpc::writeFootholds(horizon_t& h, double t_end) const {
  static_assert(static_cast<int>(StanceSource::Unknown) == msg::kFootholdSources - 1,
                "horizon_t.foothold_source carries StanceSource as a number");
  // The touch-downs the gait generator planned for the problem just solved: after the state (the
  // stances in force or lifted from are behind it) and no later than the horizon's last knot. In
  // the capacity h was shaped with (msg::shape), so that nothing is allocated.
  const std::size_t capacity = std::min({h.foothold_contact.size(), h.foothold_time.size(),
                                         h.foothold.size(), h.foothold_source.size()});
  const double t = t_last_;  // the state's plan time (h.utime)
  std::size_t n = 0;
  for (int c = 0; c < gen_->timeline().contacts() && c < h.ncontacts; ++c) {
    int of_contact = 0;
    for (int i = 0;
         i < gen_->stances(c) && of_contact < msg::kHorizonFootholdsPerContact && n < capacity;
         ++i) {
      const GaitGenerator::Stance& s = gen_->stance(c, i);
      if (!(s.touch_down > t && s.touch_down <= t_end)) continue;
      h.foothold_contact[n] = c;
      h.foothold_time[n] = s.touch_down - t;
      std::copy(s.p.data(), s.p.data() + 3, h.foothold[n].begin());
      h.foothold_source[n] = static_cast<std::int8_t>(s.source);
      ++of_contact;
      ++n;
    }
  }
  h.nfootholds = static_cast<std::int32_t>(n);
}

void Mpc::countAnswer(Clock::time_point deadline) {
  // A deadline is on the answer: whatever policy goes out after it (solved, cut, re-sent, hold)
  // is a miss; the start-up solve has none.
  if (!startup_tick_ && deadline != Clock::time_point::max() && Clock::now() > deadline)
    ++counters_.deadline_misses;
}

void Mpc::prepare(Clock::time_point deadline) {
  // After a failed or stalled solve, the warm start is made again here, from the references
  // planned on the last state, for when the next state is expected: the restart's whole
  // iteration then runs off the state-to-policy path, as every other preparation does (in the
  // tick it missed the deadline, 4 of 4 times in a 60 s real-time run).
  const bool restart = need_restart_ && have_solved_ && tried_;
  if (!solved_ && !restart) return;
  solved_ = false;  // one preparation per tick that solved, or tried to
  tried_ = false;
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
    restartWarmStart(t_last_, t_next, false);
    if (need_restart_) return;  // the references could not be planned: the next tick tries
  } else if (!resume) {
    if (!replan(t_last_)) return;  // on the trajectory's grid, as in solveTick
  }
  SolveStatus why = SolveStatus::MaxIterations;
  if (solver_->prepare(deadline, why)) {
    prepare_ms_ = solver_->prepareMillis();
  } else if (why == SolveStatus::NonFinite || why == SolveStatus::NoDescent) {
    // The trajectory cannot be linearized: the next tick starts again from standing.
    ++counters_.failed_solves;
    need_restart_ = true;
  }
  // At the deadline: not prepared yet; in real time the next tick re-sends the previous policy
  // and its period resumes this preparation.
}

void Mpc::writePolicy(std::int64_t utime, double t, std::int8_t status) {
  const ShootingProblem& problem = loco_->problem();
  const auto& xs = solver_->xs();
  const auto& us = solver_->us();
  const auto& K = solver_->K();
  const int ndx = 2 * nv_;
  policy_.utime = utime;
  policy_.knot0_utime = utime;
  policy_.tick = counters_.ticks;
  policy_.t0 = t;
  policy_.dt = config_.locomotion.dt;
  policy_.phase = status_.phase;
  policy_.status = status;
  int j = 0;
  for (int k = 0; k < problem.horizon() && j < policy_.knots; ++k) {
    const auto* knot = dynamic_cast<const KnotModel*>(&problem.knot(k));
    if (knot != nullptr && knot->mode() == KnotMode::Impulse) continue;
    std::copy(xs[k].data(), xs[k].data() + nq_ + nv_, policy_.x_ref[j].begin());
    std::copy(us[k].data(), us[k].data() + nu_, policy_.u_ff[j].begin());
    // The solver's law is u = us + K (x ⊖ xs); the policy's is u_ff + K' (x_ref ⊖ x), and
    // x_ref ⊖ x = -(x ⊖ x_ref) exactly (log(M⁻¹) = -log(M)), so K' = -K, row-major.
    double* out = policy_.K[j].data();
    for (int r = 0; r < nu_; ++r)
      for (int c = 0; c < ndx; ++c) out[r * ndx + c] = -K[k](r, c);
    ++j;
  }
  for (; j < policy_.knots; ++j) {  // a horizon shorter than the policy: hold its last knot
    policy_.x_ref[j] = policy_.x_ref[j - 1];
    policy_.u_ff[j] = policy_.u_ff[j - 1];
    policy_.K[j] = policy_.K[j - 1];
  }
  previous_ = policy_;  // same shapes: element copies, no allocation
  have_previous_ = true;
}

bool Mpc::previousPolicy(std::int64_t utime) {
  if (!have_previous_) return false;
  const double elapsed = (utime - previous_.knot0_utime) * 1e-6;
  const int skip = static_cast<int>(std::floor(elapsed / previous_.dt));
  if (skip < 0 || skip >= previous_.knots - 1) return false;  // nothing left to interpolate
  policy_.utime = utime;
  policy_.knot0_utime =
      previous_.knot0_utime + static_cast<std::int64_t>(std::llround(skip * previous_.dt * 1e6));
  policy_.t0 = previous_.t0 + skip * previous_.dt;
  policy_.dt = previous_.dt;
  policy_.tick = counters_.ticks;
  policy_.phase = previous_.phase;
  policy_.status = kPolicyPrevious;
  for (int j = 0; j < policy_.knots; ++j) {
    const int from = std::min(j + skip, previous_.knots - 1);
    policy_.x_ref[j] = previous_.x_ref[from];
    policy_.u_ff[j] = previous_.u_ff[from];
    policy_.K[j] = previous_.K[from];
  }
  return true;
}

void Mpc::holdPolicy(std::int64_t utime, double t) {
  // Joint PD to the default posture around the measured base, with the torques that hold the
  // default posture on the current phase's contacts as feed-forward.
  const unsigned phase = gen_->mask(t);
  const Eigen::VectorXd& u_hold = loco_->holdingControl(phase);
  const int ndx = 2 * nv_, base = robot_.model.hasFreeFlyer() ? 6 : 0;
  policy_.utime = utime;
  policy_.knot0_utime = utime;
  policy_.t0 = t;
  policy_.dt = config_.locomotion.dt;
  policy_.tick = counters_.ticks;
  policy_.phase = static_cast<std::int32_t>(phase);
  policy_.status = kPolicyHold;
  for (int j = 0; j < policy_.knots; ++j) {
    std::vector<double>& xr = policy_.x_ref[j];
    for (int i = 0; i < nq_; ++i) xr[i] = i < nq_ - nu_ ? x_[i] : robot_.default_q[i];
    for (int i = 0; i < nv_; ++i) xr[nq_ + i] = 0.0;
    std::copy(u_hold.data(), u_hold.data() + nu_, policy_.u_ff[j].begin());
    // The robot's hold law (messages/hold_pd.hpp), sent as gains on x_ref ⊖ x.
    for (int r = 0; r < nu_; ++r)
      msg::writeJointPdRow(policy_.K[j].data() + r * ndx, nv_, base + r, config_.hold_kp,
                           config_.hold_kd);
  }
}

void Mpc::finishStatus(Clock::time_point tick_start, std::int8_t policy_status) {
  status_.policy_status = policy_status;
  status_.deadline_misses = counters_.deadline_misses;
  status_.late_ticks = counters_.late_ticks;
  status_.fallbacks = counters_.fallbacks;
  status_.stale_states = counters_.stale_states;
  status_.ticks_without_state = counters_.ticks_without_state;
  status_.unprepared_solves = counters_.unprepared_solves;
  status_.terrain_mode = on_map_ ? 1 : steppability_.valid() ? 2 : 0;
  status_.map_age =
      steppability_.valid() && status_.utime != 0 ? (status_.utime - map_utime_) * 1e-6 : -1.0;
  status_.maps = counters_.maps;
  status_.stale_map_ticks = counters_.stale_map_ticks;
  status_.tick_ms = millisSince(tick_start);
}

}  // namespace stride
