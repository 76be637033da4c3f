#pragma once
// Plays a command script (controller/command_script.hpp) on the robot's clock: each state estimate
// that arrives is a tick of robot time, so the script runs the same in lock-step (robot time
// unrelated to wall time) and in real time.
//
// t = 0 is the first state's stamp. A state at most once per 1/rate seconds of state stamps (on a
// grid from t = 0, so a script entry at a multiple of the period starts exactly on time) is
// answered with the entry in force at its time (commandAt: before the first entry's time, the first
// entry), stamped with the state's utime. From the last entry's time + hold on, the script is done
// and its last entry keeps going out (the controller's deadman would otherwise decay it to a stand)
// until duration seconds of robot time (0: never).
// Free of LCM I/O so a test can drive it with stamps.

#include <cstdint>
#include <vector>

#include "controller/command_script.hpp"
#include "stride/command_t.hpp"

namespace stride::teleop {

struct ScriptPlayerOptions {
  double rate_hz = 20.0;  // at most this many commands per second of robot time
  double hold = 1.0;      // the last entry's length as part of the script [s]
  double duration = 0.0;  // stop after this much robot time [s]; 0: never
};

class ScriptPlayer {
 public:
  // The script must be non-empty with increasing times (as loadCommandScript returns it).
  ScriptPlayer(std::vector<ScriptedCommand> script, const ScriptPlayerOptions& options);

  struct Step {
    bool publish = false;
    command_t command{};         // when publish: the entry, stamped with the state's utime
    int entry = -1;              // when publish: the script entry sent
    bool entry_started = false;  // the first time this entry is sent
    bool script_done = false;    // the first state at or past the last entry's time + hold
  };

  // A state estimate's stamp [µs]. Stamps not newer than the last are ignored (counted); a state
  // at or past the duration publishes nothing and finishes the player (it may still be the one
  // that reports script_done).
  Step onState(std::int64_t utime);

  bool started() const { return started_; }
  bool finished() const { return finished_; }
  double time() const;  // robot time of the newest state [s]
  long states() const { return states_; }
  long published() const { return published_; }
  long outOfOrder() const { return out_of_order_; }
  const std::vector<ScriptedCommand>& script() const { return script_; }
  double end() const { return script_.back().at + options_.hold; }  // the script's length [s]

 private:
  std::vector<ScriptedCommand> script_;
  ScriptPlayerOptions options_;
  std::int64_t period_us_;
  bool started_ = false, finished_ = false, done_ = false;
  std::int64_t t0_ = 0, last_ = 0, next_due_ = 0;  // µs; next_due_ relative to t0_
  int last_entry_ = -1;
  long states_ = 0, published_ = 0, out_of_order_ = 0;
};

}  // namespace stride::teleop
