// stride-teleop: sends body velocity commands (stride.command_t) to stride-mpc, from the keyboard
// or from a command script played on the robot's clock (tools/README.md, "stride-teleop").
//   stride-teleop [--url URL] [--gaits quadruped|biped]       keyboard (stdin must be a terminal)
//   stride-teleop --commands script.yaml [--duration S]       a script, on the state stamps
//
// The controller decays to a stand when commands stop (its deadman), so both modes repeat the
// current command, at --rate: on CLOCK_MONOTONIC from the keyboard, once per 1/rate seconds of
// state stamps from a script.

#include <poll.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <lcm/lcm-cpp.hpp>
#include <optional>
#include <string>
#include <vector>

#include "config/command_line.hpp"
#include "config/robot_config.hpp"
#include "controller/command_script.hpp"
#include "messages/validate.hpp"
#include "messages/wire_auth.hpp"
#include "solver/contact/contact_set.hpp"
#include "stride/mpc_status_t.hpp"
#include "tools/teleop/keyboard_command.hpp"
#include "tools/teleop/raw_terminal.hpp"
#include "tools/teleop/script_player.hpp"

namespace {

using stride::teleop::GaitSet;

volatile std::sig_atomic_t g_stop = 0;
void onSignal(int) {
  g_stop = 1;
}

void installSignals() {
  // No SA_RESTART: a blocking poll() returns at once and the loop sees the flag.
  struct sigaction sa {};
  sa.sa_handler = onSignal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  sigaction(SIGHUP, &sa, nullptr);  // the terminal went away
}

std::int64_t monotonicMicros() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1000000 + ts.tv_nsec / 1000;
}

// Encodes, signs (with a key: messages/README.md, "Signing") and publishes commands; counts them
// and the failures.
class CommandSender {
 public:
  CommandSender(lcm::LCM& lcm, std::string channel, stride::msg::WireAuth& auth)
      : lcm_(lcm), channel_(std::move(channel)), auth_(auth) {}
  void send(const stride::command_t& c) {
    const int size = c.getEncodedSize();
    buffer_.resize(static_cast<std::size_t>(size) + stride::msg::kSignatureSize);
    c.encode(buffer_.data(), 0, size);
    const int n =
        auth_.send(channel_.c_str(), buffer_.data(), size, static_cast<int>(buffer_.size()));
    if (n > 0 && lcm_.publish(channel_, buffer_.data(), static_cast<unsigned>(n)) == 0)
      ++sent_;
    else
      ++failures_;
  }
  long sent() const { return sent_; }
  long failures() const { return failures_; }

 private:
  lcm::LCM& lcm_;
  std::string channel_;
  stride::msg::WireAuth& auth_;
  std::vector<unsigned char> buffer_;
  long sent_ = 0, failures_ = 0;
};

// ---- what became of the jumps ------------------------------------------------------------------

// The controller's statuses (mpc_status_t, on the status channel; with a key, signed with it): each
// jump asked for is said when refused (with the controller's reason) and when landed, on a line of
// its own (issue 45: a jump the robot cannot make is refused before take-off, and the operator is
// told why).
class JumpWatcher {
 public:
  explicit JumpWatcher(stride::msg::WireAuth& auth) : auth_(auth) {}
  void handle(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    const int size =
        auth_.receive(kSlot, channel.c_str(), static_cast<const std::uint8_t*>(rbuf->data),
                      static_cast<int>(rbuf->data_size), rbuf->recv_utime);
    if (size < 0 || stride::msg::checkStatusWire(rbuf->data, size) != stride::msg::Reject::None ||
        status_.decode(rbuf->data, 0, size) < 0)
      return;
    auth_.accept(kSlot);
    if (status_.jump_id <= 0 || (status_.jump_id == id_ && status_.jump_state == state_)) return;
    id_ = status_.jump_id;
    state_ = status_.jump_state;
    if (state_ == 4)
      std::printf("\nstride-teleop: jump #%d refused: %s\n", id_, status_.jump_refusal.c_str());
    else if (state_ == 3)
      std::printf("\nstride-teleop: jump #%d landed\n", id_);
    std::fflush(stdout);
  }

 private:
  static constexpr int kSlot = 1;  // the state channel's is 0 (ScriptInput)
  stride::msg::WireAuth& auth_;
  stride::mpc_status_t status_{};
  int id_ = 0;
  std::int8_t state_ = 0;
};

// ---- keyboard -----------------------------------------------------------------------------------

int runKeyboard(lcm::LCM& lcm, const std::string& channel, const std::string& status_channel,
                stride::msg::WireAuth& auth, GaitSet gaits,
                const stride::teleop::KeyboardLimits& limits, double rate_hz) {
  stride::teleop::KeyboardCommand keys(gaits, limits);
  CommandSender sender(lcm, channel, auth);
  JumpWatcher jumps(auth);
  lcm.subscribe(status_channel, &JumpWatcher::handle, &jumps);
  std::string gait_keys;
  const auto& names = stride::teleop::gaitNames(gaits);
  for (std::size_t i = 0; i < names.size(); ++i)
    gait_keys += (i ? ", " : "") + std::to_string(i + 1) + " " + names[i];
  std::printf(
      "stride-teleop: publishing on '%s' at %.0f Hz\n"
      "  W/S or Up/Down: vx +-%.2f   A/D: vy +-%.2f   Q/E or Left/Right: yaw +-%.2f   "
      "R/F: height +-%.3f\n"
      "  space: stop   gaits: %s   J: jump (dx %.2f, dy %.2f, dz %.2f m, yaw %.2f rad)   x or "
      "Ctrl-C: quit (sends a stand)\n",
      channel.c_str(), rate_hz, limits.step_vx, limits.step_vy, limits.step_yaw, limits.step_height,
      gait_keys.c_str(), limits.jump.dx, limits.jump.dy, limits.jump.dz, limits.jump.yaw);
  std::fflush(stdout);

  const auto period_us = static_cast<std::int64_t>(1e6 / rate_hz);
  std::int64_t last_stamp = 0;
  // Stamps must increase strictly (the controller drops the rest): two sends in one microsecond
  // take the next one.
  const auto send = [&] {
    last_stamp = std::max(monotonicMicros(), last_stamp + 1);
    sender.send(stride::toCommand(keys.command(), last_stamp));
    std::printf("\r%s", stride::teleop::statusLine(keys.command(), sender.sent()).c_str());
    std::fflush(stdout);
  };
  {
    stride::teleop::RawTerminal terminal(STDIN_FILENO);
    std::int64_t next = monotonicMicros();
    while (!g_stop) {
      const std::int64_t now = monotonicMicros();
      if (now >= next) {
        send();
        // After a stall (a suspended process), carry on from now rather than catching up in a
        // burst.
        next = std::max(next + period_us, now);
      }
      pollfd in[2] = {{STDIN_FILENO, POLLIN, 0}, {lcm.getFileno(), POLLIN, 0}};
      const auto wait_ms = static_cast<int>((next - monotonicMicros() + 999) / 1000);
      if (poll(in, 2, std::max(wait_ms, 0)) <= 0) continue;  // timeout or a signal
      if (in[1].revents & POLLIN) lcm.handleTimeout(0);      // the controller's statuses
      if (!(in[0].revents & POLLIN)) continue;
      char bytes[64];
      const ssize_t n = read(STDIN_FILENO, bytes, sizeof bytes);
      if (n == 0 || (n < 0 && errno != EINTR && errno != EAGAIN)) break;  // the terminal closed
      if (n < 0) continue;
      const auto event = keys.feed(bytes, static_cast<std::size_t>(n));
      if (event == stride::teleop::KeyboardCommand::Event::Quit) break;
      if (event == stride::teleop::KeyboardCommand::Event::Changed) next = monotonicMicros();
    }
    keys.stop();
    send();
  }  // the terminal is restored here, before the last newline
  std::printf("\nstride-teleop: sent %ld commands, the last a stand\n", sender.sent());
  if (sender.failures() > 0)
    std::fprintf(stderr, "stride-teleop: %ld publishes failed\n", sender.failures());
  return 0;
}

// ---- script -------------------------------------------------------------------------------------

std::string describeEntry(const stride::ScriptedCommand& c) {
  char line[160];
  std::snprintf(line, sizeof line,
                "%-5s vx %+.2f m/s  vy %+.2f m/s  yaw %+.2f rad/s  height %+.3f m", c.gait.c_str(),
                c.vx, c.vy, c.yaw_rate, c.body_height);
  return line;
}

// State estimates in, commands out. The robot's model is not known here, so the first plausible
// state fixes it (its model hash and sizes, read from the wire) and later ones must match; every
// state is size-checked before decoding and content-checked after, as every Stride program does.
class ScriptInput {
 public:
  ScriptInput(stride::teleop::ScriptPlayer& player, CommandSender& sender,
              stride::msg::WireAuth& auth, const char* until)
      : player_(player), sender_(sender), auth_(auth), until_(until) {}

  void handle(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    // The robot's clock only from the robot (with a key: signed with it).
    // With a key, a state whose signature is not fresh (a recording replayed) never moves the
    // script's clock (messages/README.md, "Freshness").
    const int size = auth_.receive(0, channel.c_str(), static_cast<const std::uint8_t*>(rbuf->data),
                                   static_cast<int>(rbuf->data_size), rbuf->recv_utime);
    if (size < 0) {
      ++rejected_;
      return;
    }
    if (model_.nq == 0 && !learnModel(rbuf->data, size)) {
      ++rejected_;
      return;
    }
    if (stride::msg::checkStateWire(rbuf->data, size, model_, kMaxContactFlags) !=
            stride::msg::Reject::None ||
        !stride::msg::decode(rbuf->data, size, state_) ||
        stride::msg::checkState(state_, model_.nq == model_.nv + 1) != stride::msg::Reject::None) {
      ++rejected_;
      return;
    }
    auth_.accept(0);
    play(state_.utime);
  }
  long rejected() const { return rejected_; }

 private:
  // A state's contact flags: at most the contact limit (solver/contact/contact_set.hpp).
  static constexpr int kMaxContactFlags = stride::kMaxContacts, kMaxDofs = 1000;

  bool learnModel(const void* buf, int size) {
    stride::msg::WireClaim claim;
    if (!stride::msg::readStateClaim(buf, size, claim)) return false;
    const int nq = claim.nq, nv = claim.nv;
    // A floating base (q holds a quaternion: nq = nv + 1, at least 7) or a fixed one (nq = nv).
    const bool floating = nq == nv + 1 && nq >= 7;
    if (nv < 1 || nv > kMaxDofs || !(floating || nq == nv)) return false;
    const stride::msg::WireModel model{claim.hash, nq, nv, 0, "the first state's"};
    if (stride::msg::checkStateWire(buf, size, model, kMaxContactFlags) !=
        stride::msg::Reject::None)
      return false;
    model_ = model;
    return true;
  }

  void play(std::int64_t utime) {
    const stride::teleop::ScriptPlayer::Step step = player_.onState(utime);
    const auto& script = player_.script();
    if (step.publish && step.entry_started) {
      // An entry shorter than the publishing period can fall between two commands: say so.
      for (int i = printed_ + 1; i < step.entry; ++i)
        std::printf("t %8.3f s  entry %d (at %.3f s) skipped: shorter than 1/rate\n",
                    player_.time(), i, script[i].at);
      std::printf("t %8.3f s  entry %d (at %.3f s): %s\n", player_.time(), step.entry,
                  script[step.entry].at, describeEntry(script[step.entry]).c_str());
      printed_ = step.entry;
    }
    if (step.script_done)
      std::printf("t %8.3f s  script done (last entry + hold); repeating the last entry until %s\n",
                  player_.time(), until_);
    if (step.publish) sender_.send(step.command);
    if (step.publish || step.script_done) std::fflush(stdout);
  }

  stride::teleop::ScriptPlayer& player_;
  CommandSender& sender_;
  stride::msg::WireAuth& auth_;
  const char* until_;  // what ends the repetition
  stride::robot_state_t state_;
  stride::msg::WireModel model_;  // nq 0 until the first plausible state
  int printed_ = -1;
  long rejected_ = 0;
};

int runScript(lcm::LCM& lcm, const std::string& channel, const std::string& state_channel,
              const std::string& status_channel, stride::msg::WireAuth& auth,
              const std::string& path, std::vector<stride::ScriptedCommand> script,
              const stride::teleop::ScriptPlayerOptions& options) {
  stride::teleop::ScriptPlayer player(std::move(script), options);
  CommandSender sender(lcm, channel, auth);
  JumpWatcher jumps(auth);
  lcm.subscribe(status_channel, &JumpWatcher::handle, &jumps);
  ScriptInput input(player, sender, auth,
                    options.duration > 0.0 ? "SIGINT/SIGTERM or --duration" : "SIGINT/SIGTERM");
  lcm::Subscription* sub = lcm.subscribe(state_channel, &ScriptInput::handle, &input);
  if (sub == nullptr) {
    std::fprintf(stderr, "stride-teleop: cannot subscribe to '%s'\n", state_channel.c_str());
    return 1;
  }
  sub->setQueueCapacity(1000);  // states may come at 1 kHz; each is handled at once
  std::printf(
      "stride-teleop: playing '%s' (%zu entries, %.3f s with the hold) on '%s', at most %.0f per "
      "second of robot time; waiting for states on '%s'\n",
      path.c_str(), player.script().size(), player.end(), channel.c_str(), options.rate_hz,
      state_channel.c_str());
  std::fflush(stdout);
  int status = 0;
  while (!g_stop && !player.finished()) {
    const int r = lcm.handleTimeout(100);
    if (r < 0 && !g_stop && errno != EINTR) {
      std::fprintf(stderr, "stride-teleop: LCM receive failed\n");
      status = 1;
      break;
    }
  }
  std::printf(
      "stride-teleop: stopped at t = %.3f s of robot time (%s): %ld commands sent, %ld states, %ld "
      "rejected, %ld out of order\n",
      player.time(), player.finished() ? "--duration" : (g_stop ? "signal" : "error"),
      sender.sent(), player.states(), input.rejected(), player.outOfOrder());
  if (sender.failures() > 0) {
    std::fprintf(stderr, "stride-teleop: %ld publishes failed\n", sender.failures());
    status = 1;
  }
  return status;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "stride-teleop: body velocity commands for stride-mpc, from the keyboard or a command "
      "script played on the robot's clock"};
  stride::commandLineConventions(app, "stride-teleop");
  std::string key_file, url, channel = "STRIDE_COMMAND", state_channel = "STRIDE_STATE",
                             status_channel = "STRIDE_STATUS", gaits_name = "quadruped", commands;
  stride::teleop::KeyboardLimits limits;
  stride::teleop::ScriptPlayerOptions script_options;
  double rate_hz = 20.0;
  app.add_option("--url", url, "LCM URL (default: LCM_DEFAULT_URL; one of the two is required)");
  app.add_option("--channel", channel, "command channel")->capture_default_str();
  app.add_option("--gaits", gaits_name, "the robot's gaits (number keys, script check)")
      ->check(CLI::IsMember({"quadruped", "biped"}))
      ->capture_default_str();
  app.add_option("--rate", rate_hz, "commands per second (script: per second of robot time)")
      ->check(CLI::Range(0.1, 1000.0))
      ->capture_default_str();
  const auto positive = CLI::Range(1e-6, 100.0);
  app.add_option("--step-v", limits.step_vx, "vx step [m/s]")
      ->check(positive)
      ->capture_default_str();
  app.add_option("--step-vy", limits.step_vy, "vy step [m/s]")
      ->check(positive)
      ->capture_default_str();
  app.add_option("--step-yaw", limits.step_yaw, "yaw rate step [rad/s]")
      ->check(positive)
      ->capture_default_str();
  app.add_option("--step-height", limits.step_height, "body height step [m]")
      ->check(positive)
      ->capture_default_str();
  const auto limit = CLI::Range(0.0, 100.0);
  app.add_option("--max-vx", limits.max_vx, "|vx| limit [m/s]")
      ->check(limit)
      ->capture_default_str();
  app.add_option("--max-vy", limits.max_vy, "|vy| limit [m/s]")
      ->check(limit)
      ->capture_default_str();
  app.add_option("--max-yaw-rate", limits.max_yaw_rate, "|yaw rate| limit [rad/s]")
      ->check(limit)
      ->capture_default_str();
  app.add_option("--max-height", limits.max_height, "|body height offset| limit [m]")
      ->check(limit)
      ->capture_default_str();
  std::vector<double> jump = {limits.jump.dx, limits.jump.dy, limits.jump.dz, limits.jump.yaw};
  app.add_option("--jump", jump,
                 "the J key's jump: DX DY DZ YAW (landing forward, left, higher [m], turn [rad])")
      ->expected(4)
      ->capture_default_str();
  app.add_option(
      "--commands", commands,
      "play this command script (controller/command_script.hpp) instead of the keyboard");
  app.add_option("--key-file", key_file,
                 "the shared key: commands are signed with it, and (script) the robot's states "
                 "must be (messages/README.md, \"Signing\"); without one the wire is "
                 "unauthenticated");
  app.add_option("--state-channel", state_channel, "script: the robot's clock comes from here")
      ->capture_default_str();
  app.add_option("--status-channel", status_channel,
                 "the controller's statuses: what became of each jump (refused, and why; landed)")
      ->capture_default_str();
  app.add_option("--hold", script_options.hold,
                 "script: the last entry lasts this long [s], then the script is done (and the "
                 "last entry repeats)")
      ->check(CLI::Range(0.0, 1e6))
      ->capture_default_str();
  app.add_option("--duration", script_options.duration,
                 "script: stop after this much robot time [s] (0: at SIGINT/SIGTERM)")
      ->check(CLI::Range(0.0, 1e9))
      ->capture_default_str();
  if (const int status = stride::parseCommandLine(app, argc, argv); status >= 0) return status;
  script_options.rate_hz = rate_hz;
  limits.jump = {jump[0], jump[1], jump[2], jump[3]};
  const GaitSet gaits = gaits_name == "biped" ? GaitSet::Biped : GaitSet::Quadruped;

  // LCM must never fall back to multicast on the host network by accident: the URL is explicit.
  url = stride::lcmUrl(url);
  if (url.empty()) return stride::noLcmUrl("stride-teleop", "pass --url");
  std::vector<stride::ScriptedCommand> script;
  if (!commands.empty()) {
    try {
      script = stride::loadCommandScript(commands);
      stride::checkScriptGaits(script, commands, stride::teleop::gaitNames(gaits),
                               "a " + gaits_name + " (--gaits " + gaits_name + ")");
    } catch (const std::exception& e) {
      std::fprintf(stderr, "stride-teleop: %s\n", e.what());
      return 2;
    }
  } else if (!isatty(STDIN_FILENO)) {
    std::fprintf(stderr,
                 "stride-teleop: stdin is not a terminal: the keyboard mode needs one (to play a "
                 "script, pass --commands FILE)\n");
    return 2;
  }

  installSignals();
  try {
    lcm::LCM lcm(url);
    if (!lcm.good()) {
      std::fprintf(stderr, "stride-teleop: cannot open LCM '%s'\n", url.c_str());
      return 2;
    }
    const std::optional<stride::msg::Key> key =
        stride::msg::keyForProgram(key_file, "stride-teleop");
    stride::msg::WireAuth auth =
        key ? stride::msg::WireAuth(*key, "stride-teleop") : stride::msg::WireAuth();
    if (!commands.empty())
      return runScript(lcm, channel, state_channel, status_channel, auth, commands,
                       std::move(script), script_options);
    return runKeyboard(lcm, channel, status_channel, auth, gaits, limits, rate_hz);
  } catch (const std::exception& e) {  // unwinding restores the terminal
    std::fprintf(stderr, "\nstride-teleop: %s\n", e.what());
    return 1;
  }
}
