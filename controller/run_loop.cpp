#include "controller/run_loop.hpp"

#include <sched.h>
#include <sys/mman.h>
#include <time.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>

namespace stride {

namespace {
timespec addNanos(timespec t, long ns) {
  t.tv_nsec += ns;
  while (t.tv_nsec >= 1000000000L) {
    t.tv_nsec -= 1000000000L;
    ++t.tv_sec;
  }
  return t;
}
bool before(const timespec& a, const timespec& b) {
  return a.tv_sec < b.tv_sec || (a.tv_sec == b.tv_sec && a.tv_nsec < b.tv_nsec);
}
double secondsBetween(const timespec& a, const timespec& b) {
  return static_cast<double>(b.tv_sec - a.tv_sec) +
         1e-9 * static_cast<double>(b.tv_nsec - a.tv_nsec);
}
bool stopped(const RunOptions& o) {
  return o.stop != nullptr && o.stop->load();
}
}  // namespace

void applyRealTimeSettings(int cpu, int fifo_priority) {
  if (cpu >= 0) {
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(cpu, &set);
    if (sched_setaffinity(0, sizeof(set), &set) != 0)
      std::fprintf(stderr, "stride-mpc: warning: cannot pin to CPU %d (%s); running unpinned\n",
                   cpu, std::strerror(errno));
  }
  if (fifo_priority > 0) {
    sched_param p{};
    p.sched_priority = fifo_priority;
    if (sched_setscheduler(0, SCHED_FIFO, &p) != 0)
      std::fprintf(stderr,
                   "stride-mpc: warning: SCHED_FIFO %d not permitted (%s); normal scheduling, "
                   "expect more latency jitter (grant CAP_SYS_NICE or run under chrt)\n",
                   fifo_priority, std::strerror(errno));
    else if (mlockall(MCL_CURRENT | MCL_FUTURE) != 0)
      std::fprintf(stderr, "stride-mpc: warning: mlockall failed (%s); pages may fault\n",
                   std::strerror(errno));
  }
}

void runRealTime(MpcNode& node, lcm::LCM& in, const RunOptions& options) {
  const long period_ns = std::lround(1e9 / node.mpc().config().rate_hz);
  const auto period = std::chrono::nanoseconds(period_ns);
  const double fraction = node.mpc().config().deadline_fraction;
  timespec start, next;
  clock_gettime(CLOCK_MONOTONIC, &start);
  next = start;
  while (!stopped(options)) {
    next = addNanos(next, period_ns);
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, nullptr) == EINTR) {
      if (stopped(options)) return;
    }
    // Every message that arrived since the last tick; the newest valid state wins.
    while (in.handleTimeout(0) > 0) {
    }
    node.applyPendingPlan();
    const auto tick_start = Mpc::Clock::now();
    node.tick(tick_start + std::chrono::duration_cast<Mpc::Clock::duration>(period * fraction));
    // The policy is out: linearize for the next state until the next tick is due (steady_clock
    // is CLOCK_MONOTONIC on Linux, so the two clocks' time points compare).
    const timespec due = addNanos(next, period_ns);
    node.prepare(Mpc::Clock::time_point(std::chrono::duration_cast<Mpc::Clock::duration>(
        std::chrono::seconds(due.tv_sec) + std::chrono::nanoseconds(due.tv_nsec))));
    timespec now;
    clock_gettime(CLOCK_MONOTONIC, &now);
    if (!before(now, due)) {
      // Overran into the next period: skip the ticks that are already late rather than bursting.
      if (!node.mpc().startupTick()) node.mpc().countOverrun();
      while (!before(now, addNanos(next, period_ns))) next = addNanos(next, period_ns);
    }
    if (options.duration > 0.0 && secondsBetween(start, now) >= options.duration) return;
  }
}

void runOnStamps(MpcNode& node, lcm::LCM& in, const RunOptions& options) {
  timespec start;
  clock_gettime(CLOCK_MONOTONIC, &start);
  while (!stopped(options)) {
    const int handled = in.handleTimeout(100);
    if (handled < 0) return;  // end of the log (file provider) or a broken input
    node.applyPendingPlan();
    if (node.tickDue()) {
      node.tick(Mpc::Clock::time_point::max());
      node.prepare(Mpc::Clock::time_point::max());
    }
    if (options.duration > 0.0) {
      timespec now;
      clock_gettime(CLOCK_MONOTONIC, &now);
      if (secondsBetween(start, now) >= options.duration) return;
    }
  }
}

LatencySummary summarizeLatencies(const MpcNode& node) {
  std::vector<float> v = node.latencies();
  LatencySummary s;
  s.count = static_cast<long>(v.size());
  if (v.empty()) return s;
  std::sort(v.begin(), v.end());
  auto at = [&](double p) {
    const auto i = static_cast<size_t>(std::ceil(p * static_cast<double>(v.size())) - 1);
    return static_cast<double>(v[std::min(i, v.size() - 1)]);
  };
  s.p50 = at(0.50);
  s.p99 = at(0.99);
  s.max = v.back();
  return s;
}

void writeSummary(const MpcNode& node, const std::string& path) {
  const MpcCounters& c = node.mpc().counters();
  const LatencySummary lat = summarizeLatencies(node);
  std::printf(
      "stride-mpc: %lld ticks, %lld states accepted, %lld rejected, tick latency p50 %.3f ms "
      "p99 %.3f ms max %.3f ms (%ld ticks), %lld deadline misses, %lld fallbacks, %lld stale "
      "states, %lld failed solves, %lld unprepared solves, %lld plan updates\n",
      static_cast<long long>(c.ticks), static_cast<long long>(node.acceptedStates()),
      static_cast<long long>(node.rejected()), lat.p50, lat.p99, lat.max, lat.count,
      static_cast<long long>(c.deadline_misses), static_cast<long long>(c.fallbacks),
      static_cast<long long>(c.stale_states), static_cast<long long>(c.failed_solves),
      static_cast<long long>(c.unprepared_solves), static_cast<long long>(node.planUpdates()));
  if (node.rejected() > 0) {
    std::printf("stride-mpc: rejected messages by reason:");
    for (int r = 1; r <= static_cast<int>(msg::Reject::Stale); ++r)
      if (node.rejected(static_cast<msg::Reject>(r)) > 0)
        std::printf(" %s: %lld;", msg::describe(static_cast<msg::Reject>(r)),
                    static_cast<long long>(node.rejected(static_cast<msg::Reject>(r))));
    std::printf("\n");
  }
  if (path.empty()) return;
  std::ofstream f(path);
  f << "{\n  \"ticks\": " << c.ticks << ",\n  \"states_accepted\": " << node.acceptedStates()
    << ",\n  \"rejected_messages\": " << node.rejected()
    << ",\n  \"tick_latency_ms\": {\"p50\": " << lat.p50 << ", \"p99\": " << lat.p99
    << ", \"max\": " << lat.max << ", \"count\": " << lat.count
    << "},\n  \"deadline_misses\": " << c.deadline_misses << ",\n  \"fallbacks\": " << c.fallbacks
    << ",\n  \"stale_states\": " << c.stale_states << ",\n  \"failed_solves\": " << c.failed_solves
    << ",\n  \"unprepared_solves\": " << c.unprepared_solves
    << ",\n  \"ticks_without_state\": " << c.ticks_without_state << "\n}\n";
  if (!f) std::fprintf(stderr, "stride-mpc: cannot write the summary to '%s'\n", path.c_str());
}

}  // namespace stride
