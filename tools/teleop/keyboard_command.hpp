#pragma once
// The interactive teleop's command, driven by the bytes a raw-mode terminal delivers: letters,
// digits, and the escape sequences of the arrow keys. Free of terminals and LCM so a test can type
// into it.
//
//   W / Up, S / Down      vx ± step_vx          A / D            vy ± step_vy (left positive)
//   Q / Left, E / Right   yaw_rate ± step_yaw   R / F            body height ± step_height
//   space                 stop: zero velocity, gait stand (the body height stays)
//   J                     jump: a new jump_id with the limits' jump target (sent until the next)
//   1 .. 7                gait: stand trot walk pace pronk bound flying_trot (quadruped);
//                         1 2 3: stand walk hop (biped)
//   x, Ctrl-C             quit (the command becomes the stop command)
// A velocity key while standing also picks the first stepping gait (trot; walk for a biped): the
// controller would hold a stand still whatever its velocity.

#include <cstddef>
#include <string>
#include <vector>

#include "controller/command_script.hpp"
#include "locomotion/jump.hpp"

namespace stride::teleop {

// What the keys ask for: a command script's entry without its time (its jump_id: the last jump
// asked for with J, 0 none), sent as such (stride::toCommand).
using TeleopCommand = ScriptedCommand;

struct KeyboardLimits {
  double step_vx = 0.1, step_vy = 0.05, step_yaw = 0.2, step_height = 0.01;
  double max_vx = 1.0, max_vy = 0.5, max_yaw_rate = 1.5, max_height = 0.1;
  JumpTarget jump{0.2, 0.0, 0.0, 0.0};  // the J key's jump (stride-teleop --jump)
};

enum class GaitSet { Quadruped, Biped };

// The gaits in number-key order: key 1 selects the first.
const std::vector<std::string>& gaitNames(GaitSet gaits);

class KeyboardCommand {
 public:
  enum class Event { None, Changed, Quit };

  KeyboardCommand(GaitSet gaits, const KeyboardLimits& limits);

  // Bytes as read from the terminal, in any chunking: an escape sequence split across two reads
  // is completed by the second. Quit as soon as a quit key is seen (the bytes after it are
  // ignored); Changed when some key changed the command; None otherwise.
  Event feed(const char* bytes, std::size_t n);
  Event feed(const std::string& bytes) { return feed(bytes.data(), bytes.size()); }

  const TeleopCommand& command() const { return command_; }
  void stop();  // zero velocity, gait stand

 private:
  Event key(char c);
  Event arrow(char final_byte);
  Event change(double& value, double delta, double limit);
  Event move(double& value, double delta, double limit);  // a velocity: leaves a stand

  std::vector<std::string> gaits_;
  KeyboardLimits limits_;
  TeleopCommand command_;
  // Escape sequences: ESC [ params final (CSI) or ESC O final (SS3, application cursor keys).
  enum class Escape { None, Esc, Csi, Ss3 } escape_ = Escape::None;
};

// The one-line display: "trot  vx +0.50 m/s  vy +0.00 m/s  yaw +0.00 rad/s  height +0.00 m
// [sent 123]".
std::string statusLine(const TeleopCommand& c, long sent);

}  // namespace stride::teleop
