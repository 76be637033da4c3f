// stride-paper-large-stride: the paper's large strides on flat ground (§V-A, Fig. 2-4). For each
// stride length: plans the contact sequence and the centroidal reference, tracks it with the IK
// baseline and with KKT-DDP (warm-started from the IK), plays the DDP policy on the mock robot,
// prints the table and writes the trajectories for tools/paper/plot_large_stride.py, and with
// --logs each motion as an LCM log for stride-viz (the snapshot figure's frames).

#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>

#include "config/command_line.hpp"
#include "solver/multibody/frames.hpp"
#include "solver/multibody/kinematics.hpp"
#include "tools/paper/large_stride.hpp"
#include "tools/paper/motion_log.hpp"
#include "tools/paper/stride_playback.hpp"

using namespace stride;

namespace {
// The points of the sagittal stick figure, and the segments between them.
const std::vector<std::string> kFigureFrames = {
    "head",         "chest",  "base_link", "L_shoulder_pitch_link",
    "L_forearm",    "L_hand", "L_thigh",   "L_shank",
    "L_ankle_link", "L_sole", "R_thigh",   "R_shank",
    "R_ankle_link", "R_sole"};
const std::vector<std::pair<int, int>> kFigureSegments = {{0, 1},  {1, 2},   {3, 4},   {4, 5},
                                                          {2, 6},  {6, 7},   {7, 8},   {8, 9},
                                                          {2, 10}, {10, 11}, {11, 12}, {12, 13}};

using json = nlohmann::ordered_json;

json metricsJson(const StrideMetrics& m) {
  return {{"peak_normal_force_N", m.peak_normal_force_N},
          {"peak_normal_force_left_N", m.peak_normal_force[0]},
          {"peak_normal_force_right_N", m.peak_normal_force[1]},
          {"peak_knee_torque_Nm", m.peak_knee_torque_Nm},
          {"torque_cost", m.torque_cost}};
}

void writeFrames(const Model& model, const std::string& path, const std::vector<double>& t,
                 const std::vector<Eigen::VectorXd>& q) {
  std::ofstream f(path);
  f << "t";
  for (const auto& n : kFigureFrames) f << "," << n << "_x," << n << "_z";
  f << "\n";
  Data data(model);
  std::vector<int> ids;
  for (const auto& n : kFigureFrames) ids.push_back(model.getFrameId(n));
  for (size_t k = 0; k < q.size(); ++k) {
    framesForwardKinematics(model, data, q[k]);
    f << t[k];
    for (int id : ids) f << "," << data.oMf[id].p.x() << "," << data.oMf[id].p.z();
    f << "\n";
  }
}

// One motion as an LCM log for stride-viz (motion_log.hpp): per sample k < N its state (v from
// the motion), the plan's contacts and the motion's contact forces as the planned forces.
void writeLog(const Robot& robot, const StridePlan& plan, const std::string& path,
              const std::vector<Eigen::VectorXd>& q, const std::vector<Eigen::VectorXd>& v,
              const std::vector<std::array<Vector6d, 2>>& wrench) {
  MotionLog log(path, robot);
  std::vector<Eigen::Vector3d> f(2);
  for (int k = 0; k < plan.N; ++k) {
    const std::vector<bool> closed = {plan.closed[k][0], plan.closed[k][1]};
    // The force part of each sole's wrench [f; τ] (world axes): what the page draws as an arrow.
    for (int c = 0; c < 2; ++c) f[c] = wrench[k][c].head<3>();
    log.state(plan.t[k], q[k], v[k], closed);
    log.plannedForces(plan.t[k], q[k], closed, f);
  }
}
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "The paper's large strides (§V-A): IK baseline vs KKT-DDP, checked on the mock robot"};
  stride::commandLineConventions(app, "stride-paper-large-stride");
  std::string robot_yaml =
      std::string(STRIDE_CONFIG_DIR) + "/robots/stride_humanoid/stride_humanoid.yaml";
  std::string out;
  std::vector<double> lengths = {0.8, 1.0};
  StridePlanOptions po;
  po.dt = 0.04;  // at 20 ms the 100 cm IK trajectory has a kink that stalls DDP (README)
  StrideDdpOptions dop;
  IkOptions iko;
  int iterations = 100;
  std::string integrator_name = "euler";
  bool verbose = false, no_sim = false, sim_trace = false, logs = false;
  app.add_option("--robot", robot_yaml, "robot YAML")->check(CLI::ExistingFile);
  CLI::Option* out_option =
      app.add_option("--out", out, "output folder (CSV, JSON); nothing written without it");
  app.add_flag("--logs", logs,
               "also write each stride's IK and DDP motions as LCM logs for stride-viz "
               "(stride_XXX/ik.lcmlog, ddp.lcmlog: states, contacts, forces as planned forces)")
      ->needs(out_option);
  app.add_option("--integrator", integrator_name,
                 "the contact knots' integrator: euler (semi-implicit) or rk4 "
                 "(Runge-Kutta-Munthe-Kaas 4; the played policy then takes v at the knots, "
                 "--no-midpoint)")
      ->check(CLI::IsMember({"euler", "rk4"}));
  app.add_option("--lengths", lengths, "stride lengths [m] (foot displacement per step)");
  app.add_option("--strides", po.strides, "full strides (plus a half step at each end)");
  app.add_option("--dt", po.dt, "knot period [s]")->check(CLI::PositiveNumber);
  app.add_option("--t-single", po.t_single, "single support [s]")->check(CLI::PositiveNumber);
  app.add_option("--t-double", po.t_double, "double support [s]")->check(CLI::PositiveNumber);
  app.add_option("--swing-height", po.swing_height, "swing apex [m]");
  app.add_option("--iterations", iterations, "DDP iterations (the paper stops at 100)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--w-com", dop.w_com, "CoM weight");
  app.add_option("--w-foot", dop.w_foot, "foot placement weight");
  app.add_option("--w-force", dop.w_force, "contact force tracking weight");
  app.add_option("--w-torque", dop.w_torque, "torque weight");
  app.add_option("--w-posture", dop.w_posture, "joint posture weight");
  app.add_option("--w-velocity", dop.w_velocity, "velocity weight");
  app.add_option("--contact-kd", dop.contact_kd,
                 "Baumgarte velocity gain of the contacts (0: 1 / dt)");
  app.add_option("--contact-kp", dop.contact_kp, "Baumgarte position gain of the contacts");
  app.add_option("--sole-margin", dop.sole_margin,
                 "the centre of pressure stays in this fraction of the sole");
  app.add_option("--mu", dop.mu, "friction coefficient of the plan");
  app.add_flag("--no-sim", no_sim, "skip the mock-robot check");
  StrideSimOptions sim_options;
  app.add_flag("!--offline-gains", sim_options.tvlqr,
               "play the offline solve's own gains instead of the TVLQR's");
  app.add_option("--lqr-w-posture", sim_options.w_track_posture,
                 "TVLQR: weight of the joints on the DDP states");
  app.add_option("--lqr-w-base-orientation", sim_options.w_track_base_orientation,
                 "TVLQR: weight of the base orientation on the DDP states");
  app.add_option("--lqr-w-velocity", sim_options.w_track_velocity,
                 "TVLQR: weight of the velocities on the DDP states");
  app.add_option("--hold", sim_options.hold_s, "standing after the walk [s]");
  app.add_option("--state-rate", sim_options.state_rate_hz,
                 "lock-step: state estimates per second of sim time");
  app.add_flag("!--no-midpoint", sim_options.midpoint,
               "policy velocities at the knots rather than at the knots' middles");
  std::vector<std::string> pushes;
  app.add_option("--push", pushes,
                 "a push on the mock robot's base: start:duration:fx,fy,fz [s, s, N] (repeatable)");
  app.add_flag("--sim-trace", sim_trace, "write the mock robot's 1 ms trace (sim_trace.csv)");
  app.add_flag("-v,--verbose", verbose, "print the iteration table");
  if (const int status = stride::parseCommandLine(app, argc, argv); status >= 0) return status;
  for (const std::string& text : pushes) {
    sim::Push p;
    char c1 = 0, c2 = 0, c3 = 0, c4 = 0;
    std::istringstream in(text);
    if (!(in >> p.start >> c1 >> p.duration >> c2 >> p.force.x() >> c3 >> p.force.y() >> c4 >>
          p.force.z()) ||
        c1 != ':' || c2 != ':' || c3 != ',' || c4 != ',' || !(p.duration > 0.0)) {
      std::fprintf(stderr, "--push %s: expected start:duration:fx,fy,fz\n", text.c_str());
      return 2;
    }
    sim_options.pushes.pushes.push_back(p);
  }

  parseIntegrator(integrator_name, dop.integrator);  // checked by CLI11 above
  // The midpoint velocity reference is the Euler step's (StrideSimOptions::midpoint): an RK4 knot
  // ends at the state of t_{k+1}.
  if (dop.integrator == Integrator::Rk4) sim_options.midpoint = false;
  const Robot robot = loadRobot(robot_yaml);
  const Model& model = robot.model;
  const std::array<std::string, 2> feet = {robot.contacts[0].frame, robot.contacts[1].frame};
  if (!out.empty()) std::filesystem::create_directories(out);

  json summary;
  summary["robot"] = robot.name;
  summary["dt"] = po.dt;
  summary["iterations"] = iterations;
  summary["integrator"] = toString(dop.integrator);
  summary["strides"] = json::array();
  struct Row {
    double length;
    StrideMetrics ik, ddp;
    StrideSimResult sim;
    bool sim_run;
    double weight;
    int ddp_iterations;
    double ddp_solve_s;
  };
  std::vector<Row> rows;
  for (size_t li = 0; li < lengths.size(); ++li) {
    StridePlanOptions o = po;
    o.stride = lengths[li];
    const StridePlan plan = planStrides(model, robot.default_q, feet, o);
    std::printf("stride %.2f m: %d samples (%.2f s), CoM lowered %.1f cm to %.3f m, leg %.2f m\n",
                o.stride, plan.N, plan.N * o.dt, 100.0 * plan.com_drop, plan.com_height,
                plan.leg_length);
    const auto t_ik = std::chrono::steady_clock::now();
    const IkTrajectory ik = trackIk(model, plan, robot.default_q, iko);
    std::printf(
        "  IK: %.2f s, max CoM error %.2g m, max foot error %.2g m, max base-row residual %.2g\n",
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t_ik).count(),
        ik.max_com_error, ik.max_foot_error, ik.max_base_residual);
    StrideProblem sp(robot, plan, dop);
    const StrideSolve solve = solveStrides(sp, ik, iterations, verbose);
    std::printf("  DDP: %d iterations (%s), %.1f s, cost %.4g -> %.4g, gap %.2g\n",
                solve.iterations, solve.status.c_str(), solve.solve_time_s, solve.cost.front(),
                solve.cost.back(), solve.gap.back());
    const auto ddp_force = sp.forces(solve.xs, solve.us);
    std::vector<Eigen::VectorXd> ddp_tau(plan.N);
    for (int k = 0; k < plan.N; ++k) ddp_tau[k] = solve.us[sp.contactKnot(k)];
    Row row{o.stride,
            strideMetrics(model, plan, ik.tau, ik.force),
            strideMetrics(model, plan, ddp_tau, ddp_force),
            {},
            !no_sim,
            plan.mass * 9.81,
            solve.iterations,
            solve.solve_time_s};
    if (!no_sim) {
      StrideSimOptions so = sim_options;
      so.record_steps = sim_trace && !out.empty();
      row.sim = simulateStrides(robot, sp, solve, so);
      std::printf(
          "  sim: %s%s, peak normal force L/R %.0f / %.0f N (1 ms), %.0f / %.0f N (knot mean), "
          "max base error %.3f m, final %.3f m, max tilt %.1f deg; %ld policies (%ld rejected), "
          "%ld steps on the hold PD, %ld past a policy, %d clamped; stop gap %.1g, stop + gains "
          "%.1f s\n",
          row.sim.completed ? "completed" : "NOT completed",
          row.sim.fell ? (" (fell at " + std::to_string(row.sim.fall_time) + " s)").c_str() : "",
          row.sim.peak_normal_force[0], row.sim.peak_normal_force[1],
          row.sim.peak_normal_force_knot[0], row.sim.peak_normal_force_knot[1],
          row.sim.max_base_error, row.sim.final_base_error, row.sim.max_tilt_deg, row.sim.policies,
          row.sim.policies_rejected, row.sim.hold_steps, row.sim.exhausted_steps,
          row.sim.clamped_steps, row.sim.stop_gap, row.sim.lqr_time_s);
    }
    rows.push_back(row);

    if (!out.empty()) {
      char name[32];
      std::snprintf(name, sizeof(name), "stride_%03d",
                    static_cast<int>(std::lround(o.stride * 100)));
      const std::string dir = out + "/" + name;
      std::filesystem::create_directories(dir);
      // Per sample: the plan, then IK and DDP forces, knee torques and CoM.
      std::ofstream f(dir + "/trajectory.csv");
      f << "t,closed_L,closed_R,com_ref_x,com_ref_y,com_ref_z,zmp_x,zmp_y,zmp_ref_x,zmp_ref_y,"
           "foot_L_x,foot_L_z,foot_R_x,foot_R_z,fref_L_z,fref_R_z,ik_fz_L,ik_fz_R,ddp_fz_L,"
           "ddp_fz_R,ik_knee_L,ik_knee_R,ddp_knee_L,ddp_knee_R,ik_base_x,ik_base_z,ddp_base_x,"
           "ddp_base_z,sim_fz_L,sim_fz_R,sim_base_x,sim_base_z,ik_cop_L_x,ik_cop_L_y,ik_cop_R_x,"
           "ik_cop_R_y,ddp_cop_L_x,ddp_cop_L_y,ddp_cop_R_x,ddp_cop_R_y\n";
      const int kl = model.joints[model.getJointId("L_knee")].idx_v - 6;
      const int kr = model.joints[model.getJointId("R_knee")].idx_v - 6;
      for (int k = 0; k < plan.N; ++k) {
        const Eigen::VectorXd& xd = solve.xs[sp.contactKnot(k)];
        f << plan.t[k] << "," << plan.closed[k][0] << "," << plan.closed[k][1] << ","
          << plan.com[k].x() << "," << plan.com[k].y() << "," << plan.com[k].z() << ","
          << plan.zmp[k].x() << "," << plan.zmp[k].y() << "," << plan.zmp_ref[k].x() << ","
          << plan.zmp_ref[k].y() << "," << plan.foot[k][0].x() << "," << plan.foot[k][0].z() << ","
          << plan.foot[k][1].x() << "," << plan.foot[k][1].z() << "," << plan.force[k][0][2] << ","
          << plan.force[k][1][2] << "," << ik.force[k][0][2] << "," << ik.force[k][1][2] << ","
          << ddp_force[k][0][2] << "," << ddp_force[k][1][2] << "," << ik.tau[k][kl] << ","
          << ik.tau[k][kr] << "," << ddp_tau[k][kl] << "," << ddp_tau[k][kr] << "," << ik.q[k][0]
          << "," << ik.q[k][2] << "," << xd[0] << "," << xd[2];
        if (row.sim_run && k < static_cast<int>(row.sim.trace.size())) {
          const auto& s = row.sim.trace[k];
          f << "," << s[1] << "," << s[2] << "," << s[3] << "," << s[4];
        } else {
          f << ",,,,";
        }
        // Centre of pressure of each sole relative to the sole frame (world axes; empty when
        // the foot carries less than 1 N): x = -τ_y / f_z, y = τ_x / f_z.
        for (const auto* force : {&ik.force, &ddp_force})
          for (int c = 0; c < 2; ++c) {
            const Vector6d& w = (*force)[k][c];
            if (w[2] > 1.0)
              f << "," << -w[4] / w[2] << "," << w[3] / w[2];
            else
              f << ",,";
          }
        f << "\n";
      }
      if (!row.sim.steps.empty()) {
        std::ofstream st(dir + "/sim_trace.csv");
        const auto& cols = StrideSimResult::stepColumns();
        for (size_t i = 0; i < cols.size(); ++i) st << (i ? "," : "") << cols[i];
        for (int i = 0; i < 2 * model.nv; ++i) st << ",dx" << i;
        for (int i = 0; i < model.nv - 6; ++i) st << ",tau" << i;
        st << "\n";
        for (const auto& r : row.sim.steps) {
          for (size_t i = 0; i < r.size(); ++i) st << (i ? "," : "") << r[i];
          st << "\n";
        }
      }
      std::ofstream it(dir + "/iterations.csv");
      it << "iteration,cost,gap";
      for (const auto& g : strideCostGroups()) it << "," << g;
      it << "\n";
      for (size_t i = 0; i < solve.breakdown.size(); ++i) {
        it << i << "," << solve.cost[i] << "," << solve.gap[i];
        for (double v : solve.breakdown[i]) it << "," << v;
        it << "\n";
      }
      std::vector<Eigen::VectorXd> qd(plan.N), qi(plan.N);
      std::vector<double> t(plan.t.begin(), plan.t.begin() + plan.N);
      for (int k = 0; k < plan.N; ++k) {
        qd[k] = solve.xs[sp.contactKnot(k)].head(model.nq);
        qi[k] = ik.q[k];
      }
      writeFrames(model, dir + "/frames_ddp.csv", t, qd);
      writeFrames(model, dir + "/frames_ik.csv", t, qi);
      if (logs) {
        std::vector<Eigen::VectorXd> vd(plan.N);
        for (int k = 0; k < plan.N; ++k) vd[k] = solve.xs[sp.contactKnot(k)].tail(model.nv);
        writeLog(robot, plan, dir + "/ddp.lcmlog", qd, vd, ddp_force);
        writeLog(robot, plan, dir + "/ik.lcmlog", qi, ik.v, ik.force);
        std::printf("  wrote %s/{ik,ddp}.lcmlog (stride-viz --log)\n", dir.c_str());
      }
    }
  }

  std::printf("\n%-8s | %-21s | %-21s | %-23s | %s\n", "stride", "peak normal force [N]",
              "peak knee torque [Nm]", "torque cost [N²m²s]",
              "mock robot: DDP policy, TVLQR gains, lock-step");
  std::printf("%-8s | %10s %10s | %10s %10s | %11s %11s |\n", "", "IK", "DDP", "IK", "DDP", "IK",
              "DDP");
  for (size_t i = 0; i < rows.size(); ++i) {
    const Row& r = rows[i];
    std::string sim = "not run";
    if (r.sim_run) {
      char b[300];
      char fell[32] = "";
      if (r.sim.fell) std::snprintf(fell, sizeof(fell), " at %.2f s", r.sim.fall_time);
      std::snprintf(b, sizeof(b),
                    "%s%s, peak L/R %.0f / %.0f N (knot mean %.0f / %.0f N; plan %.0f / %.0f N), "
                    "drift %.1f cm",
                    r.sim.completed ? "completed" : (r.sim.fell ? "FELL" : "not completed"), fell,
                    r.sim.peak_normal_force[0], r.sim.peak_normal_force[1],
                    r.sim.peak_normal_force_knot[0], r.sim.peak_normal_force_knot[1],
                    r.ddp.peak_normal_force[0], r.ddp.peak_normal_force[1],
                    100.0 * r.sim.max_base_error);
      sim = b;
    }
    std::printf("%5.0f cm | %10.0f %10.0f | %10.1f %10.1f | %11.4g %11.4g | %s\n", 100 * r.length,
                r.ik.peak_normal_force_N, r.ddp.peak_normal_force_N, r.ik.peak_knee_torque_Nm,
                r.ddp.peak_knee_torque_Nm, r.ik.torque_cost, r.ddp.torque_cost, sim.c_str());
    json entry;
    entry["length_m"] = r.length;
    entry["weight_N"] = r.weight;
    entry["ik"] = metricsJson(r.ik);
    entry["ddp"] = metricsJson(r.ddp);
    entry["ddp_iterations"] = r.ddp_iterations;
    entry["ddp_solve_time_s"] = r.ddp_solve_s;
    entry["ddp_time_per_iteration_ms"] =
        r.ddp_iterations > 0 ? 1e3 * r.ddp_solve_s / r.ddp_iterations : 0.0;
    if (r.sim_run) {
      json played;
      played["playback"] = sim_options.tvlqr ? "tvlqr" : "offline_gains";
      played["lockstep_state_rate_hz"] = sim_options.state_rate_hz;
      played["completed"] = r.sim.completed;
      played["fell"] = r.sim.fell;
      played["fall_time_s"] = r.sim.fell ? json(r.sim.fall_time) : json(nullptr);  // null: no fall
      played["peak_normal_force_N"] =
          std::max(r.sim.peak_normal_force[0], r.sim.peak_normal_force[1]);
      played["peak_normal_force_knot_mean_N"] =
          std::max(r.sim.peak_normal_force_knot[0], r.sim.peak_normal_force_knot[1]);
      played["planned_peak_normal_force_N"] = r.ddp.peak_normal_force_N;
      played["peak_normal_force_left_N"] = r.sim.peak_normal_force[0];
      played["peak_normal_force_right_N"] = r.sim.peak_normal_force[1];
      played["peak_normal_force_knot_mean_left_N"] = r.sim.peak_normal_force_knot[0];
      played["peak_normal_force_knot_mean_right_N"] = r.sim.peak_normal_force_knot[1];
      played["planned_peak_normal_force_left_N"] = r.ddp.peak_normal_force[0];
      played["planned_peak_normal_force_right_N"] = r.ddp.peak_normal_force[1];
      played["max_base_error_m"] = r.sim.max_base_error;
      played["final_base_error_m"] = r.sim.final_base_error;
      played["max_tilt_deg"] = r.sim.max_tilt_deg;
      played["clamped_steps"] = r.sim.clamped_steps;
      played["policies"] = r.sim.policies;
      played["unanswered_states"] = r.sim.unanswered;
      played["policies_rejected"] = r.sim.policies_rejected;
      played["hold_pd_steps"] = r.sim.hold_steps;
      played["exhausted_steps"] = r.sim.exhausted_steps;
      played["stop_gap"] = r.sim.stop_gap;
      played["lqr_time_s"] = r.sim.lqr_time_s;
      entry["sim"] = played;
    }
    summary["strides"].push_back(entry);
  }
  if (!out.empty()) {
    std::ofstream(out + "/summary.json") << summary.dump(2) << "\n";
    std::ofstream(out + "/skeleton.json")
        << json{{"frames", kFigureFrames}, {"segments", kFigureSegments}}.dump(2) << "\n";
  }
  return 0;
}
