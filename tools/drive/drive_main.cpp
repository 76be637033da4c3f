// stride-drive: a robot driven by a command script, controller and mock robot in one process, in
// lock-step (tools/drive/closed_loop.hpp): deterministic, as fast as the machine goes, no network.
// Prints how each command segment was tracked; optionally writes the session as an LCM log.
//   stride-drive --config config/controller/solo12.yaml --commands config/commands/solo12.yaml
//                [--robots-dir DIR] [--duration S] [--push START:DURATION:FX,FY,FZ]...
//                [--log FILE] [--summary FILE.json] [--trace FILE.csv] [--settle S]
//                [--check-tracking] [the mock robot's sensing, actuators and model mismatch:
//                sim/command_line.hpp, the same options as stride-sim's]
//                [--lose-controller AT [--controller-back-after S]] [--stand-down-grace S]
//                [--stand-down-ramp S]
// Exit status, as stride-sim's and stride-log-summary's: 0; 4 when the robot fell, 3 when the
// simulation diverged (whether or not --check-tracking); 1 with --check-tracking when a segment
// missed its command; 2 for bad arguments or files.

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>

#include "config/command_line.hpp"
#include "controller/command_script.hpp"
#include "locomotion/gait.hpp"
#include "sim/command_line.hpp"
#include "terrain/terrain_file.hpp"
#include "tools/drive/closed_loop.hpp"

namespace {

// The controller's timing over a run, from its status messages (lock-step: the controller's own
// work, the host's load aside; the real-time figures are stride-mpc's --summary).
struct Timing {
  double period_ms = 0.0, wall_s = 0.0;
  std::int64_t ticks = 0;
  double solve[3] = {0, 0, 0}, prepare[3] = {0, 0, 0}, tick[3] = {0, 0, 0};  // p50, p99, max
};

void quantiles(std::vector<double> x, double out[3]) {
  if (x.empty()) return;
  std::sort(x.begin(), x.end());
  const auto at = [&x](double p) {
    return x[std::min(x.size() - 1, static_cast<std::size_t>(p * static_cast<double>(x.size())))];
  };
  out[0] = at(0.5);
  out[1] = at(0.99);
  out[2] = x.back();
}

Timing timingOf(const stride::drive::Run& run, double rate_hz, double wall_s) {
  Timing t;
  t.period_ms = 1000.0 / rate_hz;
  t.wall_s = wall_s;
  t.ticks = static_cast<std::int64_t>(run.samples.size());
  std::vector<double> solve, prepare, tick;
  for (const stride::drive::Sample& s : run.samples) {
    solve.push_back(s.solve_ms);
    prepare.push_back(s.prepare_ms);
    tick.push_back(s.tick_ms);
  }
  quantiles(solve, t.solve);
  quantiles(prepare, t.prepare);
  quantiles(tick, t.tick);
  return t;
}

nlohmann::ordered_json quantileJson(const double q[3]) {
  return {{"p50", q[0]}, {"p99", q[1]}, {"max", q[2]}};
}

void writeJson(const std::string& path, const stride::drive::Run& run,
               const std::vector<stride::logs::Segment>& segments, bool tracked,
               const Timing& timing) {
  nlohmann::ordered_json j;
  j["fell"] = run.fell();
  j["diverged"] = run.sim.diverged;
  j["duration_s"] = run.samples.empty() ? 0.0 : run.samples.back().t;
  j["tracked"] = tracked;
  j["fallbacks"] = run.mpc.fallbacks;
  const std::string why = stride::sim::whyText(run.sim);
  j["why"] = why.empty() ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(why);
  j["failed_solves"] = run.mpc.failed_solves;
  j["terrain"] = run.terrain;
  if (run.q_end.size() >= 3) j["final_base"] = {run.q_end[0], run.q_end[1], run.q_end[2]};
  j["base_height_above_terrain_m"] = run.base_above_terrain;
  j["trips"] = run.trips;
  j["footholds"] = run.footholds;
  j["edge_footholds"] = run.edge_footholds;
  // No touch-down with an edge within the search radius (5 cm): null (infinity is not JSON).
  j["min_edge_distance_m"] = std::isfinite(run.min_edge_distance)
                                 ? nlohmann::ordered_json(run.min_edge_distance)
                                 : nlohmann::ordered_json(nullptr);
  j["sole_flat_fraction"] = std::isfinite(run.sole_flat_fraction)
                                ? nlohmann::ordered_json(run.sole_flat_fraction)
                                : nlohmann::ordered_json(nullptr);
  const double robot_s = run.samples.empty() ? 0.0 : run.samples.back().t;
  j["timing"] = {
      {"period_ms", timing.period_ms},
      {"ticks", timing.ticks},
      {"solve_ms", quantileJson(timing.solve)},
      {"prepare_ms", quantileJson(timing.prepare)},
      {"tick_ms", quantileJson(timing.tick)},
      // The share of the period the tick and its preparation take (the budget, p50 and p99).
      {"budget_share_p50", (timing.tick[0] + timing.prepare[0]) / timing.period_ms},
      {"budget_share_p99", (timing.tick[1] + timing.prepare[1]) / timing.period_ms},
      {"deadline_misses", run.mpc.deadline_misses},
      {"wall_s", timing.wall_s},
      {"robot_s_per_wall_s", timing.wall_s > 0.0 ? robot_s / timing.wall_s : 0.0}};
  j["segments"] = nlohmann::ordered_json::array();
  for (const stride::logs::Segment& s : segments) {
    nlohmann::ordered_json segment;
    segment["t0"] = s.t0;
    segment["t1"] = s.t1;
    // A script's gait may be any string: as UTF-8 replaced where invalid, not an error.
    segment["gait"] = s.gait;
    segment["command"] = s.command;
    // No state to average over: no velocity, not zero.
    segment["achieved"] = s.samples > 0 ? nlohmann::ordered_json(s.achieved) : nullptr;
    segment["fell"] = s.fell;
    j["segments"].push_back(segment);
  }
  std::ofstream f(path);
  f << j.dump(2, ' ', false, nlohmann::ordered_json::error_handler_t::replace) << "\n";
  if (!f) std::fprintf(stderr, "stride-drive: cannot write '%s'\n", path.c_str());
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"stride-drive: drive a robot with a command script, in one process, in lock-step"};
  stride::commandLineConventions(app, "stride-drive");
  std::string config_path, script_path, summary, trace_path, terrain_name, key_file;
  double ground = 0.0;
  std::vector<std::string> robots_dirs, pushes;
  stride::drive::Options options;
  options.duration = 0.0;
  bool check = false;
  stride::logs::SegmentOptions segment_options;
  app.add_option("--config", config_path, "controller YAML (config/controller/)")->required();
  app.add_option("--commands", script_path, "command script (YAML, controller/command_script.hpp)")
      ->required();
  app.add_option("--robots-dir", robots_dirs,
                 "where package:// URIs are looked for before ROS_PACKAGE_PATH (repeatable)");
  app.add_option("--duration", options.duration,
                 "seconds of robot time (default: the script's last entry + 4 s)");
  app.add_option("--push", pushes, "a push on the base: start:duration:fx,fy,fz (repeatable)");
  app.add_option("--log", options.log, "write every message as an LCM log (lcm-logger's format)");
  app.add_option("--summary", summary, "write the segments as JSON here");
  app.add_option("--key-file", key_file,
                 "sign every message with this key, and check it, as the programs do with it "
                 "(messages/README.md, \"Signing\"; in process, the wire is memq://)");
  app.add_option("--trace", trace_path,
                 "write one CSV row per controller period: base pose and velocity, tilt, feet "
                 "down, the policy's status and the solve (to see how a run went, or fell)");
  app.add_option("--settle", segment_options.settle,
                 "seconds after each command before its segment's velocity is averaged (1)");
  app.add_option("--lose-controller", options.controller_lost_at,
                 "kill the controller at this time [s] (the robot's fallback takes over)");
  app.add_option("--controller-back-after", options.controller_back_after,
                 "start a new controller this long after the kill [s] (1)");
  stride::sim::MockRobotArgs mock_args;
  stride::sim::addMockRobotOptions(app, options.sim, options.physics, mock_args);
  double controller_mu = 0.0;
  app.add_option("--controller-mu", controller_mu,
                 "the friction coefficient the controller plans with (default: its YAML's "
                 "contacts.mu); with --mu, a controller told the ground's friction");
  app.add_option("--stand-down-grace", options.sim.stand_down.grace,
                 "past a policy's end this long [s], the robot stands down (sim/README.md, "
                 "\"Controller loss\")");
  app.add_option("--stand-down-ramp", options.sim.stand_down.ramp,
                 "the robot's stand-down ramp [s] (sim/README.md, \"Controller loss\")");
  auto* terrain_option =
      app.add_option("--terrain", terrain_name,
                     "the world: a terrain file, or a name in config/terrain/ (terrain/README.md); "
                     "default: flat ground at --ground");
  app.add_option("--ground", ground, "height of the flat ground [m] (the robot starts on it)")
      ->excludes(terrain_option);
  app.add_option("--drop-height", options.drop_height,
                 "start this high above standing on the terrain [m]");
  app.add_option("--map-rate", options.sim.map.rate_hz,
                 "elevation maps (stride.terrain_t) per second; 0: none (default: 10 with "
                 "--terrain or --ground, else none)");
  app.add_option("--map-noise", options.sim.map.noise, "the maps' cell height noise, std [m]");
  app.add_option("--map-holes", options.sim.map.holes, "probability of an unknown map cell");
  app.add_option("--map-latency", options.sim.map.latency, "the maps' latency [s]");
  app.add_flag("--check-tracking", check,
               "exit 1 when a segment of 2 s or more misses its command by more than max(15%, "
               "0.05 m/s, 0.1 rad/s) (a fall always exits 4, a diverged simulation 3)");
  if (const int status = stride::parseCommandLine(app, argc, argv); status >= 0) return status;

  if (!stride::sim::finishMockRobotOptions(mock_args, options.sim, "stride-drive")) return 2;
  try {
    stride::ControllerConfig config = stride::loadControllerConfig(config_path);
    if (controller_mu > 0.0) config.locomotion.mu = controller_mu;
    config.robots_dirs = robots_dirs;
    if (!key_file.empty()) config.key_file = key_file;
    options.script = stride::loadCommandScript(script_path);
    {  // the script's gaits must be the robot's (the controller would refuse the others)
      const stride::Robot robot = stride::loadRobot(config.robot_yaml, config.robots_dirs);
      stride::checkScriptGaits(options.script, script_path,
                               stride::gaitNames(static_cast<int>(robot.contacts.size())),
                               "the robot of '" + config_path + "'");
    }
    if (!terrain_name.empty())
      options.terrain = std::make_shared<const stride::terrain::Terrain>(
          stride::terrain::loadTerrainFile(stride::terrain::findTerrainFile(
              terrain_name, stride::terrain::terrainConfigDirs())));
    else if (ground != 0.0)
      options.terrain = std::make_shared<const stride::terrain::Terrain>(ground);
    options.sim.map.seed = options.sim.seed + 2;
    // As stride-sim: the default flat world publishes no maps unless asked.
    if (app.count("--map-rate") == 0 && app.count("--terrain") == 0 && app.count("--ground") == 0)
      options.sim.map.rate_hz = 0.0;
    if (options.duration <= 0.0) options.duration = options.script.back().at + 4.0;
    for (const std::string& p : pushes) {
      stride::sim::Push push;
      if (!stride::sim::parsePush(p, push)) {
        std::fprintf(stderr, "stride-drive: --push '%s': expected start:duration:fx,fy,fz\n",
                     p.c_str());
        return 2;
      }
      options.sim.pushes.pushes.push_back(push);
    }
    std::FILE* trace = nullptr;
    if (!trace_path.empty()) {
      trace = std::fopen(trace_path.c_str(), "w");
      if (!trace) {
        std::fprintf(stderr, "stride-drive: cannot write '%s'\n", trace_path.c_str());
        return 2;
      }
      std::fprintf(trace,
                   "t,x,y,z,qx,qy,qz,qw,vx,vy,vz,wx,wy,wz,tilt_deg,feet_down,feet_mask,"
                   "policy_status,cost,gap,step,reg,k_max,solve_ms,clamped_steps,tau_max\n");
      options.each = [trace](const stride::drive::Sample& s) {
        if (s.q.size() < 7 || s.v.size() < 6) return;  // a fixed-base arm: no base to trace
        std::fprintf(trace, "%.4f", s.t);
        for (int i = 0; i < 7; ++i) std::fprintf(trace, ",%.6f", s.q[i]);
        for (int i = 0; i < 6; ++i) std::fprintf(trace, ",%.5f", s.v[i]);
        std::fprintf(trace, ",%.3f,%d,%u,%d,%.6g,%.4g,%.4g,%.4g,%.4g,%.3f,%lld,%.3f\n",
                     stride::drive::tiltDeg(s.q), s.feet_down, s.feet_mask, s.policy_status, s.cost,
                     s.gap, s.step, s.reg, s.k_max, s.solve_ms,
                     static_cast<long long>(s.clamped_steps),
                     s.tau.size() ? s.tau.cwiseAbs().maxCoeff() : 0.0);
      };
    }
    const auto wall0 = std::chrono::steady_clock::now();
    const stride::drive::Run run = stride::drive::run(config, options);
    const Timing timing =
        timingOf(run, config.rate_hz,
                 std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count());
    if (trace) std::fclose(trace);
    const std::vector<stride::logs::Segment> segments = run.segments(segment_options);
    const std::vector<stride::logs::TrackingMiss> misses = stride::logs::checkTracking(segments);
    std::printf(
        "stride-drive: %s, %.1f s of %.1f s, %s; %lld fallbacks, %lld failed solves\n",
        config_path.c_str(), run.samples.empty() ? 0.0 : run.samples.back().t, options.duration,
        run.sim.diverged ? "DIVERGED (the simulation)" : (run.fell() ? "FELL" : "no fall"),
        static_cast<long long>(run.mpc.fallbacks), static_cast<long long>(run.mpc.failed_solves));
    if (const std::string differs = stride::sim::describeMockRobot(options.sim, options.physics);
        !differs.empty())
      std::printf("  the robot differs from a perfect one: %s\n", differs.c_str());
    std::printf(
        "  timing (lock-step, this host): tick p50/p99/max %.2f/%.2f/%.2f ms, preparation "
        "p50/p99 %.2f/%.2f ms, of a %.1f ms period; %.1f s of robot time per s\n",
        timing.tick[0], timing.tick[1], timing.tick[2], timing.prepare[0], timing.prepare[1],
        timing.period_ms,
        timing.wall_s > 0.0 && !run.samples.empty() ? run.samples.back().t / timing.wall_s : 0.0);
    if (run.q_end.size() >= 7) {
      std::printf(
          "  terrain '%s': final base (%.3f, %.3f, %.3f) m, %.3f m above the terrain under it, "
          "%lld trips\n",
          run.terrain.c_str(), run.q_end[0], run.q_end[1], run.q_end[2], run.base_above_terrain,
          static_cast<long long>(run.trips));
      std::printf("  %s\n", run.footholds_text.c_str());
    }
    if (options.controller_lost_at >= 0.0)
      std::printf(
          "  controller killed at %.3f s, %s; the robot: %lld steps past a policy's end, %lld on "
          "the hold PD, %lld controller switches\n",
          options.controller_lost_at,
          run.controller_starts > 1 ? "restarted after the outage" : "not restarted before the end",
          static_cast<long long>(run.sim.exhausted_steps),
          static_cast<long long>(run.sim.hold_steps),
          static_cast<long long>(run.sim.source_switches));
    const std::string why = stride::sim::whyText(run.sim);
    if (!why.empty()) std::printf("  why: %s\n", why.c_str());
    std::printf("  %6s %6s  %-5s %23s  %23s\n", "t0", "t1", "gait", "command [vx vy yaw]",
                "achieved");
    for (const stride::logs::Segment& s : segments) {
      std::printf("  %6.1f %6.1f  %-5s %+7.3f %+7.3f %+7.3f  ", s.t0, s.t1, s.gait.c_str(),
                  s.command[0], s.command[1], s.command[2]);
      if (s.samples > 0)
        std::printf("%+7.3f %+7.3f %+7.3f%s\n", s.achieved[0], s.achieved[1], s.achieved[2],
                    s.fell ? "  fell" : "");
      else
        std::printf("%23s%s\n", "-", s.fell ? "  fell" : "");
    }
    for (const stride::logs::JumpOutcome& j : run.jumps) {
      std::printf("  jump #%d (asked at %.2f s): %s", j.id, j.t, stride::logs::describe(j).c_str());
      // Where it went: from the base at the ask to the base at the end of its landing, in the
      // heading it had at the ask, against the script's target.
      const auto target =
          std::find_if(options.script.begin(), options.script.end(),
                       [&](const stride::ScriptedCommand& c) { return c.jump_id == j.id; });
      const stride::drive::Run::Motion m = run.motion(j.t, j.t_landed + config.jump.landing);
      if (j.t_landed >= 0.0 && m.valid && target != options.script.end())
        std::printf(
            "; moved %+.3f %+.3f m, %+.3f m up, turned %+.1f deg (target %+.3f %+.3f m, "
            "%+.3f m, %+.1f deg): %.3f m from it",
            m.dx, m.dy, m.dz, m.yaw * 180.0 / M_PI, target->jump.dx, target->jump.dy,
            target->jump.dz, target->jump.yaw * 180.0 / M_PI,
            std::hypot(m.dx - target->jump.dx, m.dy - target->jump.dy));
      std::printf("\n");
    }
    for (const stride::logs::TrackingMiss& m : misses) {
      if (m.kind == stride::logs::TrackingMiss::Kind::Component)
        std::printf("  segment %d: %s %.3f, commanded %.3f (tolerance %.3f)\n", m.segment,
                    stride::logs::componentName(m.component), m.achieved, m.commanded, m.tolerance);
      else
        std::printf("  segment %d: %s\n", m.segment,
                    m.kind == stride::logs::TrackingMiss::Kind::Fell ? "fell" : "no states");
    }
    const bool tracked = misses.empty() && !run.fell();
    std::printf("stride-drive: %s\n", tracked      ? "every segment tracked its command"
                                      : run.fell() ? "the robot fell"
                                                   : "some segments missed their command");
    if (!summary.empty()) writeJson(summary, run, segments, tracked, timing);
    if (!options.log.empty()) std::printf("log: %s\n", options.log.c_str());
    if (run.sim.diverged) return 3;
    if (run.fell()) return 4;
    return check && !tracked ? 1 : 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "stride-drive: %s\n", e.what());
    return 2;
  }
}
