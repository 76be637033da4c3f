#include "locomotion/gait_generator.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

#include "solver/multibody/center_of_mass.hpp"
#include "solver/multibody/frames.hpp"
#include "solver/multibody/inverse_kinematics.hpp"
#include "terrain/foothold.hpp"
#include "terrain/ground_plane.hpp"

namespace stride {

namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr double kGravity = 9.81;
// How far past the window a foothold may need the base reference: the mid-stance of the first
// touch-down after the window's end. Beyond the samples the base moves at its last velocity.
constexpr double kLookahead = 2.0;
// Mid-stance of a stance that does not end (a stand): at most this long after the touch-down.
constexpr double kHalfStanceCap = 0.5;
// Body-height postures solved at construction (odd: one at the nominal height).
constexpr int kCrouches = 9;
// On a map, the foothold chosen for a touch-down at the last plan stays a candidate to this many
// times max_foothold_shift from the nominal (terrain::FootholdReach::kept): a hysteresis, so that
// a choice between stepping short of an unsafe band and across it does not flip with every
// centimetre the body lags or leads (the swing's target jumped by the band's width, 30 cm on
// stride_humanoid's box, from one tick to the next).
constexpr double kKeptReach = 1.5;
const Eigen::Vector2d kNoPlace =
    Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN());
// A base reference slower than this [m/s] has no direction of travel for the footholds.
constexpr double kStill = 0.01;
// On the ground next to a flight (flightLift): how long the base's vertical reference takes to go
// from the nominal height into a take-off's crouch or back from a landing's [s], and the least
// crouch depth [m].
constexpr double kPushTime = 0.2;
constexpr double kMinCrouch = 0.04;
// A jump's horizontal speed-up before its take-off and slow-down after its touch-down [s].
constexpr double kJumpRamp = 0.1;
// Feet a generator plans for: the contact limit (the ground plane's fit takes them on the stack).
constexpr int kMaxFeet = kMaxContacts;

double yawOf(double qx, double qy, double qz, double qw) {
  return std::atan2(2.0 * (qw * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz));
}

Eigen::Vector2d rotate(double yaw, double x, double y) {
  const double c = std::cos(yaw), s = std::sin(yaw);
  return {c * x - s * y, s * x + c * y};
}

// The smallest rotation that takes e_z to the unit vector n (exactly the identity for e_z: flat
// ground plans the same bits as without a map).
// Anything but an upward unit vector (never planned; a guard) counts as e_z.
Eigen::Matrix3d alignZ(const Eigen::Vector3d& n) {
  if ((n.x() == 0.0 && n.y() == 0.0) || !n.allFinite() || !(n.z() > 0.0))
    return Eigen::Matrix3d::Identity();
  return Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), n).toRotationMatrix();
}

const Eigen::Vector3d kUp = Eigen::Vector3d::UnitZ();
}  // namespace

PostureBlend postureBlend(double height, double max_height, int n) {
  if (n < 2 || !(max_height > 0.0)) return {};
  const double u = std::clamp((height + max_height) / (2.0 * max_height), 0.0, 1.0) * (n - 1);
  const int i = std::min(static_cast<int>(u), n - 2);
  return {i, u - i};
}

GaitGenerator::GaitGenerator(const Model& model, const ContactSet& contacts,
                             const Eigen::VectorXd& x_nominal, const GaitGeneratorOptions& options)
    : model_(model),
      timeline_(contacts),
      options_(options),
      nc_(contacts.size()),
      x_nominal_(x_nominal),
      data_(model) {
  if (!model.hasFreeFlyer())
    throw std::invalid_argument("GaitGenerator: the robot needs a free-flyer base");
  if (contacts.size() == 0 || contacts.size() > kMaxFeet)
    throw std::invalid_argument("GaitGenerator: the robot needs one to " +
                                std::to_string(kMaxFeet) + " contacts to walk on");
  if (x_nominal.size() != model.nq + model.nv || !x_nominal.allFinite())
    throw std::invalid_argument("GaitGenerator: x_nominal must be finite of size nq + nv");
  const GaitGeneratorOptions& o = options;
  if (!(o.horizon > 0.0) || !(o.sample_dt > 0.0) || !std::isfinite(o.horizon) ||
      !std::isfinite(o.swing_height) || !std::isfinite(o.foothold_gain) ||
      !(o.max_foothold_correction >= 0.0))
    throw std::invalid_argument(
        "GaitGenerator: horizon and sample_dt must be positive, the swing height, foothold gain "
        "and correction cap finite");
  x_nominal_.segment<4>(3).normalize();

  const auto q = x_nominal_.head(model.nq);
  framesForwardKinematics(model, data_, q);
  const Eigen::Vector3d base = q.head<3>();
  const Eigen::Quaterniond orientation(q[6], q[3], q[4], q[5]);
  const double yaw = yawOf(q[3], q[4], q[5], q[6]);
  const Eigen::Matrix3d unyaw =
      Eigen::AngleAxisd(-yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  tilt_ = Eigen::Quaterniond(unyaw) * orientation;
  z_nominal_ = base.z();
  for (int c = 0; c < nc_; ++c) {
    frames_.push_back(contacts[c].frame);
    contacts_dim_.push_back(contacts[c].dim);
    const Eigen::Vector3d p = data_.oMf[contacts[c].frame].p;
    Eigen::Vector3d off = unyaw * (p - base);
    off.z() = p.z();  // the foot's height on the ground, not relative to the base
    offset_.push_back(off);
    const Eigen::Matrix3d& R = data_.oMf[contacts[c].frame].R;
    const double foot_yaw = std::atan2(R(1, 0), R(0, 0));
    foot_yaw_.push_back(std::remainder(foot_yaw - yaw, 2.0 * kPi));
    foot_tilt_.push_back(Eigen::AngleAxisd(-foot_yaw, Eigen::Vector3d::UnitZ()) * R);
  }
  com_offset_ = unyaw * (centerOfMass(model, data_, q) - base);
  gain_ =
      o.foothold_gain >= 0.0 ? o.foothold_gain : std::sqrt(std::max(z_nominal_, 0.0) / kGravity);

  buildCrouches(contacts);
  latched_.assign(nc_, Eigen::Vector3d::Zero());
  latched_yaw_.assign(nc_, 0.0);
  latched_normal_.assign(nc_, kUp);
  early_at_.assign(nc_, -ContactTimeline::kNever);
  held_.assign(nc_, Stance{});
  held_at_.assign(nc_, -ContactTimeline::kNever);
  samples_.assign(static_cast<size_t>(std::ceil((o.horizon + kLookahead) / o.sample_dt)) + 2,
                  Sample{});
  stances_.assign(nc_, std::vector<Stance>(kMaxStances));
  n_stances_.assign(nc_, 0);
  for (int c = 0; c < nc_; ++c) {
    stances_[c][0] = {-ContactTimeline::kNever, ContactTimeline::kNever, offset_[c], foot_yaw_[c]};
    n_stances_[c] = 1;
  }
  sampleBase(0.0, base.head<2>(), yaw);
}

void GaitGenerator::buildCrouches(const ContactSet& contacts) {
  const int nq = model_.nq;
  const int n = options_.max_height > 0.0 ? kCrouches : 1;
  Data data(model_);
  const Eigen::VectorXd q0 = x_nominal_.head(nq);
  framesForwardKinematics(model_, data, q0);
  // Every foot back on its nominal place (a sole flat, its error the SE(3) log), the joints only
  // moving: damped Gauss-Newton (solver/multibody/inverse_kinematics.hpp) with a damping small
  // enough that a reachable posture is met to 1e-10.
  std::vector<IkTarget> targets;
  for (int c = 0; c < nc_; ++c)
    targets.push_back({contacts[c].frame, contacts[c].dim == 6 ? 6 : 3, ReferenceFrame::Local,
                       data.oMf[contacts[c].frame]});
  InverseKinematicsOptions o;
  o.damping = 1e-8;
  o.max_iterations = 100;
  o.tolerance = 1e-10;
  InverseKinematics ik(model_, std::move(targets), InverseKinematics::jointColumns(model_), o);
  for (int i = 0; i < n; ++i) {
    const double h = n == 1 ? 0.0 : options_.max_height * (2.0 * i / (n - 1) - 1.0);
    Eigen::VectorXd q = q0;
    q[2] += h;
    const IkResult result = ik.solve(q);
    if (!(result.error < 1e-6))
      throw std::invalid_argument(
          "GaitGenerator: with the base " + std::to_string(h) +
          " m from its nominal height the feet cannot reach their places (max_height too large)");
    crouch_.push_back(q.tail(nq - 7));
  }
}

void GaitGenerator::sampleBase(double t, const Eigen::Vector2d& p0, double yaw0) {
  const double h = options_.sample_dt;
  t_anchor_ = t;
  n_samples_ = static_cast<int>(samples_.size());
  // A jump flies in the heading the reference has at its take-off (held once in the air).
  if (jump_on_ && t < jump_lift_off_)
    jump_heading_ = yaw0 + command_.yaw_rate * (jump_lift_off_ - t);
  Eigen::Vector2d p = p0;
  for (int i = 0; i < n_samples_; ++i) {
    const double tau = i * h;
    Sample& s = samples_[i];
    s.x = p.x();
    s.y = p.y();
    s.yaw = yaw0 + command_.yaw_rate * tau;
    s.vx = command_.vx;
    s.vy = command_.vy;
    s.wz = command_.yaw_rate;
    s.height = command_.height;
    // Midpoint rule: the heading turns while the base moves.
    const double yaw_mid = yaw0 + command_.yaw_rate * (tau + 0.5 * h);
    p += h * rotate(yaw_mid, command_.vx, command_.vy);
    if (jump_on_) {  // on top of the command: the jump's motion (world), seen in the heading
      const double turned = jumpYaw(t + tau) - jumpYaw(t);
      s.yaw += turned;
      s.wz += jumpYawRate(t + tau);
      const Eigen::Vector2d v = jumpVelocity(t + tau);
      const Eigen::Vector2d v_heading = rotate(-s.yaw, v.x(), v.y());
      s.vx += v_heading.x();
      s.vy += v_heading.y();
      p += h * jumpVelocity(t + tau + 0.5 * h);
      // (the command's part turns with the jump's yaw too)
      p += h * (rotate(yaw_mid + turned, command_.vx, command_.vy) -
                rotate(yaw_mid, command_.vx, command_.vy));
    }
  }
}

void GaitGenerator::setJump(const JumpTarget& target, double lift_off, double touch_down) {
  jump_on_ = true;
  jump_landed_ = false;
  jump_ = target;
  jump_lift_off_ = lift_off;
  jump_touch_down_ = touch_down;
}

Eigen::Vector2d GaitGenerator::jumpVelocity(double t) const {
  const double a = jump_lift_off_, b = jump_touch_down_;
  if (!jump_on_ || t <= a - kJumpRamp || t >= b + kJumpRamp) return Eigen::Vector2d::Zero();
  // The flight and half of each ramp cover the target's distance.
  const double share = t < a   ? (t - (a - kJumpRamp)) / kJumpRamp
                       : t > b ? (b + kJumpRamp - t) / kJumpRamp
                               : 1.0;
  return share / (b - a + kJumpRamp) * rotate(jump_heading_, jump_.dx, jump_.dy);
}

double GaitGenerator::jumpYawRate(double t) const {
  const double a = jump_lift_off_, b = jump_touch_down_;
  return jump_on_ && t > a && t < b ? jump_.yaw / (b - a) : 0.0;
}

double GaitGenerator::jumpYaw(double t) const {
  if (!jump_on_) return 0.0;
  const double a = jump_lift_off_, b = jump_touch_down_;
  return jump_.yaw * std::clamp((t - a) / (b - a), 0.0, 1.0);
}

double GaitGenerator::riseAt(double t) const {
  return jump_on_ && !jump_landed_ && !map_ && t >= jump_touch_down_ - kPlanTimeEpsilon ? jump_.dz
                                                                                        : 0.0;
}

GaitGenerator::Sample GaitGenerator::baseAt(double t) const {
  const double h = options_.sample_dt;
  const double tau = t - t_anchor_;
  auto extrapolate = [&](const Sample& s, double d) {
    Sample e = s;
    const Eigen::Vector2d v = rotate(s.yaw + 0.5 * d * s.wz, s.vx, s.vy);
    e.x += d * v.x();
    e.y += d * v.y();
    e.yaw += d * s.wz;
    return e;
  };
  if (tau <= 0.0) return extrapolate(samples_[0], tau);
  const int last = n_samples_ - 1;
  if (tau >= last * h) return extrapolate(samples_[last], tau - last * h);
  const int i = static_cast<int>(tau / h);
  const double r = tau / h - i;
  const Sample& a = samples_[i];
  const Sample& b = samples_[i + 1];
  auto mix = [r](double u, double w) { return u + r * (w - u); };
  return {mix(a.x, b.x),   mix(a.y, b.y),   mix(a.yaw, b.yaw),      mix(a.vx, b.vx),
          mix(a.vy, b.vy), mix(a.wz, b.wz), mix(a.height, b.height)};
}

GaitGenerator::Sample GaitGenerator::robotAt(double t) const {
  Sample s = baseAt(t);
  const Eigen::Vector2d d =
      rotate(robot_turn_, s.x - samples_[0].x, s.y - samples_[0].y) + robot_xy_;
  s.x = d.x();
  s.y = d.y();
  s.yaw += robot_turn_;
  return s;
}

GaitGenerator::Stance GaitGenerator::foothold(int contact, double touch_down, double lift_off,
                                              const Eigen::Vector2d& correction,
                                              const Eigen::Vector2d& kept) const {
  const double mid = touch_down + std::min(0.5 * (lift_off - touch_down), kHalfStanceCap);
  const Sample s = baseAt(mid), r = robotAt(mid);
  const Eigen::Vector3d& off = offset_[contact];
  const Eigen::Vector2d on_reference = Eigen::Vector2d(s.x, s.y) + rotate(s.yaw, off.x(), off.y());
  const Eigen::Vector2d on_robot = Eigen::Vector2d(r.x, r.y) + rotate(r.yaw, off.x(), off.y());
  Eigen::Vector2d lead = on_reference - on_robot;
  const double n = lead.norm();
  if (n > options_.max_foothold_lead) lead *= options_.max_foothold_lead / n;
  const Eigen::Vector2d xy = on_robot + lead + correction;
  Stance stance{
      touch_down, lift_off,
      Eigen::Vector3d(xy.x(), xy.y(), off.z() + blindHeight(xy.x(), xy.y()) + riseAt(touch_down)),
      s.yaw + foot_yaw_[contact]};
  stance.source = StanceSource::Blind;
  stance.swing_height = options_.swing_height;
  if (!map_) return stance;
  // On the map: the nearest safe cell to the nominal foothold, at the map's height (issue 31).
  terrain::FootholdReach reach;
  reach.max_shift = options_.max_foothold_shift;
  reach.kept = kept;
  reach.kept_max_shift = kKeptReach * options_.max_foothold_shift;
  const Eigen::Vector2d travel = rotate(s.yaw, s.vx, s.vy);
  if (travel.norm() > kStill) reach.forward = travel.normalized();
  const terrain::Foothold f = terrain::selectFoothold(*map_, xy, reach);
  switch (f.status) {
    case terrain::FootholdStatus::Nominal:
    case terrain::FootholdStatus::Moved:
      stance.p = f.position + Eigen::Vector3d(0.0, 0.0, off.z());
      stance.normal = f.normal;
      stance.source = f.status == terrain::FootholdStatus::Nominal ? StanceSource::Nominal
                                                                   : StanceSource::Moved;
      stance.near_edge = f.edge_distance < map_->options().edge_search_radius;
      break;
    case terrain::FootholdStatus::Unreachable:
      // No safe cell within reach: the nominal place, at the map's height when it knows it.
      if (std::isfinite(f.position.z())) stance.p.z() = f.position.z() + off.z();
      stance.source = StanceSource::Unreachable;
      break;
    case terrain::FootholdStatus::Unknown:
      stance.source = StanceSource::Unknown;
      break;
  }
  return stance;
}

double GaitGenerator::swingHeight(int contact, const Stance& from, const Stance& to) const {
  if (!map_) return options_.swing_height;
  const double foot = offset_[contact].z(), clearance = options_.swing_clearance;
  double lift = terrain::swingLift(map_->map(), from.p, to.p, foot, clearance);
  if (contacts_dim_[contact] == 6 && options_.sole_half_length > 0.0) {
    // The toe and the heel on the same arc, shifted along the sole's heading at each end.
    const double l = options_.sole_half_length;
    const Eigen::Vector3d a(std::cos(from.yaw), std::sin(from.yaw), 0.0);
    const Eigen::Vector3d b(std::cos(to.yaw), std::sin(to.yaw), 0.0);
    lift = std::max(
        {lift, terrain::swingLift(map_->map(), from.p + l * a, to.p + l * b, foot, clearance),
         terrain::swingLift(map_->map(), from.p - l * a, to.p - l * b, foot, clearance)});
  }
  return std::clamp(lift, options_.swing_height,
                    std::max(options_.swing_height, options_.max_swing_height));
}

void GaitGenerator::updateGround(double t) {
  // Blind: the ground is the plane the feet down stand on (issue 31): fitted through them
  // (terrain::fitGroundPlane: across a line of feet, a trot's diagonal or a biped's soles, the
  // slope known before is kept), its height at their centroid and its slope filtered across plans
  // (a foot landing on a step moves it by a share); the filtered plane is carried to the new
  // centroid before it is blended, so a robot walking up a slope does not lag behind it.
  std::array<Eigen::Vector3d, kMaxFeet> feet;
  int down = 0;
  for (int c = 0; c < nc_; ++c)
    if (timeline_.closed(c, t)) {
      feet[down] = latched_[c];
      feet[down].z() -= offset_[c].z();
      ++down;
    }
  if (down > 0) {
    const terrain::GroundPlane prior =
        terrain::GroundPlane::through(0.0, 0.0, 0.0, slope_filtered_);
    terrain::GroundPlane fit;
    terrain::fitGroundPlane(feet.data(), down, prior, fit);
    Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
    for (int k = 0; k < down; ++k) centroid += feet[k].head<2>();
    centroid /= down;
    const double raw = fit.height(centroid.x(), centroid.y());
    if (!ground_started_) {
      ground_filtered_ = raw;  // the robot starts standing on its ground
      slope_filtered_ = fit.gradient();
      ground_started_ = true;
    } else {
      const double dt = std::clamp(t - ground_t_, 0.0, 1.0);
      const double k = dt / (options_.ground_time_constant + dt);
      const double carried = ground_filtered_ + slope_filtered_.dot(centroid - centroid_);
      ground_filtered_ = carried + k * (raw - carried);
      slope_filtered_ += k * (fit.gradient() - slope_filtered_);
    }
    centroid_ = centroid;
  }
  ground_t_ = t;
  const double band = options_.ground_dead_band;
  ground_ = ground_filtered_ > band    ? ground_filtered_ - band
            : ground_filtered_ < -band ? ground_filtered_ + band
                                       : 0.0;
  const double g = slope_filtered_.norm(), slope_band = options_.ground_slope_dead_band;
  slope_ = g > slope_band ? ((g - slope_band) / g * slope_filtered_).eval()
                          : Eigen::Vector2d::Zero().eval();
}

bool GaitGenerator::landedEarly(int contact, double t, double lift_off, double touch_down) const {
  // Blind only: on a map the touch-down is the map's foothold, and a foot loaded early there has
  // met an edge on its way (stopping it there put soles and feet on edges).
  return !map_ && measured_known_ && ((measured_ >> contact) & 1u) &&
         !timeline_.closed(contact, t) && lift_off <= t && touch_down > t &&
         t - lift_off >= 0.5 * (touch_down - lift_off);
}

double GaitGenerator::blindHeight(double x, double y) const {
  return ground_ + slope_.dot(Eigen::Vector2d(x, y) - centroid_);
}

bool GaitGenerator::plan(double t, const Eigen::Ref<const Eigen::VectorXd>& x, double t_begin,
                         double t_end) {
  const int nq = model_.nq;
  if (!std::isfinite(t) || !std::isfinite(t_begin) || !std::isfinite(t_end) || std::abs(t) > 1e9 ||
      t_end < t_begin || t_end - t_begin > options_.horizon + kPlanTimeEpsilon ||
      x.size() != nq + model_.nv || !x.allFinite())
    return false;
  const auto q = x.head(nq);
  const double n = q.segment<4>(3).norm();
  if (!(n > 0.5)) return false;
  framesForwardKinematics(model_, data_, q);
  const double yaw = yawOf(q[3] / n, q[4] / n, q[5] / n, q[6] / n);
  for (int c = 0; c < nc_; ++c)
    if (!latched_any_ || timeline_.closed(c, t)) {
      const SE3& M = data_.oMf[frames_[c]];
      latched_[c] = M.p;
      latched_yaw_[c] = std::atan2(M.R(1, 0), M.R(0, 0));
      latched_normal_[c] = kUp;
      int row, col;
      if (map_ && map_->cellOf(M.p.x(), M.p.y(), row, col) && std::isfinite(map_->slope(row, col)))
        latched_normal_[c] = map_->normal(row, col);
    }
  // Landed from a jump (blind): the ground the feet feel starts at the landing's height, which
  // the references had as the jump's rise until now; the feet down tell it from here on.
  if (jump_on_ && !jump_landed_ && t >= jump_touch_down_) {
    if (!map_) ground_filtered_ += jump_.dz;
    jump_landed_ = true;
  }
  updateGround(t);
  // The base reference carries on from the last plan, but stays within a leash of the robot. A
  // robot that stands for good is centred over the feet it stands on instead: wherever a stop left
  // the reference, the stance it settles in is the nominal one.
  Eigen::Vector2d anchor = q.head<2>();
  double anchor_yaw = yaw;
  if (timeline_.standsAt(t) && latched_any_) {
    anchor.setZero();
    for (int c = 0; c < nc_; ++c)
      anchor += latched_[c].head<2>() - rotate(yaw, offset_[c].x(), offset_[c].y());
    anchor /= nc_;
  } else if (latched_any_) {
    const Sample before = baseAt(t);
    Eigen::Vector2d lead = Eigen::Vector2d(before.x, before.y) - anchor;
    if (lead.norm() > options_.max_position_lead) lead *= options_.max_position_lead / lead.norm();
    anchor += lead;
    const double turn = std::remainder(before.yaw - yaw, 2.0 * kPi);
    anchor_yaw += std::clamp(turn, -options_.max_yaw_lead, options_.max_yaw_lead);
  }
  sampleBase(t, anchor, anchor_yaw);
  robot_xy_ = q.head<2>();
  robot_turn_ = yaw - anchor_yaw;

  latched_any_ = true;

  // The velocity the robot has beyond the command (world axes, horizontal): the next touch-down
  // of each foot moves by gain x that, capped.
  const Eigen::Quaterniond orientation(q[6] / n, q[3] / n, q[4] / n, q[5] / n);
  const Eigen::Vector3d v_world = orientation * x.segment<3>(nq);
  Eigen::Vector2d correction = gain_ * (v_world.head<2>() - rotate(yaw, command_.vx, command_.vy));
  // (a jump's flight is meant: only its excess over the jump's velocity moves the landing)
  if (jump_on_) correction -= gain_ * jumpVelocity(t);
  const double norm = correction.norm();
  if (norm > options_.max_foothold_correction)
    correction *= options_.max_foothold_correction / norm;

  const double t_from = std::min(t_begin, t);
  // Kept from one knot before: the first knot asks whether a foot lands there (mask(t0 - dt)).
  timeline_.forget(t_from - options_.sample_dt);
  for (int c = 0; c < nc_; ++c) {
    std::vector<Stance>& st = stances_[c];
    if (timeline_.closed(c, t_from))
      st[0] = {timeline_.lastChange(c, t_from), timeline_.nextChange(c, t_from), latched_[c],
               latched_yaw_[c]};
    else
      st[0] = {-ContactTimeline::kNever, timeline_.lastChange(c, t_from), latched_[c],
               latched_yaw_[c]};
    st[0].normal = latched_normal_[c];
    st[0].swing_height = options_.swing_height;
    int count = 1;
    bool next = true;  // the next touch-down after t takes the correction
    double lift_off = st[0].lift_off;
    while (count < kMaxStances && lift_off < ContactTimeline::kNever) {
      const double touch_down = timeline_.nextChange(c, lift_off);
      if (touch_down == ContactTimeline::kNever) break;
      const double next_lift_off = timeline_.nextChange(c, touch_down);
      if (touch_down <= t) {  // already down at t: where it was measured
        st[count] = {touch_down, next_lift_off, latched_[c], latched_yaw_[c]};
        st[count].normal = latched_normal_[c];
        st[count].swing_height = options_.swing_height;
      } else if (next && landedEarly(c, t, lift_off, touch_down)) {
        // On the ground already: the touch-down where the foot is (the timeline unchanged).
        const SE3& M = data_.oMf[frames_[c]];
        st[count] = {touch_down, next_lift_off, M.p, std::atan2(M.R(1, 0), M.R(0, 0))};
        st[count].normal = st[count - 1].normal;
        st[count].early = true;
        if (early_at_[c] != touch_down) {
          early_at_[c] = touch_down;
          ++early_touch_downs_;
        }
        next = false;
      } else if (next && map_ && held_at_[c] == touch_down && lift_off <= t &&
                 t - lift_off >= options_.foothold_hold * (touch_down - lift_off)) {
        st[count] = held_[c];  // past the swing's middle on a map: where it was going
        st[count].lift_off = next_lift_off;
        next = false;
      } else {
        const bool again = next && map_ && held_at_[c] == touch_down;
        st[count] = foothold(c, touch_down, next_lift_off,
                             next ? correction : Eigen::Vector2d::Zero().eval(),
                             again ? held_[c].p.head<2>().eval() : kNoPlace);
        st[count].swing_height = swingHeight(c, st[count - 1], st[count]);
        if (next && map_) {
          held_[c] = st[count];
          held_at_[c] = touch_down;
        }
        next = false;
      }
      ++count;
      if (touch_down > t_end) break;
      lift_off = next_lift_off;
    }
    n_stances_[c] = count;
  }
  planFlights(t_from, t_end);
  return true;
}

void GaitGenerator::planFlights(double t_from, double t_end) {
  // The flights that ended within a landing's braking and return before t_from stay (the landing
  // in progress needs its speed), and so does one in the air at t_from, with its touch-down as the
  // timeline has it now (the planner moves it to the measured one: Planner, "landing as it
  // happens"); those still ahead are found again (a gait switch may have moved them).
  const bool in_air = timeline_.mask(t_from) == 0u;
  int kept = 0;
  for (int k = 0; k < n_flights_; ++k) {
    Flight f = flights_[k];
    if (f.lift_off >= t_from) continue;
    if (f.touch_down > t_from + kPlanTimeEpsilon) {  // in the air at the last plan
      f.touch_down = ContactTimeline::kNever;
      for (int c = 0; c < nc_; ++c)
        f.touch_down =
            std::min(f.touch_down, in_air                        ? timeline_.nextChange(c, t_from)
                                   : timeline_.closed(c, t_from) ? timeline_.lastChange(c, t_from)
                                                                 : ContactTimeline::kNever);
      if (f.touch_down == ContactTimeline::kNever) continue;
    }
    if (f.touch_down > t_from - 2.0 * kPushTime) flights_[kept++] = f;
  }
  n_flights_ = kept;
  // A flight starts when the last foot lifts: at some foot's lift-off (or before t_from, when the
  // robot is in the air there), and ends at the first touch-down after it.
  auto add = [&](double lift_off) {
    double touch_down = ContactTimeline::kNever;
    for (int c = 0; c < nc_; ++c)
      touch_down = std::min(touch_down, timeline_.nextChange(c, lift_off));
    for (int k = 0; k < n_flights_; ++k)
      if (std::abs(flights_[k].lift_off - lift_off) < kPlanTimeEpsilon) return;
    if (n_flights_ == kMaxFlights || touch_down == ContactTimeline::kNever) return;
    // A jump's flight lands dz higher (blind: on a map the footholds' heights carry it).
    const bool jump = jump_on_ && std::abs(lift_off - jump_lift_off_) < kPlanTimeEpsilon;
    const double rise = jump && !map_ ? jump_.dz : 0.0;
    // In time order (a handful: insertion).
    int k = n_flights_++;
    for (; k > 0 && flights_[k - 1].lift_off > lift_off; --k) flights_[k] = flights_[k - 1];
    flights_[k] = {lift_off, touch_down, rise};
  };
  bool known = false;  // the flight in progress, from the last plan
  for (int k = 0; k < n_flights_; ++k)
    known = known || (flights_[k].lift_off < t_from && flights_[k].touch_down > t_from);
  if (in_air && !known) {
    double lift_off = -ContactTimeline::kNever;
    for (int c = 0; c < nc_; ++c) lift_off = std::max(lift_off, timeline_.lastChange(c, t_from));
    add(lift_off);
  }
  for (int c = 0; c < nc_; ++c)
    for (int i = 0; i < n_stances_[c]; ++i) {
      const double lift_off = stances_[c][i].lift_off;
      if (lift_off > t_from && lift_off <= t_end + kLookahead &&
          lift_off < ContactTimeline::kNever && timeline_.mask(lift_off) == 0u)
        add(lift_off);
    }
}

double GaitGenerator::flightLift(double t, double& vz) const {
  vz = 0.0;
  if (n_flights_ == 0) return 0.0;
  // The robot leaves the ground and meets it with its legs stretched as far as the body-height
  // postures reach (max_height above the nominal): a take-off from the nominal crouch pushed the
  // base through less than the legs have, and the torque-limited quadrupeds rose no higher than
  // they stand.
  const double e = options_.max_height;
  // In flight the base follows the ballistic arc from take-off to touch-down: z = e + ½ g (t - a)
  // (b - t), vz = ½ g (a + b - 2t).
  int next = 0;  // the first flight that has not ended by t
  while (next < n_flights_ && flights_[next].touch_down <= t) ++next;
  if (next < n_flights_ && flights_[next].lift_off < t) {
    // (landing `rise` higher: the take-off speed is rise / T + g T / 2)
    const Flight& f = flights_[next];
    const double T = f.touch_down - f.lift_off, u = t - f.lift_off;
    const double v0 = f.rise / T + 0.5 * kGravity * T;
    vz = v0 - kGravity * u;
    return e + v0 * u - 0.5 * kGravity * u * u;
  }
  // On the ground between a touch-down at `a` and a take-off at `b` (either may be missing): the
  // landing brakes from the speed the robot fell at, ½ g (flight time), to rest at a constant
  // deceleration over a crouch of depth D, the take-off pushes from rest to the next flight's
  // speed at a constant acceleration over the same depth, and in between the base moves between
  // those crouches (or back to its level on a longer stance) on smooth cubics of kPushTime. The
  // depth is the posture range, 2 max_height (at least kMinCrouch), or less when the stance is too
  // short for both at that depth (then S v / 4 for equal speeds: a constant force, a pronk's
  // spring). A stance-long cubic from the landing's speed to the take-off's, tried first, crouched
  // by S v / 4 on every stance: 9 cm for a 0.3 s stance at 1.2 m/s, beyond the legs' torque.
  const bool has_in = next > 0, has_out = next < n_flights_;
  const double a = has_in ? flights_[next - 1].touch_down : -ContactTimeline::kNever;
  const double b = has_out ? flights_[next].lift_off : ContactTimeline::kNever;
  // The speeds down at the touch-down and up at the take-off: g T / 2 -+ rise / T.
  auto speed = [](const Flight& f, double sign) {
    const double T = f.touch_down - f.lift_off;
    return std::max(0.0, 0.5 * kGravity * T + sign * f.rise / T);
  };
  const double v_in = has_in ? speed(flights_[next - 1], -1.0) : 0.0;
  const double v_out = has_out ? speed(flights_[next], 1.0) : 0.0;
  const double depth = std::max(2.0 * options_.max_height, kMinCrouch);
  // (A slow landing or take-off, a short flight's, crouches less: at most kPushTime at rest.)
  double d_in = has_in ? std::min(depth, 0.5 * v_in * kPushTime) : 0.0;
  double d_out = has_out ? std::min(depth, 0.5 * v_out * kPushTime) : 0.0;
  double tau_in = d_in > 0.0 ? 2.0 * d_in / v_in : 0.0;
  double tau_out = d_out > 0.0 ? 2.0 * d_out / v_out : 0.0;
  if (has_in && has_out && tau_in + tau_out > b - a) {
    const double k = (b - a) / (tau_in + tau_out);
    d_in *= k, d_out *= k, tau_in *= k, tau_out *= k;
  }
  if (tau_in > 0.0 && t < a + tau_in) {  // braking
    const double u = t - a, acc = v_in / tau_in;
    vz = -v_in + acc * u;
    return e - v_in * u + 0.5 * acc * u * u;
  }
  if (tau_out > 0.0 && t > b - tau_out) {  // pushing
    const double u = t - (b - tau_out), acc = v_out / tau_out;
    vz = acc * u;
    return e - d_out + 0.5 * acc * u * u;
  }
  // Between the crouches: z0 at t0 to z1 at t1, at rest at both ends.
  auto smooth = [&vz](double t, double t0, double t1, double z0, double z1) {
    const double span = t1 - t0, u = std::clamp((t - t0) / span, 0.0, 1.0);
    vz = (z1 - z0) * 6.0 * u * (1.0 - u) / span;
    return z0 + (z1 - z0) * u * u * (3.0 - 2.0 * u);
  };
  const double from = a + tau_in, to = b - tau_out;  // (infinite without a flight on that side)
  const double z_from = has_in ? e - d_in : 0.0, z_to = has_out ? e - d_out : 0.0;
  if (to - from <= 2.0 * kPushTime) return to > from ? smooth(t, from, to, z_from, z_to) : z_to;
  if (t < from + kPushTime) return smooth(t, from, from + kPushTime, z_from, 0.0);
  if (t > to - kPushTime) return smooth(t, to - kPushTime, to, 0.0, z_to);
  return 0.0;
}

int GaitGenerator::stanceAt(int contact, double t, double& s) const {
  const std::vector<Stance>& st = stances_[contact];
  const int n = n_stances_[contact];
  int i = 0;
  while (i + 1 < n && st[i + 1].touch_down <= t + kPlanTimeEpsilon) ++i;
  if (t + kPlanTimeEpsilon < st[i].lift_off) {
    s = 0.0;
  } else if (i + 1 == n) {
    s = -1.0;
  } else {
    const double lift_off = st[i].lift_off, touch_down = st[i + 1].touch_down;
    s = std::clamp((t - lift_off) / (touch_down - lift_off), 0.0, 1.0);
  }
  return i;
}

Eigen::Vector3d GaitGenerator::foot(int contact, double t) const {
  double s;
  const int i = stanceAt(contact, t, s);
  const std::vector<Stance>& st = stances_[contact];
  if (s <= 0.0) return st[i].p;             // down, or no touch-down known: hold the lift-off point
  if (st[i + 1].early) return st[i + 1].p;  // landed before its time: stay
  Eigen::Vector3d p = st[i].p + 0.5 * (1.0 - std::cos(kPi * s)) * (st[i + 1].p - st[i].p);
  p.z() += st[i + 1].swing_height * std::sin(kPi * s);
  return p;
}

const Eigen::Vector3d& GaitGenerator::footNormal(int contact, double t) const {
  double s;
  const int i = stanceAt(contact, t, s);
  const std::vector<Stance>& st = stances_[contact];
  return s > 0.0 ? st[i + 1].normal : st[i].normal;
}

bool GaitGenerator::footholdNearEdge(int contact, double t) const {
  double s;
  const int i = stanceAt(contact, t, s);
  const std::vector<Stance>& st = stances_[contact];
  return s > 0.0 ? st[i + 1].near_edge : st[i].near_edge;
}

Eigen::Matrix3d GaitGenerator::surfaceRotation(int contact, double t) const {
  return alignZ(footNormal(contact, t));
}

GaitGenerator::Ground GaitGenerator::groundAt(double t) const {
  if (!map_) {
    // Blind: the plane the feet feel, under the base reference.
    const Sample b = baseAt(t);
    return {blindHeight(b.x, b.y) + riseAt(t),
            Eigen::Vector3d(-slope_.x(), -slope_.y(), 1.0).normalized()};
  }
  // The feet's footholds at t (each foot's on the swing's ramp between them), on the ground.
  std::array<Eigen::Vector3d, kMaxFeet> feet;
  Eigen::Vector3d normals = Eigen::Vector3d::Zero();
  double height = 0.0;
  for (int c = 0; c < nc_; ++c) {
    double s;
    const int i = stanceAt(c, t, s);
    const std::vector<Stance>& st = stances_[c];
    feet[c] = st[i].p;
    if (s > 0.0) feet[c] += 0.5 * (1.0 - std::cos(kPi * s)) * (st[i + 1].p - st[i].p);
    feet[c].z() -= offset_[c].z();
    height += feet[c].z();
    normals += s > 0.0 ? st[i + 1].normal : st[i].normal;
  }
  // Their mean height, and the plane through them; across a line of feet (a biped, a trot's
  // diagonal) the footholds' surfaces tell the slope.
  const Eigen::Vector3d n = normals.normalized();
  terrain::GroundPlane prior, plane;
  prior.b = -n.x() / n.z();
  prior.c = -n.y() / n.z();
  if (terrain::fitGroundPlane(feet.data(), nc_, prior, plane) == 0) plane = prior;
  return {height / nc_, plane.normal()};
}

Eigen::Matrix3d GaitGenerator::footRotation(int contact, double t) const {
  double s;
  const int i = stanceAt(contact, t, s);
  const std::vector<Stance>& st = stances_[contact];
  double yaw = st[i].yaw;
  if (s > 0.0)
    yaw += 0.5 * (1.0 - std::cos(kPi * s)) * std::remainder(st[i + 1].yaw - yaw, 2.0 * kPi);
  // A sole lands flat on its foothold's surface.
  const Eigen::Vector3d& n = s > 0.0 ? st[i + 1].normal : st[i].normal;
  return alignZ(n) * Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * foot_tilt_[contact];
}

void GaitGenerator::state(double t, Eigen::Ref<Eigen::VectorXd> x_ref) const {
  const int nq = model_.nq;
  x_ref = x_nominal_;
  const Sample s = baseAt(t);
  x_ref[0] = s.x;
  x_ref[1] = s.y;
  const Ground ground = groundAt(t);
  double vz = 0.0;
  const double lift = flightLift(t, vz);
  x_ref[2] = z_nominal_ + s.height + ground.height + lift;
  // The body tilts with the ground under the feet (flat: exactly the nominal tilt).
  const Eigen::Quaterniond o = Eigen::Quaterniond(alignZ(ground.normal)) *
                               Eigen::AngleAxisd(s.yaw, Eigen::Vector3d::UnitZ()) * tilt_;
  x_ref.segment<4>(3) << o.x(), o.y(), o.z(), o.w();
  // The joints of the posture for the commanded height (interpolated between the solved ones).
  const int n = static_cast<int>(crouch_.size());
  if (n > 1) {
    const PostureBlend b = postureBlend(s.height + lift, options_.max_height, n);
    x_ref.segment(7, nq - 7) =
        (1.0 - b.weight) * crouch_[b.lower] + b.weight * crouch_[b.lower + 1];
  }
  // The twist in the base frame: the heading frame's, seen through the nominal tilt.
  const Eigen::Matrix3d untilt = tilt_.conjugate().toRotationMatrix();
  x_ref.segment<3>(nq) = untilt * Eigen::Vector3d(s.vx, s.vy, vz);
  x_ref.segment<3>(nq + 3) = untilt * Eigen::Vector3d(0.0, 0.0, s.wz);
}

Eigen::Vector3d GaitGenerator::basePosition(double t) const {
  const Sample s = baseAt(t);
  double vz;
  return {s.x, s.y, z_nominal_ + s.height + groundAt(t).height + flightLift(t, vz)};
}

double GaitGenerator::height(double t) const {
  double vz;
  return baseAt(t).height + flightLift(t, vz);
}

double GaitGenerator::baseYaw(double t) const {
  return baseAt(t).yaw;
}

Eigen::Vector3d GaitGenerator::com(double t) const {
  const Sample s = baseAt(t);
  const Eigen::Vector2d xy =
      Eigen::Vector2d(s.x, s.y) + rotate(s.yaw, com_offset_.x(), com_offset_.y());
  double vz;
  return {xy.x(), xy.y(),
          z_nominal_ + s.height + groundAt(t).height + com_offset_.z() + flightLift(t, vz)};
}

}  // namespace stride
