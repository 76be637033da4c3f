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
#include <nlohmann/json.hpp>

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
// Tells host stalls from the controller's own overruns: between two marks, the wall time the
// process had work minus the CPU time all its threads got (busy work, the emulated slowdown too,
// counts as CPU time; more threads only lower the difference).
class StallMeter {
 public:
  void mark() {
    clock_gettime(CLOCK_MONOTONIC, &wall_);
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &cpu_);
  }
  // Since the last mark (and marks again).
  bool stalled() {
    const timespec wall = wall_, cpu = cpu_;
    mark();
    return 1e3 * (secondsBetween(wall, wall_) - secondsBetween(cpu, cpu_)) > Mpc::kHostStallMs;
  }

 private:
  timespec wall_{}, cpu_{};
};
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
  // A tick's deadline is on its answer, not its start: the policy must be out by its nominal time
  // + fraction * period. The preparation that follows a tick may run past the next nominal time
  // (it is background work for that tick); the next tick then starts late, counted as a late tick,
  // and misses only if its answer is late too. Skipping a tick for every small overrun instead
  // left the robot 10 ms without an update each time (see README.md, "Deadlines").
  const long deadline_ns = std::lround(period_ns * node.mpc().config().deadline_fraction);
  const auto toTimePoint = [](const timespec& t) {
    // steady_clock is CLOCK_MONOTONIC on Linux: the two clocks' time points compare.
    return Mpc::Clock::time_point(std::chrono::duration_cast<Mpc::Clock::duration>(
        std::chrono::seconds(t.tv_sec) + std::chrono::nanoseconds(t.tv_nsec)));
  };
  timespec start, next, now;
  clock_gettime(CLOCK_MONOTONIC, &start);
  next = start;
  StallMeter meter;
  bool stalled = false;  // since the last period was counted
  while (!stopped(options)) {
    next = addNanos(next, period_ns);
    clock_gettime(CLOCK_MONOTONIC, &now);
    const bool late = !before(now, next);  // the last period's work ran past this tick's time
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, nullptr) == EINTR) {
      if (stopped(options)) return;
    }
    const timespec deadline = addNanos(next, deadline_ns);
    clock_gettime(CLOCK_MONOTONIC, &now);
    meter.mark();
    // Woken that late from a sleep: the host did not run the controller.
    if (!late && 1e3 * secondsBetween(next, now) > Mpc::kHostStallMs) stalled = true;
    if (!before(now, deadline)) {
      // Its answer could not be on time any more: the tick is lost, and the loop moves on to the
      // next period instead of bunching late ticks. (Before the first state there is no answer
      // to miss.)
      const bool miss = node.hasState();
      if (miss) node.mpc().countSkippedTick();
      node.mpc().countPeriod(miss, stalled);
      stalled = false;
      continue;
    }
    if (late) node.mpc().countLateTick();
    // Every message that arrived since the last tick; the newest valid state wins.
    while (in.handleTimeout(0) > 0) {
    }
    node.applyPendingPlan();
    const std::int64_t misses = node.mpc().counters().deadline_misses;
    node.tick(toTimePoint(deadline));
    const bool missed = node.mpc().counters().deadline_misses > misses;
    stalled = meter.stalled() || stalled;
    node.mpc().countPeriod(missed, stalled);
    stalled = false;
    // The policy is out: linearize for the next state, by half a period into the next one at the
    // latest, so that the next tick still has time for its rollout before its deadline; a
    // preparation cut there leaves the next tick to re-send the previous policy and prepare again
    // (controller/README.md, "Overload"). After a miss, by the next tick's start: that tick then
    // starts on time, with its preparation or re-sending the previous policy, and cannot miss too.
    node.prepare(toTimePoint(addNanos(next, missed ? period_ns : period_ns + period_ns / 2)));
    stalled = meter.stalled();  // a stalled preparation makes the next tick late
    clock_gettime(CLOCK_MONOTONIC, &now);
    // The start-up solve runs without deadline: the periods it took are not ticks.
    if (node.mpc().startupTick()) next = now;
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

Percentiles summarizeLatencies(const MpcNode& node) {
  const std::vector<float>& v = node.latencies();
  return percentiles(std::vector<double>(v.begin(), v.end()));
}

namespace {
// A timing in ms as the summaries write it: to the nanosecond, below the clock's resolution (a
// float latency's binary tail is noise, not precision), and null where there is no data.
nlohmann::ordered_json msOrNull(const std::optional<double>& ms) {
  if (!ms) return nullptr;
  return std::round(*ms * 1e6) / 1e6;
}
// The shape of every timing distribution in the summaries (stride-log-summary's too).
nlohmann::ordered_json timingJson(const Percentiles& p) {
  return {{"p50_ms", msOrNull(p.p50)},
          {"p99_ms", msOrNull(p.p99)},
          {"max_ms", msOrNull(p.max)},
          {"count", p.count}};
}
}  // namespace

void writeSummary(const MpcNode& node, const std::string& path) {
  const MpcCounters& c = node.mpc().counters();
  const Percentiles lat = summarizeLatencies(node);
  std::printf(
      "stride-mpc: %lld ticks, %lld states accepted, %lld rejected, tick latency p50 %.3f ms "
      "p99 %.3f ms max %.3f ms (%ld ticks), %lld deadline misses, %lld late ticks, %lld fallbacks, "
      "%lld stale states, %lld failed solves, %lld unprepared solves, %lld plan updates\n"
      "stride-mpc: overload: %lld ticks with the full step only, %lld ticks re-sending the "
      "previous policy, at most %lld misses in a row (%lld without a host stall; %lld periods "
      "stalled by the host); %lld stalled-solve restarts, %lld start-up solves made again on a "
      "newer state\n",
      static_cast<long long>(c.ticks), static_cast<long long>(node.acceptedStates()),
      static_cast<long long>(node.rejected()), lat.p50.value_or(0.0), lat.p99.value_or(0.0),
      lat.max.value_or(0.0), lat.count, static_cast<long long>(c.deadline_misses),
      static_cast<long long>(c.late_ticks), static_cast<long long>(c.fallbacks),
      static_cast<long long>(c.stale_states), static_cast<long long>(c.failed_solves),
      static_cast<long long>(c.unprepared_solves), static_cast<long long>(node.planUpdates()),
      static_cast<long long>(c.shed_line_searches), static_cast<long long>(c.shed_ticks),
      static_cast<long long>(c.max_misses_in_a_row),
      static_cast<long long>(c.max_own_misses_in_a_row), static_cast<long long>(c.host_stalls),
      static_cast<long long>(c.stall_restarts), static_cast<long long>(c.startup_resolves));
  const CommandCounters& cc = node.commands().counters();
  std::printf(
      "stride-mpc: commands: %lld accepted, %lld rejected, %lld clamped, %lld deadman timeouts\n",
      static_cast<long long>(cc.accepted),
      static_cast<long long>(cc.rejected + node.commandsMalformed()),
      static_cast<long long>(cc.clamped), static_cast<long long>(cc.timeouts));
  if (node.rejected() > 0) {
    std::printf("stride-mpc: rejected messages by reason:");
    for (int r = 1; r < msg::kRejectReasons; ++r)
      if (node.rejected(static_cast<msg::Reject>(r)) > 0)
        std::printf(" %s: %lld;", msg::describe(static_cast<msg::Reject>(r)),
                    static_cast<long long>(node.rejected(static_cast<msg::Reject>(r))));
    std::printf("\n");
  }
  for (int i = 0; i < node.mismatchCount(); ++i)
    std::printf("stride-mpc: %lld states of another model: %s\n",
                static_cast<long long>(node.mismatch(i).count), node.mismatch(i).text.data());
  if (node.clockRebasesAhead() + node.clockRebasesBack() > 0)
    std::printf(
        "stride-mpc: the robot's clock taken anew %lld times (%lld a clock offset, %lld a new "
        "robot)\n",
        static_cast<long long>(node.clockRebasesAhead() + node.clockRebasesBack()),
        static_cast<long long>(node.clockRebasesAhead()),
        static_cast<long long>(node.clockRebasesBack()));
  if (node.auth().keyed())
    std::printf(
        "stride-mpc: signed with key %08x; %lld messages not signed with it refused%s%s%s\n",
        node.auth().keyId(), static_cast<long long>(node.auth().refused()),
        node.auth().refused() > 0 ? " (" : "", msg::refusedText(node.auth()).c_str(),
        node.auth().refused() > 0 ? ")" : "");
  if (node.rivalPolicies() > 0)
    std::printf("stride-mpc: %lld policies of another controller on '%s' (a robot follows one)\n",
                static_cast<long long>(node.rivalPolicies()), node.config().policy_channel.c_str());
  if (path.empty()) return;
  nlohmann::ordered_json j;
  j["ticks"] = c.ticks;
  j["policies"] = node.policiesPublished();
  j["states_accepted"] = node.acceptedStates();
  j["rejected_messages"] = node.rejected();
  j["wrong_model"] = node.wrongModel();        // of rejected_messages: another model's states
  j["rival_policies"] = node.rivalPolicies();  // another controller's, on this one's channel
  // The robot's clock taken anew after its stamps stayed ahead (a clock offset) or went back (a
  // new robot): MpcNode::onState.
  // Messages refused for their signatures, by reason (null: no key, the wire unauthenticated).
  const msg::WireAuth& auth = node.auth();
  j["unauthenticated"] =
      auth.keyed()
          ? nlohmann::ordered_json{{"unsigned", auth.refused(msg::Verdict::Unsigned)},
                                   {"wrong_key", auth.refused(msg::Verdict::WrongKey)},
                                   {"forged", auth.refused(msg::Verdict::Forged)},
                                   {"replayed", auth.refused(msg::Verdict::Replayed)},
                                   {"stale", auth.refused(msg::Verdict::Stale)},
                                   {"future", auth.refused(msg::Verdict::Future)},
                                   {"impossible_size", auth.refused(msg::Verdict::Implausible)},
                                   {"over_rate", auth.refused(msg::Verdict::OverRate)}}
          : nlohmann::ordered_json(nullptr);
  j["other_session_states"] = node.rejected(msg::Reject::OtherSession);
  j["session_switches"] = node.sessionSwitches();
  j["clock_rebases"] = {{"offset", node.clockRebasesAhead()},
                        {"new_robot", node.clockRebasesBack()}};
  j["tick_latency"] = timingJson(lat);
  j["deadline_misses"] = c.deadline_misses;
  j["late_ticks"] = c.late_ticks;
  j["fallbacks"] = c.fallbacks;
  j["stale_states"] = c.stale_states;
  j["failed_solves"] = c.failed_solves;
  j["unprepared_solves"] = c.unprepared_solves;
  j["ticks_without_state"] = c.ticks_without_state;
  j["stall_restarts"] = c.stall_restarts;
  j["startup_resolves"] = c.startup_resolves;
  j["overload"] = {{"full_step_only", c.shed_line_searches},
                   {"previous_policy_ticks", c.shed_ticks},
                   {"max_misses_in_a_row", c.max_misses_in_a_row},
                   {"max_own_misses_in_a_row", c.max_own_misses_in_a_row},
                   {"host_stalls", c.host_stalls}};
  j["commands"] = {{"accepted", cc.accepted},
                   {"rejected", cc.rejected + node.commandsMalformed()},
                   {"clamped", cc.clamped},
                   {"deadman_timeouts", cc.timeouts}};
  std::ofstream f(path);
  f << j.dump(2) << "\n";
  if (!f) std::fprintf(stderr, "stride-mpc: cannot write the summary to '%s'\n", path.c_str());
}

}  // namespace stride
