// stride-log-summary: what happened in a recorded session (an lcm-logger log of the demo, a replay
// output, or a robot's session): how far the robot went, whether it fell, how the controller kept
// up, and how well it followed the commands it was given (segments: one per run of identical
// commands, tools/log/segments.hpp). Reads the state, status and command channels; prints a summary
// and optionally writes JSON.
//   stride-log-summary session.lcmlog [--summary summary.json] [--windows 5] [--check-tracking]
//                      [--sim-summary sim.json]
// Heights are taken above the terrain under the base where the log has an elevation map
// (stride.terrain_t) there, as the mock robot takes them.

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "config/command_line.hpp"
#include "controller/statistics.hpp"
#include "messages/signing.hpp"
#include "tools/log/segments.hpp"
#include "tools/log/session_reader.hpp"

namespace {

using json = nlohmann::ordered_json;

// Milliseconds as microseconds for the printed lines (0 without data: the counts say so).
double us(const std::optional<double>& ms) {
  return ms.value_or(0.0) * 1e3;
}
double us(const std::vector<double>& ms, double p) {
  return us(stride::percentile(ms, p));
}

// A timing in ms as the summaries write it: to the nanosecond (finer is noise), null without data.
json msOrNull(const std::optional<double>& ms) {
  if (!ms) return nullptr;
  return std::round(*ms * 1e6) / 1e6;
}
// The shape of every timing distribution in the summaries (stride-mpc's too, run_loop.cpp).
json timingJson(const stride::Percentiles& p) {
  return {{"p50_ms", msOrNull(p.p50)},
          {"p99_ms", msOrNull(p.p99)},
          {"max_ms", msOrNull(p.max)},
          {"count", p.count}};
}

// --windows: how the controller kept up in each stretch of the session (session_reader.hpp).
void printWindows(const std::vector<stride::logs::Window>& windows, double width,
                  long long misses_end, long long late_end) {
  std::printf(
      "by %g s window: start [s], ticks, deadline misses, late starts, tick latency p50 "
      "[us], preparation p50 / p99 [us], tick + preparation p50 [us]\n",
      width);
  for (std::size_t i = 0; i < windows.size(); ++i) {
    const stride::logs::Window& w = windows[i];
    const long long m1 = i + 1 < windows.size() ? windows[i + 1].misses : misses_end;
    const long long l1 = i + 1 < windows.size() ? windows[i + 1].late : late_end;
    std::printf("  %6.1f %6ld %6lld %6lld %7.0f %7.0f / %5.0f %7.0f\n", w.start, w.ticks,
                m1 - w.misses, l1 - w.late, us(w.latency_ms, 0.5), us(w.prepare_ms, 0.5),
                us(w.prepare_ms, 0.99), us(w.work_ms, 0.5));
  }
}

void printSegments(const std::vector<stride::logs::Segment>& segments, double settle) {
  std::printf(
      "command segments (t [s] from the first state; vx, vy [m/s], yaw [rad/s]; achieved: mean "
      "heading-frame velocity from t0 + %.1f s)\n"
      "   #      t0      t1  gait    command vx     vy    yaw   achieved vx     vy    yaw  "
      "samples\n",
      settle);
  for (std::size_t k = 0; k < segments.size(); ++k) {
    const stride::logs::Segment& s = segments[k];
    char achieved[64] = "               (none)";
    if (s.samples > 0)
      std::snprintf(achieved, sizeof achieved, "%+6.2f %+6.2f %+6.2f", s.achieved[0], s.achieved[1],
                    s.achieved[2]);
    std::printf("  %2zu %7.2f %7.2f  %-6s      %+6.2f %+6.2f %+6.2f       %s  %7d%s%s\n", k, s.t0,
                s.t1, s.gait.c_str(), s.command[0], s.command[1], s.command[2], achieved, s.samples,
                s.jump_id > 0 ? ("  jump #" + std::to_string(s.jump_id)).c_str() : "",
                s.fell ? "  FELL" : "");
  }
}

// One line per miss, then the verdict line. Returns whether every segment tracked.
bool reportTracking(const std::vector<stride::logs::Segment>& segments,
                    const std::vector<stride::logs::TrackingMiss>& misses,
                    const stride::logs::TrackingTolerance& tol) {
  using Kind = stride::logs::TrackingMiss::Kind;
  for (const auto& m : misses) {
    const auto& s = segments[m.segment];
    if (m.kind == Kind::Fell)
      std::printf("tracking: segment %d (%.2f .. %.2f s, %s): the robot fell\n", m.segment, s.t0,
                  s.t1, s.gait.c_str());
    else if (m.kind == Kind::NoSamples)
      std::printf("tracking: segment %d (%.2f .. %.2f s, %s): no state to measure it\n", m.segment,
                  s.t0, s.t1, s.gait.c_str());
    else
      std::printf(
          "tracking: segment %d (%.2f .. %.2f s, %s) missed %s: commanded %+.3f, achieved %+.3f, "
          "tolerance %.3f\n",
          m.segment, s.t0, s.t1, s.gait.c_str(), stride::logs::componentName(m.component),
          m.commanded, m.achieved, m.tolerance);
  }
  long checked = 0;
  for (const auto& s : segments) checked += s.t1 - s.t0 >= tol.min_duration;
  if (misses.empty())
    std::printf(
        "tracking: every segment tracked its command (%ld of %zu segments last >= %.1f s and were "
        "checked: within max(%.0f%%, %.2f m/s, %.2f rad/s)), no fall\n",
        checked, segments.size(), tol.min_duration, tol.relative * 100, tol.linear, tol.yaw_rate);
  else
    std::printf("tracking: NOT every segment tracked its command (%zu misses)\n", misses.size());
  return misses.empty();
}

json segmentsJson(const std::vector<stride::logs::Segment>& segments) {
  json out = json::array();
  for (const stride::logs::Segment& s : segments) {
    json segment;
    segment["t0"] = s.t0;
    segment["t1"] = s.t1;
    segment["command"] = s.command;
    segment["gait"] = s.gait;  // from a message: any bytes (dump replaces invalid UTF-8)
    segment["body_height"] = s.body_height;
    // No state to average over: no velocity, not zero.
    segment["achieved"] = s.samples > 0 ? json(s.achieved) : json(nullptr);
    segment["samples"] = s.samples;
    segment["commands"] = s.commands;
    segment["fell"] = s.fell;
    out.push_back(segment);
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "stride-log-summary: distance, base height, falls, controller timing and command tracking of "
      "a log"};
  stride::commandLineConventions(app, "stride-log-summary");
  std::string log_path, summary_path,
      state_channel = "STRIDE_STATE", status_channel = "STRIDE_STATUS",
      command_channel = "STRIDE_COMMAND", terrain_channel = "STRIDE_TERRAIN", sim_summary_path;
  double window = 0.0, fault_end = -1.0, fault_end_wall = -1.0;
  stride::logs::TrackingTolerance tolerance;
  stride::logs::SegmentOptions segment_options;
  bool check_tracking = false;
  long max_lost = -1;
  app.add_option("log", log_path, "LCM log file")->required()->check(CLI::ExistingFile);
  app.add_option("--summary", summary_path, "write the summary as JSON here");
  app.add_option("--state-channel", state_channel);
  app.add_option("--status-channel", status_channel);
  app.add_option("--command-channel", command_channel);
  app.add_option("--terrain-channel", terrain_channel,
                 "elevation maps: heights are taken above the terrain under the base");
  app.add_option("--sim-summary", sim_summary_path,
                 "the mock robot's own summary (stride-sim --summary): its terrain, trips, "
                 "footholds and verdict go into this one; a fall it saw is a fall here, whatever "
                 "the log holds")
      ->check(CLI::ExistingFile);
  app.add_option("--fault-end", fault_end,
                 "a fault (a controller killed, paused, ...) ended at this time [s from the first "
                 "state]: reports whether control came back (every segment starting 2 s after it "
                 "tracked) and when its command was first tracked; exit status 6 if it did not");
  app.add_option("--fault-end-wall", fault_end_wall,
                 "the same, as wall-clock seconds (date +%s.%N), placed on the log's clock by the "
                 "time the logger received the states");
  // The mock robot's fall criterion and defaults (sim/fall.hpp).
  app.add_option("--fall-height", segment_options.fall.height_fraction,
                 "fallen: base below this fraction of its first height");
  app.add_option("--fall-tilt", segment_options.fall.max_tilt_deg,
                 "fallen: base tilted more than this [deg]");
  app.add_option("--windows", window,
                 "also print the controller's timing and misses per window of this many seconds")
      ->check(CLI::Range(0.0, 3600.0));
  app.add_flag("--check-tracking", check_tracking,
               "exit status 1 when a command segment missed its command");
  app.add_option("--max-lost", max_lost,
                 "exit status 5 when more messages than this were lost: status ticks missing from "
                 "the controller's counter plus state estimates missing from their stamps' rate "
                 "(-1: no limit)")
      ->check(CLI::Range(-1L, 1000000000L));
  app.footer(
      "Exit status: 0 read, upright (and tracked, with --check-tracking); 1 a segment missed its "
      "command (--check-tracking) or the log or summary could not be read or written; 2 a usage "
      "error; 4 the robot fell (as stride-sim's); 5 more messages lost than --max-lost; 6 control "
      "did not come back after the fault (--fault-end; not when no segment starts after it).");
  app.add_option("--tolerance", tolerance.relative,
                 "tracking: allowed error as a fraction of the commanded value")
      ->check(CLI::Range(0.0, 10.0))
      ->capture_default_str();
  app.add_option("--tolerance-linear", tolerance.linear,
                 "tracking: allowed error at least this on vx and vy [m/s]")
      ->check(CLI::Range(0.0, 10.0))
      ->capture_default_str();
  app.add_option("--tolerance-yaw", tolerance.yaw_rate,
                 "tracking: allowed error at least this on yaw_rate [rad/s]")
      ->check(CLI::Range(0.0, 10.0))
      ->capture_default_str();
  app.add_option("--min-segment", tolerance.min_duration,
                 "tracking: segments shorter than this [s] are not checked")
      ->check(CLI::Range(0.0, 3600.0))
      ->capture_default_str();
  app.add_option("--settle", segment_options.settle,
                 "segments: velocities are averaged from this long after a command's start [s]")
      ->check(CLI::Range(0.0, 3600.0))
      ->capture_default_str();
  if (const int status = stride::parseCommandLine(app, argc, argv); status >= 0) return status;

  stride::logs::SessionChannels channels;
  channels.state = state_channel;
  channels.status = status_channel;
  channels.command = command_channel;
  channels.terrain = terrain_channel;
  stride::logs::Session session;
  if (std::string error; !stride::logs::readSession(log_path, channels, window,
                                                    segment_options.fall, session, error)) {
    std::fprintf(stderr, "stride-log-summary: %s\n", error.c_str());
    return 1;
  }
  const stride::logs::Session& s = session;
  const long states = s.states, statuses = s.statuses;
  bool fell = s.fell;
  if (states == 0 && statuses == 0) {
    std::fprintf(stderr, "stride-log-summary: no state on '%s' and no status on '%s' in '%s'\n",
                 state_channel.c_str(), status_channel.c_str(), log_path.c_str());
    return 1;
  }
  const long lost = s.lost_statuses + s.missing_states;
  const std::vector<stride::logs::CommandSample>& commands = s.commands;
  const std::vector<stride::logs::Segment> segments =
      stride::logs::segmentCommands(commands, s.base_samples, segment_options);
  const std::vector<stride::logs::TrackingMiss> misses =
      stride::logs::checkTracking(segments, tolerance);
  // Keyboard commands carry the teleop's CLOCK_MONOTONIC: the robot's clock in real time, not in
  // lock-step or on a replayed log. Then the segments mean nothing, and the reader must know.
  long off_clock = 0;
  if (states > 0)
    for (const auto& c : commands) off_clock += c.t < -1.0 || c.t > s.t_last - s.t_first + 1.0;
  if (states == 0)  // e.g. a replay's output: the controller's side only
    std::printf("no state estimates in this log (a replay output?): controller side only\n");
  const double distance = std::hypot(s.x1 - s.x0, s.y1 - s.y0);
  const stride::Percentiles latency = stride::percentiles(s.latency_ms),
                            solve = stride::percentiles(s.solve_ms),
                            prepare = stride::percentiles(s.prepare_ms);
  double log_tail_lost = 0.0;  // [s] of the robot's states the logger did not record
  // The mock robot's verdict: it checks the fall on every physics step, the log only holds what the
  // logger read before it was stopped.
  json sim_summary;
  if (!sim_summary_path.empty()) {
    std::ifstream in(sim_summary_path);
    try {
      sim_summary = json::parse(in);
    } catch (const json::exception& e) {
      std::fprintf(stderr, "stride-log-summary: cannot read '%s': %s\n", sim_summary_path.c_str(),
                   e.what());
      return 1;
    }
    // The logger stopped before the robot's last state (a loaded machine): said, and measured.
    if (states > 0 && sim_summary.contains("last_state_utime") &&
        sim_summary["last_state_utime"].is_number_integer()) {
      const std::int64_t robot_last = sim_summary["last_state_utime"].get<std::int64_t>();
      if (robot_last > s.last_state_utime) log_tail_lost = (robot_last - s.last_state_utime) * 1e-6;
    }
    if (log_tail_lost > 0.0)
      std::printf(
          "log: the logger stopped %.3f s before the robot's last state: the robot's own "
          "summary (%s) gives the fall\n",
          log_tail_lost, sim_summary_path.c_str());
    if (sim_summary.value("fell", false) && !fell) {
      std::printf("robot: the mock robot fell (%s), after the log's last state\n",
                  sim_summary_path.c_str());
      fell = true;
    }
    // Why it did not follow its controller, when it did not (sim::whyText).
    if (sim_summary.contains("why") && sim_summary["why"].is_string())
      std::printf("robot: %s\n", sim_summary["why"].get<std::string>().c_str());
  }
  if (states > 0)
    std::printf(
        "session %.1f s: walked %.3f m (x %+.3f, y %+.3f), base height %.3f .. %.3f m, "
        "max tilt %.1f deg, %s\n",
        s.t_last - s.t_first, distance, s.x1 - s.x0, s.y1 - s.y0, s.z_min, s.z_max, s.max_tilt_deg,
        fell ? "FELL" : "did not fall");
  std::printf(
      "controller: %ld ticks, tick latency p50 %.0f us, p99 %.0f us, max %.0f us, "
      "solve p50 %.0f us, %lld deadline misses (%lld late starts), %lld fallbacks, %lld rejected "
      "messages\n",
      statuses, us(latency.p50), us(latency.p99), us(latency.max), us(solve.p50),
      static_cast<long long>(s.last_status.deadline_misses),
      static_cast<long long>(s.last_status.late_ticks),
      static_cast<long long>(s.last_status.fallbacks),
      static_cast<long long>(s.last_status.rejected_messages));
  std::printf(
      "lost: %ld status messages (gaps in the tick counter), %ld state estimates (stamp gaps; "
      "period %.3f ms)%s\n",
      s.lost_statuses, s.missing_states, s.state_period_ms,
      max_lost >= 0 && lost > max_lost ? ": MORE THAN --max-lost" : "");
  // The other half of each iteration (run after the policy went out) and how the line search
  // went: a tick's latency is one rollout per step length tried.
  const long solved = s.full_steps + s.short_steps + s.no_steps;
  const auto pct = [&](long n) { return solved > 0 ? 100.0 * n / solved : 0.0; };
  std::printf(
      "solver: %ld of %zu ticks answered a prepared iteration (preparation p50 %.0f us, p99 %.0f "
      "us); steps: full %.0f%%, shorter %.0f%%, none %.0f%%\n",
      s.prepared, s.latency_ms.size(), us(prepare.p50), us(prepare.p99), pct(s.full_steps),
      pct(s.short_steps), pct(s.no_steps));
  if (!s.windows.empty())
    printWindows(s.windows, window, s.last_status.deadline_misses, s.last_status.late_ticks);
  // Refused as the live receivers refuse them (messages/validate.hpp), counted by reason.
  const std::pair<const char*, const stride::logs::Refusals*> refusals[] = {
      {"states", &s.refused_states},
      {"status messages", &s.refused_statuses},
      {"elevation maps", &s.refused_maps}};
  for (const auto& [what, refused] : refusals)
    if (refused->total > 0)
      std::printf("log: %ld malformed %s refused (%s)\n", refused->total, what,
                  refused->said().c_str());
  const std::string terrain_name =
      sim_summary.contains("terrain") && sim_summary["terrain"].is_string()
          ? sim_summary["terrain"].get<std::string>()
          : (s.maps > 0 ? "(from the log's maps)" : "flat");
  if (states > 0)
    std::printf(
        "terrain '%s': final base (%.3f, %.3f, %.3f) m, %.3f m above the terrain under it%s; %ld "
        "elevation maps%s\n",
        terrain_name.c_str(), s.x1, s.y1, s.z1, s.z1 - s.ground_last,
        s.ground_known || s.maps == 0 ? "" : " (no map covered it: above z = 0)", s.maps,
        s.bad_maps > 0 ? (", " + std::to_string(s.bad_maps) + " refused").c_str() : "");
  bool tracked = true;
  if (commands.empty()) {
    std::printf("commands: none on '%s'%s\n", command_channel.c_str(),
                check_tracking ? "; --check-tracking checks the fall only" : "");
    tracked = !fell;
  } else {
    printSegments(segments, segment_options.settle);
    // Each jump's segment: what the controller said of it, and where the base went in it.
    for (const stride::logs::JumpOutcome& j : s.jumps) {
      std::printf("jump #%d: %s", j.id, stride::logs::describe(j).c_str());
      for (const stride::logs::Segment& seg : segments)
        if (seg.jump_id == j.id) {
          const stride::logs::Motion m = stride::logs::motion(s.base_samples, seg.t0, seg.t1);
          if (m.valid)
            std::printf(
                "; in its segment (%.2f .. %.2f s) the base moved %+.3f %+.3f m, %+.3f m "
                "up, turned %+.1f deg",
                seg.t0, seg.t1, m.dx, m.dy, m.dz, m.yaw * 180.0 / M_PI);
        }
      std::printf("\n");
    }
    tracked = reportTracking(segments, misses, tolerance);
    // A fall outside every segment (before the first command) fails the check too.
    if (fell && tracked) {
      std::printf("tracking: the robot fell outside the command segments\n");
      tracked = false;
    }
  }
  // Recovery after a fault (issue 33): did control come back, and when.
  if (fault_end_wall >= 0.0 && states > 0)
    fault_end = (fault_end_wall * 1e6 - static_cast<double>(s.state_event0)) * 1e-6;
  stride::logs::Recovery recovery;
  const bool judge_recovery = fault_end >= 0.0 || fault_end_wall >= 0.0;
  if (judge_recovery) {
    recovery = stride::logs::recovery(segments, s.base_samples, fault_end, tolerance, {},
                                      segment_options.fall);
    char when[96] = "its command never tracked after it";
    if (recovery.time_to_tracking >= 0.0)
      std::snprintf(when, sizeof(when), "its command tracked %.2f s after the fault's end",
                    recovery.time_to_tracking);
    if (recovery.segments_after == 0)
      std::printf(
          "recovery: the fault ended at %.2f s; no checked segment starts 2 s after it: "
          "not judged (%s)\n",
          fault_end, when);
    else
      std::printf(
          "recovery: the fault ended at %.2f s; %d of %d segments starting 2 s after it "
          "tracked: %s; %s\n",
          fault_end, recovery.segments_after - recovery.missed_after, recovery.segments_after,
          recovery.recovered ? "control came back" : "control did NOT come back", when);
  }
  if (off_clock > 0)
    std::printf(
        "commands: %ld of %zu stamped more than 1 s outside the states' time span: their clock is "
        "not the robot's, the segments are not meaningful\n",
        off_clock, commands.size());
  if (s.command_rejects > 0)
    std::printf("commands: %ld rejected (wrong size, non-finite or stamps not increasing)\n",
                s.command_rejects);
  if (s.stale_signed > 0)
    std::printf(
        "log: %ld signed messages stamped more than %.1f s from the logger's clock refused, as "
        "the receivers refuse them (a recording replayed on the bus, or a host whose clock is "
        "off)\n",
        s.stale_signed, 1e-6 * static_cast<double>(stride::msg::kFreshnessWindowMicros));
  if (!summary_path.empty()) {
    // Without a state estimate (a replay's output) the robot's side has no data: null; without a
    // status, the controller's counters.
    const auto robot = [&](double value) { return states > 0 ? json(value) : json(nullptr); };
    const auto controller = [&](std::int64_t value) {
      return statuses > 0 ? json(value) : json(nullptr);
    };
    json j;
    j["duration_s"] = robot(s.t_last - s.t_first);
    j["distance_m"] = robot(distance);
    j["base_height_min_m"] = robot(s.z_min);
    j["base_height_max_m"] = robot(s.z_max);
    j["max_tilt_deg"] = robot(s.max_tilt_deg);
    j["fell"] = fell;
    j["terrain"] = terrain_name;
    j["final_base"] = states > 0 ? json::array({s.x1, s.y1, s.z1}) : json(nullptr);
    j["base_height_above_terrain_m"] = robot(s.z1 - s.ground_last);
    j["trips"] = sim_summary.contains("trips") ? sim_summary["trips"] : json(nullptr);
    // The feet's touch-downs near edges of the true terrain: only the mock robot knows them.
    for (const char* key :
         {"footholds", "edge_footholds", "min_edge_distance_m", "sole_flat_fraction", "why"})
      j[key] = sim_summary.contains(key) ? sim_summary[key] : json(nullptr);
    j["terrain_maps"] = s.maps;
    // Malformed messages the log holds, refused as the live receivers refuse them.
    j["refused_states"] = s.refused_states.total;
    j["refused_statuses"] = s.refused_statuses.total;
    j["refused_terrain_maps"] = s.refused_maps.total;
    j["terrain_map_top_m"] = std::isfinite(s.map_top) ? json(s.map_top) : json(nullptr);
    j["tick_latency"] = timingJson(latency);
    j["solve_time"] = timingJson(solve);
    j["deadline_misses"] = controller(s.last_status.deadline_misses);
    j["late_ticks"] = controller(s.last_status.late_ticks);
    j["fallbacks"] = controller(s.last_status.fallbacks);
    j["ticks"] = statuses;
    j["rejected_messages"] = controller(s.last_status.rejected_messages);
    j["prepared_ticks"] = s.prepared;
    j["prepare_time"] = timingJson(prepare);
    j["line_search"] = {{"full", s.full_steps}, {"shorter", s.short_steps}, {"none", s.no_steps}};
    j["commands"] = commands.size();
    j["command_rejects"] = s.command_rejects;
    j["stale_signed"] = s.stale_signed;
    j["segments"] = segmentsJson(segments);
    j["tracked"] = tracked;
    j["lost"] = {{"statuses", s.lost_statuses}, {"states", s.missing_states}};
    j["log_tail_lost_s"] = log_tail_lost;
    if (judge_recovery)
      j["recovery"] = {
          {"fault_end_s", fault_end},
          {"segments_after", recovery.segments_after},
          {"missed_after", recovery.missed_after},
          {"recovered", recovery.recovered},
          {"time_to_tracking_s",
           recovery.time_to_tracking >= 0.0 ? json(recovery.time_to_tracking) : json(nullptr)}};
    std::ofstream f(summary_path);
    f << j.dump(2, ' ', false, json::error_handler_t::replace) << "\n";
    if (!f) {
      std::fprintf(stderr, "stride-log-summary: cannot write '%s'\n", summary_path.c_str());
      return 1;
    }
  }
  if (fell) return 4;
  if (max_lost >= 0 && lost > max_lost) return 5;
  // Not judged (no segment after the fault) is no verdict either way: said, not a failure.
  if (judge_recovery && recovery.segments_after > 0 && !recovery.recovered) return 6;
  return check_tracking && !tracked ? 1 : 0;
}
