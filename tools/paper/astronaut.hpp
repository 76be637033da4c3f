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
//
// The waypoints alone do not remove the ambiguity: log3 measures an orientation error the short
// way round, so once the motion lags a goal by more than 180° that goal pulls backwards (a single
// solve over the whole horizon turned to 114° and back to 0°). solveAstronaut therefore plans in
// receding windows over the waypoints: a window covers the next `window` waypoint segments from
// the state reached so far, asks for `window_step_deg` more per segment from the orientation
// reached (capped at the final goal), is solved with DDP (the first window from zero torques,
// each later one from the previous window's torques beyond what it committed and zero torques on
// its new segments), and its first `window_commit` segments are committed. No goal a window sees
// is more than window · window_step_deg (120°) ahead, so never on the wrong side of 180°, and a
// later window cannot undo the rotation already committed. The last window (reaching the end, at
// rest) is committed whole. The plan is one trajectory, the rollout of its torques from x0.

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "solver/ddp/solver.hpp"
#include "solver/ocp/knot.hpp"
#include "solver/ocp/problem.hpp"
#include "tools/paper/locked_model.hpp"

namespace stride {

struct AstronautOptions {
  double dt = 0.02;
  int knots = 8000;              // T running knots: 160 s (README: what limits the rotation)
  double turn_deg = 360.0;       // total rotation about +y
  int waypoints = 64;            // orientation goals at t = i·T/n, i = 1..n (the n-th is terminal)
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
  // The knots' integrator: Euler (the paper's), or Rk4, whose step conserves the momentum of the
  // free-floating body to O(dt⁴) per knot (knot_rk4.hpp) at four KKT solves per knot.
  Integrator integrator = Integrator::Euler;
  // Left/right mirror symmetry (MirrorResidual in astronaut.cpp): weights on q_L - q_R, on the
  // rates and on the torques of the `mirror` pairs. Off by default (all weights 0): with it the
  // motion is planar (no roll, no yaw) but turns about half as fast, and DDP does not find the
  // symmetric leg cycles from the hip-limit corner (README: "Why not planar").
  std::vector<std::pair<std::string, std::string>> mirror = {{"L_hip_pitch", "R_hip_pitch"},
                                                             {"L_knee", "R_knee"}};
  double w_mirror = 0.0;
  double w_mirror_velocity = 0.0;
  double w_mirror_control = 0.0;
  // Receding windows (solveAstronaut): segments per window (0 or >= waypoints, with
  // window_step_deg = 0: one solve of the full problem from zero torques, the previous scheme),
  // DDP iterations per window and on the last one.
  int window = 12;
  int window_commit = 4;          // segments kept from each window
  double window_step_deg = 10.0;  // a window's goals advance by this per segment (0: turn / n)
  int window_iterations = 150;
  int final_iterations = 200;
  SolverKind solver = SolverKind::Ddp;
  std::vector<std::string> free_joints = {"L_hip_pitch", "L_knee", "R_hip_pitch", "R_knee"};
  std::string base_frame = "base_link";
};

// The locked robot, the problem on it and its start. By default the full problem: from rest in
// the default posture, base at the origin (x0()), to the last waypoint, at rest. A window
// (first, last, start): the knots from waypoint `first` (0: the start) to waypoint `last`, from
// the state `start`, with waypoint `last` as the terminal cost (at rest only when it is the last
// one). `goals` (rad, one per waypoint first..last; 0 is the start) replaces the schedule.
// Not movable: the knots keep references to the model.
class AstronautProblem {
 public:
  AstronautProblem(const Robot& robot, const AstronautOptions& options, int first = 0,
                   int last = -1, const Eigen::VectorXd& start = Eigen::VectorXd(),
                   const std::vector<double>& goals = {});
  AstronautProblem(const AstronautProblem&) = delete;
  AstronautProblem& operator=(const AstronautProblem&) = delete;

  const Model& model() const { return locked_.model; }
  const LockedRobot& locked() const { return locked_; }
  ShootingProblem& problem() { return *problem_; }
  const Eigen::VectorXd& x0() const { return x0_; }  // rest, default posture (not the window's)
  const AstronautOptions& options() const { return options_; }
  // Knot index and goal angle (rad) of each orientation waypoint (the last: T, terminal).
  // (All n of them, in knots from the start of the whole motion, also in a window.)
  const std::vector<std::pair<int, double>>& waypoints() const { return waypoints_; }
  // Knot of waypoint i (0: the start of the motion).
  int waypointKnot(int i) const { return i == 0 ? 0 : waypoints_[i - 1].first; }
  int horizon() const { return problem_->horizon(); }

 private:
  AstronautOptions options_;
  LockedRobot locked_;
  Eigen::VectorXd x0_;
  std::unique_ptr<ShootingProblem> problem_;
  std::vector<std::pair<int, double>> waypoints_;
};

// One receding window of solveAstronaut.
struct AstronautWindow {
  int first = 0, last = 0;  // waypoints it spans (first = 0: the start)
  int committed = 0;        // segments kept (window_commit, or all for the last window)
  int knots = 0;            // its horizon
  double goal = 0.0;        // goal at the end of what it committed, rad
  double pitch = 0.0;       // base pitch reached there (AstronautMotion::pitch_axis), rad
  int iterations = 0;
  double solve_s = 0.0;  // Solver::solve only
  SolveStatus status = SolveStatus::MaxIterations;
  bool restarted = false;  // re-solved from zero torques (the warm start blew up)
};

struct AstronautSolution {
  std::unique_ptr<AstronautProblem> problem;  // the full problem (model, waypoints, cost)
  std::vector<Eigen::VectorXd> xs, us;        // the committed plan, knots 0..T
  std::vector<AstronautWindow> windows;
  std::vector<IterationStats> stats;  // every iteration of every window, in order
  std::vector<int> stats_window;      // the window (0-based) of each entry of stats
  int iterations = 0;                 // over all windows
  double solve_s = 0.0;               // Σ Solver::solve over the windows
  double wall_s = 0.0;                // the whole of solveAstronaut (building the windows too)
  double cost = 0.0;                  // of the plan on the full problem
  // False when a window failed (non-finite) even from zero torques: the plan stops there
  // (xs, us shorter than the horizon).
  bool finite = true;
};

// Zero warm start + receding windows over the waypoints (options.window). `progress`, when set,
// is called after every window; `callback` after every DDP iteration.
AstronautSolution solveAstronaut(const Robot& robot, const AstronautOptions& options,
                                 const std::function<void(const AstronautWindow&)>& progress = {},
                                 const std::function<void(const IterationStats&)>& callback = {});

// What the experiment reports, per knot (T + 1 entries) and overall.
struct AstronautMotion {
  std::vector<double> t;
  // Accumulated base rotation about world y, rad: Σ of the y components of the increments
  // log3(R_{k+1} R_kᵀ). Path-dependent when the base also rolls and yaws.
  std::vector<double> pitch;
  // The angle of the base's forward axis (R e_x) in the world x-z plane, unwrapped, rad: how far
  // the body has turned round in the sagittal plane (0 at the start, 2π after a full turn, the
  // final one differing from the final orientation's only by roll and yaw). Well defined while
  // the base's y axis stays away from x-z (tilt below).
  std::vector<double> pitch_axis;
  std::vector<double> off_axis;  // |rotation about world x and z| accumulated, rad
  std::vector<double> tilt;      // angle between the base's y axis and world y, rad
  // The base orientation as R = Ry(pitch) Rz(yaw) Rx(roll) (pitch: the forward-axis angle):
  // yaw lifts the forward axis out of the sagittal x-z plane, roll turns the base about it. Zero
  // for a planar (sagittal) motion.
  std::vector<double> roll, yaw;
  std::vector<Eigen::Vector3d> h;  // whole-body angular momentum about the CoM, world axes
  // Angular momentum of each leg (the bodies its hip_pitch moves) about the whole-body CoM.
  std::vector<Eigen::Vector3d> h_left, h_right;
  std::vector<Eigen::Vector3d> com;
  double max_h = 0.0, max_h_leg = 0.0, max_com_drift = 0.0, max_tilt = 0.0;
  double max_roll = 0.0, max_yaw = 0.0;  // largest |roll|, |yaw|, rad
};

// Unwrapped pitch: the base rotation increments of successive states, log3(R_{k+1} R_kᵀ) in world
// axes, summed (never atan2 of a final orientation, which cannot tell 0° from 360°).
AstronautMotion analyzeMotion(const Model& model, const std::vector<Eigen::VectorXd>& xs, double dt,
                              const std::string& base_frame = "base_link");

// The plan checked against a finer integrator, knot by knot: each knot's torque applied from the
// planned state xs[k] over dt in `substeps` steps of `integrator` (semi-implicit Euler by default;
// an RK4 plan is checked with RK4 substeps, which Euler's O(dt / substeps) error would swamp). An
// open-loop replay of the whole horizon is not a fair check over tens of seconds (the free-floating
// chain is unstable without feedback, and any integrator difference grows); the knot-wise one
// measures what the discretization adds per knot: the pitch it would accumulate and the momentum it
// creates.
struct FineCheck {
  double pitch = 0.0;        // Σ pitch increments of the fine steps, rad
  double pitch_axis = 0.0;   // Σ forward-axis angle changes (AstronautMotion::pitch_axis), rad
  double max_dh_plan = 0.0;  // max over knots of |h(xs[k+1]) - h(xs[k])| (the knots' dynamics)
  double max_dh_fine = 0.0;  // max over knots of |h(fine step from xs[k]) - h(xs[k])|
};
FineCheck checkWithFinerSteps(const Model& model, const std::vector<Eigen::VectorXd>& xs,
                              const std::vector<Eigen::VectorXd>& us, double dt, int substeps,
                              const std::string& base_frame = "base_link",
                              Integrator integrator = Integrator::Euler);

}  // namespace stride
