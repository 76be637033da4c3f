#pragma once
// Authenticated LCM messages (messages/README.md, "Signing"): a signature trailer appended to the
// LCM-encoded bytes, in the manner of MAVLink 2's message signing. A shared 32-byte secret key,
// its key id, a per-sender id and a per-sender strictly increasing timestamp against replay, and a
// MAC (HMAC-SHA256 truncated to 16 bytes) over the channel, those fields and the payload's SHA-256.
//
// Trailer (kSignatureSize = 36 bytes after the payload; integers big-endian):
//   key_id (4) | sender (4) | timestamp (8, microseconds, signed) | mac (16) | magic "STS1" (4)
// The magic comes last, so that a receiver finds the trailer from the end; LCM decoders read from
// the front and ignore trailing bytes, so lcm-spy and the type fingerprints are unaffected.
// A receiver judges the trailer's fields and the size first (cheap), then the mac (messages/
// README.md, "Cheap refusals").
//   key_id = first 4 bytes of SHA-256("stride key id" || key)
//   mac    = first 16 bytes of HMAC-SHA256(key, "stride-sig-v1" || channel || 0x00 || key_id ||
//                                               sender || timestamp || SHA-256(payload))
//
// Signer::sign and Verifier::check allocate nothing and throw nothing (real-time paths); only the
// key files' functions (and randomSenderId, makeKey, if libsodium cannot start) throw.

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>

namespace stride::msg {

constexpr int kSignatureSize = 36;     // the trailer's bytes
constexpr int kKeySize = 32;           // the shared secret's bytes
constexpr int kSignatureMacSize = 16;  // HMAC-SHA256 truncated to its first 16 bytes
// The last 4 bytes of a signed message.
constexpr std::array<std::uint8_t, 4> kSignatureMagic = {'S', 'T', 'S', '1'};
// The freshness window (messages/README.md, "Freshness"): a signed message is taken only when its
// timestamp is within this much of the receiver's own clock (CLOCK_REALTIME when it arrived),
// behind or ahead. What it must cover: the clock offset between the two hosts (chrony on a LAN
// keeps it under a millisecond, PTP under a microsecond) and the time from signing to arrival
// (a LAN: under a millisecond; a 160 kB policy in fragments: ~2 ms). Half a second is hundreds
// of times that, and short enough that a recording is stale within it; a replay inside it meets
// the per-sender table and the sessions (robot_state_t.session). The controller's
// lcm.signature_window_s and stride-sim's --signature-window change it.
constexpr std::int64_t kFreshnessWindowMicros = 500'000;
// Senders a Verifier remembers; beyond them the least recently accepted one is forgotten.
constexpr int kReplaySenders = 16;
// The messages per second a Verifier hashes from senders it has not accepted yet (a sender is
// new for its first accepted message only), with a burst of this many: a flood of frames with
// made-up sender ids costs at most this many hashes a second (messages/README.md, "Cheap
// refusals"). 1000/s: a 1 kHz estimator's start, or a receiver that refuses every state of a
// sender for its content (another robot's), are not cut.
constexpr double kNewSenderRate = 1000.0, kNewSenderBurst = 100.0;

// A shared secret key and its id (keyId(bytes)). Make one with makeKey or loadKeyFile, which
// compute the id.
struct Key {
  std::array<std::uint8_t, kKeySize> bytes{};
  std::uint32_t id = 0;
};

// The first 4 bytes (big-endian) of SHA-256("stride key id" || bytes).
std::uint32_t keyId(const std::array<std::uint8_t, kKeySize>& bytes);
// A key of these bytes, with its id.
Key makeKey(const std::array<std::uint8_t, kKeySize>& bytes);

// Reads a key file: 64 hex digits (surrounding whitespace allowed), readable and writable by its
// owner only. Throws std::runtime_error naming the file when it is missing or unreadable, when its
// permissions let the group or others in ("permissions 0644 for 'F' are too open: chmod 600 F"),
// or when its content is not exactly 64 hex digits.
Key loadKeyFile(const std::string& path);
// Writes a new random key to a file that must not exist yet: 64 lowercase hex digits and a
// newline, mode 0600. Throws std::runtime_error naming the file when it exists or cannot be
// written.
void writeNewKeyFile(const std::string& path);

// A random nonzero sender id (libsodium's generator): one per process.
std::uint32_t randomSenderId();

// Signs messages in place: appends the trailer after the payload.
class Signer {
 public:
  Signer(const Key& key, std::uint32_t sender) noexcept : key_(key), sender_(sender) {}

  // Appends the trailer to the payload_size bytes at buf (capacity bytes in all) and returns the
  // signed size, payload_size + kSignatureSize, or -1 (buf untouched) when capacity is too small or
  // the arguments make no sense. The timestamp is CLOCK_REALTIME in microseconds, or the previous
  // one + 1 if that is not newer: strictly increasing for this signer.
  int sign(const char* channel, std::uint8_t* buf, int payload_size, int capacity) noexcept;
  // The same with the given timestamp, for tests: nothing is enforced and the signer's own last
  // timestamp is left as it was.
  int signAt(const char* channel, std::uint8_t* buf, int payload_size, int capacity,
             std::int64_t timestamp) const noexcept;

  std::uint32_t sender() const { return sender_; }
  std::uint32_t keyId() const { return key_.id; }
  // The timestamp of the last sign() (INT64_MIN before the first).
  std::int64_t lastTimestamp() const { return last_; }

 private:
  Key key_;
  std::uint32_t sender_;
  std::int64_t last_ = std::numeric_limits<std::int64_t>::min();
};

// The verdicts in the order they are judged: the cheap ones (nothing but the trailer's fields and
// the size: Unsigned to OverRate) before the mac is computed; Forged after it.
enum class Verdict : std::uint8_t {
  Ok,           // signed with our key, fresh, newer than the sender's last, the mac matches
  Unsigned,     // too short for a trailer, or no magic at the end
  WrongKey,     // signed, with another key (key id not ours)
  Forged,       // our key id, but the mac does not match (altered, or a forgery)
  Replayed,     // the timestamp is not newer than the last accepted from the sender
  Stale,        // the timestamp is further behind the receiver's clock than the window
  Future,       // the timestamp is further ahead of the receiver's clock than the window
  Implausible,  // a size no message of the channel's type has (SizeRule)
  OverRate,     // over the budget of messages from senders not accepted yet (kNewSenderRate)
};
constexpr int kVerdicts = static_cast<int>(Verdict::OverRate) + 1;
const char* describe(Verdict verdict);

// The payload sizes (before the trailer) a channel's type can have: min, min + step, min + 2 step
// ... up to max. A state of one robot has a handful of sizes, a policy one per knot count: any
// other size cannot be ours and is refused before hashing.
struct SizeRule {
  std::int64_t min = 0, max = std::numeric_limits<std::int64_t>::max(), step = 1;
  bool allows(std::int64_t payload) const {
    return payload >= min && payload <= max && (step <= 1 || (payload - min) % step == 0);
  }
};

// Checks signed messages against one key and the receiver's clock, and remembers, per sender, the
// newest timestamp accepted (kReplaySenders senders, preallocated). The table changes only in
// accept(), which a receiver calls once it has accepted the message's content too: a message
// refused for any reason (its signature, its freshness, its payload) locks nobody out.
class Verifier {
 public:
  explicit Verifier(const Key& key, std::int64_t window_us = kFreshnessWindowMicros) noexcept
      : key_(key), window_(window_us) {}

  // The sizes this channel's payloads may have (default: any).
  void setSizes(const SizeRule& sizes) { sizes_ = sizes; }
  // The budget of messages per second from senders not accepted yet (<= 0: none).
  void setNewSenderRate(double per_second, double burst);

  // The verdict on size bytes at buf received on channel at now_us (the receiver's CLOCK_REALTIME
  // when it arrived, microseconds). payload_size is set to the bytes before the trailer when there
  // is one (every verdict but Unsigned), else to size. Counted. Ok leaves the message pending:
  // accept() remembers it.
  Verdict check(const char* channel, const std::uint8_t* buf, int size, std::int64_t now_us,
                int& payload_size) noexcept;
  // The message of the last Ok verdict was accepted by its receiver: its sender's timestamp is
  // remembered (a replay of it, or of anything older of that sender, is refused from now on).
  // Nothing when the last verdict was not Ok or was accepted already.
  void accept() noexcept;
  // The last message's timestamp minus the receiver's clock [µs] (positive: ahead), as checked.
  std::int64_t lastOffset() const { return offset_; }
  std::int64_t window() const { return window_; }

  // Messages per verdict so far (indexed by the Verdict's value).
  const std::array<std::int64_t, kVerdicts>& counters() const { return counters_; }
  std::int64_t count(Verdict verdict) const { return counters_[static_cast<int>(verdict)]; }
  // True exactly once per verdict, at the first call after one was counted: a node says the first
  // refusal of each reason and counts the rest.
  bool sayOnce(Verdict verdict) noexcept;

  std::uint32_t keyId() const { return key_.id; }
  // Senders remembered now (at most kReplaySenders).
  int senders() const { return used_; }

 private:
  struct Sender {
    std::uint32_t id = 0;
    std::int64_t last_timestamp = 0;
    std::uint64_t last_accepted = 0;  // order of acceptance (accepted_ when it was last accepted)
  };
  // The table's entry of a sender, or null. The table has one key (ours: a mac is valid only with
  // it), so a sender id alone names a (key_id, sender) pair.
  Sender* find(std::uint32_t sender) noexcept;
  // The new-sender budget: false when it is spent (a token bucket on the receiver's clock).
  bool spendNewSender(std::int64_t now_us) noexcept;

  Key key_;
  std::int64_t window_;
  SizeRule sizes_;
  double new_rate_ = kNewSenderRate, new_burst_ = kNewSenderBurst, tokens_ = kNewSenderBurst;
  std::int64_t tokens_at_ = 0;
  bool tokens_started_ = false;
  std::array<Sender, kReplaySenders> table_{};
  int used_ = 0;
  std::uint64_t accepted_ = 0;
  bool pending_ = false;  // the last verdict was Ok and not accepted yet
  std::uint32_t pending_sender_ = 0;
  std::int64_t pending_timestamp_ = 0, offset_ = 0;
  std::array<std::int64_t, kVerdicts> counters_{};
  std::array<bool, kVerdicts> said_{};
};

// For receivers without a key (viewers, log summaries): the payload's size when the buffer ends
// with a signature trailer (size - kSignatureSize), else size. Nothing is verified.
std::int64_t unsignedPayloadSize(const std::uint8_t* buf, int size);
// A trailer's fields as claimed (nothing is verified): for readers without the key that judge
// freshness as the receivers do (log summaries: the logger's receive time is the receiver's
// clock), and for the fault tools that claim a live sender's id. False when the buffer does not
// end with a signature trailer.
struct SignatureClaim {
  std::uint32_t key_id = 0, sender = 0;
  std::int64_t timestamp = 0;
};
bool readSignatureClaim(const std::uint8_t* buf, int size, SignatureClaim& claim);

namespace detail {
// SHA-256 by OpenSSL's libcrypto (SHA256_Init/Update/Final: no allocation, SHA extensions).
std::array<std::uint8_t, 32> sha256(const std::uint8_t* data, std::size_t size) noexcept;
// HMAC-SHA256 by libsodium (crypto_auth_hmacsha256_*: state on the stack), any key length.
std::array<std::uint8_t, 32> hmacSha256(const std::uint8_t* key, std::size_t key_size,
                                        const std::uint8_t* data, std::size_t size) noexcept;
}  // namespace detail

}  // namespace stride::msg
