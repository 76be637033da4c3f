#pragma once
// The IK baseline of the large-stride experiment: a whole-body inverse-kinematics tracker that
// follows the plan's CoM and foot references instant by instant (no preview), and the ground
// reaction forces and joint torques its motion needs under the same rigid contacts.
//
// Kinematics: at each sample k, Gauss-Newton iterations from q_{k-1} on the stacked tasks
//   w_com |com(q) - c_k|² + w_foot Σ_c |log6(M_c(q)⁻¹ M_c,k)|² + w_base |log3(R_base(q)ᵀ)|²
//   + w_base |log3(R_chest(q)ᵀ)|² (base and torso upright)
//   + w_posture |q_joints - q_nominal|²,
// each step the damped least-squares solution (Σ wᵢ Jᵢᵀ Jᵢ + λ I) dq = Σ wᵢ Jᵢᵀ eᵢ, then the
// joint limits by projection.
// Velocities and accelerations by finite differences, matching the knots' semi-implicit Euler:
//   v_0 = 0, v_k = (q_k ⊖ q_{k-1}) / dt, a_k = (v_{k+1} - v_k) / dt.
// Dynamics: τ_full = M a + b (rnea). The contact wrenches [f; τ] (world axes, at each closed
// sole, as the DDP knots report them) satisfy the floating-base rows Jc,baseᵀ λ = τ_full,base; λ
// is their damped least-norm solution λ = A ᵀ (A Aᵀ + ε I)⁻¹ τ_full,base, A = Jc,baseᵀ (unique in
// single support, the least-norm split in double support: the paper's "damped Cholesky" for the
// rank-deficient Jc). The joint torques are then the actuated rows τ = τ_full,act - Jc,actᵀ λ.

#include <array>
#include <string>
#include <vector>

#include "solver/multibody/model.hpp"
#include "tools/paper/centroidal_planner.hpp"

namespace stride {

struct IkOptions {
  double w_com = 1e3, w_foot = 1e4, w_base = 10.0, w_posture = 1e-2;
  double damping = 1e-6;        // λ of the least-squares step
  int iterations = 30;          // Gauss-Newton iterations per sample (stops earlier when converged)
  double tolerance = 1e-10;     // on |dq|
  double force_damping = 1e-9;  // ε of the least-norm forces (relative to the trace of A Aᵀ)
};

struct IkTrajectory {
  std::vector<Eigen::VectorXd> q, v, a;              // N + 1 each
  std::vector<Eigen::VectorXd> tau;                  // N + 1 joint torques (size nu)
  std::vector<std::array<Vector6d, 2>> force;        // per sample, per foot (zero when open)
  double max_com_error = 0.0, max_foot_error = 0.0;  // of the kinematics [m]
  // Largest residual of the floating-base equations (zero when the forces explain the motion).
  double max_base_residual = 0.0;
};

// q_nominal: the posture the regularization pulls to (its base part is ignored).
IkTrajectory trackIk(const Model& model, const StridePlan& plan, const Eigen::VectorXd& q_nominal,
                     const IkOptions& options = {});

// Inverse dynamics of a motion sample with the plan's contacts at sample k (the same computation
// as trackIk's): fills tau (nu) and the forces. Returns the base-row residual norm.
double contactInverseDynamics(const Model& model, const StridePlan& plan, int k,
                              const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                              const Eigen::VectorXd& a, double force_damping, Eigen::VectorXd& tau,
                              std::array<Vector6d, 2>& force);

}  // namespace stride
