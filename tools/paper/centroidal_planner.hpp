#pragma once
// The inputs of the paper's large-stride experiment (§V-A): a contact sequence and a centroidal
// reference, from a simple planner of our own (the paper took them from a contact planner and a
// centroidal optimal-control solver).
//
// Stride: the displacement of one foot in one step (the usual "stride" of gait analysis, one
// foot's travel per gait cycle). At double support the feet are then stride / 2 apart. The walk
// starts and ends standing with the feet side by side: a half step of the right foot, `strides`
// full strides alternating left / right, and a half step that brings the trailing foot beside the
// other one.
//
// Timing: rest (double support) t_rest, then per step a single support t_single and a double
// support t_double (the last one t_rest).
//
// Feet: each sole flat (orientation: identity); a swing from a to b at phase s ∈ [0, 1] follows
//   x(s) = a + (b - a)(s - sin(2π s) / (2π)),   z(s) = h (1 - cos 2π s) / 2
// (zero velocity and zero horizontal acceleration at lift-off and touch-down).
//
// CoM: at a constant height (low enough for the legs to reach both feet at double support:
// com_drop), horizontally the cart-table (linear inverted pendulum) motion whose ZMP
//   p = c - (z_c / g) c̈
// follows a reference in the support polygons: under the stance foot in single support (rolling
// forward by zmp_travel), a
// smooth ramp from one foot to the next in double support. Found per axis by least squares over
// the samples: Σ (p_k - p_ref,k)² + w_jerk Σ (dt³ c⃛)², starting and ending at rest.
//
// Forces: the total contact force m (c̈ + g) (wrench about each sole: zero torque), all on the
// stance foot in single support; in double support split between the feet by where the ZMP lies
// on the segment between them (so the per-foot centres of pressure reproduce the ZMP).

#include <array>
#include <vector>

#include "locomotion/contact_plan.hpp"
#include "solver/multibody/model.hpp"

namespace stride {

struct StridePlanOptions {
  double stride = 1.0;  // foot displacement per step [m]
  int strides = 3;      // full strides (plus a half step at each end)
  double t_rest = 0.6, t_single = 0.9, t_double = 0.3;
  double dt = 0.02;            // sample period (the DDP knot period)
  double swing_height = 0.10;  // [m]
  // Fraction of the hip-to-ankle length (straight knee) the legs use at double support: sets the
  // CoM height. Below 1 so that the knee stays bent (IK and DDP keep their Jacobians regular).
  double leg_reach = 0.93;
  // In single support the ZMP reference rolls from heel to toe of the stance sole over this
  // length (centred on the sole), as in human and humanoid walking.
  double zmp_travel = 0.10;
  double w_jerk = 1e-6;  // [s⁶]: a jerk of 10 m/s³ weighs like a ZMP error of 1 cm
};

// The plan, sampled at t_k = k dt, k = 0..N. Contact index 0 = left sole, 1 = right sole (the
// robot YAML's order: the names are in `feet`).
struct StridePlan {
  StridePlanOptions options;
  std::array<std::string, 2> feet;
  ContactPlan contact_plan;  // the phases (for the record and the schedule)
  double mass = 0.0, com_height = 0.0, com_drop = 0.0, leg_length = 0.0;
  int N = 0;
  std::vector<double> t;                             // N + 1
  std::vector<std::array<bool, 2>> closed;           // per sample
  std::vector<char> touchdown;                       // a foot closes at sample k (k ≥ 1)
  std::vector<std::array<Eigen::Vector3d, 2>> foot;  // sole positions (flat soles)
  std::vector<Eigen::Vector3d> com, com_acc, zmp, zmp_ref;
  std::vector<std::array<Vector6d, 2>> force;  // [f; τ] world axes at each sole
};

// The plan for a robot standing in q_stand (both soles flat on the ground). Throws
// std::invalid_argument for a stride the legs cannot reach (the CoM would have to go below half
// its standing height) or bad options.
StridePlan planStrides(const Model& model, const Eigen::VectorXd& q_stand,
                       const std::array<std::string, 2>& feet, const StridePlanOptions& options);

}  // namespace stride
