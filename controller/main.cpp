// stride-mpc: the receding-horizon KKT-DDP controller daemon (README, controller/README.md).
//   stride-mpc --config config/controller/stride_quad.yaml              real time, LCM in and out
//   stride-mpc --config ... --lockstep                                  ticks on state stamps
//   stride-mpc --config ... --replay session.lcmlog --output out.lcmlog  a logged session, offline

#include <CLI/CLI.hpp>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <lcm/lcm-cpp.hpp>
#include <memory>

#include "config/command_line.hpp"
#include "config/describe_model.hpp"
#include "controller/run_loop.hpp"
#include "messages/wire_auth.hpp"

namespace {
std::atomic<bool> g_stop{false};
void onSignal(int) {
  g_stop = true;
}
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"stride-mpc: real-time whole-body MPC (KKT-DDP) over LCM"};
  stride::commandLineConventions(app, "stride-mpc");
  std::string config_path, replay, output, input_url, output_url, summary, key_file;
  bool lockstep = false, print_model = false;
  double duration = 0.0, slow_host = 1.0;
  std::vector<std::string> robots_dirs;
  app.add_option("--config", config_path, "controller YAML (config/controller/)")->required();
  app.add_option("--replay", replay, "run on the states of this LCM log, as fast as possible");
  app.add_option("--output", output, "with --replay: the log to write policies and status to");
  app.add_flag("--lockstep", lockstep, "tick on state stamps (with stride-sim --lockstep)");
  app.add_option("--input-url", input_url, "LCM URL to receive on (overrides the YAML)");
  app.add_option("--output-url", output_url, "LCM URL to publish on (overrides the YAML)");
  app.add_option("--duration", duration, "stop after this many seconds (0: on SIGINT/SIGTERM)");
  app.add_option("--summary", summary, "write the run's counters and latencies as JSON here");
  app.add_option("--key-file", key_file,
                 "the shared key (overrides lcm.key_file): policies and status are signed with "
                 "it, and only states, commands, plans and maps signed with it are taken "
                 "(messages/README.md, \"Signing\"); a replay reads its log unverified");
  app.add_option("--robots-dir", robots_dirs,
                 "where package:// URIs of the robot YAML are looked for before ROS_PACKAGE_PATH "
                 "(repeatable)");
  app.add_flag("--print-model", print_model,
               "print the robot in wire order (q, v, u, contacts, limits) and exit");
  app.add_option("--emulate-slow-host", slow_host,
                 "testing: every solver phase takes this many times its duration (busy), as on a "
                 "slower host, to exercise the overload handling")
      ->check(CLI::Range(1.0, 10.0));
  app.footer(
      "Exit status: 0 ran until stopped (or the log's end); 1 an error: configuration, robot, a "
      "replay log that cannot be read, or states that came and were all rejected (another "
      "robot's: stderr says which); 2 a usage error or an LCM URL that cannot be opened.");
  if (const int status = stride::parseCommandLine(app, argc, argv); status >= 0) return status;

  std::signal(SIGINT, onSignal);
  std::signal(SIGTERM, onSignal);
  try {
    stride::ControllerConfig config = stride::loadControllerConfig(config_path);
    config.robots_dirs = robots_dirs;
    config.emulated_slowdown = slow_host;
    if (print_model) {
      const stride::Robot robot = stride::loadRobot(config.robot_yaml, robots_dirs);
      std::printf("%s", stride::describeModel(robot).c_str());
      std::printf("gaits:");
      for (const std::string& g : stride::gaitNames(static_cast<int>(robot.contacts.size())))
        std::printf(" %s", g.c_str());
      std::printf("\n");
      return 0;
    }
    if (!key_file.empty()) config.key_file = key_file;
    if (!replay.empty()) {
      config.key_file.clear();  // a file, not a bus: read as recorded, signatures stripped
    } else if (config.key_file.empty()) {
      stride::msg::keyForProgram("", "stride-mpc");  // says the wire is unauthenticated
    }
    if (!input_url.empty()) config.input_url = input_url;
    if (!output_url.empty()) config.output_url = output_url;
    const bool replaying = !replay.empty();
    if (replaying) {
      config.input_url = "file://" + replay + "?speed=0";
      if (output.empty()) output = replay + ".mpc";
      config.output_url = "file://" + output + "?mode=w";
    }
    // LCM must never fall back to multicast on the host network by accident: a URL is explicit
    // (YAML, flag or LCM_DEFAULT_URL).
    config.input_url = stride::lcmUrl(config.input_url);
    if (config.output_url.empty()) config.output_url = config.input_url;
    if (config.input_url.empty())
      return stride::noLcmUrl("stride-mpc", "set lcm.input in the YAML, pass --input-url,");
    lcm::LCM in(config.input_url);
    if (!in.good() && replaying) {
      std::fprintf(stderr, "stride-mpc: cannot read the log '%s'\n", replay.c_str());
      return 1;
    }
    if (!in.good()) {
      std::fprintf(stderr, "stride-mpc: cannot open LCM input '%s'\n", config.input_url.c_str());
      return 2;
    }
    std::unique_ptr<lcm::LCM> separate_out;
    lcm::LCM* out = &in;
    if (config.output_url != config.input_url) {
      separate_out = std::make_unique<lcm::LCM>(config.output_url);
      if (!separate_out->good()) {
        std::fprintf(stderr, "stride-mpc: cannot open LCM output '%s'\n",
                     config.output_url.c_str());
        return 2;
      }
      out = separate_out.get();
    }
    stride::LcmPublisher publisher(*out);
    const bool on_stamps = replaying || lockstep;
    stride::MpcNode node(config, publisher,
                         on_stamps ? stride::TimeSource::Stamps : stride::TimeSource::RealTime);
    node.subscribe(in, /*watch_policies=*/!replaying);  // a log holds the recorded controller's
    // A replay's output is a file, never a bus a robot follows: a fixed source id keeps two
    // replays of one log bit-identical.
    if (replaying) node.setSourceId(node.wireModel().hash);
    std::printf(
        "stride-mpc: %s, %s, %s, %d iteration(s) per tick at %.0f Hz, "
        "%s mode, in '%s', out '%s'\n",
        node.mpc().robot().name.c_str(), stride::describeHorizon(config.locomotion).c_str(),
        stride::toString(config.solver), config.max_iterations, config.rate_hz,
        replaying ? "replay" : (lockstep ? "lock-step" : "real-time"), config.input_url.c_str(),
        config.output_url.c_str());
    const std::string datagram =
        stride::policyDatagramWarning(static_cast<int>(node.mpc().policy().getEncodedSize()),
                                      config.policy_knots, config.output_url);
    if (!datagram.empty()) std::fprintf(stderr, "stride-mpc: warning: %s\n", datagram.c_str());
    std::fflush(stdout);

    stride::RunOptions options;
    options.duration = duration;
    options.stop = &g_stop;
    if (on_stamps) {
      stride::runOnStamps(node, in, options);
    } else {
      stride::applyRealTimeSettings(config.cpu, config.fifo_priority);
      stride::runRealTime(node, in, options);
    }
    stride::writeSummary(node, summary);
    if (publisher.failures() > 0)
      std::fprintf(stderr, "stride-mpc: %ld publishes failed\n", publisher.failures());
    // A run that accepted no state computed nothing: a log of another robot or of other
    // channels, or another robot's estimator live, must not look like a successful run.
    if (node.acceptedStates() == 0 && node.rejected() > 0) {
      std::fprintf(stderr, "stride-mpc: %s accepted none of the %lld states on '%s':",
                   replaying ? "the replay" : "the run", static_cast<long long>(node.rejected()),
                   config.state_channel.c_str());
      for (int r = 1; r < stride::msg::kRejectReasons; ++r) {
        const auto reason = static_cast<stride::msg::Reject>(r);
        if (node.rejected(reason) > 0)
          std::fprintf(stderr, " %lld %s;", static_cast<long long>(node.rejected(reason)),
                       stride::msg::describe(reason));
      }
      char hash[17];
      stride::msg::formatHash(node.wireModel().hash, hash);
      std::fprintf(stderr, " the model expects nq %d, nv %d (%s, hash %s)\n", node.wireModel().nq,
                   node.wireModel().nv, node.mpc().robot().name.c_str(), hash);
      return 1;
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "stride-mpc: %s\n", e.what());
    return 1;
  }
  return 0;
}
