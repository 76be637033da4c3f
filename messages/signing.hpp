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
// A sender a Verifier does not know yet is accepted only with a timestamp newer than this much
// before the newest one it has accepted from anybody (MAVLink's rule for a new stream).
constexpr std::int64_t kNewSenderWindowMicros = 60'000'000;
// Senders a Verifier remembers; beyond them the least recently accepted one is forgotten.
constexpr int kReplaySenders = 16;

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

enum class Verdict : std::uint8_t {
  Ok,        // signed with our key, the mac matches, newer than the sender's last
  Unsigned,  // too short for a trailer, or no magic at the end
  WrongKey,  // signed, with another key (key id not ours)
  Forged,    // our key id, but the mac does not match (altered, or a forgery)
  Replayed,  // a valid mac, but the timestamp is not newer than the last accepted from the sender
};
constexpr int kVerdicts = static_cast<int>(Verdict::Replayed) + 1;
const char* describe(Verdict verdict);

// Checks signed messages against one key and remembers, per sender, the newest timestamp it
// accepted (kReplaySenders senders, preallocated). Only messages with a valid mac update it.
class Verifier {
 public:
  explicit Verifier(const Key& key) noexcept : key_(key) {}

  // The verdict on size bytes at buf received on channel. payload_size is set to the bytes before
  // the trailer when there is one (every verdict but Unsigned), else to size. Counted.
  Verdict check(const char* channel, const std::uint8_t* buf, int size, int& payload_size) noexcept;

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
  // Ok (and the table updated), or Replayed, for a message whose mac is valid. The table has one
  // key (ours: a mac is valid only with it), so a sender id alone names a (key_id, sender) pair.
  Verdict admit(std::uint32_t sender, std::int64_t timestamp) noexcept;

  Key key_;
  std::array<Sender, kReplaySenders> table_{};
  int used_ = 0;
  std::uint64_t accepted_ = 0;
  bool have_newest_ = false;
  std::int64_t newest_ = 0;  // the newest timestamp accepted from any sender
  std::array<std::int64_t, kVerdicts> counters_{};
  std::array<bool, kVerdicts> said_{};
};

// For receivers without a key (viewers, log summaries): the payload's size when the buffer ends
// with a signature trailer (size - kSignatureSize), else size. Nothing is verified.
std::int64_t unsignedPayloadSize(const std::uint8_t* buf, int size);

namespace detail {
// SHA-256 by OpenSSL's libcrypto (SHA256_Init/Update/Final: no allocation, SHA extensions).
std::array<std::uint8_t, 32> sha256(const std::uint8_t* data, std::size_t size) noexcept;
// HMAC-SHA256 by libsodium (crypto_auth_hmacsha256_*: state on the stack), any key length.
std::array<std::uint8_t, 32> hmacSha256(const std::uint8_t* key, std::size_t key_size,
                                        const std::uint8_t* data, std::size_t size) noexcept;
}  // namespace detail

}  // namespace stride::msg
