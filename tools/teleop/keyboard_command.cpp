#include "tools/teleop/keyboard_command.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "locomotion/gait.hpp"

namespace stride::teleop {

const std::vector<std::string>& gaitNames(GaitSet gaits) {
  // The controller's own lists (locomotion/gait.hpp), by number of contacts.
  static const std::vector<std::string> quadruped = stride::gaitNames(4);
  static const std::vector<std::string> biped = stride::gaitNames(2);
  return gaits == GaitSet::Quadruped ? quadruped : biped;
}

KeyboardCommand::KeyboardCommand(GaitSet gaits, const KeyboardLimits& limits)
    : gaits_(gaitNames(gaits)), limits_(limits) {}

KeyboardCommand::Event KeyboardCommand::feed(const char* bytes, std::size_t n) {
  Event result = Event::None;
  for (std::size_t i = 0; i < n; ++i) {
    const char c = bytes[i];
    Event e = Event::None;
    switch (escape_) {
      case Escape::None:
        if (c == '\x1b')
          escape_ = Escape::Esc;
        else
          e = key(c);
        break;
      case Escape::Esc:
        // ESC then anything but [ or O was the Escape key itself followed by a normal key (or by
        // another ESC, which starts over).
        if (c == '[') {
          escape_ = Escape::Csi;
        } else if (c == 'O') {
          escape_ = Escape::Ss3;
        } else if (c != '\x1b') {
          escape_ = Escape::None;
          e = key(c);
        }
        break;
      case Escape::Csi:
        // Parameter and intermediate bytes (0x20-0x3f, e.g. the "1;5" of Ctrl+Up) until the
        // final byte; only the arrows' finals mean something here.
        if (c >= 0x40 && c <= 0x7e) {
          escape_ = Escape::None;
          e = arrow(c);
        } else if (c < 0x20 || c > 0x3f) {
          escape_ = Escape::None;  // not a sequence after all
        }
        break;
      case Escape::Ss3:
        escape_ = Escape::None;
        e = arrow(c);
        break;
    }
    if (e == Event::Quit) return Event::Quit;
    if (e == Event::Changed) result = Event::Changed;
  }
  return result;
}

void KeyboardCommand::stop() {
  command_.vx = command_.vy = command_.yaw_rate = 0.0;
  command_.gait = "stand";
}

KeyboardCommand::Event KeyboardCommand::move(double& value, double delta, double limit) {
  const Event e = change(value, delta, limit);
  // A stand stands (the controller zeroes its velocity): moving means stepping, in the first
  // stepping gait, until a number key says otherwise.
  if (e == Event::Changed && value != 0.0 && command_.gait == gaits_[0] && gaits_.size() > 1)
    command_.gait = gaits_[1];
  return e;
}

KeyboardCommand::Event KeyboardCommand::change(double& value, double delta, double limit) {
  const double before = value;
  value = std::clamp(value + delta, -limit, limit);
  // Steps of 0.1 do not add up exactly: snap what should be zero, so it never shows as -0.00.
  if (std::abs(value) < 1e-9) value = 0.0;
  return value != before ? Event::Changed : Event::None;
}

KeyboardCommand::Event KeyboardCommand::arrow(char final_byte) {
  const KeyboardLimits& l = limits_;
  switch (final_byte) {
    case 'A':  // up
      return change(command_.vx, l.step_vx, l.max_vx);
    case 'B':  // down
      return change(command_.vx, -l.step_vx, l.max_vx);
    case 'C':  // right: turn clockwise
      return change(command_.yaw_rate, -l.step_yaw, l.max_yaw_rate);
    case 'D':  // left: turn counter-clockwise
      return change(command_.yaw_rate, l.step_yaw, l.max_yaw_rate);
    default:
      return Event::None;
  }
}

KeyboardCommand::Event KeyboardCommand::key(char c) {
  const KeyboardLimits& l = limits_;
  if (c == 'x' || c == 'X' || c == '\x03') {  // Ctrl-C arrives as a byte: the terminal is raw
    stop();
    return Event::Quit;
  }
  if (c >= '1' && c <= '9') {
    const auto i = static_cast<std::size_t>(c - '1');
    if (i >= gaits_.size() || command_.gait == gaits_[i]) return Event::None;
    command_.gait = gaits_[i];
    return Event::Changed;
  }
  switch (c) {
    case 'w':
    case 'W':
      return move(command_.vx, l.step_vx, l.max_vx);
    case 's':
    case 'S':
      return move(command_.vx, -l.step_vx, l.max_vx);
    case 'a':
    case 'A':
      return move(command_.vy, l.step_vy, l.max_vy);
    case 'd':
    case 'D':
      return move(command_.vy, -l.step_vy, l.max_vy);
    case 'q':
    case 'Q':
      return move(command_.yaw_rate, l.step_yaw, l.max_yaw_rate);
    case 'e':
    case 'E':
      return move(command_.yaw_rate, -l.step_yaw, l.max_yaw_rate);
    case 'r':
    case 'R':
      return change(command_.body_height, l.step_height, l.max_height);
    case 'f':
    case 'F':
      return change(command_.body_height, -l.step_height, l.max_height);
    case 'j':
    case 'J':  // a discrete command: a new id is a new jump (the controller makes each id once)
      ++command_.jump_id;
      command_.jump = l.jump;
      return Event::Changed;
    case ' ': {
      const TeleopCommand before = command_;
      stop();
      return before.vx != 0.0 || before.vy != 0.0 || before.yaw_rate != 0.0 ||
                     before.gait != command_.gait
                 ? Event::Changed
                 : Event::None;
    }
    default:
      return Event::None;
  }
}

std::string statusLine(const TeleopCommand& c, long sent) {
  char line[200];
  const int n =
      std::snprintf(line, sizeof line,
                    "%-5s vx %+.2f m/s  vy %+.2f m/s  yaw %+.2f rad/s  height %+.2f m  [sent %ld]",
                    c.gait.c_str(), c.vx, c.vy, c.yaw_rate, c.body_height, sent);
  if (c.jump_id > 0 && n > 0 && n < static_cast<int>(sizeof line))
    std::snprintf(line + n, sizeof line - n, "  jump #%d", c.jump_id);
  return line;
}

}  // namespace stride::teleop
