// stride-paper-astronaut: the paper's astronaut reorientation (§V-B, Fig. 5-6). Builds the
// problem (astronaut.hpp), plans it with DDP from zero torques in receding windows over the
// orientation waypoints, checks the plan by re-integrating its torques with a finer step, prints
// the numbers and writes the trajectories for tools/paper/plot_astronaut.py, and with --log the
// motion as an LCM log of the full robot for stride-viz (the snapshot figure's frames).

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>

#include "config/command_line.hpp"
#include "solver/multibody/frames.hpp"
#include "solver/multibody/kinematics.hpp"
#include "solver/multibody/lie_group.hpp"
#include "tools/paper/astronaut.hpp"
#include "tools/paper/motion_log.hpp"

using namespace stride;

namespace {
constexpr double kDeg = 180.0 / M_PI;
// Where the log puts the initial CoM above the viewer's ground grid [m]: the problem has no ground
// (zero gravity, base at the origin), and a body turning about its CoM at z = 0 would cut the grid.
// 1.2 m clears the feet at every orientation (the feet are < 1 m from the CoM).
constexpr double kLogCoMHeight = 1.2;

// The points of the sagittal stick figure, and the segments between them.
const std::vector<std::string> kFigureFrames = {
    "head",         "chest",  "base_link", "L_shoulder_pitch_link",
    "L_forearm",    "L_hand", "L_thigh",   "L_shank",
    "L_ankle_link", "L_sole", "R_thigh",   "R_shank",
    "R_ankle_link", "R_sole"};
const std::vector<std::pair<std::string, std::string>> kFigureSegments = {
    {"head", "chest"},
    {"chest", "base_link"},
    {"L_shoulder_pitch_link", "L_forearm"},
    {"L_forearm", "L_hand"},
    {"base_link", "L_thigh"},
    {"L_thigh", "L_shank"},
    {"L_shank", "L_ankle_link"},
    {"L_ankle_link", "L_sole"},
    {"base_link", "R_thigh"},
    {"R_thigh", "R_shank"},
    {"R_shank", "R_ankle_link"},
    {"R_ankle_link", "R_sole"}};
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"The paper's astronaut reorientation (§V-B): 360° in zero gravity, legs only"};
  stride::commandLineConventions(app, "stride-paper-astronaut");
  AstronautOptions o;
  std::string robot_yaml =
      std::string(STRIDE_CONFIG_DIR) + "/robots/stride_humanoid/stride_humanoid.yaml";
  std::string out, log_path;
  std::string solver_name = "ddp";
  // RK4 by default (issue 43): the experiment is about momentum, and Euler's knots make up 0.113
  // kg m2/s of it where RK4's make 2.0e-4 (README.md, "Integrator").
  std::string integrator_name = "rk4";
  int substeps = 10;
  bool verbose = false;
  app.add_option("--robot", robot_yaml, "robot YAML")->check(CLI::ExistingFile);
  app.add_option("--out", out, "output folder (CSV, JSON); nothing written without it");
  app.add_option("--log", log_path,
                 "also write the motion as an LCM log of the full robot for stride-viz (locked "
                 "joints at their default angles, the initial CoM 1.2 m above the viewer's "
                 "ground)");
  app.add_option("--dt", o.dt, "knot duration, s")->check(CLI::PositiveNumber);
  app.add_option("--knots", o.knots, "running knots")->check(CLI::PositiveNumber);
  app.add_option("--turn", o.turn_deg, "rotation about +y, degrees");
  app.add_option("--waypoints", o.waypoints, "orientation goals along the horizon")
      ->check(CLI::PositiveNumber);
  app.add_option("--window", o.window,
                 "waypoint segments per receding window (0 or >= waypoints: one solve of the "
                 "whole problem)");
  app.add_option("--window-commit", o.window_commit, "segments kept from each window")
      ->check(CLI::PositiveNumber);
  app.add_option("--window-step", o.window_step_deg,
                 "degrees a window's goals advance per segment (0: turn / waypoints)");
  app.add_option("--window-iterations", o.window_iterations, "DDP iterations per window")
      ->check(CLI::PositiveNumber);
  app.add_option("--iterations", o.final_iterations,
                 "DDP iterations on the last window (the one that reaches the end)")
      ->check(CLI::PositiveNumber);
  app.add_option("--solver", solver_name, "ddp or fddp")->check(CLI::IsMember({"ddp", "fddp"}));
  app.add_option("--integrator", integrator_name,
                 "the knots' integrator: rk4 (default; Runge-Kutta-Munthe-Kaas 4: conserves the "
                 "momentum to 4th order, four KKT solves per knot) or euler (semi-implicit, the "
                 "paper's)")
      ->check(CLI::IsMember({"euler", "rk4"}));
  app.add_option("--replay-substeps", substeps, "substeps of the re-integration")
      ->check(CLI::PositiveNumber);
  app.add_option("--w-orientation", o.w_orientation, "waypoint weight");
  app.add_option("--w-posture", o.w_posture, "joint posture weight");
  CLI::Option* w_control_option =
      app.add_option("--w-control", o.w_control,
                     "torque weight (default 1e-2 with rk4, 1e-4 with --integrator euler)");
  app.add_option("--w-momentum", o.w_momentum, "centroidal momentum weight (0: off)");
  app.add_option("--margin", o.limit_margin, "fraction of the joint ranges allowed");
  app.add_option("--w-mirror", o.w_mirror,
                 "left/right symmetry weight on the hip_pitch and knee angles (default 0: off)");
  app.add_option("--w-mirror-velocity", o.w_mirror_velocity, "same, on their rates");
  app.add_option("--w-mirror-control", o.w_mirror_control, "same, on their torques");
  app.add_flag("-v,--verbose", verbose, "print the iteration table");
  if (const int status = stride::parseCommandLine(app, argc, argv); status >= 0) return status;

  o.solver = solver_name == "ddp" ? SolverKind::Ddp : SolverKind::Fddp;
  parseIntegrator(integrator_name, o.integrator);  // checked by CLI11 above
  // RK4 knots conserve the momentum of fast leg cycles too, so the momentum term no longer keeps
  // the torques down as it does on Euler knots: at 1e-4 DDP found 580-650 N m cycles (joint rates
  // at 92 % of their limits) that turned the body the wrong way round to its goals (-240° for
  // +120°), and the plan ended at 8°. At 1e-2 its torques peak where Euler's do (27 N m) and it
  // turns 359° (README.md, "Integrator").
  if (o.integrator == Integrator::Rk4 && w_control_option->count() == 0) o.w_control = 1e-2;
  const Robot robot = loadRobot(robot_yaml);
  std::printf(
      "astronaut reorientation (paper §V-B): %d knots x %.3f s (%s), %d waypoints, goal %.0f deg\n",
      o.knots, o.dt, toString(o.integrator), o.waypoints, o.turn_deg);
  // Zero warm start (paper): the first window starts from zero torques; each later one from the
  // previous one's torques and zeros on its new segment (astronaut.hpp).
  std::printf("  %-7s %9s %6s %10s %11s %6s %7s\n", "window", "waypoints", "knots", "goal,deg",
              "reached,deg", "iters", "time,s");
  const AstronautSolution sol = solveAstronaut(
      robot, o,
      [&](const AstronautWindow& w) {
        std::printf("  %-7d %4d-%-4d %6d %10.1f %11.1f %6d %7.2f%s\n", w.first + 1, w.first, w.last,
                    w.knots, w.goal * kDeg, w.pitch * kDeg, w.iterations, w.solve_s,
                    w.restarted ? "  (restarted from zero torques)" : "");
        std::fflush(stdout);
      },
      verbose ? std::function<void(const IterationStats&)>(Solver::printIterationTable)
              : std::function<void(const IterationStats&)>());
  if (!sol.finite) {
    std::fprintf(stderr, "a window failed (non-finite) even from zero torques: no plan\n");
    return 1;
  }
  const AstronautProblem& astro = *sol.problem;
  const Model& model = astro.model();
  const double solve_s = sol.solve_s;
  const std::vector<Eigen::VectorXd>& xs = sol.xs;
  const std::vector<Eigen::VectorXd>& us = sol.us;

  const AstronautMotion m = analyzeMotion(model, xs, o.dt, o.base_frame);
  const FineCheck fine =
      checkWithFinerSteps(model, xs, us, o.dt, substeps, o.base_frame, o.integrator);
  // Distance of the final base orientation from the last goal (identity for 360°).
  const double final_err =
      log3(Eigen::AngleAxisd(astro.waypoints().back().second, Eigen::Vector3d::UnitY())
               .toRotationMatrix()
               .transpose() *
           Eigen::Quaterniond(xs.back().segment<4>(3)).toRotationMatrix())
          .norm();
  const double max_pitch = *std::max_element(m.pitch_axis.begin(), m.pitch_axis.end());
  // Joint limits: the smallest distance of a free joint to its position limits, and the largest
  // rate as a fraction of its velocity limit (nq-indexed limits, nv-indexed velocity limits).
  double min_limit_margin = INFINITY, max_velocity_ratio = 0.0;
  for (const auto& x : xs)
    for (int j = 0; j < model.nv - 6; ++j) {
      const double q = x[7 + j], v = x[model.nq + 6 + j];
      min_limit_margin = std::min({min_limit_margin, q - model.lowerPositionLimit[7 + j],
                                   model.upperPositionLimit[7 + j] - q});
      max_velocity_ratio = std::max(max_velocity_ratio, std::abs(v) / model.velocityLimit[6 + j]);
    }
  double max_tau = 0.0;
  for (const auto& u : us) max_tau = std::max(max_tau, u.cwiseAbs().maxCoeff());

  std::printf("  %-44s %12s\n", "quantity", "value");
  std::printf("  %-44s %12.1f\n", "base pitch at the end (forward axis, unwrapped)",
              m.pitch_axis.back() * kDeg);
  std::printf("  %-44s %12.1f\n", "base pitch at the end (sum of y increments)",
              m.pitch.back() * kDeg);
  std::printf("  %-44s %12.1f\n", "largest base pitch reached (forward axis), deg",
              max_pitch * kDeg);
  std::printf("  %-44s %12.1f\n", "max tilt of the base y axis from world y, deg",
              m.max_tilt * kDeg);
  std::printf("  %-44s %12.1f\n", "max |roll| of the base, deg", m.max_roll * kDeg);
  std::printf("  %-44s %12.1f\n", "max |yaw| of the base, deg", m.max_yaw * kDeg);
  std::printf("  %-44s %12.2f\n", "off-axis rotation (roll/yaw) accumulated, deg",
              m.off_axis.back() * kDeg);
  std::printf("  %-44s %12.2f\n", "final orientation error to the goal, deg", final_err * kDeg);
  std::printf("  %-44s %12.3e\n", "max |angular momentum| whole body, kg m^2/s", m.max_h);
  std::printf("  %-44s %12.3f\n", "max |angular momentum| one leg, kg m^2/s", m.max_h_leg);
  std::printf("  %-44s %12.3e\n", "max CoM drift, m", m.max_com_drift);
  std::printf("  %-44s %12.1f\n", "max |torque|, Nm", max_tau);
  std::printf("  %-44s %12.3f\n", "min distance of a joint to its limits, rad", min_limit_margin);
  std::printf("  %-44s %12.2f\n", "max joint rate / velocity limit", max_velocity_ratio);
  std::printf("  %-44s %12d\n", "DDP iterations (all windows)", sol.iterations);
  std::printf("  %-44s %12zu\n", "windows", sol.windows.size());
  std::printf("  %-44s %12.2f\n", "solve time (all windows), s", solve_s);
  std::printf("  %-44s %12.2f\n", "solve time per iteration, ms",
              sol.iterations > 0 ? 1e3 * solve_s / sol.iterations : 0.0);
  std::printf("  %-44s %12.2f\n", "wall time (building the windows too), s", sol.wall_s);
  std::printf("  %-44s %12s\n", "last window", toString(sol.windows.back().status));
  std::printf("  %-44s %12.3e\n", "cost of the plan (full problem)", sol.cost);
  std::printf("  %-44s %12.1f\n",
              ("pitch re-integrated knot-wise at dt/" + std::to_string(substeps) + ", deg").c_str(),
              fine.pitch * kDeg);
  std::printf("  %-44s %12.1f\n",
              ("  forward-axis pitch, same, dt/" + std::to_string(substeps) + ", deg").c_str(),
              fine.pitch_axis * kDeg);
  std::printf("  %-44s %12.3e\n", "max momentum change in one knot: plan", fine.max_dh_plan);
  std::printf("  %-44s %12.3e\n",
              ("max momentum change in one knot: dt/" + std::to_string(substeps)).c_str(),
              fine.max_dh_fine);

  const int nq = model.nq, nv = model.nv, T = o.knots;
  // The locked joints and the angles they are locked at (the robot's default posture).
  std::map<std::string, double> locked_angles;
  for (int i = 1; i < robot.model.njoints(); ++i) {
    const Joint& j = robot.model.joints[i];
    if (j.type != JointType::FreeFlyer && !model.existJoint(j.name))
      locked_angles[j.name] = robot.default_q[j.idx_q];
  }
  if (!log_path.empty()) {
    // The full robot, so that the viewer draws stride_humanoid from its own URDF with its own
    // model hash: every state expanded (locked joints at their angles, at rest), in the full
    // model's wire order, the whole motion shifted so that its initial CoM is kLogCoMHeight above
    // the ground (a translation changes nothing in zero gravity). No contact is closed.
    if (const auto dir = std::filesystem::path(log_path).parent_path(); !dir.empty())
      std::filesystem::create_directories(dir);
    MotionLog log(log_path, robot);
    const Eigen::Vector3d shift = Eigen::Vector3d(0.0, 0.0, kLogCoMHeight) - m.com.front();
    const std::vector<bool> open(robot.contacts.size(), false);
    for (int k = 0; k <= T; ++k) {
      Eigen::VectorXd q = expandConfiguration(robot.model, model, xs[k].head(nq), robot.default_q);
      q.head<3>() += shift;
      log.state(m.t[k], q, expandVelocity(robot.model, model, xs[k].tail(nv)), open);
    }
    std::printf("  wrote %s (%ld events: the full robot's states, stride-viz --log)\n",
                log_path.c_str(), log.events());
  }

  if (out.empty()) return 0;
  std::filesystem::create_directories(out);
  std::vector<std::string> joints = astro.locked().free;

  std::ofstream traj(out + "/trajectory.csv");
  traj << "t,pitch_deg,pitch_sum_deg,tilt_deg,roll_deg,yaw_deg,off_axis_deg,h_x,h_y,h_z,h_norm,"
          "h_left_y,h_right_y,h_left_norm,h_right_norm,com_x,com_z";
  for (const auto& j : joints) traj << ",q_" << j;
  for (const auto& j : joints) traj << ",v_" << j;
  for (const auto& j : joints) traj << ",tau_" << j;
  traj << "\n";
  traj.precision(9);
  for (int k = 0; k <= T; ++k) {
    const Eigen::VectorXd& x = xs[k];
    traj << m.t[k] << ',' << m.pitch_axis[k] * kDeg << ',' << m.pitch[k] * kDeg << ','
         << m.tilt[k] * kDeg << ',' << m.roll[k] * kDeg << ',' << m.yaw[k] * kDeg << ','
         << m.off_axis[k] * kDeg << ',' << m.h[k].x() << ',' << m.h[k].y() << ',' << m.h[k].z()
         << ',' << m.h[k].norm() << ',' << m.h_left[k].y() << ',' << m.h_right[k].y() << ','
         << m.h_left[k].norm() << ',' << m.h_right[k].norm() << ',' << m.com[k].x() << ','
         << m.com[k].z();
    for (int j = 0; j < nv - 6; ++j) traj << ',' << x[7 + j];
    for (int j = 0; j < nv - 6; ++j) traj << ',' << x[nq + 6 + j];
    // Torques are held over a knot: the last state has none.
    for (int j = 0; j < nv - 6; ++j) {
      traj << ',';
      if (k < T) traj << us[k][j];
    }
    traj << "\n";
  }

  // Frame positions in the sagittal plane (x forward, z up), relative to the initial CoM.
  std::ofstream frames(out + "/frames.csv");
  frames << "t";
  for (const auto& f : kFigureFrames) frames << ',' << f << "_x," << f << "_z";
  frames << "\n";
  frames.precision(6);
  Data data(model);
  for (int k = 0; k <= T; ++k) {
    framesForwardKinematics(model, data, xs[k].head(nq));
    frames << m.t[k];
    for (const auto& f : kFigureFrames) {
      const Eigen::Vector3d p = data.oMf[model.getFrameId(f)].p - m.com.front();
      frames << ',' << p.x() << ',' << p.z();
    }
    frames << "\n";
  }

  std::ofstream iters(out + "/iterations.csv");
  iters << "window,iteration,cost,step,regularization,time_ms\n";
  for (std::size_t i = 0; i < sol.stats.size(); ++i) {
    const IterationStats& s = sol.stats[i];
    iters << sol.stats_window[i] << ',' << s.iteration << ',' << s.cost << ',' << s.step << ','
          << s.regularization << ',' << s.time_ms << "\n";
  }

  using json = nlohmann::ordered_json;
  std::ofstream(out + "/skeleton.json") << json{{"segments", kFigureSegments}}.dump(2) << "\n";

  json sum;
  sum["base_pitch_deg"] = m.pitch_axis.back() * kDeg;
  sum["base_pitch_sum_deg"] = m.pitch.back() * kDeg;
  sum["max_tilt_deg"] = m.max_tilt * kDeg;
  sum["max_roll_deg"] = m.max_roll * kDeg;
  sum["max_yaw_deg"] = m.max_yaw * kDeg;
  sum["max_base_pitch_deg"] = max_pitch * kDeg;
  sum["max_angular_momentum_norm"] = m.max_h;
  sum["max_leg_angular_momentum_norm"] = m.max_h_leg;
  sum["iterations"] = sol.iterations;
  sum["solve_time_s"] = solve_s;
  sum["time_per_iteration_ms"] = sol.iterations > 0 ? 1e3 * solve_s / sol.iterations : 0.0;
  sum["integrator"] = toString(o.integrator);
  sum["w_control"] = o.w_control;
  sum["wall_time_s"] = sol.wall_s;
  sum["window_segments"] = o.window;
  sum["window_iterations"] = o.window_iterations;
  sum["last_window_iterations"] = o.final_iterations;
  sum["last_window_status"] = toString(sol.windows.back().status);
  sum["plan_cost"] = sol.cost;
  sum["off_axis_deg"] = m.off_axis.back() * kDeg;
  sum["max_com_drift_m"] = m.max_com_drift;
  sum["max_torque_nm"] = max_tau;
  sum["min_joint_limit_margin_rad"] = min_limit_margin;
  sum["max_joint_velocity_ratio"] = max_velocity_ratio;
  sum["replay_substeps"] = substeps;
  sum["fine_base_pitch_deg"] = fine.pitch_axis * kDeg;
  sum["fine_base_pitch_sum_deg"] = fine.pitch * kDeg;
  sum["max_knot_momentum_change_plan"] = fine.max_dh_plan;
  sum["max_knot_momentum_change_fine"] = fine.max_dh_fine;
  sum["final_orientation_error_deg"] = final_err * kDeg;
  sum["locked_joints"] = locked_angles;
  sum["log"] = log_path.empty() ? json(nullptr) : json(log_path);
  sum["log_com_height_m"] = kLogCoMHeight;
  sum["knots"] = T;
  sum["dt"] = o.dt;
  sum["waypoints"] = json::array();
  for (const auto& [k, goal] : astro.waypoints())
    sum["waypoints"].push_back(
        {{"t", k * o.dt}, {"goal_deg", goal * kDeg}, {"pitch_deg", m.pitch_axis[k] * kDeg}});
  sum["windows"] = json::array();
  for (const AstronautWindow& w : sol.windows)
    sum["windows"].push_back({{"first", w.first},
                              {"last", w.last},
                              {"committed", w.committed},
                              {"goal_deg", w.goal * kDeg},
                              {"pitch_deg", w.pitch * kDeg},
                              {"iterations", w.iterations},
                              {"solve_time_s", w.solve_s},
                              {"restarted", w.restarted}});
  std::ofstream(out + "/summary.json") << sum.dump(2) << "\n";
  std::printf("  wrote %s/{summary.json,trajectory.csv,frames.csv,iterations.csv,skeleton.json}\n",
              out.c_str());
  return sol.finite ? 0 : 1;
}
