// stride-sim: the mock robot (sim/README.md). Integrates the robot with contacts found from the
// ground's geometry, applies the controller's latest policy at every step, publishes estimates.
//   stride-sim --robot config/robots/stride_quad/stride_quad.yaml --lockstep --rate 200
//   stride-sim --robot ... --rate 1000 --push 6:0.1:15,0,0          real time, with a push

#include <time.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <cstdlib>

#include "config/command_line.hpp"
#include "config/describe_model.hpp"
#include "sim/command_line.hpp"
#include "sim/sim_node.hpp"
#include "terrain/terrain_file.hpp"

namespace {
std::atomic<bool> g_stop{false};
void onSignal(int) {
  g_stop = true;
}

std::int64_t monotonicMicros() {
  timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1000000 + ts.tv_nsec / 1000;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"stride-sim: mock robot for stride-mpc (terrain, unilateral contacts, friction)"};
  stride::commandLineConventions(app, "stride-sim");
  std::string robot_yaml, url, summary, terrain_name;
  bool lockstep = false, print_model = false;
  std::vector<std::string> robots_dirs;
  double duration = 10.0, timeout = 5.0, drop_height = 0.0;
  std::vector<std::string> pushes;
  stride::sim::SimOptions sim;
  stride::sim::SimNodeOptions node_options;
  std::string key_file;
  app.add_option("--robot", robot_yaml, "robot YAML (config/robots/)")->required();
  app.add_flag("--lockstep", lockstep,
               "advance one state period only after the controller answered (deterministic)");
  app.add_option("--rate", node_options.state_rate_hz,
                 "state estimates per second (lock-step: the controller's rate)");
  app.add_option("--duration", duration, "seconds of simulated time");
  app.add_option("--url", url, "LCM URL (default: LCM_DEFAULT_URL)");
  app.add_option("--dt", sim.dt, "physics step [s]");
  app.add_option("--substeps", sim.substeps, "substeps per physics step");
  auto* terrain_option = app.add_option(
      "--terrain", terrain_name,
      "the world: a terrain file, or a name in config/terrain/ (stairs_anymal_c, ...); default: "
      "flat ground at --ground (terrain/README.md)");
  app.add_option("--ground", sim.ground_height,
                 "height of the flat ground [m] (the robot starts standing on it)")
      ->excludes(terrain_option);
  app.add_option("--drop-height", drop_height, "start this high above standing on the terrain [m]");
  app.add_option("--map-rate", node_options.map.rate_hz,
                 "elevation maps (stride.terrain_t) per second of robot time; 0: none (default: 10 "
                 "with --terrain or --ground, else none)");
  app.add_option("--map-size", node_options.map.size, "side of the square map around the base [m]");
  app.add_option("--map-resolution", node_options.map.resolution, "the map's cell side [m]");
  app.add_option("--map-noise", node_options.map.noise, "noise of each cell's height, std [m]");
  app.add_option("--map-holes", node_options.map.holes,
                 "probability that a cell is unknown (NaN) in a map");
  app.add_option("--map-latency", node_options.map.latency,
                 "a map shows the terrain around where the robot was this long ago [s]");
  app.add_option("--map-channel", node_options.map.channel, "the maps' LCM channel");
  stride::sim::MockRobotArgs mock_args;
  stride::sim::addMockRobotOptions(app, node_options, sim, mock_args);
  app.add_option("--push", pushes, "a push on the base: start:duration:fx,fy,fz (repeatable)");
  app.add_option("--lockstep-timeout", timeout, "lock-step: wall seconds to wait for an answer");
  app.add_option("--hold-kp", node_options.hold_kp,
                 "the robot's joint PD (before the first policy, standing down) [Nm/rad] "
                 "(default: the robot YAML's joint_pd)");
  app.add_option("--hold-kd", node_options.hold_kd, "its damping [Nm s/rad]");
  app.add_option(
      "--stand-down-grace", node_options.stand_down.grace,
      "seconds past a policy's end, its last knot held, before the robot stands down (0)");
  app.add_option("--stand-down-ramp", node_options.stand_down.ramp,
                 "seconds from the robot as it is to the default posture (0.3)");
  app.add_option("--summary", summary, "write the run's summary as JSON here");
  app.add_option("--robots-dir", robots_dirs,
                 "where package:// URIs of the robot YAML are looked for before ROS_PACKAGE_PATH "
                 "(repeatable)");
  app.add_option("--key-file", key_file,
                 "the shared key (64 hex digits, mode 0600; stride-keygen makes one): states and "
                 "maps are signed with it, and only policies signed with it are taken "
                 "(messages/README.md, \"Signing\"); without one the wire is unauthenticated");
  double signature_window = static_cast<double>(stride::msg::kFreshnessWindowMicros) * 1e-6;
  app.add_option("--signature-window", signature_window,
                 "seconds a signed policy's timestamp may be from this host's clock, behind or "
                 "ahead (0.5; messages/README.md, \"Freshness\")")
      ->check(CLI::Range(0.001, 60.0));
  app.add_flag("--print-model", print_model,
               "print the robot in wire order (q, v, u, contacts, limits) and exit");
  app.footer(
      "Exit status: 0 the run ended upright; 1 an error (robot, LCM); 2 a usage error; 3 the "
      "simulation diverged; 4 the robot fell (sim/README.md).");
  if (const int status = stride::parseCommandLine(app, argc, argv); status >= 0) return status;

  if (!stride::sim::finishMockRobotOptions(mock_args, node_options, "stride-sim")) return 2;
  std::signal(SIGINT, onSignal);
  std::signal(SIGTERM, onSignal);
  try {
    for (const std::string& p : pushes) {
      stride::sim::Push push;
      if (!stride::sim::parsePush(p, push)) {
        std::fprintf(stderr, "stride-sim: --push '%s': expected start:duration:fx,fy,fz\n",
                     p.c_str());
        return 2;
      }
      node_options.pushes.pushes.push_back(push);
    }
    const stride::Robot robot = stride::loadRobot(robot_yaml, robots_dirs);
    if (!terrain_name.empty())
      sim.terrain = std::make_shared<const stride::terrain::Terrain>(
          stride::terrain::loadTerrainFile(stride::terrain::findTerrainFile(
              terrain_name, stride::terrain::terrainConfigDirs())));
    node_options.map.seed = node_options.seed + 2;
    // The default world, the flat ground at 0, has nothing to map: no 400 kB/s of flat maps on
    // the bus of every run that did not ask for a world (sim/README.md, "Terrain map").
    if (app.count("--map-rate") == 0 && app.count("--terrain") == 0 && app.count("--ground") == 0)
      node_options.map.rate_hz = 0.0;
    if (print_model) {
      std::printf("%s", stride::describeModel(robot).c_str());
      return 0;
    }
    node_options.key = stride::msg::keyForProgram(key_file, "stride-sim");
    node_options.signature_window = signature_window;
    url = stride::lcmUrl(url);
    if (url.empty()) return stride::noLcmUrl("stride-sim", "pass --url");
    lcm::LCM lcm(url);
    if (!lcm.good()) {
      std::fprintf(stderr, "stride-sim: cannot open LCM '%s'\n", url.c_str());
      return 2;
    }
    if (!lockstep) node_options.utime_base = monotonicMicros();
    stride::LcmPublisher publisher(lcm);
    stride::sim::SimNode node(robot, sim, node_options, publisher);
    node.subscribe(lcm);
    // Standing on the terrain under its default place (sim/README.md, "Terrain").
    const Eigen::VectorXd q =
        stride::sim::startingPose(robot, node.simulator().terrain(), drop_height);
    node.reset(q, Eigen::VectorXd::Zero(robot.model.nv));
    std::printf(
        "stride-sim: %s, %s, %.0f Hz physics, estimates at %.0f Hz, %.1f s, terrain '%s', '%s'\n",
        robot.name.c_str(), lockstep ? "lock-step" : "real time", 1.0 / sim.dt,
        node_options.state_rate_hz, duration, node.simulator().terrain().name().c_str(),
        url.c_str());
    if (const std::string differs = stride::sim::describeMockRobot(node_options, sim);
        !differs.empty())
      std::printf("stride-sim: the robot differs from a perfect one: %s\n", differs.c_str());
    std::fflush(stdout);

    const int per_state = node.stepsPerState();
    if (lockstep) {
      while (!g_stop && node.simulator().time() < duration - 1e-9) {
        const std::int64_t stamp = node.publishState();
        if (stamp >= 0) {
          const std::int64_t give_up = monotonicMicros() + static_cast<std::int64_t>(timeout * 1e6);
          while (!node.answered(stamp) && !g_stop) {
            const std::int64_t left_ms = (give_up - monotonicMicros()) / 1000;
            if (left_ms <= 0) {
              node.countLockstepTimeout();
              break;
            }
            if (lcm.handleTimeout(static_cast<int>(std::min<std::int64_t>(left_ms, 100))) < 0) {
              std::fprintf(stderr, "stride-sim: LCM receive failed\n");
              g_stop = true;
            }
          }
        }
        if (!node.advance(per_state)) break;  // fell or diverged: the run is over
      }
    } else {
      const long step_ns = std::lround(sim.dt * 1e9);
      timespec next;
      clock_gettime(CLOCK_MONOTONIC, &next);
      long steps = 0;
      while (!g_stop && node.simulator().time() < duration - 1e-9) {
        if (steps % per_state == 0) node.publishState();
        while (lcm.handleTimeout(0) > 0) {
        }
        if (!node.advance(1)) break;
        ++steps;
        next.tv_nsec += step_ns;
        while (next.tv_nsec >= 1000000000L) {
          next.tv_nsec -= 1000000000L;
          ++next.tv_sec;
        }
        clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, nullptr);
      }
    }
    // The fallen pose goes out too: a log then shows the fall the run stopped at (the estimate
    // of the last step before it may still look upright).
    if (node.stats().fell) node.publishState();
    node.writeSummary(summary);
    if (node.stats().diverged) {
      std::fprintf(stderr, "stride-sim: the simulation diverged at t = %.3f s (stopped)\n",
                   node.simulator().time());
      return 3;
    }
    // A fall is the run's outcome, not an error of the program, but whoever started the run (a
    // script, CI, a batch of drives) must see it without parsing the text: its own status.
    if (node.stats().fell) {
      std::printf("stride-sim: the robot fell at t = %.3f s: run stopped\n",
                  node.simulator().time());
      return 4;
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "stride-sim: %s\n", e.what());
    return 1;
  }
  return 0;
}
