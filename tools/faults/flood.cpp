// stride-flood: a stream of policies that no robot here may take, published on a policy channel at
// a fixed rate (issue 19: a flood of rejected messages must cost bounded time and never starve the
// valid stream). Each is a well-formed policy_t of another robot's sizes and model hash, so every
// receiver refuses it on its raw bytes (messages/validate.hpp) after paying for its delivery:
// what a misconfigured controller of a bigger robot on the same network would send.
// With --forged KEY_FILE (issue 44), frames an attacker without the key would send instead: --size
// random bytes with a signature trailer that claims the key's id (read from the file: the wire
// shows it), a new sender id each, a timestamp of now (fresh), a random mac: each receiver with the
// key must refuse them without hashing them (a size no message of the channel has, the new
// senders' budget), and the robot walk on. --channel takes several channels, comma-separated,
// sent in turn.
// With --future KEY_FILE (issue 44), what a holder of the key with a wrong clock, or a compromised
// one, can send: junk policies of the robot's model (a NaN gain, no run's session) signed with
// the key under the live controller's sender id (read from the policy channel's trailers),
// stamped in turn INT64_MAX, an hour ahead and 0.3 s ahead. The first two are outside every
// receiver's window and refused unread; the third is read and refused as of another run. None may
// change the replay table, so the live controller keeps the robot.
//   stride-flood [--url URL] [--channel STRIDE_POLICY] [--rate 1000] [--duration S]
//                [--nq 20] [--nv 19] [--nu 13] [--knots 10] [--forged KEY_FILE --size 60000]
//                [--future KEY_FILE]
// Exit status: 0 after --duration (or SIGINT/SIGTERM); 1 LCM could not start; 2 bad arguments.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <lcm/lcm-cpp.hpp>
#include <limits>
#include <string>
#include <vector>

#include "config/command_line.hpp"
#include "messages/signing.hpp"
#include "messages/validate.hpp"
#include "stride/policy_t.hpp"

namespace {

volatile std::sig_atomic_t g_stop = 0;
void onSignal(int) {
  g_stop = 1;
}

std::int64_t wallMicros() {
  timespec wall{};
  clock_gettime(CLOCK_REALTIME, &wall);
  return static_cast<std::int64_t>(wall.tv_sec) * 1000000 + wall.tv_nsec / 1000;
}

// The live controller as the policy channel shows it: its sender id (the trailer's) and its
// robot's model (the policy's own claim).
struct LiveSender {
  std::uint32_t sender = 0;
  stride::msg::WireClaim claim;
  void onPolicy(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    const auto* b = static_cast<const std::uint8_t*>(rbuf->data);
    const int n = static_cast<int>(rbuf->data_size);
    stride::msg::SignatureClaim signature;
    if (!stride::msg::readSignatureClaim(b, n, signature) ||
        !stride::msg::readPolicyClaim(b, n, claim))
      return;
    sender = signature.sender;
  }
};

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
  std::string forged_key;
  int forged_size = 60000;
  app.add_option("--forged", forged_key,
                 "send forged frames claiming this key file's key id instead (the key itself is "
                 "not used)");
  app.add_option("--size", forged_size, "bytes of a forged frame's payload (60000)")
      ->check(CLI::Range(1, 1 << 24));
  std::string future_key;
  app.add_option("--future", future_key,
                 "send junk policies signed with this key file's key, under the live "
                 "controller's sender id, stamped far ahead, instead")
      ->excludes("--forged");
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
  std::uint32_t key_id = 0;
  if (!forged_key.empty()) {
    try {
      key_id = stride::msg::loadKeyFile(forged_key).id;
    } catch (const std::exception& e) {
      std::fprintf(stderr, "stride-flood: %s\n", e.what());
      return 2;
    }
    bytes.assign(static_cast<std::size_t>(forged_size) + stride::msg::kSignatureSize, 0);
    for (std::size_t i = 0; i < bytes.size(); ++i)
      bytes[i] = static_cast<unsigned char>(std::rand());
  }
  // The channels, sent in turn.
  std::vector<std::string> channels;
  for (std::size_t at = 0; at <= channel.size();) {
    const std::size_t comma = std::min(channel.find(',', at), channel.size());
    if (comma > at) channels.push_back(channel.substr(at, comma - at));
    at = comma + 1;
  }
  if (channels.empty()) {
    std::fprintf(stderr, "stride-flood: --channel names no channel\n");
    return 2;
  }
  stride::msg::Key future{};
  if (!future_key.empty()) {
    try {
      future = stride::msg::loadKeyFile(future_key);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "stride-flood: %s\n", e.what());
      return 2;
    }
    if (channels.size() != 1) {
      std::fprintf(stderr, "stride-flood: --future takes one policy channel\n");
      return 2;
    }
  }

  lcm::LCM lcm(url);
  if (!lcm.good()) {
    std::fprintf(stderr, "stride-flood: cannot start LCM on '%s'\n", url.c_str());
    return 1;
  }
  struct sigaction sa {};
  sa.sa_handler = onSignal;
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  LiveSender live;
  if (!future_key.empty()) {
    lcm.subscribe(channels[0], &LiveSender::onPolicy, &live);
    std::printf(
        "stride-flood: %.0f junk policies/s signed with key %08x under the live controller's "
        "sender id, stamped INT64_MAX, +1 h and +0.3 s in turn, on '%s'\n",
        rate, future.id, channels[0].c_str());
  } else if (forged_key.empty())
    std::printf(
        "stride-flood: %.0f policies/s of %zu bytes (nq %d, nv %d, nu %d, %d knots, model "
        "hash 0x5eed) on '%s'\n",
        rate, bytes.size(), nq, nv, nu, knots, channel.c_str());
  else
    std::printf(
        "stride-flood: %.0f forged frames/s of %zu bytes claiming key id %08x, fresh timestamps, "
        "a new sender each, on '%s'\n",
        rate, bytes.size(), key_id, channel.c_str());
  std::fflush(stdout);

  const long long period_ns = static_cast<long long>(1e9 / rate);
  timespec start, next;
  clock_gettime(CLOCK_MONOTONIC, &start);
  next = start;
  long long sent = 0, failed = 0, waited = 0;
  while (!g_stop) {
    if (!future_key.empty()) {
      // Read what the bus brought meanwhile (the live sender), then sign one junk policy.
      while (lcm.handleTimeout(0) > 0) {
      }
      if (live.sender == 0) {
        ++waited;  // no signed policy seen yet: nothing to claim
      } else {
        stride::policy_t junk;
        stride::msg::shape(junk, 8, live.claim.nq, live.claim.nv, live.claim.nv - 6);
        junk.model_hash = live.claim.hash;
        junk.dt = 0.01;
        junk.K[0][0] = std::numeric_limits<double>::quiet_NaN();
        bytes.assign(static_cast<std::size_t>(junk.getEncodedSize()) + stride::msg::kSignatureSize,
                     0);
        const int n = junk.encode(bytes.data(), 0, junk.getEncodedSize());
        const std::int64_t ahead[3] = {std::numeric_limits<std::int64_t>::max(),
                                       wallMicros() + 3600LL * 1000000, wallMicros() + 300000};
        const stride::msg::Signer signer(future, live.sender);
        const int size = signer.signAt(channels[0].c_str(), bytes.data(), n,
                                       static_cast<int>(bytes.size()), ahead[sent % 3]);
        if (lcm.publish(channels[0], bytes.data(), static_cast<unsigned>(size)) == 0)
          ++sent;
        else
          ++failed;
      }
    } else if (!forged_key.empty()) {
      // The trailer: key id, a new sender, now, a made-up mac, the magic (big-endian fields).
      unsigned char* t = bytes.data() + bytes.size() - stride::msg::kSignatureSize;
      timespec wall{};
      clock_gettime(CLOCK_REALTIME, &wall);
      const std::uint64_t now =
          static_cast<std::uint64_t>(wall.tv_sec) * 1000000u + wall.tv_nsec / 1000;
      const std::uint32_t sender = static_cast<std::uint32_t>(sent) * 2654435761u + 1u;
      for (int i = 0; i < 4; ++i) t[i] = static_cast<unsigned char>(key_id >> (24 - 8 * i));
      for (int i = 0; i < 4; ++i) t[4 + i] = static_cast<unsigned char>(sender >> (24 - 8 * i));
      for (int i = 0; i < 8; ++i) t[8 + i] = static_cast<unsigned char>(now >> (56 - 8 * i));
      for (int i = 0; i < 16; ++i) t[16 + i] = static_cast<unsigned char>(std::rand());
      std::memcpy(t + 32, stride::msg::kSignatureMagic.data(), 4);
    }
    if (future_key.empty()) {
      const std::string& to = channels[static_cast<std::size_t>(sent + failed) % channels.size()];
      if (lcm.publish(to, bytes.data(), static_cast<unsigned>(bytes.size())) == 0)
        ++sent;
      else
        ++failed;
    }
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
  std::printf("stride-flood: %lld %s sent in %.1f s (%.0f/s), %lld failed to send", sent,
              !future_key.empty()  ? "junk policies from the future"
              : forged_key.empty() ? "policies"
                                   : "forged frames",
              elapsed, elapsed > 0.0 ? sent / elapsed : 0.0, failed);
  if (!future_key.empty()) std::printf(", %lld not sent before a signed policy was seen", waited);
  std::printf("\n");
  return 0;
}
