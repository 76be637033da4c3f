#pragma once
// The paper's astronaut reorientation (§V-B, Fig. 5-6): the humanoid floats with no gravity and no
// contacts, only the sagittal hip and knee joints move, and KKT-DDP from zero torques must find a
// joint motion that turns the base 360° about the sagittal (y) axis. With no external force the
// angular momentum stays zero (it starts at rest), a non-holonomic constraint (paper eq. 5): the
// rotation can only come from cycles of the legs' shape (falling cat), which no time-invariant
// feedback law can produce (Brockett), so the horizon must plan them.
//
// A final orientation cost alone cannot tell 0° from 360° (the start already satisfies it), so
// the goal is a sequence of orientation waypoints Ry(θ_i), θ_i = i·360°/n at t = i·T/n, the last
// one the terminal cost. A running posture cost regularizes, and quadratic barriers keep the
// joints inside (a margin of) their limits, standing in for self-collision avoidance as in the
// paper.

#include <memory>
#include <string>
#include <vector>

#include "solver/ddp/solver.hpp"
#include "solver/ocp/problem.hpp"
#include "tools/paper/locked_model.hpp"

namespace stride {

struct AstronautOptions {
  double dt = 0.02;
  int knots = 4500;              // T running knots: 90 s (a leg cycle turns the base ~10°: README)
  double turn_deg = 360.0;       // total rotation about +y
  int waypoints = 36;            // orientation goals at t = i·T/n, i = 1..n (the n-th is terminal)
  int waypoint_width = 1;        // knots on each side of a waypoint where its goal is also on
  double w_orientation = 100.0;  // per waypoint knot
  double w_posture = 1e-2;       // joint angles towards the default posture
  double w_joint_velocity = 1e-3;
  double w_control = 1e-4;
  double w_limits = 1e3;      // barrier on the joint position and velocity limits
  double limit_margin = 0.9;  // fraction of each joint's range allowed (limits.hpp activation)
  double w_terminal_velocity = 10.0;  // the motion ends at rest
  // The knots' semi-implicit Euler step does not conserve momentum: a one-knot velocity spike
  // creates spurious angular momentum (error ~ dt·v²), and DDP exploits it, "rotating" by
  // coasting on momentum that the true dynamics would not have (a replay at dt/10 turned a planned
  // +90° into -150°). The true motion keeps h_g = 0, so penalizing h_g at every knot keeps the plan
  // where the discretization is faithful; it changes nothing for the continuous-time dynamics.
  double w_momentum = 100.0;
  std::vector<std::string> free_joints = {"L_hip_pitch", "L_knee", "R_hip_pitch", "R_knee"};
  std::string base_frame = "base_link";
};

// The locked robot, the problem on it and its start (rest, default posture, base at the origin).
// Not movable: the knots keep references to the model.
class AstronautProblem {
 public:
  AstronautProblem(const Robot& robot, const AstronautOptions& options);
  AstronautProblem(const AstronautProblem&) = delete;
  AstronautProblem& operator=(const AstronautProblem&) = delete;

  const Model& model() const { return locked_.model; }
  const LockedRobot& locked() const { return locked_; }
  ShootingProblem& problem() { return *problem_; }
  const Eigen::VectorXd& x0() const { return x0_; }
  const AstronautOptions& options() const { return options_; }
  // Knot index and goal angle (rad) of each orientation waypoint (the last: T, terminal).
  const std::vector<std::pair<int, double>>& waypoints() const { return waypoints_; }

 private:
  AstronautOptions options_;
  LockedRobot locked_;
  Eigen::VectorXd x0_;
  std::unique_ptr<ShootingProblem> problem_;
  std::vector<std::pair<int, double>> waypoints_;
};

// What the experiment reports, per knot (T + 1 entries) and overall.
struct AstronautMotion {
  std::vector<double> t;
  std::vector<double> pitch;       // accumulated (unwrapped) base rotation about world y, rad
  std::vector<double> off_axis;    // |rotation about world x and z| accumulated, rad
  std::vector<Eigen::Vector3d> h;  // whole-body angular momentum about the CoM, world axes
  // Angular momentum of each leg (the bodies its hip_pitch moves) about the whole-body CoM.
  std::vector<Eigen::Vector3d> h_left, h_right;
  std::vector<Eigen::Vector3d> com;
  double max_h = 0.0, max_h_leg = 0.0, max_com_drift = 0.0;
};

// Unwrapped pitch: the base rotation increments of successive states, log3(R_{k+1} R_kᵀ) in world
// axes, summed (never atan2 of a final orientation, which cannot tell 0° from 360°).
AstronautMotion analyzeMotion(const Model& model, const std::vector<Eigen::VectorXd>& xs, double dt,
                              const std::string& base_frame = "base_link");

// The plan checked against a finer integrator, knot by knot: each knot's torque applied from the
// planned state xs[k] over dt in `substeps` semi-implicit Euler steps. An open-loop replay of the
// whole horizon is not a fair check over tens of seconds (the free-floating chain is unstable
// without feedback, and any integrator difference grows); the knot-wise one measures what the
// discretization adds per knot: the pitch it would accumulate and the momentum it creates.
struct FineCheck {
  double pitch = 0.0;        // Σ pitch increments of the fine steps, rad
  double max_dh_plan = 0.0;  // max over knots of |h(xs[k+1]) - h(xs[k])| (the knots' dynamics)
  double max_dh_fine = 0.0;  // max over knots of |h(fine step from xs[k]) - h(xs[k])|
};
FineCheck checkWithFinerSteps(const Model& model, const std::vector<Eigen::VectorXd>& xs,
                              const std::vector<Eigen::VectorXd>& us, double dt, int substeps,
                              const std::string& base_frame = "base_link");

}  // namespace stride
