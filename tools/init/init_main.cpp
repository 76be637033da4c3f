// stride-init: bring your own robot (issue 34; tools/init/README.md). From a URDF and an SRDF it
// writes the robot YAML, a controller YAML and a command script, loads them as stride-mpc would,
// drives the robot in lock-step (tools/drive/closed_loop.hpp) and prints a report card.
//   stride-init --urdf URI --srdf URI [--posture NAME] [--name N] [--feet F1,F2,...]
//               [--sole-half-extents X,Y] [--torque-limit NM] [--robots-dir DIR]... --out DIR
//               [--force] [--no-drive]
// Exit status: 0 every segment tracked and no fall (or --no-drive and the files load); 1 a
// segment missed its command or the robot fell; 2 bad input (the message says what to pass).

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "config/command_line.hpp"
#include "config/robot_config.hpp"
#include "controller/command_script.hpp"
#include "locomotion/gait.hpp"
#include "sim/disturbances.hpp"
#include "tools/drive/closed_loop.hpp"
#include "tools/init/robot_setup.hpp"

namespace {

namespace fs = std::filesystem;

double median(std::vector<double> x) {
  if (x.empty()) return 0.0;
  std::sort(x.begin(), x.end());
  return x[x.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"stride-init: set up a new robot from its URDF and SRDF, drive it, report"};
  stride::commandLineConventions(app, "stride-init");
  stride::init::InitInput in;
  in.config_dir = STRIDE_CONFIG_DIR;
  std::string sole;
  bool force = false, no_drive = false;
  app.add_option("--urdf", in.urdf_uri, "the URDF: a path or package://NAME/...")->required();
  app.add_option("--srdf", in.srdf_uri, "the SRDF (feet, postures): a path or package://...")
      ->required();
  app.add_option("--posture", in.posture,
                 "the SRDF group_state to stand in (default: standing, half_sitting or "
                 "straight_standing, the first found)");
  app.add_option("--name", in.name, "the robot's name and the files' (default: the URDF's)");
  app.add_option("--feet", in.feet, "the foot links (default: the SRDF's end effectors)")
      ->delimiter(',');
  app.add_option("--sole-half-extents", sole,
                 "X,Y: flat soles of this half length and width [m] (default: from the feet's "
                 "collision boxes; point feet without one)");
  app.add_option("--torque-limit", in.torque_limit,
                 "every joint's torque limit [N m] (required when the URDF's efforts are "
                 "placeholders)");
  std::vector<std::string> locks;
  app.add_option(
      "--lock", locks,
      "NAME[=VALUE]: hold this joint at VALUE [rad or m] (default 0), fixed in the model "
      "(grippers, a head; repeatable). The leaders of the URDF's <mimic> joints are "
      "locked at 0 unless given");
  app.add_option("--robots-dir", in.robots_dirs,
                 "where package:// URIs are looked for before ROS_PACKAGE_PATH (repeatable)");
  app.add_option("--out", in.out_dir, "the folder to write the three files in")->required();
  app.add_option("--config-dir", in.config_dir,
                 "the shipped config/ folder: the controller templates and their robots");
  app.add_flag("--force", force, "overwrite existing files");
  app.add_flag("--no-drive", no_drive, "write and check the files, do not drive");
  if (const int status = stride::parseCommandLine(app, argc, argv); status >= 0) return status;
  for (std::string& d : in.robots_dirs) d = fs::absolute(d).string();
  for (const std::string& lock : locks) {
    const std::size_t eq = lock.find('=');
    double value = 0.0;
    if (eq != std::string::npos) {
      std::istringstream v(lock.substr(eq + 1));
      if (!(v >> value) || !(v >> std::ws).eof() || !std::isfinite(value)) {
        std::fprintf(stderr, "stride-init: --lock '%s': expected NAME or NAME=VALUE\n",
                     lock.c_str());
        return 2;
      }
    }
    in.locked[lock.substr(0, eq)] = value;
  }
  if (!sole.empty()) {
    double x = 0, y = 0;
    char comma = 0;
    std::istringstream s(sole);
    if (!(s >> x >> comma >> y) || comma != ',' || !(x > 0) || !(y > 0)) {
      std::fprintf(stderr, "stride-init: --sole-half-extents '%s': expected X,Y > 0 [m]\n",
                   sole.c_str());
      return 2;
    }
    in.sole_given = true;
    in.sole_half_extents << x, y;
  }
  if (app.count("--torque-limit") && !(in.torque_limit > 0.0)) {
    std::fprintf(stderr, "stride-init: --torque-limit must be positive\n");
    return 2;
  }

  stride::init::Setup setup;
  std::vector<std::string> files;
  stride::Robot robot;
  try {
    setup = stride::init::analyse(in);
    files = stride::init::outputFiles(in, setup.name);
    for (const std::string& f : files)
      if (fs::exists(f) && !force) {
        std::fprintf(stderr,
                     "stride-init: '%s' exists: not overwritten (pass --force to overwrite it)\n",
                     f.c_str());
        return 2;
      }
    for (const std::string& note : setup.notes) std::printf("  %s\n", note.c_str());
    stride::init::writeFiles(in, setup);
    for (const std::string& note : setup.notes)
      if (note.rfind("policy_knots", 0) == 0) std::printf("  %s\n", note.c_str());
    std::printf("stride-init: wrote %s, %s, %s\n", files[0].c_str(), files[1].c_str(),
                files[2].c_str());
    // The final check: the files load as stride-mpc and stride-drive load them.
    robot = stride::loadRobot(files[0], in.robots_dirs);
    const stride::ControllerConfig check = stride::loadControllerConfig(files[1]);
    stride::checkScriptGaits(stride::loadCommandScript(files[2]), files[2],
                             stride::gaitNames(static_cast<int>(robot.contacts.size())),
                             "the robot of '" + files[1] + "'");
    (void)check;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "stride-init: %s\n", e.what());
    return 2;
  }

  const double com = stride::comOutsideSupport(robot, robot.default_q);
  std::printf("\nreport card: %s (%.2f kg, %zu %s feet, leg %.3f m; template %s, x%.3f timing)\n",
              setup.name.c_str(), setup.mass, setup.feet.size(),
              setup.feet.front().dim == 6 ? "flat" : "point", setup.leg_length,
              setup.template_name.c_str(), setup.ratio);
  std::printf("  posture   '%s': centre of mass %.1f mm %s the support polygon%s\n",
              setup.posture.c_str(), std::abs(com) * 1000, com <= 0 ? "inside" : "outside",
              setup.corrected_joints.empty() ? "" : " (hip pitches corrected)");
  if (no_drive) return 0;

  try {
    stride::ControllerConfig config = stride::loadControllerConfig(files[1]);
    config.robots_dirs = in.robots_dirs;
    stride::drive::Options options;
    options.script = stride::loadCommandScript(files[2]);
    options.duration = options.script.back().at + 4.0;
    options.sim.map.rate_hz = 0.0;  // as stride-drive on flat ground: no elevation maps
    const stride::drive::Run run = stride::drive::run(config, options);
    std::vector<double> tick, prepare;
    for (const stride::drive::Sample& s : run.samples) {
      tick.push_back(s.tick_ms);
      prepare.push_back(s.prepare_ms);
    }
    const double period_ms = 1000.0 / config.rate_hz;
    const double share = (median(tick) + median(prepare)) / period_ms;
    std::printf(
        "  budget    tick p50 %.2f ms + preparation p50 %.2f ms = %.0f %% of the %.1f ms period "
        "(lock-step, this host)%s\n",
        median(tick), median(prepare), share * 100, period_ms, share > 1.0 ? "  OVER" : "");
    const std::vector<stride::logs::Segment> segments = run.segments();
    const std::vector<stride::logs::TrackingMiss> misses = stride::logs::checkTracking(segments);
    std::printf("  tracking  %6s %6s  %-5s %23s  %23s\n", "t0", "t1", "gait", "command [vx vy yaw]",
                "achieved");
    for (std::size_t i = 0; i < segments.size(); ++i) {
      const stride::logs::Segment& s = segments[i];
      bool missed = false;
      for (const stride::logs::TrackingMiss& m : misses)
        missed = missed || m.segment == static_cast<int>(i);
      std::printf("            %6.1f %6.1f  %-5s %+7.3f %+7.3f %+7.3f  ", s.t0, s.t1,
                  s.gait.c_str(), s.command[0], s.command[1], s.command[2]);
      if (s.samples > 0)
        std::printf("%+7.3f %+7.3f %+7.3f", s.achieved[0], s.achieved[1], s.achieved[2]);
      else
        std::printf("%23s", "-");
      std::printf("  %s\n", s.t1 - s.t0 < 2.0 ? "(short, not checked)"
                            : missed          ? "MISSED"
                                              : "tracked");
    }
    for (const stride::logs::TrackingMiss& m : misses)
      if (m.kind == stride::logs::TrackingMiss::Kind::Component)
        std::printf("            segment %d: %s %.3f, commanded %.3f (tolerance %.3f)\n", m.segment,
                    stride::logs::componentName(m.component), m.achieved, m.commanded, m.tolerance);
    std::printf("            %s; %lld fallbacks, %lld failed solves\n",
                run.fell() ? "the robot FELL" : "no fall",
                static_cast<long long>(run.mpc.fallbacks),
                static_cast<long long>(run.mpc.failed_solves));

    // The push: walking forward, a lateral push in 0.1 s of the impulse that gives the base's mass
    // (its body and what is fixed to it: the free-flyer's inertia) 0.3 m/s.
    stride::drive::Options push_options;
    push_options.sim.map.rate_hz = 0.0;
    push_options.script = {options.script[0], options.script[1], options.script[2]};
    push_options.script[1].at = 1.0;
    push_options.script[2].at = 2.0;
    const double push_at = 4.0, push_s = 0.1, base_mass = robot.model.inertias[1].m,
                 push_force = base_mass * 0.3 / push_s;
    stride::sim::Push push;
    push.start = push_at;
    push.duration = push_s;
    push.force = Eigen::Vector3d(0.0, push_force, 0.0);
    push_options.sim.pushes.pushes.push_back(push);
    push_options.duration = push_at + 3.0;
    const stride::drive::Run pushed = stride::drive::run(config, push_options);
    std::printf(
        "  push      %.1f N for %.1f s sideways (%.2f N s: 0.3 m/s of the base's %.2f kg; %.2f m/s "
        "of the robot's) at %.1f s, walking at %.2f m/s: %s\n",
        push_force, push_s, push_force * push_s, base_mass, push_force * push_s / setup.mass,
        push_at, push_options.script[2].vx, pushed.fell() ? "FELL" : "survived");
    const bool ok = misses.empty() && !run.fell() && !pushed.fell();
    std::printf("stride-init: %s\n",
                ok ? "every segment tracked, no fall: ready" : "not ready (see above)");
    if (ok) {
      // The next step: the two processes, in real time, its own script beside the controller's.
      std::string dirs;
      for (const std::string& d : in.robots_dirs) dirs += " --robots-dir " + d;
      std::printf("drive it: tools/demo.sh --config %s%s [--viz]\n", files[1].c_str(),
                  dirs.c_str());
    }
    return ok ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "stride-init: %s\n", e.what());
    return 2;
  }
}
