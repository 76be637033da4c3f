#include "messages/wire_auth.hpp"

#include <time.h>

#include <cmath>
#include <cstdio>
#include <cstring>

namespace stride::msg {

namespace {
std::int64_t realtimeNowMicros() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1000000 + ts.tv_nsec / 1000;
}
}  // namespace

WireAuth::WireAuth(const Key& key, const char* who, std::int64_t window_us) : who_(who) {
  signer_.emplace(key, randomSenderId());
  for (auto& v : verifiers_) v.emplace(key, window_us);
}

void WireAuth::setSizes(int slot, const SizeRule& sizes) {
  if (keyed() && slot >= 0 && slot < kMaxChannels) verifiers_[slot]->setSizes(sizes);
}

int WireAuth::receive(int slot, const char* channel, const std::uint8_t* buf, int size,
                      std::int64_t recv_utime) noexcept {
  if (!keyed()) return static_cast<int>(unsignedPayloadSize(buf, size));
  if (slot < 0 || slot >= kMaxChannels) return -1;
  Verifier& v = *verifiers_[slot];
  int payload = size;
  // Freshness against this host's clock when the message arrived (LCM's receive thread), not when
  // the node got to it: a node busy for a moment does not make fresh messages stale.
  const std::int64_t now = recv_utime > 0 ? recv_utime : realtimeNowMicros();
  const Verdict verdict = v.check(channel, buf, size, now, payload);
  if (verdict == Verdict::Ok) return payload;
  if (v.sayOnce(verdict)) {
    if (verdict == Verdict::Stale || verdict == Verdict::Future)
      // The offset says which: a recording (seconds to days behind) or a host whose clock is off
      // (messages/README.md, "Freshness": chrony or PTP keeps them together).
      std::fprintf(stderr,
                   "%s: warning: refused a message on '%s': %s: its timestamp is %.3f s %s this "
                   "host's clock (window %.3f s): a recording replayed, or the sender's clock is "
                   "off (keep the hosts' clocks together: chrony or PTP); the first such, the "
                   "later ones are counted\n",
                   who_, channel, describe(verdict),
                   std::abs(static_cast<double>(v.lastOffset())) * 1e-6,
                   verdict == Verdict::Stale ? "behind" : "ahead of",
                   static_cast<double>(v.window()) * 1e-6);
    else
      std::fprintf(stderr,
                   "%s: warning: refused a message on '%s': %s (the first such; the later ones "
                   "are counted)\n",
                   who_, channel, describe(verdict));
  }
  return -1;
}

void WireAuth::accept(int slot) noexcept {
  if (keyed() && slot >= 0 && slot < kMaxChannels) verifiers_[slot]->accept();
}

int WireAuth::send(const char* channel, std::uint8_t* buf, int payload_size,
                   int capacity) noexcept {
  if (!keyed()) return payload_size;
  return signer_->sign(channel, buf, payload_size, capacity);
}

std::int64_t WireAuth::refused(Verdict verdict) const {
  std::int64_t n = 0;
  for (const auto& v : verifiers_)
    if (v) n += v->count(verdict);
  return n;
}

std::int64_t WireAuth::refused() const {
  std::int64_t n = 0;
  for (int r = 1; r < kVerdicts; ++r) n += refused(static_cast<Verdict>(r));
  return n;
}

std::optional<Key> keyForProgram(const std::string& path, const char* who) {
  if (!path.empty()) return loadKeyFile(path);
  std::fprintf(stderr,
               "%s: warning: no key (--key-file, or lcm.key_file in the controller's YAML): the "
               "wire is unauthenticated, anyone on the bus can send this program messages "
               "(messages/README.md, \"Signing\")\n",
               who);
  return std::nullopt;
}

std::string refusedText(const WireAuth& auth) {
  if (auth.refused() == 0) return "";
  std::string text;
  const char* names[kVerdicts] = {"",
                                  "unsigned",
                                  "signed with another key",
                                  "forged",
                                  "replayed",
                                  "stale",
                                  "from the future",
                                  "of an impossible size",
                                  "over the new senders' rate"};
  bool first = true;
  for (int r = 1; r < kVerdicts; ++r) {
    const std::int64_t n = auth.refused(static_cast<Verdict>(r));
    if (n == 0) continue;
    text += (first ? "" : ", ") + std::to_string(n) + " " + names[r];
    first = false;
  }
  return text;
}

SigningPublisher::SigningPublisher(Publisher& out, WireAuth& auth, int capacity)
    : out_(out), auth_(auth) {
  if (auth_.keyed()) buffer_.resize(static_cast<std::size_t>(capacity) + kSignatureSize);
}

void SigningPublisher::reserve(int capacity) {
  const std::size_t n = static_cast<std::size_t>(capacity) + kSignatureSize;
  if (auth_.keyed() && buffer_.size() < n) buffer_.resize(n);
}

void SigningPublisher::publish(const std::string& channel, const void* data, int size) {
  if (!auth_.keyed()) {
    out_.publish(channel, data, size);
    return;
  }
  if (buffer_.size() < static_cast<std::size_t>(size) + kSignatureSize)
    buffer_.resize(static_cast<std::size_t>(size) + kSignatureSize);
  std::memcpy(buffer_.data(), data, static_cast<std::size_t>(size));
  const int n = auth_.send(channel.c_str(), buffer_.data(), size, static_cast<int>(buffer_.size()));
  if (n > 0) out_.publish(channel, buffer_.data(), n);
}

}  // namespace stride::msg
