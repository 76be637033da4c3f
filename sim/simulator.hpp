#pragma once
// The mock robot's physics: rigid multibody dynamics with unilateral ground contact and Coulomb
// friction, integrated by a velocity-level time-stepping scheme (Stewart-Trinkle / Anitescu):
//
//   M (v⁺ − v) = h (S τ − b(q, v) + J_extᵀ f_ext) + J_cᵀ p,    q⁺ = q ⊕ h v⁺,
//
// with, for each candidate constraint (a point's support on the terrain, or a vertical face beside
// it: terrain/terrain.hpp), the impulse p = (p_t1, p_t2, p_n) in the constraint's frame (the flat
// ground's: world axes, normal +z):
//   0 ≤ p_n  ⟂  v_n⁺ − v_target ≥ 0      (no penetration at the end of the step; v_target carries
//                                          the distance still to close and the drift correction)
//   |p_t| ≤ μ p_n, p_t opposing the sliding velocity (maximal dissipation, circular cone).
// Solved by projected Gauss-Seidel on the Delassus matrix G = J M⁻¹ Jᵀ. Touch-downs are plastic.
// Details and the reasons: sim/README.md.
//
// Real time: the Model is copied in and a workspace sized for every candidate point at once is
// built at construction; step() allocates nothing and never throws.

#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "config/robot_config.hpp"
#include "sim/ground_contact.hpp"
#include "solver/multibody/data.hpp"

namespace stride::sim {

struct SimOptions {
  double dt = 1e-3;  // one step(); a step runs `substeps` substeps of dt / substeps
  int substeps = 1;
  double ground_height = 0.0;  // the flat ground's height, when no terrain is given
  // The world (terrain/terrain.hpp); null: the flat ground at ground_height.
  std::shared_ptr<const terrain::Terrain> terrain;
  double friction = 0.8;         // Coulomb coefficient μ
  bool clamp_torques = true;     // clamp τ to the model's effort limits
  double contact_margin = 1e-3;  // a point is a candidate below this height (plus its fall in h)
  // Penetration correction: a point deeper than `penetration_slop` is pushed out at
  // `penetration_gain` × (depth − slop) / h, capped at `max_correction_velocity` (m/s).
  double penetration_gain = 0.1;
  double penetration_slop = 1e-4;
  double max_correction_velocity = 0.2;
  // Projected Gauss-Seidel: stop when no impulse moved by more than `pgs_tolerance` times the
  // largest impulse over one sweep, or after `pgs_max_iterations` sweeps.
  int pgs_max_iterations = 100;
  double pgs_tolerance = 1e-7;
  // Added to each diagonal entry of G relative to its 3 x 3 block's mean diagonal: keeps redundant
  // points (a sole's 4 corners) well posed; a compliance of ~1e-8 of the point's mobility.
  double regularization = 1e-8;
  // A step whose velocity exceeds this anywhere (rad/s, m/s) has left physics: it is held and
  // reported as a non-finite state (the run diverged).
  double max_velocity = 1e3;
  // Footholds (SimCounters::footholds): a touch-down is an edge foothold when its contact point is
  // closer than `edge_distance` horizontally to a line where the terrain's height jumps by more
  // than `edge_rise`, looked for within `edge_search_radius` (terrain::Terrain::edgeDistance; the
  // steppability of terrain/README.md asks the same 2 cm of a map). A touch-down is one after a
  // swing: the point rose more than `foothold_lift` above its support since it last loaded it (a
  // foot bouncing or rocking in place, up to ~1 cm on the light PD legs, is not a new foothold).
  double foothold_lift = 0.02;
  double edge_rise = 0.02;
  double edge_distance = 0.02;
  double edge_search_radius = 0.05;
  // A sole down is flat when every corner is this close to the terrain under it
  // (SimCounters::sole_flat_steps).
  double sole_flat_tolerance = 0.005;
};

enum class StepStatus : std::uint8_t {
  Ok,
  RejectedTorque,  // non-finite τ: zero torque was applied instead
  NonFiniteState,  // the step produced a non-finite state or a velocity past max_velocity: q kept,
                   // v set to zero
  SingularMassMatrix,  // M not positive definite (non-finite q?): the state was not advanced
};
const char* toString(StepStatus status);

struct SimCounters {
  std::int64_t steps = 0;
  std::int64_t rejected_torques = 0;  // steps whose τ was not finite
  std::int64_t clamped_steps = 0;     // steps where at least one torque was clamped
  std::int64_t nonfinite_states = 0;  // substeps whose result was not finite (state held)
  std::int64_t pgs_unconverged = 0;   // substeps where PGS hit pgs_max_iterations
  int last_pgs_iterations = 0;        // sweeps of the last substep with contacts
  // Times a contact point started pushing on a vertical face of the terrain (a riser, a box's
  // side): a foot that hit an obstacle instead of stepping onto it.
  std::int64_t trips = 0;
  // Touch-downs: a contact point that starts carrying a normal impulse on its support after a swing
  // (it rose more than SimOptions::foothold_lift above the terrain since it last loaded it), each
  // sole corner on its own; the points standing on the terrain at a reset count too. Measured on
  // the true terrain at the point's place on its support.
  std::int64_t footholds = 0;
  // Touch-downs closer than SimOptions::edge_distance (horizontally) to an edge of the terrain: a
  // height step of more than edge_rise, at the top of a drop or at the foot of a wall.
  std::int64_t edge_footholds = 0;
  // The smallest distance of a touch-down to an edge [m]; +infinity while no touch-down had one
  // within SimOptions::edge_search_radius (always on flat ground).
  double min_edge_distance = std::numeric_limits<double>::infinity();
  // Soles (contacts of several points: a dim-6 sole's corners) on the ground, per substep:
  // loading their support with at least one corner, and of those flat on it (every corner within
  // SimOptions::sole_flat_tolerance of the terrain under it). A 20 cm sole set down level on a
  // 10° ramp has one end 3.5 cm above it.
  std::int64_t sole_steps = 0;
  std::int64_t sole_flat_steps = 0;
};

// The footholds in words, for the summaries of stride-sim and stride-drive: "412 footholds
// (touch-downs), 3 closer than 2 cm to an edge of more than 2 cm, nearest 0.012 m" (or "no edge
// within 5 cm of any").
std::string footholdText(const SimCounters& counters, const SimOptions& options);
// sole_flat_steps / sole_steps; NaN without a sole on the ground (point feet).
double soleFlatFraction(const SimCounters& counters);

// What one candidate point did in the last step.
struct PointContact {
  bool candidate = false;   // within the detection margin at the last substep
  bool in_contact = false;  // carried a positive normal impulse at the last substep
  // Signed height above the ground (< 0: inside) where the last substep detected contacts, i.e. at
  // its start: the geometry of the state before the step, not recomputed after it.
  double height = 0.0;
  Eigen::Vector3d force = Eigen::Vector3d::Zero();  // world force on the robot, mean over the step
};

class Simulator {
 public:
  // `points`: the candidate contact points (contactPointsFromRobot). Throws std::invalid_argument
  // for bad options or points.
  Simulator(const Model& model, std::vector<ContactPoint> points, const SimOptions& options = {});
  // The robot's own contact points; starts at rest in robot.default_q. (The other constructor
  // starts at rest in the neutral configuration: call reset.)
  explicit Simulator(const Robot& robot, const SimOptions& options = {});

  // Sets the state and time, clears external wrenches and the warm start. Throws
  // std::invalid_argument for wrong sizes or non-finite values; normalizes the quaternion.
  void reset(const Eigen::Ref<const Eigen::VectorXd>& q, const Eigen::Ref<const Eigen::VectorXd>& v,
             double time = 0.0);
  // Advances one dt with the actuated torques τ (size nu), clamped to the effort limits if enabled.
  // Non-finite τ is replaced by zero (StepStatus::RejectedTorque, counted). Never throws for a
  // correctly sized τ; allocates nothing.
  StepStatus step(const Eigen::Ref<const Eigen::VectorXd>& tau);

  // A wrench [force; moment about the base origin] in world axes, acting on the base until the
  // simulated time reaches `until_time` (replaces any previous one). Floating-base robots only.
  void applyExternalWrench(const Vector6d& wrench_world_on_base, double until_time);
  void clearExternalWrench() { wrench_until_ = -1.0; }

  const Eigen::VectorXd& q() const { return q_; }
  const Eigen::VectorXd& v() const { return v_; }
  double time() const { return time_; }
  const Model& model() const { return model_; }
  const SimOptions& options() const { return options_; }
  const terrain::Terrain& terrain() const { return terrain_; }
  int nu() const { return nu_; }
  // The torque applied during the last step (after rejection and clamping).
  const Eigen::VectorXd& appliedTorque() const { return tau_applied_; }

  const std::vector<ContactPoint>& contactPoints() const { return points_; }
  const std::vector<PointContact>& pointContacts() const { return contacts_; }
  // 3 x points: the world force on the robot at each point, mean over the last step.
  const Eigen::Matrix3Xd& contactForces() const { return forces_; }
  // The sum of the normal forces of one robot contact (ContactPoint::contact), last step.
  double normalForce(int contact) const;
  double totalNormalForce() const { return forces_.row(2).sum(); }

  const SimCounters& counters() const { return counters_; }
  StepStatus lastStatus() const { return last_status_; }
  // Kinetic energy ½ vᵀ M v at the current state (recomputes M: a diagnostic, not for the tick).
  double kineticEnergy();

 private:
  // One substep of length h; returns false when the state could not be advanced.
  StepStatus substep(double h);
  int solveContacts(double h, int active);  // PGS over the first `active` compacted points

  Model model_;
  SimOptions options_;
  std::vector<ContactPoint> points_;
  terrain::Terrain terrain_;
  Data data_;
  int nu_ = 0;
  int tau_first_ = 0;  // first actuated velocity index (6 for a free-flyer)

  Eigen::VectorXd q_, v_;
  double time_ = 0.0;
  Vector6d wrench_ = Vector6d::Zero();
  double wrench_until_ = -1.0;

  // Per-step workspaces, sized at construction (P = number of candidate points).
  Eigen::VectorXd tau_applied_;  // nu
  Eigen::VectorXd rhs_;          // nv: generalized force, then acceleration
  Eigen::VectorXd v_free_;       // nv: velocity without contact impulses
  Eigen::VectorXd q_prev_;       // nq: kept to hold the state on a non-finite result
  ContactGeometry geometry_;
  // S = kConstraintsPerPoint * P constraint slots (ground_contact.hpp).
  std::vector<int> active_;  // the candidate slots of this substep
  Eigen::MatrixXd Jc_;       // 3S x nv: rows of the active slots, compacted
  RowMatrixXd MinvJt_;       // nv x 3S: M⁻¹ Jcᵀ (row-major: the LᵀDL solve runs on rows)
  Eigen::MatrixXd G_;        // 3S x 3S Delassus matrix
  Eigen::VectorXd c_;        // 3S: contact velocity without impulses minus its target
  Eigen::VectorXd p_;        // 3S: impulses of the active slots, each in its frame [t1 t2 n]
  Eigen::Matrix3Xd warm_;    // 3 x S: last impulse of each slot (warm start)
  Eigen::Matrix3Xd impulse_sum_;  // 3 x P: impulses summed over the substeps of this step
  Eigen::Matrix3Xd forces_;       // 3 x P
  std::vector<PointContact> contacts_;
  std::vector<char> on_wall_, touching_wall_;   // per point: pushing on a face (trips)
  std::vector<char> swung_, touching_support_;  // per point: swung, loading its support
  std::vector<std::pair<int, int>> soles_;      // first point and count of each sole

  SimCounters counters_;
  StepStatus last_status_ = StepStatus::Ok;
};

}  // namespace stride::sim
