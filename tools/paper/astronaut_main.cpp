// stride-paper-astronaut: the paper's astronaut reorientation (§V-B, Fig. 5-6). Builds the
// problem (astronaut.hpp), solves it with DDP from zero torques, checks the plan by re-integrating
// its torques with a finer step, prints the numbers and writes the trajectories for
// tools/paper/plot_astronaut.py.

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>

#include "solver/multibody/frames.hpp"
#include "solver/multibody/kinematics.hpp"
#include "solver/multibody/lie_group.hpp"
#include "tools/paper/astronaut.hpp"

using namespace stride;

namespace {
constexpr double kDeg = 180.0 / M_PI;

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
  AstronautOptions o;
  std::string robot_yaml =
      std::string(STRIDE_CONFIG_DIR) + "/robots/stride_humanoid/stride_humanoid.yaml";
  std::string out;
  std::string solver_name = "ddp";
  int iterations = 500, substeps = 10;  // defaults: the README run
  bool verbose = false;
  app.add_option("--robot", robot_yaml, "robot YAML")->check(CLI::ExistingFile);
  app.add_option("--out", out, "output folder (CSV, JSON); nothing written without it");
  app.add_option("--dt", o.dt, "knot duration, s")->check(CLI::PositiveNumber);
  app.add_option("--knots", o.knots, "running knots")->check(CLI::PositiveNumber);
  app.add_option("--turn", o.turn_deg, "rotation about +y, degrees");
  app.add_option("--waypoints", o.waypoints, "orientation goals along the horizon")
      ->check(CLI::PositiveNumber);
  app.add_option("--iterations", iterations, "DDP iteration budget")->check(CLI::PositiveNumber);
  app.add_option("--solver", solver_name, "ddp or fddp")->check(CLI::IsMember({"ddp", "fddp"}));
  app.add_option("--replay-substeps", substeps, "substeps of the re-integration")
      ->check(CLI::PositiveNumber);
  app.add_option("--w-orientation", o.w_orientation, "waypoint weight");
  app.add_option("--w-posture", o.w_posture, "joint posture weight");
  app.add_option("--w-control", o.w_control, "torque weight");
  app.add_option("--w-momentum", o.w_momentum, "centroidal momentum weight (0: off)");
  app.add_option("--margin", o.limit_margin, "fraction of the joint ranges allowed");
  app.add_flag("-v,--verbose", verbose, "print the iteration table");
  CLI11_PARSE(app, argc, argv);

  const Robot robot = loadRobot(robot_yaml);
  AstronautProblem astro(robot, o);
  const Model& model = astro.model();
  Solver solver(astro.problem(), solver_name == "ddp" ? SolverKind::Ddp : SolverKind::Fddp);
  if (verbose) solver.callback = Solver::printIterationTable;
  // No warm start (paper): the solver starts from x0 everywhere and zero torques.
  const auto t0 = std::chrono::steady_clock::now();
  const SolveStatus status = solver.solve(iterations);
  const double solve_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  const AstronautMotion m = analyzeMotion(model, solver.xs(), o.dt, o.base_frame);
  const FineCheck fine =
      checkWithFinerSteps(model, solver.xs(), solver.us(), o.dt, substeps, o.base_frame);
  // Distance of the final base orientation from the last goal (identity for 360°).
  const double final_err =
      log3(Eigen::AngleAxisd(astro.waypoints().back().second, Eigen::Vector3d::UnitY())
               .toRotationMatrix()
               .transpose() *
           Eigen::Quaterniond(solver.xs().back().segment<4>(3)).toRotationMatrix())
          .norm();
  const double max_pitch = *std::max_element(m.pitch.begin(), m.pitch.end());
  double max_tau = 0.0;
  for (const auto& u : solver.us()) max_tau = std::max(max_tau, u.cwiseAbs().maxCoeff());

  std::printf(
      "astronaut reorientation (paper §V-B): %d knots x %.3f s, %d waypoints, goal %.0f deg\n",
      o.knots, o.dt, o.waypoints, o.turn_deg);
  std::printf("  %-44s %12s\n", "quantity", "value");
  std::printf("  %-44s %12.1f\n", "base pitch at the end (unwrapped), deg", m.pitch.back() * kDeg);
  std::printf("  %-44s %12.1f\n", "largest base pitch reached, deg", max_pitch * kDeg);
  for (const auto& [k, goal] : astro.waypoints())
    std::printf("  %-44s %12.1f\n",
                ("  pitch at t = " + std::to_string(k * o.dt).substr(0, 4) + " s (goal " +
                 std::to_string(static_cast<int>(std::lround(goal * kDeg))) + "), deg")
                    .c_str(),
                m.pitch[k] * kDeg);
  std::printf("  %-44s %12.2f\n", "off-axis rotation (roll/yaw) accumulated, deg",
              m.off_axis.back() * kDeg);
  std::printf("  %-44s %12.2f\n", "final orientation error to the goal, deg", final_err * kDeg);
  std::printf("  %-44s %12.3e\n", "max |angular momentum| whole body, kg m^2/s", m.max_h);
  std::printf("  %-44s %12.3f\n", "max |angular momentum| one leg, kg m^2/s", m.max_h_leg);
  std::printf("  %-44s %12.3e\n", "max CoM drift, m", m.max_com_drift);
  std::printf("  %-44s %12.1f\n", "max |torque|, Nm", max_tau);
  std::printf("  %-44s %12d\n", "iterations", solver.iterations());
  std::printf("  %-44s %12.2f\n", "solve time, s", solve_s);
  std::printf("  %-44s %12s\n", "status", toString(status));
  std::printf("  %-44s %12.3e\n", "final cost", solver.cost());
  std::printf("  %-44s %12.1f\n",
              ("pitch re-integrated knot-wise at dt/" + std::to_string(substeps) + ", deg").c_str(),
              fine.pitch * kDeg);
  std::printf("  %-44s %12.3e\n", "max momentum change in one knot: plan", fine.max_dh_plan);
  std::printf("  %-44s %12.3e\n",
              ("max momentum change in one knot: dt/" + std::to_string(substeps)).c_str(),
              fine.max_dh_fine);

  if (out.empty()) return 0;
  std::filesystem::create_directories(out);
  const int nq = model.nq, nv = model.nv, T = o.knots;
  std::vector<std::string> joints = astro.locked().free;

  std::ofstream traj(out + "/trajectory.csv");
  traj << "t,pitch_deg,off_axis_deg,h_x,h_y,h_z,h_norm,"
          "h_left_y,h_right_y,h_left_norm,h_right_norm,com_x,com_z";
  for (const auto& j : joints) traj << ",q_" << j;
  for (const auto& j : joints) traj << ",v_" << j;
  for (const auto& j : joints) traj << ",tau_" << j;
  traj << "\n";
  traj.precision(9);
  for (int k = 0; k <= T; ++k) {
    const Eigen::VectorXd& x = solver.xs()[k];
    traj << m.t[k] << ',' << m.pitch[k] * kDeg << ',' << m.off_axis[k] * kDeg << ',' << m.h[k].x()
         << ',' << m.h[k].y() << ',' << m.h[k].z() << ',' << m.h[k].norm() << ',' << m.h_left[k].y()
         << ',' << m.h_right[k].y() << ',' << m.h_left[k].norm() << ',' << m.h_right[k].norm()
         << ',' << m.com[k].x() << ',' << m.com[k].z();
    for (int j = 0; j < nv - 6; ++j) traj << ',' << x[7 + j];
    for (int j = 0; j < nv - 6; ++j) traj << ',' << x[nq + 6 + j];
    // Torques are held over a knot: the last state has none.
    for (int j = 0; j < nv - 6; ++j) {
      traj << ',';
      if (k < T) traj << solver.us()[k][j];
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
    framesForwardKinematics(model, data, solver.xs()[k].head(nq));
    frames << m.t[k];
    for (const auto& f : kFigureFrames) {
      const Eigen::Vector3d p = data.oMf[model.getFrameId(f)].p - m.com.front();
      frames << ',' << p.x() << ',' << p.z();
    }
    frames << "\n";
  }

  std::ofstream iters(out + "/iterations.csv");
  iters << "iteration,cost,step,regularization,time_ms\n";
  for (int i = 0; i < solver.statsCount(); ++i) {
    const IterationStats& s = solver.stats()[i];
    iters << s.iteration << ',' << s.cost << ',' << s.step << ',' << s.regularization << ','
          << s.time_ms << "\n";
  }

  std::ofstream skel(out + "/skeleton.json");
  skel << "{\"segments\": [";
  for (std::size_t i = 0; i < kFigureSegments.size(); ++i)
    skel << (i ? ", " : "") << "[\"" << kFigureSegments[i].first << "\", \""
         << kFigureSegments[i].second << "\"]";
  skel << "]}\n";

  std::ofstream sum(out + "/summary.json");
  sum.precision(9);
  sum << "{\n"
      << "  \"base_pitch_deg\": " << m.pitch.back() * kDeg << ",\n"
      << "  \"max_base_pitch_deg\": " << max_pitch * kDeg << ",\n"
      << "  \"max_angular_momentum_norm\": " << m.max_h << ",\n"
      << "  \"max_leg_angular_momentum_norm\": " << m.max_h_leg << ",\n"
      << "  \"iterations\": " << solver.iterations() << ",\n"
      << "  \"solve_time_s\": " << solve_s << ",\n"
      << "  \"status\": \"" << toString(status) << "\",\n"
      << "  \"final_cost\": " << solver.cost() << ",\n"
      << "  \"off_axis_deg\": " << m.off_axis.back() * kDeg << ",\n"
      << "  \"max_com_drift_m\": " << m.max_com_drift << ",\n"
      << "  \"max_torque_nm\": " << max_tau << ",\n"
      << "  \"replay_substeps\": " << substeps << ",\n"
      << "  \"fine_base_pitch_deg\": " << fine.pitch * kDeg << ",\n"
      << "  \"max_knot_momentum_change_plan\": " << fine.max_dh_plan << ",\n"
      << "  \"max_knot_momentum_change_fine\": " << fine.max_dh_fine << ",\n"
      << "  \"final_orientation_error_deg\": " << final_err * kDeg << ",\n"
      << "  \"knots\": " << T << ",\n"
      << "  \"dt\": " << o.dt << ",\n"
      << "  \"waypoints\": [";
  for (std::size_t i = 0; i < astro.waypoints().size(); ++i) {
    const auto& [k, goal] = astro.waypoints()[i];
    sum << (i ? ", " : "") << "{\"t\": " << k * o.dt << ", \"goal_deg\": " << goal * kDeg
        << ", \"pitch_deg\": " << m.pitch[k] * kDeg << "}";
  }
  sum << "]\n}\n";
  std::printf("  wrote %s/{summary.json,trajectory.csv,frames.csv,iterations.csv,skeleton.json}\n",
              out.c_str());
  return status == SolveStatus::NonFinite ? 1 : 0;
}
