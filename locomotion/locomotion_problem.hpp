#pragma once
// The locomotion problem: a shooting problem of contact / impulse knots that all carry the same
// cost terms, re-configured in place every tick from the references of a GaitGenerator
// (gait_generator.hpp: which feet are down, footholds and swing arcs, the base's pose and twist).
//
// Every running knot has
//   "state"        ½ Σ w_i (x ⊖ x_ref)_i²: x_ref = the generator's base pose and twist, the
//                  joints at the posture of the commanded body height, at rest;
//   "control"      ½ w |u - u_ref|²: u_ref = the torques that hold the posture of the commanded
//                  body height (the nominal one without setPostures) still on the knot's closed
//                  contacts (minimum-norm forces), so standing costs nothing;
//   "cone_<c>"     friction cone of contact c, on while c is closed;
//   "cop_<c>"      centre of pressure of surface contact c inside its sole (options.
//                  sole_half_extents), on while c is closed;
//   "com"          the centre of mass on the generator's reference (options.weights.com > 0);
//   "swing_<c>"    position of foot c on its swing arc, on while c is open and at its touch-down
//                  knot (reference: the new foothold, so the foot lands where planned);
//   "swing_rot_<c>" orientation of surface contact c (a sole) on its way to the next heading,
//                  when it is on as swing_<c> is (options.weights.swing_rotation > 0): a sole lands
//                  turned with the body.
// The terminal knot has "state" only. A touch-down inserts an impulse knot (options.impulses) with
// the contacts closed after it; it takes no time, so knot k stands for time t0 + the durations of
// the contact knots before it, knotTime(k).
//
// Time grid (options.grid, e.g. 10 ms knots near now and 40 ms ones in the tail; options.dt
// throughout without one): each segment's knots in turn, then knots of the segment's duration
// (the last one shortened) up to the next segment's first boundary on the plan clock, a multiple of
// its duration. So the long knots sit at fixed plan times: as the horizon moves by one short
// knot, only the short segments change length, and a touch-down in the tail snaps to the same
// knot boundary at every tick instead of jumping between two. The last segment takes the
// remaining knots. A knot's costs stand for its duration: its weights are scaled by dt / dt_0, so
// a 40 ms knot weighs as the four 10 ms knots it replaces. Impulse knots take a slot each but no
// time: with n touch-downs in the horizon, it ends n long knots earlier, so a grid that is to
// cover 1 s while trotting lists 1 s plus the long knots of its touch-downs. Contacts switch at
// knot boundaries: a contact is closed in a knot when it is closed at the knot's start (a
// touch-down inside a 40 ms knot lands at its end).

#include <algorithm>
#include <vector>

#include "locomotion/gait_generator.hpp"
#include "solver/ocp/knot.hpp"
#include "solver/ocp/problem.hpp"

namespace stride {

struct LocomotionWeights {
  // State regularization per group (base entries of a free-flyer, then the joints), unless
  // `state` (2 nv entries, the tangent space [dq; dv]) is given.
  double base_position = 0.0;
  double base_orientation = 10.0;
  double joint_position = 1.0;
  double base_velocity = 1.0;
  double joint_velocity = 1.0;
  Eigen::VectorXd state;
  double control = 1e-2;
  double swing = 1e4;  // per axis, on the foot position error [m]
  // On its x and y, if not negative (else `swing`): lighter than `swing`, the solver may move a
  // foothold by a few cm where the dynamics need it (a robot braking from a run steps further).
  // Not a foothold a map placed near an edge (GaitGenerator::footholdNearEdge): the foot must land
  // there, and its swing weighs `swing` on every axis (with 1e4 solo12 landed its hind feet 1.4 cm
  // ahead of such footholds on average, up to 2.1 cm: 2 cm from the edge they were kept 4 cm
  // from).
  double swing_horizontal = -1.0;
  double swing_rotation = 0.0;   // per axis, on a sole's orientation error [rad] (0: no term)
  double friction = 1e2;         // on the cone rows' violation [N]
  double cop = 1e2;              // on the centre-of-pressure rows' violation [N m] (6D contacts)
  double com = 0.0;              // per axis, on the CoM position error [m] (0: no such term)
  double terminal_state = 10.0;  // the terminal state weights are the running ones times this
};

// `knots` contact knots of `dt` each, on a non-uniform time grid.
struct KnotSegment {
  int knots = 0;
  double dt = 0.0;
};

struct LocomotionOptions {
  double dt = 0.01;
  int knots = 100;  // running knots; a terminal knot follows
  // The time grid as segments, in order from now, durations not decreasing; when not empty it
  // replaces knots and dt (knots = the segments' sum, dt = the first segment's: the policy's knot
  // spacing).
  std::vector<KnotSegment> grid;
  double mu = 0.7;  // friction coefficient (flat ground, normal +z)
  double min_normal_force = 0.0;
  LocomotionWeights weights;
  bool impulses = true;  // impulse knots at touch-downs (else contact knots throughout)
  // How every contact knot integrates (knot.hpp): Euler, or Rk4 (4th order, four KKT solves per
  // knot). Impulse knots are instantaneous, the same under both.
  Integrator integrator = Integrator::Euler;
  // Surface (6D) contacts: the centre of pressure stays in this rectangle around the contact
  // frame (half extents along its x and y; zero: no such term). Use the sole's, shrunk by a margin.
  Eigen::Vector2d sole_half_extents = Eigen::Vector2d::Zero();
  bool torque_limits = false;  // controlLower/Upper from the model's effort limits (else ±inf)
  // The plan's share of those limits: the rest is left to the feedback and to what the model does
  // not know (a heavier robot, weaker motors; controller/README.md, "Robustness").
  double torque_limit_fraction = 1.0;
};

class LocomotionProblem {
 public:
  // Every contact a gait may close (at most stride::kMaxContacts, contact_set.hpp; forces are
  // expected LOCAL_WORLD_ALIGNED, for which the flat-ground cone needs no rotation; LOCAL forces
  // get the cone in the foot's axes). x_nominal: the nominal posture (the joints' references, the
  // holding torques). Throws std::invalid_argument for an x_nominal of the wrong size or options
  // out of range (dt ≤ 0, knots < 1, a grid segment without knots or duration, μ ≤ 0, weights of
  // the wrong size), or too many contacts.
  LocomotionProblem(const Model& model, const ContactSet& contacts,
                    const Eigen::VectorXd& x_nominal, const LocomotionOptions& options = {});

  ShootingProblem& problem() { return *problem_; }
  const ShootingProblem& problem() const { return *problem_; }
  const ContactSet& contacts() const { return contacts_; }
  // The options as used: with a grid, knots and dt are the grid's (its sum and first duration).
  const LocomotionOptions& options() const { return options_; }
  const Eigen::VectorXd& nominal() const { return x_nominal_; }
  double startTime() const { return t0_; }
  // The longest span of the horizon's contact knots [s] (no impulse knot): what a generator's
  // window must cover.
  double span() const { return span_; }

  // Re-configures every knot in place for the references from time t0 on (the generator planned
  // for a window from t0 of span()): contacts, knot modes, which cost terms are on, swing, state
  // and CoM references. No allocation (the controller's tick calls it after
  // ShootingProblem::shift). False (nothing changed) for a non-finite or absurd t0.
  bool update(double t0, const GaitGenerator& reference);
  // The time knot k stands for after the last update (k = horizon(): the terminal knot).
  double knotTime(int k) const { return knot_time_[k]; }
  const std::vector<double>& knotTimes() const { return knot_time_; }  // T + 1
  // The contacts knot k closes after the last update (bit c: contact c), k < horizon().
  unsigned contactMask(int k) const;

  // The torques that hold the nominal posture still on the contacts of `mask` (bit c: contact c
  // closed; minimum-norm forces); the joint gravity torques with no contact.
  const Eigen::VectorXd& holdingControl(unsigned mask) const { return u_hold_[mask]; }
  // The same for posture q (configuration, size nq), one per mask. Allocates: for start-up.
  std::vector<Eigen::VectorXd> holdingControlsOf(const Eigen::VectorXd& q) const;
  // The body-height postures a generator's references move through (GaitGenerator::
  // crouchPostures: joint positions for offsets spread evenly over [-max_height, max_height]):
  // each knot's control reference then holds the posture of the commanded body height
  // (GaitGenerator::height, blended by postureBlend as the joints' reference is; not the base's
  // height, which carries the ground's too) instead of the nominal one, whose torques are not
  // those of a raised or crouched body (on the quadruped's trot the effect on the height reached
  // is small: ~1 mm). Setup (allocates); fewer than two postures: none.
  void setPostures(const std::vector<Eigen::VectorXd>& joints, double max_height);
  // A warm start that follows the references: each knot's state reference and holding control
  // (after update).
  void referenceWarmStart(const GaitGenerator& reference, std::vector<Eigen::VectorXd>& xs,
                          std::vector<Eigen::VectorXd>& us) const;
  // A warm start that stays where the robot is: state x0 at knot 0, its posture at rest at every
  // other knot, each knot's torques holding that posture on the knot's contacts (after update).
  // Allocates (holdingControlsOf): for a controller's first solve.
  void measuredWarmStart(const Eigen::VectorXd& x0, std::vector<Eigen::VectorXd>& xs,
                         std::vector<Eigen::VectorXd>& us) const;
  // Control bounds for the box solver (size nu; ±infinity unless options.torque_limits).
  const Eigen::VectorXd& controlLower() const { return u_lower_; }
  const Eigen::VectorXd& controlUpper() const { return u_upper_; }

 private:
  const Model& model_;
  ContactSet contacts_;
  Eigen::VectorXd x_nominal_;
  LocomotionOptions options_;
  std::unique_ptr<ShootingProblem> problem_;
  int com_term_ = -1;
  std::vector<Eigen::VectorXd> u_hold_;                  // per contact mask
  std::vector<std::vector<Eigen::VectorXd>> u_posture_;  // per posture, per contact mask
  double max_height_ = 0.0;
  Eigen::VectorXd u_ref_;  // scratch: the interpolated holding torques
  // The holding torques of mask at the commanded body height `height` (postureBlend).
  const Eigen::VectorXd& holdingControlAt(unsigned mask, double height);
  Eigen::VectorXd u_lower_, u_upper_;
  // The duration of the contact knot starting at plan time t, in grid segment seg with left of its
  // knots still due (both advanced).
  double contactKnotDuration(double t, int& seg, int& left) const;
  // Term indices, the same in every running knot (all are built alike).
  int state_term_ = -1, control_term_ = -1;
  // cop, swing_rot: -1 for point contacts (and for swing_rot without its weight)
  std::vector<int> cone_term_, swing_term_, cop_term_, swing_rot_term_;
  double swing_ = 0.0, swing_xy_ = 0.0;  // the swing weights: vertical (and placed), horizontal
  Eigen::VectorXd x_ref_;                // scratch for the state references
  std::vector<KnotSegment> segments_;    // the grid (one segment without options.grid)
  std::vector<double> base_weight_;      // per term: the weight of a knot of duration dt
  double span_ = 0.0;
  double t0_ = 0.0;
  std::vector<double> knot_time_;  // T + 1
};

}  // namespace stride
