#include "locomotion/planner.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "solver/ddp/solver.hpp"

namespace stride {

namespace {
// The gait reported while a planner's plan replaces the gaits.
const std::string kPlanGait = "plan";
// The gait reported while a jump is made.
const std::string kJumpGait = "jump";
// Velocity-level Baumgarte term of the planning model's contacts (a + kd v = 0 at the foot): a
// foot's drift velocity decays in 1/kd = 20 ms instead of growing over the 1 s horizon.
constexpr double kContactDamping = 50.0;
// The planned centre of pressure stays in this fraction of the sole: at the edge, the slightest
// disturbance tips the foot.
constexpr double kSoleMargin = 0.8;
// Landing as it happens (Planner::landOnMeasuredContacts): a foot loaded after this share of a
// flight has landed; a flight the clock ends with no foot loaded goes on by kLateStep at a time,
// at most kMaxLate in all [s].
constexpr double kEarlyShare = 0.5;
constexpr double kLateStep = 0.02;
constexpr double kMaxLate = 0.15;
// A map this much older than the one in use is a restarted robot's clock, not one out of order.
constexpr std::int64_t kMapClockRestartUs = 1000000;

GaitTiming timingOf(const GaitConfig& gait, const std::string& name) {
  const auto timing = gait.timing.find(name);
  return timing == gait.timing.end() ? GaitTiming{} : timing->second;
}
}  // namespace

Planner::Planner(const Robot& robot, const PlannerOptions& options, const std::string& config_path)
    : robot_(robot), options_(options), config_path_(config_path) {
  const Model& model = robot_.model;
  for (const ContactSpec& c : robot_.contacts)
    contacts_.add(model, c.frame, c.dim, ReferenceFrame::LocalWorldAligned, 0.0, kContactDamping);
  options_.locomotion.sole_half_extents = kSoleMargin * robot_.sole_half_extents;
  options_.generator.sole_half_length = robot_.sole_half_extents.x();
  gaits_ = gaitNames(static_cast<int>(robot_.contacts.size()));
  for (const std::string& g : gaits_)  // a bad timing fails here, not at the first state
    makeGaitPattern(g, timingOf(options_.gait, g), robot_.contacts);
  if (!options_.gait.plan_file.empty()) {
    plan_ = loadContactPlan(options_.gait.plan_file);
    have_plan_ = true;
    try {
      plan_.validate(contacts_);
    } catch (const std::invalid_argument& e) {
      throw ConfigError(config_path_ + ": the contact plan does not fit the robot: " + e.what());
    }
  }
  // What the first state builds must not fail then: the references' checks (contacts, the
  // body-height postures) run here, once.
  try {
    Eigen::VectorXd x = Eigen::VectorXd::Zero(model.nq + model.nv);
    x.head(model.nq) = robot_.default_q;
    GaitGenerator check(model, contacts_, x, options_.generator);
  } catch (const std::invalid_argument& e) {
    throw ConfigError(config_path_ + ": " + e.what());
  }
  steppability_ = terrain::Steppability(options_.terrain.steppability, options_.terrain.max_cells);
}

Planner::~Planner() = default;

void Planner::setPlan(const ContactPlan& plan, std::int64_t start_utime) {
  plan.validate(contacts_);
  plan_ = plan;
  have_plan_ = true;
  plan_start_utime_ = start_utime;
  plan_start_set_ = true;
  plan_pending_ = true;
}

void Planner::setCommand(const BodyCommand& command, int gait) {
  command_ = command;
  if (gait >= 0 && gait < static_cast<int>(gaits_.size())) gait_ = gait;
}

bool Planner::setMap(const terrain::ElevationMap& map, std::int64_t utime) {
  if (static_cast<long>(map.rows) * map.cols > options_.terrain.max_cells ||
      (steppability_.valid() && utime < map_utime_ && utime > map_utime_ - kMapClockRestartUs))
    return false;
  if (!steppability_.update(map)) return false;
  map_utime_ = utime;
  return true;
}

void Planner::shiftClock(std::int64_t offset_us) {
  plan_start_utime_ += offset_us;
  if (steppability_.valid()) map_utime_ += offset_us;
}

void Planner::build(std::int64_t utime) {
  if (!plan_start_set_) {
    plan_start_utime_ = utime;
    plan_start_set_ = true;
  }
  const Model& model = robot_.model;
  // The nominal posture at the origin: the references are anchored on the measured state at
  // every tick (GaitGenerator::plan), so where the robot stands now needs no rebuild.
  Eigen::VectorXd x_nominal = Eigen::VectorXd::Zero(model.nq + model.nv);
  x_nominal.head(model.nq) = robot_.default_q;
  loco_ = std::make_unique<LocomotionProblem>(model, contacts_, x_nominal, options_.locomotion);
  loco_->problem().setThreads(options_.threads);
  gen_ = std::make_unique<GaitGenerator>(model, contacts_, x_nominal, options_.generator);
  loco_->setPostures(gen_->crouchPostures(), options_.generator.max_height);
  ContactTimeline& timeline = gen_->timeline();
  gait_pattern_.clear();
  for (const std::string& g : gaits_)
    gait_pattern_.push_back(
        timeline.addPattern(makeGaitPattern(g, timingOf(options_.gait, g), robot_.contacts)));
  // The jumps: every foot down for the push, none in the flight, every foot down after.
  jump_pattern_.clear();
  const JumpLimits& jl = options_.jump;
  if (jl.max_distance > 0.0 && jl.flight_step > 0.0) {
    std::vector<std::string> all;
    for (const ContactSpec& c : robot_.contacts) all.push_back(c.frame);
    for (double T = jl.min_flight; T <= jl.max_flight + 1e-9; T += jl.flight_step) {
      ContactPlan jump;
      jump.phases = {{jl.push, all}, {T, {}}, {jl.landing, all}};
      jump_pattern_.push_back(timeline.addPattern(jump));
    }
  }
  jump_active_ = false;
  gen_->clearJump();
  // A plan starts at plan time 0 (the plan's start); the gaits start standing.
  timeline.reset(have_plan_ ? timeline.addPattern(plan_) : gait_pattern_[0], 0.0);
  knot_times_ = loco_->knotTimes();
  knot_masks_.assign(options_.locomotion.knots, 0u);
  plan_pending_ = false;
}

bool Planner::requestJump(int id, const JumpTarget& target, double t) {
  JumpStatus& s = jump_status_;
  s.id = id;
  // why: the reason, or null when planJump wrote it already.
  auto refuse = [&](const char* why) {
    if (why) std::snprintf(s.refusal, sizeof s.refusal, "%s", why);
    s.state = JumpState::Refused;
    ++s.refused;
    return false;
  };
  JumpPlan plan;
  if (!planJump(target, options_.jump, plan, s.refusal, sizeof s.refusal)) return refuse(nullptr);
  if (!gen_) return refuse("the controller has no state yet");
  if (have_plan_) return refuse("a contact plan replaces the gaits");
  if (jump_active_) return refuse("another jump is under way");
  const JumpLimits& jl = options_.jump;
  const long k = std::lround((plan.flight - jl.min_flight) / jl.flight_step);
  if (k < 0 || k >= static_cast<long>(jump_pattern_.size()))
    return refuse("its flight time is outside jump.min_flight .. jump.max_flight");
  const double at = gen_->timeline().switchTo(jump_pattern_[k], t);
  if (at == ContactTimeline::kNever) return refuse("the gait in force cannot be left for it");
  jump_active_ = true;
  jump_active_id_ = id;
  jump_target_ = target;
  jump_phase_ = JumpState::Accepted;
  jump_lift_off_ = at + jl.push;
  jump_touch_down_ = jump_lift_off_ + plan.flight;
  jump_end_ = jump_touch_down_ + jl.landing;
  gen_->setJump(target, jump_lift_off_, jump_touch_down_);
  s.state = JumpState::Accepted;
  s.refusal[0] = '\0';
  return true;
}

void Planner::landOnMeasuredContacts(double t, unsigned loaded) {
  ContactTimeline& tl = gen_->timeline();
  const int nc = tl.contacts();
  double shift = 0.0;
  if (loaded != 0u) late_since_ = -1.0;  // a foot down: a late flight has landed
  if (tl.mask(t) == 0u) {                // in the air by the clock
    if (loaded == 0u) return;
    double lift_off = -ContactTimeline::kNever, touch_down = ContactTimeline::kNever;
    for (int c = 0; c < nc; ++c) {
      lift_off = std::max(lift_off, tl.lastChange(c, t));
      touch_down = std::min(touch_down, tl.nextChange(c, t));
    }
    // A foot loaded in the second half: landed (a take-off's push still loads them early on).
    if (touch_down == ContactTimeline::kNever ||
        t - lift_off < kEarlyShare * (touch_down - lift_off))
      return;
    shift = t - touch_down;
    if (!tl.retimeFrom(t, shift)) return;
    ++early_landings_;
  } else {  // on the ground by the clock
    if (loaded != 0u) return;
    // Just after a flight the clock ended (its first touch-down), no foot feels the ground yet.
    double touch_down = ContactTimeline::kNever;
    for (int c = 0; c < nc; ++c)
      if (tl.closed(c, t)) touch_down = std::min(touch_down, tl.lastChange(c, t));
    if (!(t - touch_down <= kLateStep) || tl.mask(touch_down - kLateStep) != 0u) return;
    if (late_since_ < 0.0) late_since_ = touch_down;
    if (t + kLateStep - late_since_ > kMaxLate) return;  // then the clock's: it lands where it is
    shift = t + kLateStep - touch_down;
    if (!tl.retimeFrom(t, shift)) return;
    if (late_since_ == touch_down) ++late_landings_;
  }
  // A jump's touch-down and end move with it.
  if (jump_active_ && t > jump_lift_off_ && t < jump_end_) {
    jump_touch_down_ += shift;
    jump_end_ += shift;
    gen_->setJump(jump_target_, jump_lift_off_, jump_touch_down_);
  }
}

MapChoice Planner::beginTick(double t, std::int64_t utime, std::optional<unsigned> loaded) {
  ContactTimeline& timeline = gen_->timeline();
  // A jump under way: in the air from its take-off, landed at its touch-down, over at its end
  // (the gait asked for comes back then).
  if (jump_active_) {
    // (knot times carry rounding: kPlanTimeEpsilon, as the timeline's phase boundaries)
    const double now = t + kPlanTimeEpsilon;
    if (now >= jump_lift_off_ && jump_phase_ == JumpState::Accepted) jump_phase_ = JumpState::InAir;
    if (now >= jump_touch_down_ && jump_phase_ == JumpState::InAir) {
      jump_phase_ = JumpState::Landed;
      ++jump_status_.made;
    }
    // The status tells the last jump asked for: this one, unless another was refused since.
    if (jump_status_.id == jump_active_id_) jump_status_.state = jump_phase_;
    if (now >= jump_end_) {
      jump_active_ = false;
      gen_->clearJump();
    }
  }
  if (loaded) landOnMeasuredContacts(t, *loaded);
  // The gait asked for: switched to foot by foot (ContactTimeline), after the jump under way.
  if (!have_plan_ && !jump_active_ && timeline.lastPattern() != gait_pattern_[gait_])
    timeline.switchTo(gait_pattern_[gait_], t);
  // The velocity command waits while a jump is under way (the jump moves the base).
  BodyCommand command = command_;
  if (jump_active_) command.vx = command.vy = command.yaw_rate = 0.0;
  gen_->setCommand(command);
  // The map when it was measured at most max_map_age before the state (both stamps on the
  // robot's clock, so lock-step and replays decide the same), else blind.
  MapChoice choice = MapChoice::None;
  on_map_ = false;
  if (steppability_.valid()) {
    const double age = (utime - map_utime_) * 1e-6;
    on_map_ = age >= -options_.terrain.max_map_age && age <= options_.terrain.max_map_age;
    choice = on_map_ ? MapChoice::Fresh : MapChoice::Stale;
  }
  gen_->setMap(on_map_ ? &steppability_ : nullptr);
  if (loaded)
    gen_->setMeasuredContacts(*loaded);
  else
    gen_->clearMeasuredContacts();
  return choice;
}

bool Planner::replan(double t, const Eigen::VectorXd& x, double t_warm, Solver& solver) {
  // The knots' times before the update: where the warm start's states are (knot_masks_: on which
  // feet, kept from the last update, as the knot models have moved with the shift since).
  const int T = loco_->problem().horizon();
  knot_times_ = loco_->knotTimes();
  if (!gen_->plan(t, x, t_warm, t_warm + loco_->span()) || !loco_->update(t_warm, *gen_))
    return false;
  // On the new grid (shifted by whole short knots, or moved by an impulse knot coming in), the
  // warm start at the knots' new times: the short knots near now only change places, the long
  // ones of the tail are interpolated.
  const std::vector<double>& times = loco_->knotTimes();
  solver.retimeWarmStart(knot_times_, times);
  // A knot that lifts a foot the warm start had down (a new gait coming in, a step entering the
  // horizon) starts from the torques that hold the posture on its contacts: the stance torques
  // on a lifted leg would swing it at thousands of rad/s² (gaps that blew up the first rollouts
  // of every trot start on a grid of 20-30 ms knots).
  int j = 0;  // the last old knot at or before knot k's time
  for (int k = 0; k < T; ++k) {
    while (j + 1 < T && knot_times_[j + 1] <= times[k] + kPlanTimeEpsilon) ++j;
    const unsigned mask = loco_->contactMask(k);
    if (knot_masks_[j] & ~mask) solver.setControl(k, loco_->holdingControl(mask));
  }
  for (int k = 0; k < T; ++k) knot_masks_[k] = loco_->contactMask(k);
  return true;
}

void Planner::referenceWarmStart(std::vector<Eigen::VectorXd>& xs,
                                 std::vector<Eigen::VectorXd>& us) const {
  loco_->referenceWarmStart(*gen_, xs, us);
}

void Planner::measuredWarmStart(const Eigen::VectorXd& x, std::vector<Eigen::VectorXd>& xs,
                                std::vector<Eigen::VectorXd>& us) const {
  loco_->measuredWarmStart(x, xs, us);
}

const std::string& Planner::gaitAt(double t) const {
  if (have_plan_) return kPlanGait;
  const int in_force = gen_->timeline().patternAt(t);
  for (std::size_t g = 0; g < gait_pattern_.size(); ++g)
    if (gait_pattern_[g] == in_force) return gaits_[g];
  return kJumpGait;
}

}  // namespace stride
