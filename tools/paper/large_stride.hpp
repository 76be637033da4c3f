#pragma once
// The paper's large-stride experiment (§V-A, Fig. 2-4): a walk of large strides on flat ground,
// planned from the same contact sequence and centroidal reference (centroidal_planner.hpp) by
//   - the IK baseline (ik.hpp): instant-by-instant whole-body IK, forces and torques by contact
//     inverse dynamics;
//   - KKT-DDP (this file): box-FDDP over rigid contact knots (impulse knots at touch-downs)
//     with the paper's costs, warm-started from the IK trajectory;
// then compared on the same measures (peak normal force per foot, peak knee torque, torque cost)
// and the DDP motion played on the mock robot (stride-sim's node, lock-step: stride_playback.hpp).
//
// DDP costs per contact knot (weights in StrideDdpOptions):
//   "com"      w_com |com - c_ref|²                        CoM tracking
//   "foot_<c>" w_foot |log6(M_c,ref⁻¹ M_c)|²               foot placement (swing arc; footholds)
//   "force_<c>" w_force |λ_c - λ_c,ref|²                   contact force tracking, closed feet
//   "torque"   w_torque |τ|²                               torque minimization
//   "posture"  Σ w (x ⊖ x_ref)²: base orientation upright, joints to the nominal posture
//              (w_posture), all velocities to zero (w_velocity)
//   "cone_<c>", "cop_<c>": friction pyramid and centre of pressure in the sole (bounds, so the
//              motion is one a real foot can make; both are zero for the IK warm start's forces
//              when they are feasible)
// and the torque limits as the box of box-FDDP. Impulse knots carry posture, torque (u has no
// effect there) and feet; the terminal knot the posture (at rest) and the CoM.

#include <array>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "config/robot_config.hpp"
#include "solver/ddp/solver.hpp"
#include "solver/ocp/knot.hpp"
#include "solver/ocp/problem.hpp"
#include "tools/paper/centroidal_planner.hpp"
#include "tools/paper/ik.hpp"

namespace stride {

struct StrideDdpOptions {
  double w_com = 1e4;
  double w_foot = 1e5;
  double w_force = 1e-3;
  double w_torque = 1e-4;
  double w_posture = 1e-1;
  double w_base_orientation = 10.0;
  double w_velocity = 1e-2;
  double w_cone = 1e2, w_cop = 1e2;
  double w_terminal = 10.0;  // the terminal posture weights are the running ones times this
  double mu = 0.7;
  double sole_margin = 0.8;  // the centre of pressure stays in this fraction of the sole
  // Baumgarte gains of the rigid contacts. kd ≤ 0: 1 / dt, which stops a contact velocity in one
  // knot (semi-implicit Euler: v⁺ = (1 - kd dt) v; the 50 /s of 20 ms knots flips its sign every
  // 40 ms knot). kp pulls a sole back to its planned, flat placement: a foot that lands a little
  // tilted on its heel is flattened rather than held tilted (on the mock robot's four corners a
  // tilted sole has its centre of pressure at the edge and tips).
  double contact_kd = 0.0;
  double contact_kp = 200.0;  // with kd = 25 (40 ms knots): damping ratio kd / (2 √kp) ≈ 0.9
  bool torque_limits = true;
  // The contact knots' integrator (knot.hpp; impulse knots are instantaneous under both).
  Integrator integrator = Integrator::Euler;
};

// The cost groups of the breakdown (Fig. 2), in this order.
const std::vector<std::string>& strideCostGroups();

class StrideProblem {
 public:
  // The whole plan: knots for samples 0..N-1, the terminal knot at sample N (posture at rest, the
  // regularization pulls to robot.default_q).
  StrideProblem(const Robot& robot, const StridePlan& plan, const StrideDdpOptions& options);
  // A window of the plan (the playback's stop after the walk, from first = N, and its TVLQR, from
  // first = 0 past N): `knots` contact knots for samples first, first + 1, ... (past N they
  // repeat the final standing sample N), plus the impulse knots of the touch-downs inside the
  // window (not one at `first`: the window starts from a given state there); the
  // terminal knot tracks x_terminal (posture weights × w_terminal, the CoM of its sample).
  // With x_refs (one per knot, impulse knots included, as sampleOfKnot orders them), the
  // "posture" term tracks those states instead of the nominal posture at rest.
  StrideProblem(const Robot& robot, const StridePlan& plan, const StrideDdpOptions& options,
                int first, int knots, const Eigen::VectorXd& x_terminal,
                const std::vector<Eigen::VectorXd>* x_refs = nullptr);
  // The knots of a window: (sample, impulse) in order, without building it.
  static std::vector<std::pair<int, bool>> windowKnots(const StridePlan& plan, int first,
                                                       int knots);
  StrideProblem(const StrideProblem&) = delete;
  StrideProblem& operator=(const StrideProblem&) = delete;

  ShootingProblem& problem() { return *problem_; }
  const StridePlan& plan() const { return plan_; }
  const Model& model() const { return robot_.model; }
  // The plan sample a knot stands for; impulse knots share the sample of the contact knot after
  // them. contactKnot(k): the contact knot of sample k (k < N; for a window, of its k-th contact
  // knot, sample first + k).
  int sampleOfKnot(int knot) const { return sample_[knot]; }
  bool isImpulse(int knot) const { return impulse_[knot] != 0; }
  int contactKnot(int sample) const { return contact_knot_[sample]; }
  int contactKnots() const { return static_cast<int>(contact_knot_.size()); }
  const StrideDdpOptions& options() const { return options_; }
  const Eigen::VectorXd& controlLower() const { return u_lower_; }
  const Eigen::VectorXd& controlUpper() const { return u_upper_; }

  // The warm start from an IK trajectory (its x0 becomes the problem's x0).
  void warmStart(const IkTrajectory& ik, std::vector<Eigen::VectorXd>& xs,
                 std::vector<Eigen::VectorXd>& us);
  // The cost of each group (strideCostGroups) at (xs, us): the problem evaluated with only that
  // group's terms on. Leaves the problem's data at the full cost of (xs, us).
  std::vector<double> costBreakdown(const std::vector<Eigen::VectorXd>& xs,
                                    const std::vector<Eigen::VectorXd>& us);
  // The contact forces of every sample k < N at (xs, us) ([f; τ], world axes, per foot).
  std::vector<std::array<Vector6d, 2>> forces(const std::vector<Eigen::VectorXd>& xs,
                                              const std::vector<Eigen::VectorXd>& us);

 private:
  void build(int first, int knots, const Eigen::VectorXd* x_terminal,
             const std::vector<Eigen::VectorXd>* x_refs);
  void setGroup(int group);  // -1: every term as built

  const Robot& robot_;
  StridePlan plan_;
  StrideDdpOptions options_;
  std::unique_ptr<ShootingProblem> problem_;
  std::vector<int> sample_, contact_knot_;
  std::vector<char> impulse_;
  // Per knot (the terminal last): each term's group and its activity as built.
  std::vector<std::vector<int>> term_group_;
  std::vector<std::vector<char>> term_active_;
  Eigen::VectorXd u_lower_, u_upper_;
};

// The measures of one motion over samples k < N.
struct StrideMetrics {
  std::array<double, 2> peak_normal_force{0.0, 0.0};  // per foot [N]
  double peak_normal_force_N = 0.0;                   // max of both
  double peak_knee_torque_Nm = 0.0;                   // |τ| of either knee
  double torque_cost = 0.0;                           // Σ dt |τ|² [N² m² s]
  double peak_total_normal_force_N = 0.0;
};
StrideMetrics strideMetrics(const Model& model, const StridePlan& plan,
                            const std::vector<Eigen::VectorXd>& tau,
                            const std::vector<std::array<Vector6d, 2>>& force);

// The DDP solve, iteration by iteration, with the cost breakdown after each.
struct StrideSolve {
  std::vector<Eigen::VectorXd> xs, us;
  std::vector<Eigen::MatrixXd> K;
  std::vector<std::vector<double>> breakdown;  // [iteration 0 = warm start, 1..]
  std::vector<double> cost, gap;
  int iterations = 0;
  double solve_time_s = 0.0;
  std::string status;
};
StrideSolve solveStrides(StrideProblem& sp, const IkTrajectory& ik, int iterations,
                         bool verbose = false);

}  // namespace stride
