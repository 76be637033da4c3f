#pragma once
// What a node does with message signatures (messages/README.md, "Signing"). With a key it signs
// what it sends and reads only what is signed with the key: a message unsigned, forged, replayed
// or signed with another key is refused, counted by reason, and the first of each reason is said
// once on stderr. Without a key it signs nothing and reads signed messages as plain ones (the
// trailer stripped, nothing verified): the wire is unauthenticated, as it was before signing.
//
// What it checks, cheapest first (messages/README.md, "Freshness", "Cheap refusals"): a size the
// channel's type cannot have (setSizes), a timestamp outside the freshness window around this
// host's clock when the message arrived, a replay of a sender's, the budget of new senders, and
// only then the mac. A message it passes is pending until the node has checked its content too
// and calls accept(slot): only then is its sender's timestamp remembered.
//
// One Verifier per channel a node reads: a sender's timestamps increase across all its channels,
// and a large policy that arrives in fragments may complete after a later, smaller message of the
// same sender on another channel.

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "messages/publisher.hpp"
#include "messages/signing.hpp"

namespace stride::msg {

class WireAuth {
 public:
  static constexpr int kMaxChannels = 6;

  // No key: unauthenticated.
  WireAuth() = default;
  // Signs as a random sender (one per process start); `who` prefixes what it says
  // ("stride-mpc"). window_us: the freshness window (kFreshnessWindowMicros).
  WireAuth(const Key& key, const char* who, std::int64_t window_us = kFreshnessWindowMicros);

  bool keyed() const { return signer_.has_value(); }
  std::uint32_t keyId() const { return keyed() ? signer_->keyId() : 0; }

  // The payload's size to decode at buf (size bytes received on `channel`, the node's channel
  // number `slot` < kMaxChannels, at recv_utime: LCM's wall-clock arrival, µs; <= 0: now), or -1
  // when the message is refused. No allocation.
  int receive(int slot, const char* channel, const std::uint8_t* buf, int size,
              std::int64_t recv_utime = 0) noexcept;
  // The node took the message receive() passed last on `slot` (its content checked too): its
  // sender's timestamp is remembered against replay. No allocation.
  void accept(int slot) noexcept;
  // The payload sizes a slot's channel can carry: others are refused before hashing.
  void setSizes(int slot, const SizeRule& sizes);
  // Signs the payload_size bytes at buf in place when keyed; returns the size to publish, or -1
  // when the buffer has no room for the trailer (the buffers are sized with kSignatureSize
  // spare: never). No allocation.
  int send(const char* channel, std::uint8_t* buf, int payload_size, int capacity) noexcept;

  // Refused messages by verdict (summed over channels; Ok counts the accepted ones), and in all.
  std::int64_t refused(Verdict verdict) const;
  std::int64_t refused() const;

 private:
  std::optional<Signer> signer_;
  std::array<std::optional<Verifier>, kMaxChannels> verifiers_;
  const char* who_ = "";
};

// The key of a --key-file option or a configuration's key_file: loaded when `path` is not empty
// (throws std::runtime_error as loadKeyFile does), else none, with one warning on stderr that the
// wire is unauthenticated (`who` says whose).
std::optional<Key> keyForProgram(const std::string& path, const char* who);

// The refusals by reason, "10 unsigned, 2 forged", or "" when none was refused.
std::string refusedText(const WireAuth& auth);

}  // namespace stride::msg

namespace stride::msg {

// A Publisher that signs every message with `auth` (when it has a key) before handing it to
// `out`: the nodes sign all they send, so a receiver with the key can trust any of it. The
// message is copied into a buffer preallocated for `capacity` payload bytes (a larger message
// grows it once: an allocation).
class SigningPublisher : public Publisher {
 public:
  SigningPublisher(Publisher& out, WireAuth& auth, int capacity);
  void publish(const std::string& channel, const void* data, int size) override;
  // Room for messages of `capacity` bytes (at start: a larger message later allocates).
  void reserve(int capacity);

 private:
  Publisher& out_;
  WireAuth& auth_;
  std::vector<std::uint8_t> buffer_;
};

}  // namespace stride::msg
