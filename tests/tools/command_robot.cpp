// Test helper for stride-teleop's multi-process tests (teleop_script.sh, teleop_pty.py):
//   command-robot run [--duration S] [--rate HZ] [--speed X]   a robot that follows the commands
//   command-robot check LOG SCRIPT --rate HZ --duration S      the commands in a log against a
//   script command-robot dump LOG                                     the commands in a log, one a
//   line
//
// `run` publishes state estimates of a floating base (no joints) at --rate per second of robot
// time, --speed times faster than the wall clock, and moves the base exactly as the newest command
// says (vx, vy in the heading frame, yaw_rate, body height): a perfect robot, so stride-log-summary
// --check-tracking must pass on its log. Its LCM URL comes from LCM_DEFAULT_URL; it refuses udpm
// unless only loopback is visible (a private network namespace, LCM-NOTES.md).

#include <poll.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <set>
#include <string>
#include <vector>

#include "controller/command_script.hpp"
#include "messages/validate.hpp"

namespace {

bool onlyLoopback() {
  std::ifstream f("/proc/net/dev");
  std::string line;
  int n = 0;
  for (int i = 0; std::getline(f, line); ++i) {
    if (i < 2) continue;
    const auto colon = line.find(':');
    if (colon == std::string::npos) continue;
    const auto start = line.find_first_not_of(' ');
    if (line.substr(start, colon - start) != "lo") return false;
    ++n;
  }
  return n == 1;
}

double wallSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

class Robot {
 public:
  void onCommand(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    stride::command_t m{};
    const int size = static_cast<int>(rbuf->data_size);
    if (stride::msg::checkCommandWire(rbuf->data, size) != stride::msg::Reject::None ||
        m.decode(rbuf->data, 0, size) < 0 ||
        stride::msg::checkCommand(m) != stride::msg::Reject::None)
      return;
    command_ = m;
    ++commands_;
  }

  stride::robot_state_t state(std::int64_t utime) const {
    stride::robot_state_t s;
    s.utime = utime;
    s.model_hash = 0;  // a bare base: no model to name (stride-teleop learns the first state's)
    s.session = 1;
    s.nq = 7;
    s.nv = 6;
    s.q = {x_, y_, 0.3 + command_.body_height, 0, 0, std::sin(yaw_ / 2), std::cos(yaw_ / 2)};
    // The base frame is the heading frame (no tilt): the command is the base velocity.
    s.v = {command_.vx, command_.vy, 0, 0, 0, command_.yaw_rate};
    s.ncontacts = 0;
    return s;
  }

  void step(double dt) {
    x_ += (std::cos(yaw_) * command_.vx - std::sin(yaw_) * command_.vy) * dt;
    y_ += (std::sin(yaw_) * command_.vx + std::cos(yaw_) * command_.vy) * dt;
    yaw_ += command_.yaw_rate * dt;
  }
  long commands() const { return commands_; }

 private:
  stride::command_t command_{};
  double x_ = 0, y_ = 0, yaw_ = 0;
  long commands_ = 0;
};

int run(double duration, double rate, double speed, std::int64_t utime0) {
  const char* env = std::getenv("LCM_DEFAULT_URL");
  const std::string url = env != nullptr ? env : "";
  const bool udpm = url.rfind("udpm://", 0) == 0;
  if (url.empty() || (udpm && (!onlyLoopback() || url.find("ttl=0") == std::string::npos))) {
    std::fprintf(stderr,
                 "command-robot: needs LCM_DEFAULT_URL, and udpm only with ttl=0 in a private "
                 "network namespace (only lo in /proc/net/dev)\n");
    return 1;
  }
  lcm::LCM lcm(url);
  if (!lcm.good()) return 1;
  Robot robot;
  lcm.subscribe("STRIDE_COMMAND", &Robot::onCommand, &robot)->setQueueCapacity(1000);
  const int n = static_cast<int>(std::llround(duration * rate));
  const double dt = 1.0 / rate, start = wallSeconds();
  std::vector<unsigned char> buf;
  for (int i = 0; i <= n; ++i) {
    const stride::robot_state_t s = robot.state(utime0 + std::llround(i * 1e6 / rate));
    buf.resize(static_cast<std::size_t>(s.getEncodedSize()));
    s.encode(buf.data(), 0, static_cast<int>(buf.size()));
    lcm.publish("STRIDE_STATE", buf.data(), static_cast<unsigned>(buf.size()));
    // Until the next state is due on the wall clock, take in commands (the answer to this one).
    const double due = start + (i + 1) * dt / speed;
    for (double now = wallSeconds(); now < due; now = wallSeconds()) {
      pollfd p{lcm.getFileno(), POLLIN, 0};
      if (poll(&p, 1, static_cast<int>(std::ceil((due - now) * 1e3))) > 0) lcm.handle();
    }
    robot.step(dt);
  }
  std::printf("command-robot: %d states, %ld commands received\n", n + 1, robot.commands());
  return 0;
}

struct LoggedCommand {
  std::int64_t utime;
  stride::command_t m{};
};

std::vector<LoggedCommand> readCommands(const std::string& path, std::set<std::int64_t>* states) {
  lcm::LogFile log(path, "r");
  std::vector<LoggedCommand> out;
  if (!log.good()) return out;
  for (const lcm::LogEvent* e = log.readNextEvent(); e != nullptr; e = log.readNextEvent()) {
    if (e->channel == "STRIDE_COMMAND") {
      LoggedCommand c;
      if (stride::msg::checkCommandWire(e->data, e->datalen) != stride::msg::Reject::None ||
          c.m.decode(e->data, 0, e->datalen) < 0)
        continue;
      c.utime = c.m.utime;
      out.push_back(c);
    } else if (e->channel == "STRIDE_STATE" && states != nullptr) {
      stride::robot_state_t s;
      if (s.decode(e->data, 0, e->datalen) >= 0) states->insert(s.utime);
    }
  }
  return out;
}

int dump(const std::string& path) {
  for (const LoggedCommand& c : readCommands(path, nullptr))
    std::printf("%lld %.17g %.17g %.17g %s %.17g\n", static_cast<long long>(c.utime), c.m.vx,
                c.m.vy, c.m.yaw_rate, c.m.gait.empty() ? "-" : c.m.gait.c_str(), c.m.body_height);
  return 0;
}

// Every command answers a logged state, on the 1/rate grid from the first state, with exactly the
// script's entry in force at that state's time, and none at or after the duration.
int check(const std::string& path, const std::string& script_path, double rate, double duration) {
  std::set<std::int64_t> states;
  const std::vector<LoggedCommand> commands = readCommands(path, &states);
  const std::vector<stride::ScriptedCommand> script = stride::loadCommandScript(script_path);
  int failures = 0;
  const auto fail = [&](const std::string& what) {
    if (++failures <= 10) std::printf("FAIL: %s\n", what.c_str());
  };
  if (states.empty() || commands.empty()) {
    std::printf("FAIL: %zu states and %zu commands in the log\n", states.size(), commands.size());
    return 1;
  }
  const std::int64_t t0 = *states.begin();
  const auto period = static_cast<std::int64_t>(std::llround(1e6 / rate));
  const auto expected = static_cast<std::size_t>((std::llround(duration * 1e6) - 1) / period + 1);
  if (commands.size() != expected)
    fail(std::to_string(commands.size()) + " commands, expected " + std::to_string(expected));
  std::set<int> entries;
  std::size_t lost = 0;  // commands whose state the logger did not record
  for (std::size_t k = 0; k < commands.size(); ++k) {
    const LoggedCommand& c = commands[k];
    const std::string at =
        "command " + std::to_string(k) + " (utime " + std::to_string(c.utime) + ")";
    // A state the logger lost (UDP, a busy machine: it happens under ctest -j2) leaves its command
    // without a logged state; the stamp must still be on the states' grid (checked below).
    if (!states.count(c.utime)) {
      if (c.utime > *states.rbegin()) fail(at + ": no state has its stamp");
      ++lost;
    }
    if (c.utime != t0 + static_cast<std::int64_t>(k) * period)
      fail(at + ": expected at " + std::to_string(t0 + static_cast<std::int64_t>(k) * period));
    const double t = static_cast<double>(c.utime - t0) / 1e6;
    if (t >= duration) fail(at + ": after the duration");
    const int i = stride::commandAt(script, t);
    entries.insert(i);
    const stride::ScriptedCommand& e = script[i];
    if (c.m.vx != e.vx || c.m.vy != e.vy || c.m.yaw_rate != e.yaw_rate || c.m.gait != e.gait ||
        c.m.body_height != e.body_height)
      fail(at + ": not entry " + std::to_string(i));
  }
  if (entries.size() != script.size())
    fail("only " + std::to_string(entries.size()) + " of the script's entries were sent");
  if (lost > commands.size() / 20)
    fail(std::to_string(lost) + " commands answer states missing from the log: more than 5 %");
  if (failures > 0) return 1;
  std::printf(
      "PASS: %zu commands on the %lld us grid of %zu states (%zu states not logged), every entry "
      "on time\n",
      commands.size(), static_cast<long long>(period), states.size(), lost);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"command-robot: a test robot and log checks for stride-teleop"};
  app.require_subcommand(1);
  double duration = 5.0, rate = 200.0, speed = 1.0, command_rate = 20.0;
  long long utime0 = 5000000;
  std::string log, script;
  CLI::App* run_cmd = app.add_subcommand("run", "publish states, follow the commands");
  run_cmd->add_option("--duration", duration, "robot time [s]");
  run_cmd->add_option("--rate", rate, "states per second of robot time");
  run_cmd->add_option("--speed", speed, "robot time per wall time");
  run_cmd->add_option("--start-utime", utime0);
  CLI::App* check_cmd = app.add_subcommand("check", "a log's commands against a script");
  check_cmd->add_option("log", log)->required();
  check_cmd->add_option("script", script)->required();
  check_cmd->add_option("--rate", command_rate, "stride-teleop's --rate");
  check_cmd->add_option("--duration", duration, "stride-teleop's --duration")->required();
  CLI::App* dump_cmd = app.add_subcommand("dump", "a log's commands, one a line");
  dump_cmd->add_option("log", log)->required();
  CLI11_PARSE(app, argc, argv);
  if (*run_cmd) return run(duration, rate, speed, utime0);
  if (*check_cmd) return check(log, script, command_rate, duration);
  return dump(log);
}
