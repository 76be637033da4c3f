// Message signing (signing.hpp; messages/README.md, "Signing").
//
// Two libraries, each for what it does best here, both without allocation per message:
// - The payload's SHA-256 (the bulk of the work: a policy is 31 kB for stride_quad, 160 kB for
//   talos_reduced) comes from OpenSSL's libcrypto, through its low-level SHA256_Init/Update/Final:
//   the context is a plain struct on the stack, and the code uses the CPU's SHA extensions when it
//   has them (~1.45 GB/s measured here, against ~350 MB/s for libsodium's portable C). They are
//   deprecated in OpenSSL 3.0 in favour of EVP, but present; EVP allocates per message in 3.0
//   (measured with OpenSSL 3.0.19: 2 blocks with a reused EVP_MD_CTX, 3 for EVP_Digest), which a
//   real-time path must not do. The deprecation warnings are silenced here only
//   (OPENSSL_SUPPRESS_DEPRECATED, before the header).
// - The HMAC over the short header (the domain string, channel, key id, sender, timestamp and the
//   payload's digest: ~80 bytes) comes from libsodium's crypto_auth_hmacsha256_init/update/final,
//   whose state also sits on the stack. Hash-then-MAC keeps the keyed part short and the fast hash
//   on the long part. libsodium also gives the random bytes (keys, sender ids) and the
//   constant-time comparison of the macs (sodium_memcmp).

#define OPENSSL_SUPPRESS_DEPRECATED
#include "messages/signing.hpp"

#include <fcntl.h>
#include <openssl/sha.h>
#include <sodium.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <stdexcept>

namespace stride::msg {
namespace {

constexpr std::uint8_t kKeyIdDomain[] = {'s', 't', 'r', 'i', 'd', 'e', ' ',
                                         'k', 'e', 'y', ' ', 'i', 'd'};
constexpr std::uint8_t kMacDomain[] = {'s', 't', 'r', 'i', 'd', 'e', '-',
                                       's', 'i', 'g', '-', 'v', '1'};
static_assert(sizeof(kKeyIdDomain) == 13 && sizeof(kMacDomain) == 13);

// Offsets in the trailer.
constexpr int kKeyIdAt = 0, kSenderAt = 4, kTimestampAt = 8, kMacAt = 16, kMagicAt = 32;
static_assert(kMagicAt + 4 == kSignatureSize);

// A key file is 64 hex digits and a newline; anything much longer is not a key file.
constexpr std::size_t kMaxKeyFileBytes = 4096;

// libsodium must be started before its other functions (idempotent and thread-safe; a static so
// that it runs once). Called by everything that makes keys or random numbers: a Signer or Verifier
// gets its key from one of those, so sign() and check() never need to.
void startSodium() {
  static const int status = sodium_init();
  if (status < 0) throw std::runtime_error("libsodium could not start (sodium_init failed)");
}

void putBe32(std::uint8_t* p, std::uint32_t v) {
  for (int i = 3; i >= 0; --i, v >>= 8) p[i] = static_cast<std::uint8_t>(v);
}
void putBe64(std::uint8_t* p, std::uint64_t v) {
  for (int i = 7; i >= 0; --i, v >>= 8) p[i] = static_cast<std::uint8_t>(v);
}
std::uint32_t getBe32(const std::uint8_t* p) {
  std::uint32_t v = 0;
  for (int i = 0; i < 4; ++i) v = (v << 8) | p[i];
  return v;
}
std::uint64_t getBe64(const std::uint8_t* p) {
  std::uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v = (v << 8) | p[i];
  return v;
}

// The 16-byte mac of a message: HMAC-SHA256(key, domain || channel || 0 || header || SHA-256
// (payload)) truncated, where header is the trailer's first 16 bytes (key id, sender, timestamp).
// The channel's terminating NUL is the 0x00 that separates it from the header (a C string holds no
// other NUL, so the encoding is unambiguous).
void computeMac(const Key& key, const char* channel, const std::uint8_t* header,
                const std::uint8_t* payload, std::size_t payload_size, std::uint8_t* mac) {
  const std::array<std::uint8_t, 32> digest = detail::sha256(payload, payload_size);
  if (channel == nullptr) channel = "";
  crypto_auth_hmacsha256_state state;
  crypto_auth_hmacsha256_init(&state, key.bytes.data(), key.bytes.size());
  crypto_auth_hmacsha256_update(&state, kMacDomain, sizeof(kMacDomain));
  crypto_auth_hmacsha256_update(&state, reinterpret_cast<const unsigned char*>(channel),
                                std::strlen(channel) + 1);
  crypto_auth_hmacsha256_update(&state, header, kMacAt);
  crypto_auth_hmacsha256_update(&state, digest.data(), digest.size());
  std::uint8_t full[crypto_auth_hmacsha256_BYTES];
  crypto_auth_hmacsha256_final(&state, full);  // wipes the state
  std::memcpy(mac, full, kSignatureMacSize);
}

std::int64_t realtimeMicros() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1000000 + ts.tv_nsec / 1000;
}

bool endsWithMagic(const std::uint8_t* buf, int size) {
  return buf != nullptr && size >= kSignatureSize &&
         std::memcmp(buf + size - 4, kSignatureMagic.data(), 4) == 0;
}

int hexValue(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

bool isSpace(char c) {
  return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f';
}

std::string quoted(const std::string& path) {
  return "'" + path + "'";
}

// Closes a file descriptor on every way out.
struct FileDescriptor {
  int fd;
  ~FileDescriptor() {
    if (fd >= 0) ::close(fd);
  }
};

}  // namespace

namespace detail {

std::array<std::uint8_t, 32> sha256(const std::uint8_t* data, std::size_t size) noexcept {
  std::array<std::uint8_t, 32> out{};
  SHA256_CTX context;
  SHA256_Init(&context);
  SHA256_Update(&context, data, size);
  SHA256_Final(out.data(), &context);
  return out;
}

std::array<std::uint8_t, 32> hmacSha256(const std::uint8_t* key, std::size_t key_size,
                                        const std::uint8_t* data, std::size_t size) noexcept {
  std::array<std::uint8_t, 32> out{};
  crypto_auth_hmacsha256_state state;
  crypto_auth_hmacsha256_init(&state, key, key_size);
  crypto_auth_hmacsha256_update(&state, data, size);
  crypto_auth_hmacsha256_final(&state, out.data());
  return out;
}

}  // namespace detail

std::uint32_t keyId(const std::array<std::uint8_t, kKeySize>& bytes) {
  std::uint8_t input[sizeof(kKeyIdDomain) + kKeySize];
  std::memcpy(input, kKeyIdDomain, sizeof(kKeyIdDomain));
  std::memcpy(input + sizeof(kKeyIdDomain), bytes.data(), kKeySize);
  const std::array<std::uint8_t, 32> digest = detail::sha256(input, sizeof(input));
  sodium_memzero(input, sizeof(input));
  return getBe32(digest.data());
}

Key makeKey(const std::array<std::uint8_t, kKeySize>& bytes) {
  startSodium();
  Key key;
  key.bytes = bytes;
  key.id = keyId(bytes);
  return key;
}

Key loadKeyFile(const std::string& path) {
  startSodium();
  FileDescriptor file{::open(path.c_str(), O_RDONLY | O_CLOEXEC)};
  if (file.fd < 0) {
    throw std::runtime_error("cannot read key file " + quoted(path) + ": " + std::strerror(errno));
  }
  // The permissions of the file opened (not of whatever the path names a moment later).
  struct stat st {};
  if (::fstat(file.fd, &st) != 0) {
    throw std::runtime_error("cannot read key file " + quoted(path) + ": " + std::strerror(errno));
  }
  if (!S_ISREG(st.st_mode))
    throw std::runtime_error("key file " + quoted(path) + " is not a regular file");
  if ((st.st_mode & 077) != 0) {
    char mode[8];
    std::snprintf(mode, sizeof(mode), "%04o", static_cast<unsigned>(st.st_mode & 07777));
    throw std::runtime_error(std::string("permissions ") + mode + " for " + quoted(path) +
                             " are too open: chmod 600 " + path);
  }
  char text[kMaxKeyFileBytes + 1];
  std::size_t length = 0;
  for (;;) {
    const ssize_t n = ::read(file.fd, text + length, sizeof(text) - length);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const int error = errno;
      sodium_memzero(text, sizeof(text));
      throw std::runtime_error("cannot read key file " + quoted(path) + ": " +
                               std::strerror(error));
    }
    if (n == 0) break;
    length += static_cast<std::size_t>(n);
    if (length == sizeof(text)) break;
  }
  std::size_t begin = 0, end = length;
  while (begin < end && isSpace(text[begin])) ++begin;
  while (end > begin && isSpace(text[end - 1])) --end;
  std::string problem;
  for (std::size_t i = begin; i < end && problem.empty(); ++i) {
    if (hexValue(text[i]) < 0) {
      // The character itself is not shown: it may be part of a secret.
      problem = "a character that is not a hex digit at byte " + std::to_string(i);
    }
  }
  if (problem.empty() && end - begin != 2 * kKeySize) {
    problem = length > kMaxKeyFileBytes
                  ? std::string("more than ") + std::to_string(kMaxKeyFileBytes) + " bytes"
                  : std::to_string(end - begin) + " hex digits";
  }
  if (!problem.empty()) {
    sodium_memzero(text, sizeof(text));
    throw std::runtime_error("key file " + quoted(path) +
                             ": expected 64 hex digits (a 32-byte key, as stride-keygen writes), "
                             "found " +
                             problem);
  }
  std::array<std::uint8_t, kKeySize> bytes{};
  for (int i = 0; i < kKeySize; ++i) {
    bytes[i] = static_cast<std::uint8_t>(hexValue(text[begin + 2 * i]) << 4 |
                                         hexValue(text[begin + 2 * i + 1]));
  }
  sodium_memzero(text, sizeof(text));
  Key key = makeKey(bytes);
  sodium_memzero(bytes.data(), bytes.size());
  return key;
}

void writeNewKeyFile(const std::string& path) {
  startSodium();
  std::array<std::uint8_t, kKeySize> bytes{};
  randombytes_buf(bytes.data(), bytes.size());
  // The digits and a newline (sodium_bin2hex ends the digits with a NUL, which the newline
  // replaces; the last byte is room for it and is not written).
  constexpr std::size_t kFileBytes = 2 * kKeySize + 1;
  char text[kFileBytes + 1];
  sodium_bin2hex(text, 2 * kKeySize + 1, bytes.data(), bytes.size());  // lowercase
  text[2 * kKeySize] = '\n';
  sodium_memzero(bytes.data(), bytes.size());
  // O_EXCL: never replace a key (every program that uses it would be locked out); 0600 from the
  // start, so that the key is never readable by others, not even for a moment.
  FileDescriptor file{::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600)};
  if (file.fd < 0) {
    const int error = errno;
    sodium_memzero(text, sizeof(text));
    if (error == EEXIST) {
      throw std::runtime_error("key file " + quoted(path) +
                               " exists already: not overwritten (remove it first to replace the "
                               "key, and give the new one to every program)");
    }
    throw std::runtime_error("cannot create key file " + quoted(path) + ": " +
                             std::strerror(error));
  }
  // The umask may have taken bits away (a key its owner cannot read): exactly 0600.
  int error = ::fchmod(file.fd, 0600) == 0 ? 0 : errno;
  std::size_t written = 0;
  while (error == 0 && written < kFileBytes) {
    const ssize_t n = ::write(file.fd, text + written, kFileBytes - written);
    if (n < 0 && errno == EINTR) continue;
    if (n > 0)
      written += static_cast<std::size_t>(n);
    else
      error = n < 0 ? errno : EIO;
  }
  sodium_memzero(text, sizeof(text));
  if (error == 0 && ::fsync(file.fd) != 0) error = errno;
  if (::close(file.fd) != 0 && error == 0) error = errno;
  file.fd = -1;
  if (error != 0) {
    ::unlink(path.c_str());
    throw std::runtime_error("cannot write key file " + quoted(path) + ": " + std::strerror(error));
  }
}

std::uint32_t randomSenderId() {
  startSodium();
  // Uniform in [0, 2^32 - 2], + 1: nonzero.
  return randombytes_uniform(0xffffffffu) + 1u;
}

int Signer::signAt(const char* channel, std::uint8_t* buf, int payload_size, int capacity,
                   std::int64_t timestamp) const noexcept {
  if (buf == nullptr || payload_size < 0 || capacity < payload_size ||
      capacity - payload_size < kSignatureSize) {
    return -1;
  }
  std::uint8_t* trailer = buf + payload_size;
  putBe32(trailer + kKeyIdAt, key_.id);
  putBe32(trailer + kSenderAt, sender_);
  putBe64(trailer + kTimestampAt, static_cast<std::uint64_t>(timestamp));
  computeMac(key_, channel, trailer, buf, static_cast<std::size_t>(payload_size), trailer + kMacAt);
  std::memcpy(trailer + kMagicAt, kSignatureMagic.data(), kSignatureMagic.size());
  return payload_size + kSignatureSize;
}

int Signer::sign(const char* channel, std::uint8_t* buf, int payload_size, int capacity) noexcept {
  const std::int64_t now = realtimeMicros();
  // Strictly increasing even when the clock steps back or two messages share a microsecond.
  const std::int64_t timestamp =
      last_ == std::numeric_limits<std::int64_t>::min() || now > last_ ? now : last_ + 1;
  const int size = signAt(channel, buf, payload_size, capacity, timestamp);
  if (size >= 0) last_ = timestamp;
  return size;
}

const char* describe(Verdict verdict) {
  switch (verdict) {
    case Verdict::Ok:
      return "signed with our key and new";
    case Verdict::Unsigned:
      return "unsigned (no signature trailer)";
    case Verdict::WrongKey:
      return "signed with another key (key id not ours)";
    case Verdict::Forged:
      return "forged or altered (the signature does not match)";
    case Verdict::Replayed:
      return "replayed (timestamp not newer than the sender's last accepted one)";
    case Verdict::Stale:
      return "stale (timestamp further behind this host's clock than the freshness window)";
    case Verdict::Future:
      return "from the future (timestamp further ahead of this host's clock than the freshness "
             "window)";
    case Verdict::Implausible:
      return "a size no message of this channel's type has (refused before its signature was "
             "checked)";
    case Verdict::OverRate:
      return "over the budget of messages from new senders (refused before its signature was "
             "checked)";
  }
  return "unknown verdict";
}

void Verifier::setNewSenderRate(double per_second, double burst) {
  new_rate_ = per_second;
  new_burst_ = burst;
  tokens_ = burst;
  tokens_started_ = false;
}

Verifier::Sender* Verifier::find(std::uint32_t sender) noexcept {
  for (int i = 0; i < used_; ++i)
    if (table_[i].id == sender) return &table_[i];
  return nullptr;
}

bool Verifier::spendNewSender(std::int64_t now_us) noexcept {
  if (new_rate_ <= 0.0) return true;
  if (tokens_started_ && now_us > tokens_at_)
    tokens_ =
        std::min(new_burst_, tokens_ + new_rate_ * static_cast<double>(now_us - tokens_at_) * 1e-6);
  if (!tokens_started_ || now_us > tokens_at_) tokens_at_ = now_us;
  tokens_started_ = true;
  if (tokens_ < 1.0) return false;
  tokens_ -= 1.0;
  return true;
}

Verdict Verifier::check(const char* channel, const std::uint8_t* buf, int size, std::int64_t now_us,
                        int& payload_size) noexcept {
  pending_ = false;
  Verdict verdict = Verdict::Unsigned;
  payload_size = size;
  if (endsWithMagic(buf, size)) {
    payload_size = size - kSignatureSize;
    const std::uint8_t* trailer = buf + payload_size;
    const std::uint32_t sender = getBe32(trailer + kSenderAt);
    const auto timestamp = static_cast<std::int64_t>(getBe64(trailer + kTimestampAt));
    // In double: a timestamp near either end of int64 minus the clock would overflow.
    const double offset = static_cast<double>(timestamp) - static_cast<double>(now_us);
    offset_ = offset > 9e18    ? std::numeric_limits<std::int64_t>::max()
              : offset < -9e18 ? std::numeric_limits<std::int64_t>::min()
                               : timestamp - now_us;
    const Sender* known = find(sender);
    // The cheap refusals, on the trailer's fields as claimed (unverified) and the size: a frame
    // refused here costs no hashing.
    if (getBe32(trailer + kKeyIdAt) != key_.id) {
      verdict = Verdict::WrongKey;
    } else if (!sizes_.allows(payload_size)) {
      verdict = Verdict::Implausible;
    } else if (offset < -static_cast<double>(window_)) {
      verdict = Verdict::Stale;
    } else if (offset > static_cast<double>(window_)) {
      verdict = Verdict::Future;
    } else if (known != nullptr && timestamp <= known->last_timestamp) {
      verdict = Verdict::Replayed;
    } else if (known == nullptr && !spendNewSender(now_us)) {
      verdict = Verdict::OverRate;
    } else {
      std::uint8_t mac[kSignatureMacSize];
      computeMac(key_, channel, trailer, buf, static_cast<std::size_t>(payload_size), mac);
      if (sodium_memcmp(mac, trailer + kMacAt, kSignatureMacSize) != 0) {
        verdict = Verdict::Forged;
      } else {
        verdict = Verdict::Ok;
        pending_ = true;
        pending_sender_ = sender;
        pending_timestamp_ = timestamp;
      }
    }
  }
  ++counters_[static_cast<int>(verdict)];
  return verdict;
}

void Verifier::accept() noexcept {
  if (!pending_) return;
  pending_ = false;
  Sender* entry = find(pending_sender_);
  if (entry == nullptr) {
    if (used_ < kReplaySenders) {
      entry = &table_[used_++];
    } else {
      entry = &table_[0];  // full: forget the least recently accepted sender
      for (Sender& s : table_)
        if (s.last_accepted < entry->last_accepted) entry = &s;
    }
    entry->id = pending_sender_;
    entry->last_timestamp = pending_timestamp_;
  }
  // Accepted messages of one sender may complete out of their signing order only across channels
  // (one Verifier each): here the newest wins.
  entry->last_timestamp = std::max(entry->last_timestamp, pending_timestamp_);
  entry->last_accepted = ++accepted_;
}

bool Verifier::sayOnce(Verdict verdict) noexcept {
  const int i = static_cast<int>(verdict);
  if (counters_[i] == 0 || said_[i]) return false;
  said_[i] = true;
  return true;
}

std::int64_t unsignedPayloadSize(const std::uint8_t* buf, int size) {
  return endsWithMagic(buf, size) ? size - kSignatureSize : size;
}

bool readSignatureClaim(const std::uint8_t* buf, int size, SignatureClaim& claim) {
  if (!endsWithMagic(buf, size)) return false;
  const std::uint8_t* trailer = buf + size - kSignatureSize;
  claim.key_id = getBe32(trailer + kKeyIdAt);
  claim.sender = getBe32(trailer + kSenderAt);
  claim.timestamp = static_cast<std::int64_t>(getBe64(trailer + kTimestampAt));
  return true;
}

}  // namespace stride::msg
