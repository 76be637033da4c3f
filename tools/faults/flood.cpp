// stride-flood: a stream of policies that no robot here may take, published on a policy channel at
// a fixed rate (issue 19: a flood of rejected messages must cost bounded time and never starve the
// valid stream). Each is a well-formed policy_t of another robot's sizes and model hash, so every
// receiver refuses it on its raw bytes (messages/validate.hpp) after paying for its delivery:
// what a misconfigured controller of a bigger robot on the same network would send.
//   stride-flood [--url URL] [--channel STRIDE_POLICY] [--rate 1000] [--duration S]
//                [--nq 20] [--nv 19] [--nu 13] [--knots 10]
// Exit status: 0 after --duration (or SIGINT/SIGTERM); 1 LCM could not start; 2 bad arguments.
#include <CLI/CLI.hpp>

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <lcm/lcm-cpp.hpp>
#include <string>
#include <vector>

#include "config/command_line.hpp"
#include "messages/validate.hpp"
#include "stride/policy_t.hpp"

namespace {

volatile std::sig_atomic_t g_stop = 0;
void onSignal(int) {
  g_stop = 1;
}

void addNanos(timespec& t, long long ns) {
  t.tv_nsec += ns;
  while (t.tv_nsec >= 1000000000L) {
    t.tv_nsec -= 1000000000L;
    ++t.tv_sec;
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"stride-flood: policies of another robot on a policy channel, at a fixed rate"};
  stride::commandLineConventions(app, "stride-flood");
  std::string url, channel = "STRIDE_POLICY";
  double rate = 1000.0, duration = 0.0;
  int nq = 20, nv = 19, nu = 13, knots = 10;
  app.add_option("--url", url, "LCM URL (default: LCM_DEFAULT_URL; one of the two is required)");
  app.add_option("--channel", channel, "the policy channel to flood (STRIDE_POLICY)");
  app.add_option("--rate", rate, "policies per second (1000)")->check(CLI::Range(1.0, 1e5));
  app.add_option("--duration", duration, "seconds, 0 until SIGINT/SIGTERM (0)")
      ->check(CLI::NonNegativeNumber);
  // The default sizes: a 13-joint legged robot's, 10 knots: 44 kB, the flood (42 kB), in
  // one UDP datagram.
  app.add_option("--nq", nq, "its configuration size (20)")->check(CLI::Range(1, 1000));
  app.add_option("--nv", nv, "its velocity size (19)")->check(CLI::Range(1, 1000));
  app.add_option("--nu", nu, "its control size (13)")->check(CLI::Range(1, 1000));
  app.add_option("--knots", knots, "its knots (10)")->check(CLI::Range(1, 1000));
  if (const int status = stride::parseCommandLine(app, argc, argv); status >= 0) return status;
  url = stride::lcmUrl(url);
  if (url.empty()) return stride::noLcmUrl("stride-flood", "pass --url");

  stride::policy_t foreign;
  stride::msg::shape(foreign, knots, nq, nv, nu);
  foreign.model_hash = 0x5eed;  // no robot's
  foreign.source_id = 0xf100d;  // no controller's
  foreign.dt = 0.01;
  std::vector<unsigned char> bytes(foreign.getEncodedSize());
  foreign.encode(bytes.data(), 0, static_cast<int>(bytes.size()));

  lcm::LCM lcm(url);
  if (!lcm.good()) {
    std::fprintf(stderr, "stride-flood: cannot start LCM on '%s'\n", url.c_str());
    return 1;
  }
  struct sigaction sa {};
  sa.sa_handler = onSignal;
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  std::printf(
      "stride-flood: %.0f policies/s of %zu bytes (nq %d, nv %d, nu %d, %d knots, model "
      "hash 0x5eed) on '%s'\n",
      rate, bytes.size(), nq, nv, nu, knots, channel.c_str());
  std::fflush(stdout);

  const long long period_ns = static_cast<long long>(1e9 / rate);
  timespec start, next;
  clock_gettime(CLOCK_MONOTONIC, &start);
  next = start;
  long long sent = 0, failed = 0;
  while (!g_stop) {
    if (lcm.publish(channel, bytes.data(), static_cast<unsigned>(bytes.size())) == 0)
      ++sent;
    else
      ++failed;
    addNanos(next, period_ns);
    // Behind by more than a period (the host kept it off the CPU): no burst to catch up.
    timespec now;
    clock_gettime(CLOCK_MONOTONIC, &now);
    const double behind = static_cast<double>(now.tv_sec - next.tv_sec) * 1e9 +
                          static_cast<double>(now.tv_nsec - next.tv_nsec);
    if (behind > static_cast<double>(period_ns)) next = now;
    if (duration > 0.0 && static_cast<double>(next.tv_sec - start.tv_sec) +
                                  1e-9 * static_cast<double>(next.tv_nsec - start.tv_nsec) >=
                              duration)
      break;
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, nullptr) == EINTR && !g_stop) {
    }
  }
  timespec end;
  clock_gettime(CLOCK_MONOTONIC, &end);
  const double elapsed = static_cast<double>(end.tv_sec - start.tv_sec) +
                         1e-9 * static_cast<double>(end.tv_nsec - start.tv_nsec);
  std::printf("stride-flood: %lld policies sent in %.1f s (%.0f/s), %lld failed to send\n", sent,
              elapsed, elapsed > 0.0 ? sent / elapsed : 0.0, failed);
  return 0;
}
