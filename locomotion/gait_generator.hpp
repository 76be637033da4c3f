#pragma once
// The references a commanded robot walks by, re-planned every tick from the measured state and a
// body velocity command: when each foot is down (a ContactTimeline of gait patterns), where each
// touch-down lands, the swing arcs between footholds, and the base's pose and twist over the
// horizon. The locomotion problem (locomotion_problem.hpp) reads them knot by knot.
//
// Body height: the base is raised (or lowered) by the command's height offset, and the joints'
// reference follows it: the posture that keeps every foot on its nominal place with the base at
// that offset, solved at construction for offsets across [-max_height, max_height] and
// interpolated.
//
// Base: from the last plan's reference at the state's time t, held within a leash of the measured
// base (max_position_lead, max_yaw_lead), or, for a robot that stands for good, from the centre of
// the feet it stands on; then integrated from the command in force (vx, vy in the heading frame,
// yaw rate), held over the whole horizon. The controller smooths a new command tick by tick
// (controller/command.hpp), so each re-plan moves the horizon by one tick's step of it. (A horizon
// that ramped to the target command instead moved every touch-down of its tail at once when a
// command changed: the swing costs of the warm start jumped 100-fold, one iteration per tick left
// gaps for several ticks, and the torque-limited quadruped fell in 11 of 81 perturbed starts and
// reversals that this passes; controller/README.md, "Commands".) Height and tilt are the nominal
// posture's (plus the height offset); the base velocity reference is the command. In a flight
// (every foot in the air, issue 45) the height follows the ballistic arc between take-off and
// touch-down and the vertical velocity its slope, and on the ground next to a flight it brakes the
// landing and pushes for the take-off (flightLift): a level reference would have the state cost
// fight the arc that the momentum, conserved in flight, makes anyway.
//
// Footholds (Raibert's heuristic, on the reference instead of the hip's current position): a
// touch-down at t_td that lasts until lift-off t_lo lands under the foot's nominal stance position
// (its place relative to the base in the nominal posture, on the ground) carried by the base
// reference to mid-stance t_mid = t_td + ½ min(t_lo - t_td, 1 s), rotated by the reference yaw
// there, and within max_foothold_lead of where the same rule puts it on a reference anchored at the
// measured base. The next touch-down of each foot also moves by k (v - v_cmd), the measured
// horizontal velocity's excess over the command (capped): a robot that is too fast (pushed) steps
// further, as a capture point would. A foot down at t keeps the position measured there (latched
// while it is down, so the foot it lifts from is where it really was).
//
// Swing from foothold a to b, s = (t - lift-off) / (touch-down - lift-off):
//   p(s) = a + ½ (1 - cos πs)(b - a) + h sin(πs) e_z
// (no horizontal speed at either end: a landing needs no tangential impulse). A foot's heading
// turns on the same ramp, from its yaw at lift-off to the reference yaw at the next mid-stance
// (plus its nominal yaw relative to the base): a sole lands turned with the body.
//
// plan() allocates nothing and queries are array look-ups; the sizes are fixed at construction.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "locomotion/contact_timeline.hpp"
#include "locomotion/jump.hpp"
#include "solver/multibody/data.hpp"
#include "terrain/steppability.hpp"

namespace stride {

// A body command: velocity in the base's heading frame and the base height offset.
struct BodyCommand {
  double vx = 0.0, vy = 0.0;  // [m/s]
  double yaw_rate = 0.0;      // [rad/s]
  double height = 0.0;        // [m], from the nominal posture's
};

// Where a body height offset falls among the body-height postures (GaitGenerator::
// crouchPostures: n postures for offsets spread evenly over [-max_height, max_height]): between
// posture `lower` and `lower + 1`, with `weight` on the upper one; the offset clamped to the range.
// The one interpolation of the postures: the joints' reference (GaitGenerator::state) and the
// holding torques of the control reference (LocomotionProblem) both blend by it, at the commanded
// offset (GaitGenerator::height), never at the base's height, which also carries the ground's.
struct PostureBlend {
  int lower = 0;
  double weight = 0.0;
};
PostureBlend postureBlend(double height, double max_height, int n);

// Where a stance's position came from (horizon_t.foothold_source carries it as a number).
enum class StanceSource : std::uint8_t {
  Measured = 0,     // the foot is (or was) down there: its measured position
  Blind = 1,        // planned on the ground the feet feel (no map, or a stale one)
  Nominal = 2,      // the map's: the nominal foothold was safe
  Moved = 3,        // the map's: moved to the nearest steppable cell
  Unreachable = 4,  // the map knows no steppable cell within reach: blind height, nominal place
  Unknown = 5,      // the map does not know the place: blind
};

struct GaitGeneratorOptions {
  double swing_height = 0.05;  // apex of the swing arcs above the line between footholds [m]
  // Raibert gain k [s] on the velocity excess; negative: sqrt(h / g) of the nominal base height h
  // (the capture point's time constant).
  double foothold_gain = -1.0;
  double max_foothold_correction = 0.1;  // cap on |k (v - v_cmd)| [m]
  // How far the base reference may lead (or trail) the measured base: position [m], yaw [rad].
  double max_position_lead = 0.1;
  double max_yaw_lead = 0.3;
  // How far a foothold may be from where the same foothold would be if the reference were
  // anchored at the measured base [m]: a robot that lags its reference is not asked to reach
  // beyond its legs.
  double max_foothold_lead = 0.05;
  double max_height = 0.0;  // the largest |height offset| a command may ask for [m]
  // The ground the feet feel (blind: no map): the mean height of the feet down at each plan,
  // filtered with this time constant [s]; offsets within ground_dead_band of the nominal ground
  // (z = 0) are taken as the nominal ground, so that a flat floor plans exactly as without it.
  double ground_time_constant = 0.3;
  double ground_dead_band = 0.005;
  // Its slope: the plane through the feet down, filtered alike; a gradient within this of level
  // (1.7 degrees) is level, beyond it the band is subtracted.
  double ground_slope_dead_band = 0.03;
  // On a map (setMap): how far a foothold may move from the nominal one to a steppable cell [m],
  // the swing's clearance over the terrain between its footholds [m], and the highest apex a swing
  // may take above the line between them [m].
  double max_foothold_shift = 0.08;
  double swing_clearance = 0.05;
  double max_swing_height = 0.25;
  // On a map, a swing's foothold is chosen again at every plan until this part of the swing has
  // passed, then held: a target that jumps between cells (the nominal crossing from one to the
  // next) late in a swing is one the foot cannot reach, and it lands between them, on the edge.
  double foothold_hold = 0.5;
  // Half the length of a surface contact's sole along its heading [m] (0: point feet): on a map its
  // toe and heel clear the terrain as its centre does.
  double sole_half_length = 0.0;
  // The longest span plan() is asked to cover (t_end - t_begin) [s], and the step of the base
  // trajectory's samples.
  double horizon = 1.0;
  double sample_dt = 0.01;
};

class GaitGenerator {
 public:
  static constexpr int kMaxStances = 32;  // per foot, in a planned window

  // x_nominal: the nominal posture (its base pose sets the height and tilt; its position and yaw
  // do not matter). Throws std::invalid_argument for a fixed-base model, sizes or options.
  GaitGenerator(const Model& model, const ContactSet& contacts, const Eigen::VectorXd& x_nominal,
                const GaitGeneratorOptions& options = {});

  ContactTimeline& timeline() { return timeline_; }
  const ContactTimeline& timeline() const { return timeline_; }
  const GaitGeneratorOptions& options() const { return options_; }
  double footholdGain() const { return gain_; }
  // The joints of the body-height postures, for offsets spread evenly over
  // [-options.max_height, options.max_height] (empty without a body-height range).
  const std::vector<Eigen::VectorXd>& crouchPostures() const { return crouch_; }

  // The terrain to plan on (terrain/steppability.hpp), or none (nullptr): blind, the ground the
  // feet feel. The map must outlive its use (until the next setMap); the controller sets it before
  // each plan() from the newest map that is fresh enough (controller/README.md, "Terrain").
  //
  // With a map, each touch-down after the plan time goes to terrain::selectFoothold of its
  // nominal place (within max_foothold_shift), at the map's height there; the swing that lands
  // there rises high enough to clear the terrain between its footholds (terrain::swingLift with
  // swing_clearance, at least swing_height, at most max_swing_height); the base's height follows
  // the mean height of the feet's footholds along the horizon (each foot's on the swing's ramp
  // between them), and its tilt the plane through them (terrain::fitGroundPlane, across a line of
  // feet the mean of the footholds' surface normals); a foot's friction cone and a sole's
  // orientation follow the surface normal of its foothold.
  void setMap(const terrain::Steppability* map) { map_ = map && map->valid() ? map : nullptr; }
  const terrain::Steppability* map() const { return map_; }

  // The command in force (the controller's smoothed command), held over the horizon.
  void setCommand(const BodyCommand& command) { command_ = command; }

  // A jump (locomotion/jump.hpp) whose flight the timeline has from lift_off to touch_down: the
  // base reference speeds up to its horizontal velocity in the last kJumpRamp of the push, flies
  // to the target (forward, left, turning by its yaw in the air) and slows down in the first
  // kJumpRamp after the touch-down; blind, the ground after the touch-down is dz higher (once
  // the robot has landed, the ground it feels takes that over). For the next plan()s, until
  // clearJump(). Allocation-free.
  void setJump(const JumpTarget& target, double lift_off, double touch_down);
  void clearJump() { jump_on_ = false; }
  bool jumping() const { return jump_on_; }
  const BodyCommand& command() const { return command_; }

  // Re-plans from the measured state x at plan time t for the window [t_begin, t_end] (at most
  // options.horizon long): anchors the base, latches the feet that are down at t, places every
  // touch-down up to the first after t_end. False (nothing changed) for a non-finite time or
  // state, a wrong size, or a window longer than options.horizon.
  bool plan(double t, const Eigen::Ref<const Eigen::VectorXd>& x, double t_begin, double t_end);

  // The contacts the robot's estimator reports loaded (bit c: contact c), for the next plan()s; or
  // none known (the default). Blind (no map), a foot in the second half of its swing that is
  // reported loaded has landed early (higher ground than planned): its touch-down stays where the
  // timeline has it (the horizon's contact sequence does not change), but its reference holds the
  // place it landed on instead of going on down the arc. A foot that is late (still in the air at
  // its touch-down time) is closed by the clock, latched where it is measured, and the ground the
  // feet feel follows it down (controller/README.md, "Terrain").
  void setMeasuredContacts(unsigned mask) {
    measured_ = mask;
    measured_known_ = true;
  }
  void clearMeasuredContacts() { measured_known_ = false; }
  // Swings ended early by a reported touch-down, counted once each.
  long earlyTouchDowns() const { return early_touch_downs_; }

  // After plan(): contact c closed at time t (the timeline's), its reference position (foothold
  // or swing arc), the state reference (base pose and twist; joints at the posture of the body
  // height, at
  // rest), the centre of mass reference (the nominal CoM carried by the base reference).
  bool closed(int contact, double t) const { return timeline_.closed(contact, t); }
  unsigned mask(double t) const { return timeline_.mask(t); }
  Eigen::Vector3d foot(int contact, double t) const;
  // Its reference orientation: the nominal tilt of the foot, turned to the planned heading (and on
  // a map tilted onto the surface of its foothold).
  Eigen::Matrix3d footRotation(int contact, double t) const;
  // The surface normal (world) where contact c stands at t, or where it lands when in the air, and
  // the smallest rotation that takes e_z to it (the identity on flat ground): its friction cone's.
  const Eigen::Vector3d& footNormal(int contact, double t) const;
  Eigen::Matrix3d surfaceRotation(int contact, double t) const;
  // Whether the foothold contact c stands on at t, or lands on when in the air, is a map's near
  // an edge (Stance::near_edge): one the foot must land on, not a few cm off.
  bool footholdNearEdge(int contact, double t) const;
  void state(double t, Eigen::Ref<Eigen::VectorXd> x_ref) const;
  Eigen::Vector3d com(double t) const;
  // The base reference at t: position, yaw.
  Eigen::Vector3d basePosition(double t) const;
  // The body height offset at t: the command's, plus the vertical profile next to and in a
  // flight (flightLift), over the ground under the feet (the base's reference height is the
  // nominal one plus it plus the ground's): the posture the joints' and the control's references
  // hold (postureBlend; in flight the highest, the legs stretched for the landing).
  double height(double t) const;
  // The ground the feet feel, blind (options.ground_time_constant), beyond the dead bands: its
  // height at the centroid of the feet down [m] and its slope (dz/dx, dz/dy); every blind
  // foothold, the base and the centre of mass are planned on that plane.
  double ground() const { return ground_; }
  const Eigen::Vector2d& groundSlope() const { return slope_; }
  double baseYaw(double t) const;

  // The planned stances of a foot: touch-down, lift-off (±infinity when outside the timeline's
  // knowledge), position. Stance 0 is the one in force at the window's start (or the last before
  // it, for a foot in the air), at its latched position.
  struct Stance {
    double touch_down, lift_off;
    Eigen::Vector3d p;
    double yaw;  // the foot's heading
    // Where p came from: measured (a foot down), blind (the ground the feet feel), or the map's
    // foothold selection (terrain::FootholdStatus: Nominal, Moved, Unreachable, Unknown).
    StanceSource source = StanceSource::Measured;
    Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // the surface's there (world, up)
    double swing_height = 0.0;  // the apex of the swing that lands here, above the line [m]
    bool early = false;         // landed before its touch-down time: the swing to it is over
    // On a map, chosen (Nominal or Moved) within the map's edge_search_radius of an edge.
    bool near_edge = false;
  };
  int stances(int contact) const { return n_stances_[contact]; }
  // The flights planned (every foot in the air) from the window's start: take-off, touch-down.
  struct Flight {
    double lift_off, touch_down;
    double rise = 0.0;  // the landing's height above the take-off's (a jump's dz, blind)
  };
  static constexpr int kMaxFlights = 16;
  int flights() const { return n_flights_; }
  const Flight& flight(int i) const { return flights_[i]; }
  // The base's height above its level reference at t, and its vertical velocity: on a flight's
  // ballistic arc, and on the ground next to one a landing's braking and a take-off's push (0 away
  // from flights).
  double flightLift(double t, double& vz) const;
  const Stance& stance(int contact, int i) const { return stances_[contact][i]; }
  // A foot's nominal stance position relative to the base, in the heading frame.
  const Eigen::Vector3d& stanceOffset(int contact) const { return offset_[contact]; }

 private:
  struct Sample {
    double x, y, yaw, vx, vy, wz, height;
  };
  void sampleBase(double t, const Eigen::Vector2d& p0, double yaw0);
  Sample baseAt(double t) const;
  // The ground under the base at t: on a map, the mean height of the feet's footholds and the
  // normal of the plane through them; else ground_, level.
  struct Ground {
    double height;
    Eigen::Vector3d normal;
  };
  Ground groundAt(double t) const;
  // The same command carried from the measured base instead (where footholds are planned).
  Sample robotAt(double t) const;
  // A planned stance's position and heading; `kept`: on a map, where the last plan put this
  // touch-down (NaN: nowhere), kept within a longer reach (kKeptReach).
  Stance foothold(int contact, double touch_down, double lift_off,
                  const Eigen::Vector2d& correction, const Eigen::Vector2d& kept) const;
  // The apex of the swing from `from` to `to` (swing_height; on a map, high enough to clear it).
  double swingHeight(int contact, const Stance& from, const Stance& to) const;
  // Whether contact c, in the air at t on its swing from lift_off to touch_down, is reported
  // loaded in the second half of that swing (setMeasuredContacts).
  bool landedEarly(int contact, double t, double lift_off, double touch_down) const;
  // The ground the feet down feel at plan time t (ground_).
  void updateGround(double t);
  // The stance in force (or last lifted from) at t, and how far along the swing to the next one
  // t is (0 while down, 1 when landed; -1 when no next stance is known).
  int stanceAt(int contact, double t, double& s) const;
  void planFlights(double t_from, double t_end);
  // The jump's horizontal velocity (world) and yaw rate at t, and its yaw turned by t.
  Eigen::Vector2d jumpVelocity(double t) const;
  double jumpYawRate(double t) const;
  double jumpYaw(double t) const;
  // Blind: the jump's rise of the ground from its touch-down on, until the robot has landed.
  double riseAt(double t) const;

  const Model& model_;
  ContactTimeline timeline_;
  GaitGeneratorOptions options_;
  int nc_;
  std::vector<int> frames_;
  std::vector<int> contacts_dim_;  // 3: a point foot, 6: a sole
  Eigen::VectorXd x_nominal_;
  Eigen::Quaterniond tilt_;  // the nominal base orientation without its yaw
  double z_nominal_ = 0.0;
  double gain_ = 0.0;
  std::vector<Eigen::Vector3d> offset_;     // heading frame, z: the foot's height
  std::vector<double> foot_yaw_;            // each foot's nominal yaw relative to the base
  std::vector<Eigen::Matrix3d> foot_tilt_;  // each foot's nominal orientation without its yaw
  Eigen::Vector3d com_offset_;              // nominal CoM relative to the base, heading frame
  // Joint postures for height offsets spread evenly over [-max_height, max_height].
  std::vector<Eigen::VectorXd> crouch_;
  void buildCrouches(const ContactSet& contacts);
  BodyCommand command_;

  Data data_;  // forward kinematics of the measured state
  bool latched_any_ = false;
  // The filtered mean height of the feet down relative to their nominal height, and the last
  // plan's time; ground_: it past the dead band.
  double ground_filtered_ = 0.0, ground_ = 0.0, ground_t_ = 0.0;
  // The plane's gradient, filtered and past its dead band, and the centroid of the feet down at
  // the last plan (where ground_ is the plane's height).
  Eigen::Vector2d slope_filtered_ = Eigen::Vector2d::Zero(), slope_ = Eigen::Vector2d::Zero();
  Eigen::Vector2d centroid_ = Eigen::Vector2d::Zero();
  // The blind ground's height at (x, y): ground_ at the centroid, along slope_.
  double blindHeight(double x, double y) const;
  bool ground_started_ = false;
  std::vector<Eigen::Vector3d> latched_;  // where each foot was last measured while down
  std::vector<double> latched_yaw_;
  std::vector<Eigen::Vector3d> latched_normal_;  // the map's normal where the foot stands
  const terrain::Steppability* map_ = nullptr;
  unsigned measured_ = 0;
  bool measured_known_ = false;
  long early_touch_downs_ = 0;
  std::vector<double> early_at_;  // the touch-down time of each contact's last early landing
  // On a map, the foothold the last plan chose for each foot's next touch-down (held_at_: its
  // touch-down time; -kNever: none): kept within a longer reach, and held from the swing's middle.
  std::vector<Stance> held_;
  std::vector<double> held_at_;
  double t_anchor_ = 0.0;
  Eigen::Vector2d robot_xy_ = Eigen::Vector2d::Zero();  // measured base at t_anchor_
  double robot_turn_ = 0.0;                             // measured yaw - reference yaw there
  std::vector<Sample> samples_;  // base reference from t_anchor_, every options.sample_dt
  int n_samples_ = 0;
  std::vector<std::vector<Stance>> stances_;
  std::vector<int> n_stances_;
  Flight flights_[kMaxFlights];
  int n_flights_ = 0;
  bool jump_on_ = false, jump_landed_ = false;
  JumpTarget jump_;
  double jump_lift_off_ = 0.0, jump_touch_down_ = 0.0;
  double jump_heading_ = 0.0;  // the base reference's yaw at the take-off
};

}  // namespace stride
