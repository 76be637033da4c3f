#include "tools/teleop/script_player.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace stride::teleop {

ScriptPlayer::ScriptPlayer(std::vector<ScriptedCommand> script, const ScriptPlayerOptions& options)
    : script_(std::move(script)), options_(options) {
  if (script_.empty()) throw std::invalid_argument("ScriptPlayer: empty script");
  if (!(options_.rate_hz > 0.0)) throw std::invalid_argument("ScriptPlayer: rate must be > 0");
  period_us_ = std::max<std::int64_t>(1, std::llround(1e6 / options_.rate_hz));
}

double ScriptPlayer::time() const {
  // Divided, not multiplied by 1e-6: 2000000 / 1e6 is exactly 2.0, so an entry at 2.0 starts on
  // the state stamped 2 s after the first.
  return started_ ? static_cast<double>(last_ - t0_) / 1e6 : 0.0;
}

ScriptPlayer::Step ScriptPlayer::onState(std::int64_t utime) {
  Step step;
  if (finished_) return step;
  if (!started_) {
    started_ = true;
    t0_ = utime;
  } else if (utime <= last_) {
    ++out_of_order_;
    return step;
  }
  last_ = utime;
  ++states_;
  const double t = time();
  if (!done_ && t >= end()) step.script_done = done_ = true;
  if (options_.duration > 0.0 && t >= options_.duration) {
    finished_ = true;
    return step;
  }
  const std::int64_t rel = utime - t0_;
  if (rel < next_due_) return step;
  next_due_ = (rel / period_us_ + 1) * period_us_;

  const int i = commandAt(script_, t);
  const ScriptedCommand& c = script_[i];
  step.publish = true;
  step.entry = i;
  step.entry_started = i != last_entry_;
  last_entry_ = i;
  step.command = toCommand(c, utime);
  ++published_;
  return step;
}

}  // namespace stride::teleop
