// stride-log-summary: what happened in a recorded session (an lcm-logger log of the demo, a replay
// output, or a robot's session): how far the robot went, whether it fell, how the controller kept
// up. Reads the state and status channels only; prints a summary and optionally writes JSON.
//   stride-log-summary session.lcmlog [--summary summary.json] [--windows 5]

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <vector>

#include "stride/mpc_status_t.hpp"
#include "stride/robot_state_t.hpp"

namespace {

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const auto i = static_cast<size_t>(std::ceil(p * static_cast<double>(v.size())) - 1);
  return v[std::min(i, v.size() - 1)];
}

// A stretch of the session (--windows): how the controller kept up in it. Misses come in stretches
// where a period's work (the tick and the preparation before it) outgrows the period; this puts the
// two next to each other.
constexpr std::size_t kMaxWindows = 100000;

struct Window {
  double start = 0.0;  // [s] from the first status
  long ticks = 0;
  long long misses = 0, late = 0;  // cumulative counters at the window's start
  std::vector<double> latency_ms, prepare_ms, work_ms;
};

void printWindows(const std::vector<Window>& windows, double width, long long misses_end,
                  long long late_end) {
  std::printf(
      "by %.0f s window: start [s], ticks, deadline misses, late starts, tick latency p50 "
      "[us], preparation p50 / p99 [us], tick + preparation p50 [us]\n",
      width);
  for (std::size_t i = 0; i < windows.size(); ++i) {
    const Window& w = windows[i];
    const long long m1 = i + 1 < windows.size() ? windows[i + 1].misses : misses_end;
    const long long l1 = i + 1 < windows.size() ? windows[i + 1].late : late_end;
    std::printf("  %6.1f %6ld %6lld %6lld %7.0f %7.0f / %5.0f %7.0f\n", w.start, w.ticks,
                m1 - w.misses, l1 - w.late, percentile(w.latency_ms, 0.5) * 1e3,
                percentile(w.prepare_ms, 0.5) * 1e3, percentile(w.prepare_ms, 0.99) * 1e3,
                percentile(w.work_ms, 0.5) * 1e3);
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"stride-log-summary: distance, base height, falls and controller timing of a log"};
  std::string log_path, summary_path, state_channel = "STRIDE_STATE",
                                      status_channel = "STRIDE_STATUS";
  double fall_height = 0.5, fall_tilt_deg = 60.0, window = 0.0;
  app.add_option("log", log_path, "LCM log file")->required()->check(CLI::ExistingFile);
  app.add_option("--summary", summary_path, "write the summary as JSON here");
  app.add_option("--state-channel", state_channel);
  app.add_option("--status-channel", status_channel);
  app.add_option("--fall-height", fall_height,
                 "fallen: base below this fraction of its first height");
  app.add_option("--fall-tilt", fall_tilt_deg, "fallen: base tilted more than this [deg]");
  app.add_option("--windows", window,
                 "also print the controller's timing and misses per window of this many seconds")
      ->check(CLI::Range(0.0, 3600.0));
  CLI11_PARSE(app, argc, argv);

  lcm::LogFile log(log_path, "r");
  if (!log.good()) {
    std::fprintf(stderr, "stride-log-summary: cannot read '%s'\n", log_path.c_str());
    return 1;
  }
  long states = 0, statuses = 0, bad = 0;
  bool fell = false, policy_seen = false;
  double x0 = 0, y0 = 0, x1 = 0, y1 = 0, z_first = 0, z_min = INFINITY, z_max = -INFINITY;
  double max_tilt = 0.0, t_first = 0.0, t_last = 0.0;
  std::vector<double> latency_ms, solve_ms, prepare_ms;
  long prepared = 0, full_steps = 0, short_steps = 0, no_steps = 0;
  stride::mpc_status_t last_status{};
  std::vector<Window> windows;
  std::int64_t status_t0 = -1;
  for (const lcm::LogEvent* e = log.readNextEvent(); e != nullptr; e = log.readNextEvent()) {
    if (e->channel == state_channel) {
      stride::robot_state_t s;
      if (s.decode(e->data, 0, static_cast<int>(e->datalen)) < 0 || s.nq < 7 ||
          static_cast<int>(s.q.size()) != s.nq) {
        ++bad;
        continue;
      }
      const double z = s.q[2];
      if (states == 0) {
        x0 = s.q[0];
        y0 = s.q[1];
        z_first = z;
        t_first = s.utime * 1e-6;
      }
      x1 = s.q[0];
      y1 = s.q[1];
      t_last = s.utime * 1e-6;
      z_min = std::min(z_min, z);
      z_max = std::max(z_max, z);
      // Tilt: the angle between the base's z axis and the world's (quaternion x y z w).
      const double qx = s.q[3], qy = s.q[4];
      const double tilt = std::acos(std::clamp(1.0 - 2.0 * (qx * qx + qy * qy), -1.0, 1.0));
      max_tilt = std::max(max_tilt, tilt * 180.0 / M_PI);
      if (z < fall_height * z_first || tilt * 180.0 / M_PI > fall_tilt_deg) fell = true;
      ++states;
    } else if (e->channel == status_channel) {
      stride::mpc_status_t st;
      if (st.decode(e->data, 0, static_cast<int>(e->datalen)) < 0) {
        ++bad;
        continue;
      }
      ++statuses;
      if (window > 0.0) {
        if (status_t0 < 0) status_t0 = e->timestamp;
        const double t = 1e-6 * static_cast<double>(e->timestamp - status_t0);
        // A time stamp far ahead (a corrupt log) must not open millions of windows: past the cap
        // a status joins the last window.
        while ((windows.empty() || t >= windows.back().start + window) &&
               windows.size() < kMaxWindows) {
          Window w;
          w.start = windows.empty() ? 0.0 : windows.back().start + window;
          w.misses = last_status.deadline_misses;
          w.late = last_status.late_ticks;
          windows.push_back(std::move(w));
        }
      }
      last_status = st;
      // The first published policy comes from the start-up solve (no deadline): not a tick.
      if (st.policy_status >= 0) {
        if (policy_seen) {
          latency_ms.push_back(st.tick_ms);
          solve_ms.push_back(st.solve_ms);
          if (st.prepared) {
            ++prepared;
            prepare_ms.push_back(st.prepare_ms);
          }
          if (!windows.empty()) {
            Window& w = windows.back();
            ++w.ticks;
            w.latency_ms.push_back(st.tick_ms);
            if (st.prepared) {
              w.prepare_ms.push_back(st.prepare_ms);
              w.work_ms.push_back(st.tick_ms + st.prepare_ms);
            }
          }
          if (st.solver_status >= 0)
            (st.step >= 1.0 ? full_steps : st.step > 0.0 ? short_steps : no_steps)++;
        }
        policy_seen = true;
      }
    }
  }
  if (states == 0 && statuses == 0) {
    std::fprintf(stderr, "stride-log-summary: no state on '%s' and no status on '%s' in '%s'\n",
                 state_channel.c_str(), status_channel.c_str(), log_path.c_str());
    return 1;
  }
  if (states == 0) {  // e.g. a replay's output: the controller's side only
    z_min = z_max = 0.0;
    std::printf("no state estimates in this log (a replay output?): controller side only\n");
  }
  const double distance = std::hypot(x1 - x0, y1 - y0);
  const double p50 = percentile(latency_ms, 0.5) * 1e3, p99 = percentile(latency_ms, 0.99) * 1e3;
  const double lmax =
      latency_ms.empty() ? 0.0 : *std::max_element(latency_ms.begin(), latency_ms.end()) * 1e3;
  if (states > 0)
    std::printf(
        "session %.1f s: walked %.3f m (x %+.3f, y %+.3f), base height %.3f .. %.3f m, "
        "max tilt %.1f deg, %s\n",
        t_last - t_first, distance, x1 - x0, y1 - y0, z_min, z_max, max_tilt,
        fell ? "FELL" : "did not fall");
  std::printf(
      "controller: %ld ticks, tick latency p50 %.0f us, p99 %.0f us, max %.0f us, "
      "solve p50 %.0f us, %lld deadline misses (%lld late starts), %lld fallbacks, %lld rejected "
      "messages\n",
      statuses, p50, p99, lmax, percentile(solve_ms, 0.5) * 1e3,
      static_cast<long long>(last_status.deadline_misses),
      static_cast<long long>(last_status.late_ticks), static_cast<long long>(last_status.fallbacks),
      static_cast<long long>(last_status.rejected_messages));
  // The other half of each iteration (run after the policy went out) and how the line search
  // went: a tick's latency is one rollout per step length tried.
  const long solved = full_steps + short_steps + no_steps;
  const auto pct = [&](long n) { return solved > 0 ? 100.0 * n / solved : 0.0; };
  std::printf(
      "solver: %ld of %zu ticks answered a prepared iteration (preparation p50 %.0f us, p99 %.0f "
      "us); steps: full %.0f%%, shorter %.0f%%, none %.0f%%\n",
      prepared, latency_ms.size(), percentile(prepare_ms, 0.5) * 1e3,
      percentile(prepare_ms, 0.99) * 1e3, pct(full_steps), pct(short_steps), pct(no_steps));
  if (!windows.empty())
    printWindows(windows, window, last_status.deadline_misses, last_status.late_ticks);
  if (bad > 0) std::printf("log: %ld undecodable events skipped\n", bad);
  if (!summary_path.empty()) {
    std::ofstream f(summary_path);
    f << "{\n  \"duration_s\": " << t_last - t_first << ",\n  \"distance_m\": " << distance
      << ",\n  \"base_height_min_m\": " << z_min << ",\n  \"base_height_max_m\": " << z_max
      << ",\n  \"max_tilt_deg\": " << max_tilt << ",\n  \"fell\": " << (fell ? "true" : "false")
      << ",\n  \"tick_latency_us\": {\"p50\": " << p50 << ", \"p99\": " << p99
      << ", \"max\": " << lmax << "},\n  \"solve_time_us_p50\": " << percentile(solve_ms, 0.5) * 1e3
      << ",\n  \"deadline_misses\": " << last_status.deadline_misses
      << ",\n  \"late_ticks\": " << last_status.late_ticks
      << ",\n  \"fallbacks\": " << last_status.fallbacks << ",\n  \"ticks\": " << statuses
      << ",\n  \"rejected_messages\": " << last_status.rejected_messages
      << ",\n  \"prepared_ticks\": " << prepared
      << ",\n  \"prepare_time_us\": {\"p50\": " << percentile(prepare_ms, 0.5) * 1e3
      << ", \"p99\": " << percentile(prepare_ms, 0.99) * 1e3 << "}"
      << ",\n  \"line_search\": {\"full\": " << full_steps << ", \"shorter\": " << short_steps
      << ", \"none\": " << no_steps << "}\n}\n";
    if (!f) {
      std::fprintf(stderr, "stride-log-summary: cannot write '%s'\n", summary_path.c_str());
      return 1;
    }
  }
  return 0;
}
