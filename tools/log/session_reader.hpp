#pragma once
// What stride-log-summary reads from a recorded session, gathered in one pass over the log: the
// base's path and the fall, the terrain under it, the controller's timing and counters, the
// commands, and the messages lost or refused. Reading is one idea, reporting another
// (log_summary.cpp prints and writes what this gathers; tools/log/README.md).
//
// Messages are read as the live receivers read them (messages/validate.hpp): the counts and the
// size on the raw bytes (a signature trailer stripped: the summary reads, it does not verify), then
// the decode, then the content. A malformed message is refused and counted by reason, never
// decoded on trust: lcm-gen's decoders believe the counts (a count of 2^31 allocates that much).

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "messages/validate.hpp"
#include "stride/mpc_status_t.hpp"
#include "tools/log/segments.hpp"

namespace stride::logs {

// Messages of one kind refused, by reason.
struct Refusals {
  long by_reason[msg::kRejectReasons] = {};
  long total = 0;
  void add(msg::Reject why) {
    ++by_reason[static_cast<int>(why)];
    ++total;
  }
  // "2 (a size that does not match 1, NaN or infinity 1)", or "" for none.
  std::string said() const;
};

// A stretch of the session (--windows): how the controller kept up in it. Misses come in stretches
// where a period's work (the tick and the preparation before it) outgrows the period; this puts the
// two next to each other.
struct Window {
  double start = 0.0;  // [s] from the first status
  long ticks = 0;
  long long misses = 0, late = 0;  // cumulative counters at the window's start
  std::vector<double> latency_ms, prepare_ms, work_ms;
};

struct SessionChannels {
  std::string state = "STRIDE_STATE", status = "STRIDE_STATUS", command = "STRIDE_COMMAND",
              terrain = "STRIDE_TERRAIN";
};

struct Session {
  // The robot's side (state estimates): heights above the terrain under the base where a map of
  // the log covers it (the last known height, else 0), as the mock robot takes them.
  long states = 0;
  bool fell = false;
  double x0 = 0, y0 = 0, x1 = 0, y1 = 0, z1 = 0, z_first = 0;
  double z_min = 0, z_max = 0;  // 0 without a state
  double max_tilt_deg = 0.0, t_first = 0.0, t_last = 0.0;
  std::int64_t state_utime0 = 0, state_event0 = 0;  // the first state's stamp and log time
  std::int64_t last_state_utime = -1;
  std::vector<BaseSample> base_samples;  // t from the first state's stamp
  Refusals refused_states;
  // Elevation maps: the newest one's height under the base.
  long maps = 0, bad_maps = 0;
  double map_top = -std::numeric_limits<double>::infinity();  // the highest known cell of any map
  double ground_last = 0.0;
  bool ground_known = false;
  Refusals refused_maps;
  // The controller's side (status messages). The first policy comes from the start-up solve (no
  // deadline): not a tick, so not in the timings.
  long statuses = 0;
  std::vector<double> latency_ms, solve_ms, prepare_ms;
  long prepared = 0, full_steps = 0, short_steps = 0, no_steps = 0;
  mpc_status_t last_status{};
  std::vector<Window> windows;  // with a window width > 0
  Refusals refused_statuses;
  // Commands accepted as the controller accepts them, t on the first state's clock.
  std::vector<CommandSample> commands;
  std::vector<JumpOutcome> jumps;  // each jump asked for, as the statuses tell it
  long command_rejects = 0;
  // Signed messages stamped further from the logger's clock than the receivers' freshness window
  // (msg::kFreshnessWindowMicros): a recording replayed on the bus, or a host whose clock is off.
  // The live receivers refused them as stale or from the future; so does the summary, on every
  // channel it reads, before anything else.
  long stale_signed = 0;
  // Lost messages: each status carries its tick number (+1 per tick; a restarted controller
  // starts again from 1), and the estimator publishes at a fixed rate (its period: the median
  // interval between stamps), so a missing tick or a stamp gap of n periods is a message the log
  // does not have.
  long lost_statuses = 0, missing_states = 0;
  double state_period_ms = 0.0;
};

// Reads the log at `path` into `session` (window > 0: also per window of that many seconds).
// False, with the reason in `error`, when the file cannot be read.
bool readSession(const std::string& path, const SessionChannels& channels, double window,
                 const FallLimits& fall, Session& session, std::string& error);

}  // namespace stride::logs
