#pragma once
// The locomotion problem: a contact plan turned into a shooting problem of contact / impulse knots
// that all carry the same cost terms, re-configured in place for any start time of the plan.
//
// Every running knot has
//   "state"        ½ Σ w_i (x ⊖ x_ref)_i²: x_ref = x_nominal, its base moved by the mean
//                  planned displacement of the feet (so the body follows the footholds);
//   "control"      ½ w |u - u_ref|²: u_ref = the torques that hold x_nominal still on the
//                  phase's closed contacts (minimum-norm forces), so standing costs nothing;
//   "cone_<c>"     friction cone of contact c, on while c is closed;
//   "cop_<c>"      centre of pressure of surface contact c inside its sole (options.
//                  sole_half_extents), on while c is closed;
//   "com"          the centre of mass on its nominal position moved like the base (options.
//                  weights.com > 0);
//   "swing_<c>"    position of foot c on its swing arc, on while c is open and at its touch-down
//                  knot (reference: the new foothold, so the foot lands where planned).
// The terminal knot has "state" only. A touch-down inserts an impulse knot (options.impulses) with
// the contacts closed after it; it takes no time, so knot k stands for time t0 + dt · (contact
// knots before k), knotTime(k).
//
// Footholds: foot c starts at its position in x_nominal and moves by options.step at each of its
// touch-downs, counted from the plan's start; a swing from foothold n to n + 1 follows
//   p(s) = p_n + ½ (1 - cos π s) (p_{n+1} - p_n) + h sin(π s) e_z,
//   s = (t - lift-off) / (touch-down - lift-off)
// (no horizontal speed at either end, so a landing needs no tangential impulse).

#include <algorithm>
#include <vector>

#include "solver/ocp/contact_plan.hpp"
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
  double swing = 1e4;            // per axis, on the foot position error [m]
  double friction = 1e2;         // on the cone rows' violation [N]
  double cop = 1e2;              // on the centre-of-pressure rows' violation [N m] (6D contacts)
  double com = 0.0;              // per axis, on the CoM position error [m] (0: no such term)
  double terminal_state = 10.0;  // the terminal state weights are the running ones times this
};

struct LocomotionOptions {
  double dt = 0.01;
  int knots = 100;  // running knots; a terminal knot follows
  double mu = 0.7;  // friction coefficient (flat ground, normal +z)
  double min_normal_force = 0.0;
  double swing_height = 0.05;
  Eigen::Vector3d step = Eigen::Vector3d::Zero();  // displacement of a foot per step (world)
  // Touch-downs up to this plan time land where the foot lifted off (stepping in place); later
  // ones move the foot by `step`. So one plan can stand, trot in place, then walk.
  double step_after = 0.0;
  // A footstep list instead of a constant step: the displacements of the successive touch-downs
  // after step_after, in the plan's order (touch-downs at one instant in contact order); later
  // touch-downs land in place. Empty: `step` for every touch-down.
  std::vector<Eigen::Vector3d> footsteps;
  LocomotionWeights weights;
  bool impulses = true;  // impulse knots at touch-downs (else contact knots throughout)
  // Surface (6D) contacts: the centre of pressure stays in this rectangle around the contact
  // frame (half extents along its x and y; zero: no such term). Use the sole's, shrunk by a margin.
  Eigen::Vector2d sole_half_extents = Eigen::Vector2d::Zero();
  bool torque_limits = false;  // controlLower/Upper from the model's effort limits (else ±inf)
};

class LocomotionProblem {
 public:
  // contacts: every foot the plan names (forces are expected LOCAL_WORLD_ALIGNED, for which the
  // flat-ground cone needs no rotation; LOCAL forces get the cone in the foot's axes). Throws
  // std::invalid_argument for a bad plan (ContactPlan::validate), an x_nominal of the wrong size,
  // or options out of range (dt ≤ 0, knots < 1, μ ≤ 0, weights of the wrong size).
  LocomotionProblem(const Model& model, const ContactSet& contacts, const ContactPlan& plan,
                    const Eigen::VectorXd& x_nominal, const LocomotionOptions& options = {});

  ShootingProblem& problem() { return *problem_; }
  const ShootingProblem& problem() const { return *problem_; }
  const ContactSchedule& schedule() const { return schedule_; }
  const ContactSet& contacts() const { return contacts_; }
  const LocomotionOptions& options() const { return options_; }
  const Eigen::VectorXd& nominal() const { return x_nominal_; }
  double startTime() const { return t0_; }

  // Re-configures every knot in place for the plan from time t0: contacts, knot modes, which cost
  // terms are on, swing and state references. No allocation (the controller's tick calls it after
  // ShootingProblem::shift). False (nothing changed) for a non-finite or absurd t0.
  bool update(double t0);
  // The time knot k stands for after the last update (k = horizon(): the terminal knot).
  double knotTime(int k) const { return knot_time_[k]; }

  // Foot c's target at time t: its foothold while closed, its swing arc while open.
  Eigen::Vector3d footReference(int contact, double t) const;
  // Foot c's foothold after n touch-downs (those up to options.step_after do not move it).
  Eigen::Vector3d foothold(int contact, long n) const;
  // The gravity-compensating control of x_nominal in (local) phase i of the plan.
  const Eigen::VectorXd& holdingControl(int phase) const { return u_hold_[phase]; }
  // A standing warm start: x_nominal everywhere, each knot's holding control (after update).
  void standingWarmStart(std::vector<Eigen::VectorXd>& xs, std::vector<Eigen::VectorXd>& us) const;
  // Control bounds for the box solver (size nu; ±infinity unless options.torque_limits).
  const Eigen::VectorXd& controlLower() const { return u_lower_; }
  const Eigen::VectorXd& controlUpper() const { return u_upper_; }

 private:
  void setStateReference(Eigen::VectorXd& x_ref, double t) const;

  const Model& model_;
  ContactSet contacts_;
  ContactSchedule schedule_;
  Eigen::VectorXd x_nominal_;
  LocomotionOptions options_;
  std::unique_ptr<ShootingProblem> problem_;
  std::vector<Eigen::Vector3d> initial_feet_;
  std::vector<long> fixed_steps_;  // per contact: touch-downs up to options.step_after
  // With a footstep list: foot c's displacement after n touch-downs, n = 0.. (held past the end).
  std::vector<std::vector<Eigen::Vector3d>> foot_offsets_;
  int com_term_ = -1;
  Eigen::Vector3d com_nominal_ = Eigen::Vector3d::Zero();
  // The base's (and CoM's) displacement at time t: the feet's mean planned progress.
  Eigen::Vector3d bodyDisplacement(double t) const;
  std::vector<Eigen::VectorXd> u_hold_;  // per local phase
  Eigen::VectorXd u_lower_, u_upper_;
  // Term indices, the same in every running knot (all are built alike).
  int state_term_ = -1, control_term_ = -1;
  std::vector<int> cone_term_, swing_term_, cop_term_;  // cop: -1 for point contacts
  Eigen::VectorXd x_ref_;                               // scratch for the state references
  double t0_ = 0.0;
  std::vector<double> knot_time_;  // T + 1
};

}  // namespace stride
