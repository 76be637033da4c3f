#pragma once
// A timed command script (YAML), as stride-teleop --commands, tools/demo.sh --commands and the
// tests play it:
//
//   - {at: 0.0, gait: stand}
//   - {at: 2.0, gait: trot, vx: 0.5}
//   - {at: 6.0, yaw_rate: 1.0}          # vx stays 0.5, gait stays trot
//   - {at: 9.0, vx: 0.0, yaw_rate: 0.0, gait: stand}
//
// Each entry holds from `at` (seconds from the script's start) until the next one; a field an
// entry does not give keeps its previous value (initially 0 and gait "stand"). Keys: at, vx, vy,
// yaw_rate, gait, body_height, jump. Times must increase strictly.
//
// A jump (issue 45) is the entry's own, never carried to the next: `{at: 4.0, jump: {dx: 0.3,
// dy: 0.0, dz: 0.1, yaw: 1.57}}` (each key optional, 0 by default; locomotion/jump.hpp) asks for
// one jump at 4 s, sent with the entry's jump_id (its entry number + 1) as long as the entry
// holds.

#include <cstdint>
#include <string>
#include <vector>

#include "locomotion/jump.hpp"
#include "stride/command_t.hpp"

namespace stride {

struct ScriptedCommand {
  double at = 0.0;
  double vx = 0.0, vy = 0.0, yaw_rate = 0.0;  // heading frame [m/s, m/s, rad/s]
  std::string gait = "stand";
  double body_height = 0.0;  // [m]
  int jump_id = 0;           // 0: no jump
  JumpTarget jump;
};

// The message an entry sends, stamped `utime`.
command_t toCommand(const ScriptedCommand& c, std::int64_t utime);

// Every entry with all its fields resolved. Throws ConfigError naming the file, the entry and the
// key: not a list, an unknown key, a wrong type, a non-finite number, times not increasing, or
// an empty script.
std::vector<ScriptedCommand> loadCommandScript(const std::string& path);

// Throws ConfigError naming the file, the entry, its time and the robot's gaits when an entry asks
// for a gait not in `gaits` (gaitNames(contacts): trot on a biped). The controller would refuse
// that command and keep the gait in force: a script meant for another robot would walk on
// silently in the wrong gait (issue 34). `what` names the robot ("the robot of 'x.yaml'", "a biped
// (--gaits biped)").
void checkScriptGaits(const std::vector<ScriptedCommand>& script, const std::string& path,
                      const std::vector<std::string>& gaits, const std::string& what);

// The entry in force at time t (the last with at <= t; the first before it).
int commandAt(const std::vector<ScriptedCommand>& script, double t);

}  // namespace stride
