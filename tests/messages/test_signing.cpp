// Message signing (messages/signing.hpp): the primitives against published test vectors, a
// trailer against one computed independently, every single-bit alteration refused, the replay
// rule (per sender, new senders, eviction), key files, and no allocation in sign() and check().
#include <fcntl.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <limits>
#include <ostream>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

// Interposes malloc for this binary: this is its only source file.
#include "allocation_counter.hpp"
#include "messages/signing.hpp"

namespace stride::msg {

// Verdicts by name in the failures' messages (found by argument-dependent lookup).
void PrintTo(Verdict verdict, std::ostream* os) {
  *os << describe(verdict);
}

namespace test_signing {

using Bytes = std::vector<std::uint8_t>;

constexpr const char* kPolicyChannel = "STRIDE_POLICY";
constexpr std::int64_t kSecond = 1000000;
constexpr std::int64_t kT0 = 1700000000000000;  // 2023-11-14, in microseconds

std::string hex(const std::uint8_t* data, std::size_t size) {
  static const char digits[] = "0123456789abcdef";
  std::string s;
  for (std::size_t i = 0; i < size; ++i) {
    s += digits[data[i] >> 4];
    s += digits[data[i] & 15];
  }
  return s;
}
template <std::size_t N>
std::string hex(const std::array<std::uint8_t, N>& a) {
  return hex(a.data(), N);
}
const std::uint8_t* bytesOf(const char* s) {
  return reinterpret_cast<const std::uint8_t*>(s);
}

Key testKey(std::uint8_t first = 0) {
  std::array<std::uint8_t, kKeySize> bytes{};
  for (int i = 0; i < kKeySize; ++i) bytes[i] = static_cast<std::uint8_t>(first + i);
  return makeKey(bytes);
}

Bytes payloadOf(int size, std::uint8_t seed = 1) {
  Bytes p(static_cast<std::size_t>(size));
  for (int i = 0; i < size; ++i) p[i] = static_cast<std::uint8_t>(seed + 31 * i + (i >> 8));
  return p;
}

// The payload signed at the given timestamp.
Bytes signedAt(const Signer& signer, const Bytes& payload, std::int64_t timestamp,
               const char* channel = kPolicyChannel) {
  Bytes buf(payload);
  buf.resize(payload.size() + kSignatureSize);
  const int size = signer.signAt(channel, buf.data(), static_cast<int>(payload.size()),
                                 static_cast<int>(buf.size()), timestamp);
  EXPECT_EQ(size, static_cast<int>(buf.size()));
  return buf;
}

// The verdict of a receiver whose clock reads `now`; a message passed is accepted (its content
// taken), as the nodes do after their own checks.
Verdict checkOf(Verifier& verifier, const Bytes& buf, const char* channel = kPolicyChannel,
                std::int64_t now = kT0) {
  int payload_size = -1;
  const Verdict v =
      verifier.check(channel, buf.data(), static_cast<int>(buf.size()), now, payload_size);
  verifier.accept();
  return v;
}

Verdict checkAt(Verifier& verifier, const Bytes& buf, std::int64_t now) {
  return checkOf(verifier, buf, kPolicyChannel, now);
}

std::int64_t trailerTimestamp(const std::uint8_t* buf, int size) {
  std::uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v = (v << 8) | buf[size - kSignatureSize + 8 + i];
  return static_cast<std::int64_t>(v);
}

// (1) The primitives against published test vectors.
TEST(SigningPrimitives, HmacSha256MatchesRfc4231) {
  // RFC 4231, test case 1: a 20-byte key of 0x0b, "Hi There".
  const std::array<std::uint8_t, 20> key1 = [] {
    std::array<std::uint8_t, 20> k{};
    k.fill(0x0b);
    return k;
  }();
  EXPECT_EQ(hex(detail::hmacSha256(key1.data(), key1.size(), bytesOf("Hi There"), 8)),
            "b0344c61d8db38535ca8afceaf0bf12b881dc200c9833da726e9376c2e32cff7");
  // Test case 2: key "Jefe", "what do ya want for nothing?".
  const char* data2 = "what do ya want for nothing?";
  EXPECT_EQ(hex(detail::hmacSha256(bytesOf("Jefe"), 4, bytesOf(data2), std::strlen(data2))),
            "5bdcc146bf60754e6a042426089575c75a003f089d2739839dec58b964ec3843");
}

TEST(SigningPrimitives, Sha256MatchesFips180) {
  // FIPS 180-2, appendix B.1: "abc".
  EXPECT_EQ(hex(detail::sha256(bytesOf("abc"), 3)),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  // The empty message (FIPS 180-2's SHA-256 of "", as every implementation gives it).
  EXPECT_EQ(hex(detail::sha256(nullptr, 0)),
            "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
}

// (2) A trailer against one computed independently, with python3's hashlib and hmac:
//   key = bytes(range(32))
//   kid = sha256(b"stride key id" + key).digest()[:4]
//   msg = b"stride-sig-v1" + b"STRIDE_POLICY" + b"\0" + kid + pack(">I", 0x01020304)
//         + pack(">q", 1700000000000000) + sha256(b"hello stride").digest()
//   trailer = kid + pack(">I", 0x01020304) + pack(">q", 1700000000000000)
//             + hmac.new(key, msg, sha256).digest()[:16] + b"STS1"
TEST(Signing, KnownAnswerTrailer) {
  const Key key = testKey();
  EXPECT_EQ(key.id, 0x1c13aac1u);
  const Signer signer(key, 0x01020304);
  const char* payload = "hello stride";
  std::array<std::uint8_t, 12 + kSignatureSize> buf{};
  std::memcpy(buf.data(), payload, 12);
  ASSERT_EQ(signer.signAt("STRIDE_POLICY", buf.data(), 12, static_cast<int>(buf.size()), kT0),
            12 + kSignatureSize);
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(buf.data()), 12), payload);
  EXPECT_EQ(hex(buf.data() + 12, kSignatureSize),
            "1c13aac1"                          // key id
            "01020304"                          // sender
            "00060a24181e4000"                  // timestamp
            "e8ddf774e936abf664c8d02a7076d051"  // mac
            "53545331");                        // "STS1"
  Verifier verifier(key);
  int payload_size = 0;
  EXPECT_EQ(
      verifier.check("STRIDE_POLICY", buf.data(), static_cast<int>(buf.size()), kT0, payload_size),
      Verdict::Ok);
  EXPECT_EQ(payload_size, 12);
}

// (3) Round trip, and every single-bit alteration refused.
TEST(Signing, RoundTrip) {
  const Key key = testKey();
  Signer signer(key, 42);
  for (int size : {0, 1, 55, 64, 600, 31000}) {
    const Bytes payload = payloadOf(size);
    Bytes buf(payload);
    buf.resize(payload.size() + kSignatureSize + 10);  // room to spare
    const int signed_size =
        signer.sign(kPolicyChannel, buf.data(), size, static_cast<int>(buf.size()));
    ASSERT_EQ(signed_size, size + kSignatureSize);
    EXPECT_TRUE(std::equal(payload.begin(), payload.end(), buf.begin()));
    Verifier verifier(key);
    int payload_size = -1;
    EXPECT_EQ(verifier.check(kPolicyChannel, buf.data(), signed_size,
                             trailerTimestamp(buf.data(), signed_size), payload_size),
              Verdict::Ok)
        << size;
    EXPECT_EQ(payload_size, size);
    EXPECT_EQ(unsignedPayloadSize(buf.data(), signed_size), size);
  }
}

TEST(Signing, EverySingleBitFlipIsRefused) {
  const Key key = testKey();
  const Signer signer(key, 0xdeadbeef);
  const Bytes payload = payloadOf(300);
  const Bytes good = signedAt(signer, payload, kT0);
  const int n = static_cast<int>(good.size());
  const int trailer = n - kSignatureSize;
  for (int i = 0; i < n; ++i) {
    // Every bit of the trailer; one bit (cycling through the positions) of each payload byte.
    const int first_bit = i < trailer ? i % 8 : 0, last_bit = i < trailer ? i % 8 : 7;
    for (int bit = first_bit; bit <= last_bit; ++bit) {
      Bytes bad(good);
      bad[i] ^= static_cast<std::uint8_t>(1u << bit);
      Verifier verifier(key);
      int payload_size = -1;
      const Verdict v = verifier.check(kPolicyChannel, bad.data(), n, kT0, payload_size);
      Verdict expected = Verdict::Forged;  // payload, sender, timestamp, mac
      if (i >= trailer && i < trailer + 4) expected = Verdict::WrongKey;  // the key id
      if (i >= n - 4) expected = Verdict::Unsigned;                       // the magic
      if (i >= trailer + 8 && i < trailer + 16) {  // the timestamp: outside the window unhashed
        const std::int64_t t = trailerTimestamp(bad.data(), n);
        if (t < kT0 - kFreshnessWindowMicros) expected = Verdict::Stale;
        if (t > kT0 + kFreshnessWindowMicros) expected = Verdict::Future;
      }
      EXPECT_EQ(v, expected) << "byte " << i << " bit " << bit;
      EXPECT_EQ(verifier.count(Verdict::Ok), 0);
    }
  }
  Verifier verifier(key);
  EXPECT_EQ(checkOf(verifier, good), Verdict::Ok);
}

TEST(Signing, TheChannelIsSigned) {
  const Key key = testKey();
  const Signer signer(key, 7);
  const Bytes buf = signedAt(signer, payloadOf(100), kT0, "STRIDE_POLICY");
  Verifier verifier(key);
  EXPECT_EQ(checkOf(verifier, buf, "STRIDE_POLICY_2"), Verdict::Forged);
  EXPECT_EQ(checkOf(verifier, buf, "STRIDE_POLIC"), Verdict::Forged);
  EXPECT_EQ(checkOf(verifier, buf, ""), Verdict::Forged);
  EXPECT_EQ(checkOf(verifier, buf, "STRIDE_POLICY"), Verdict::Ok);
}

// (4) Replay.
TEST(SigningReplay, SameBytesTwiceAndOlderAreReplayed) {
  const Key key = testKey();
  const Signer signer(key, 1);
  const Bytes payload = payloadOf(100);
  Verifier verifier(key);
  const Bytes first = signedAt(signer, payload, kT0);
  EXPECT_EQ(checkOf(verifier, first), Verdict::Ok);
  EXPECT_EQ(checkOf(verifier, first), Verdict::Replayed);
  EXPECT_EQ(checkOf(verifier, signedAt(signer, payload, kT0 - 1)), Verdict::Replayed);
  EXPECT_EQ(checkOf(verifier, signedAt(signer, payload, kT0 + 1)), Verdict::Ok);
  EXPECT_EQ(checkOf(verifier, signedAt(signer, payload, kT0 + 1)), Verdict::Replayed);
  EXPECT_EQ(checkOf(verifier, signedAt(signer, payload, kT0 + 2)), Verdict::Ok);
  EXPECT_EQ(checkOf(verifier, first), Verdict::Replayed);
  EXPECT_EQ(verifier.count(Verdict::Ok), 3);
  EXPECT_EQ(verifier.count(Verdict::Replayed), 4);
}

TEST(SigningReplay, SendersInterleaved) {
  const Key key = testKey();
  const Signer a(key, 10), b(key, 11);
  const Bytes payload = payloadOf(64);
  Verifier verifier(key);
  // b runs 0.3 s behind a (within the window): each sender only has to be newer than itself.
  const std::int64_t behind = 3 * kSecond / 10;
  for (int k = 0; k < 20; ++k) {
    EXPECT_EQ(checkOf(verifier, signedAt(a, payload, kT0 + k * 1000)), Verdict::Ok) << k;
    EXPECT_EQ(checkOf(verifier, signedAt(b, payload, kT0 - behind + k * 1000)), Verdict::Ok) << k;
  }
  EXPECT_EQ(checkOf(verifier, signedAt(b, payload, kT0 - behind + 19 * 1000)), Verdict::Replayed);
  EXPECT_EQ(verifier.senders(), 2);
}

// Issue 44: every message, a new sender's first included, within the window around the receiver's
// clock, behind and ahead; the old rule (a new sender within 60 s of the newest accepted) took a
// first message however old.
TEST(SigningFreshness, EveryMessageWithinTheWindowOfTheReceiversClock) {
  const Key key = testKey();
  const Bytes payload = payloadOf(64);
  const std::int64_t w = kFreshnessWindowMicros;
  Verifier verifier(key);
  // A recording: its first message, to a receiver that knows nobody, a minute and a day late.
  EXPECT_EQ(checkAt(verifier, signedAt(Signer(key, 1), payload, kT0), kT0 + 60 * kSecond),
            Verdict::Stale);
  EXPECT_EQ(checkAt(verifier, signedAt(Signer(key, 1), payload, kT0), kT0 + 86400 * kSecond),
            Verdict::Stale);
  EXPECT_EQ(verifier.lastOffset(), -86400 * kSecond);
  // The edges: the window itself passes, a microsecond more does not.
  EXPECT_EQ(checkAt(verifier, signedAt(Signer(key, 2), payload, kT0 - w), kT0), Verdict::Ok);
  EXPECT_EQ(checkAt(verifier, signedAt(Signer(key, 3), payload, kT0 - w - 1), kT0), Verdict::Stale);
  EXPECT_EQ(checkAt(verifier, signedAt(Signer(key, 4), payload, kT0 + w), kT0), Verdict::Ok);
  EXPECT_EQ(checkAt(verifier, signedAt(Signer(key, 5), payload, kT0 + w + 1), kT0),
            Verdict::Future);
  EXPECT_EQ(verifier.lastOffset(), w + 1);
  // A sender an hour ahead (its clock off, or a key holder's junk) is refused and locks nobody
  // out: the sender's next message in the window passes.
  const Signer live(key, 6);
  EXPECT_EQ(checkAt(verifier, signedAt(live, payload, kT0 + 3600 * kSecond), kT0), Verdict::Future);
  EXPECT_EQ(
      checkAt(verifier, signedAt(live, payload, std::numeric_limits<std::int64_t>::max()), kT0),
      Verdict::Future);
  EXPECT_EQ(
      checkAt(verifier, signedAt(live, payload, std::numeric_limits<std::int64_t>::min()), kT0),
      Verdict::Stale);
  EXPECT_EQ(checkAt(verifier, signedAt(live, payload, kT0 + 1), kT0), Verdict::Ok);
  EXPECT_EQ(verifier.count(Verdict::Stale), 4);
  EXPECT_EQ(verifier.count(Verdict::Future), 3);
  // Another window.
  Verifier wide(key, 60 * kSecond);
  EXPECT_EQ(wide.window(), 60 * kSecond);
  EXPECT_EQ(checkAt(wide, signedAt(Signer(key, 7), payload, kT0 - 59 * kSecond), kT0), Verdict::Ok);
}

// Issue 44: the table changes only when the receiver accepts the message (its content too). A
// message with a valid mac that the receiver then refuses (a junk payload, with the key) leaves
// nothing behind: the sender's next, older but still fresh message passes.
TEST(SigningFreshness, OnlyAcceptedMessagesChangeTheTable) {
  const Key key = testKey();
  const Signer signer(key, 8);
  const Bytes payload = payloadOf(64);
  Verifier verifier(key);
  int payload_size = 0;
  const Bytes junk = signedAt(signer, payload, kT0 + 400000);
  ASSERT_EQ(
      verifier.check(kPolicyChannel, junk.data(), static_cast<int>(junk.size()), kT0, payload_size),
      Verdict::Ok);
  // Not accepted (its content refused): the sender is still unknown.
  EXPECT_EQ(verifier.senders(), 0);
  EXPECT_EQ(checkOf(verifier, signedAt(signer, payload, kT0)), Verdict::Ok);
  EXPECT_EQ(verifier.senders(), 1);
  // accept() twice, or after a refusal, changes nothing.
  verifier.accept();
  EXPECT_EQ(checkOf(verifier, signedAt(signer, payload, kT0 + 1)), Verdict::Ok);
  EXPECT_EQ(checkOf(verifier, signedAt(signer, payload, kT0 + 1)), Verdict::Replayed);
  verifier.accept();
  EXPECT_EQ(checkOf(verifier, signedAt(signer, payload, kT0 + 2)), Verdict::Ok);
}

// Issue 44: cheap refusals before hashing. A size the channel's type cannot have; more frames from
// unknown senders than the budget; a stale or replayed claim. Made-up frames at 4000/s for 1 s
// hash at most the budget's.
TEST(SigningCheapRefusals, ImpossibleSizesAndTheNewSendersBudget) {
  const Key key = testKey();
  Verifier verifier(key);
  verifier.setSizes({100, 1000, 100});  // 100, 200, ... 1000
  const Signer signer(key, 9);
  EXPECT_EQ(checkOf(verifier, signedAt(signer, payloadOf(300), kT0)), Verdict::Ok);
  EXPECT_EQ(checkOf(verifier, signedAt(signer, payloadOf(301), kT0 + 1)), Verdict::Implausible);
  EXPECT_EQ(checkOf(verifier, signedAt(signer, payloadOf(1100), kT0 + 2)), Verdict::Implausible);
  EXPECT_EQ(checkOf(verifier, signedAt(signer, payloadOf(60000), kT0 + 3)), Verdict::Implausible);
  EXPECT_EQ(checkOf(verifier, signedAt(signer, payloadOf(50), kT0 + 4)), Verdict::Implausible);
  EXPECT_EQ(checkOf(verifier, signedAt(signer, payloadOf(1000), kT0 + 5)), Verdict::Ok);

  // Forged frames (our key id, a made-up mac) from a new sender id each, at 4000/s for a second:
  // at most the budget's burst and rate are hashed (Forged), the rest refused before.
  Verifier flooded(key);
  Bytes forged = signedAt(Signer(key, 1), payloadOf(600), kT0);
  const int n = static_cast<int>(forged.size());
  const Signer live(key, 0xabc);
  int live_ok = 0;
  for (int i = 0; i < 4000; ++i) {
    const std::int64_t now = kT0 + i * 250;
    for (int b = 0; b < 4; ++b)
      forged[n - kSignatureSize + 4 + b] = static_cast<std::uint8_t>((0x10000 + i) >> (8 * b));
    for (int b = 0; b < 8; ++b)
      forged[n - kSignatureSize + 8 + b] =
          static_cast<std::uint8_t>(std::uint64_t(now) >> (56 - 8 * b));
    const Verdict v = checkAt(flooded, forged, now);
    EXPECT_TRUE(v == Verdict::Forged || v == Verdict::OverRate) << describe(v);
    // The live sender, known after its first message, is not held by the new senders' budget.
    if (i % 40 == 0)
      live_ok += checkAt(flooded, signedAt(live, payloadOf(600), now), now) == Verdict::Ok;
  }
  EXPECT_LE(flooded.count(Verdict::Forged), kNewSenderBurst + kNewSenderRate + 2);
  EXPECT_GE(flooded.count(Verdict::OverRate), 4000 - kNewSenderBurst - kNewSenderRate - 2);
  EXPECT_GE(live_ok, 99);  // the first may meet a spent budget
  // Frames claiming a known sender with a timestamp not newer than its last: refused unhashed.
  Bytes replay = signedAt(live, payloadOf(600), kT0);
  replay[10] ^= 1;  // the payload altered: a forgery, but refused before its mac is computed
  EXPECT_EQ(checkAt(flooded, replay, kT0 + 4000 * 250), Verdict::Stale);
  Bytes older = signedAt(live, payloadOf(600), kT0 + 3960 * 250 - 1);
  older[10] ^= 1;
  EXPECT_EQ(checkAt(flooded, older, kT0 + 4000 * 250), Verdict::Replayed);
}

TEST(SigningReplay, SeventeenSendersEvictTheLeastRecentlyAccepted) {
  const Key key = testKey();
  const Bytes payload = payloadOf(64);
  Verifier verifier(key);
  std::vector<Bytes> last(18);
  for (std::uint32_t s = 1; s <= 16; ++s) {
    last[s] = signedAt(Signer(key, s), payload, kT0 + s);
    EXPECT_EQ(checkOf(verifier, last[s]), Verdict::Ok) << s;
  }
  EXPECT_EQ(verifier.senders(), kReplaySenders);
  // Sender 1 speaks again: sender 2 is now the least recently accepted.
  last[1] = signedAt(Signer(key, 1), payload, kT0 + 100);
  EXPECT_EQ(checkOf(verifier, last[1]), Verdict::Ok);
  last[17] = signedAt(Signer(key, 17), payload, kT0 + 17);
  EXPECT_EQ(checkOf(verifier, last[17]), Verdict::Ok);
  EXPECT_EQ(verifier.senders(), kReplaySenders);
  for (std::uint32_t s = 1; s <= 17; ++s) {
    if (s == 2) continue;
    EXPECT_EQ(checkOf(verifier, last[s]), Verdict::Replayed) << s;  // still remembered
  }
  // Sender 2 was forgotten: its last message passes again, as a new sender's within the window.
  // This is the documented limit of a fixed table (messages/README.md, "Signing").
  EXPECT_EQ(checkOf(verifier, last[2]), Verdict::Ok);
  EXPECT_EQ(checkOf(verifier, last[2]), Verdict::Replayed);
  // And it took the place of the least recently accepted then (sender 3).
  EXPECT_EQ(checkOf(verifier, last[3]), Verdict::Ok);
}

TEST(SigningReplay, OnlyValidMacsUpdateTheTable) {
  const Key key = testKey();
  const Signer signer(key, 5);
  const Bytes payload = payloadOf(64);
  Verifier verifier(key);
  Bytes forged = signedAt(signer, payload, kT0 + kSecond / 10);
  forged[3] ^= 1;
  EXPECT_EQ(checkOf(verifier, forged), Verdict::Forged);
  EXPECT_EQ(verifier.senders(), 0);
  EXPECT_EQ(checkOf(verifier, signedAt(signer, payload, kT0)), Verdict::Ok);
  EXPECT_EQ(checkOf(verifier, signedAt(Signer(testKey(1), 5), payload, kT0 + kSecond)),
            Verdict::WrongKey);
  EXPECT_EQ(checkOf(verifier, signedAt(signer, payload, kT0 + 1)), Verdict::Ok);
}

// (5) Unsigned, another key, truncated.
TEST(Signing, UnsignedWrongKeyAndTruncated) {
  const Key key = testKey();
  const Signer signer(key, 9);
  const Bytes payload = payloadOf(200);
  Verifier verifier(key);
  int payload_size = -1;
  EXPECT_EQ(checkOf(verifier, payload), Verdict::Unsigned);
  EXPECT_EQ(verifier.check(kPolicyChannel, payload.data(), 200, kT0, payload_size),
            Verdict::Unsigned);
  EXPECT_EQ(payload_size, 200);
  EXPECT_EQ(unsignedPayloadSize(payload.data(), 200), 200);

  const Bytes other = signedAt(Signer(testKey(100), 9), payload, kT0);
  EXPECT_EQ(verifier.check(kPolicyChannel, other.data(), static_cast<int>(other.size()), kT0,
                           payload_size),
            Verdict::WrongKey);
  EXPECT_EQ(payload_size, 200);

  const Bytes good = signedAt(signer, payload, kT0);
  for (int cut = 1; cut <= kSignatureSize + 10; ++cut) {
    const int size = static_cast<int>(good.size()) - cut;
    const Verdict v = verifier.check(kPolicyChannel, good.data(), size, kT0, payload_size);
    EXPECT_NE(v, Verdict::Ok) << cut << ": " << describe(v);
  }
  // The payload cut short, the trailer whole.
  Bytes shorter(good.begin(), good.begin() + 150);
  shorter.insert(shorter.end(), good.end() - kSignatureSize, good.end());
  EXPECT_EQ(checkOf(verifier, shorter), Verdict::Forged);

  for (int size = 0; size < kSignatureSize; ++size) {
    // The last `size` bytes of a signed message: the magic, but too short for a trailer.
    EXPECT_EQ(
        verifier.check(kPolicyChannel, good.data() + good.size() - size, size, kT0, payload_size),
        Verdict::Unsigned)
        << size;
    EXPECT_EQ(payload_size, size);
    EXPECT_EQ(unsignedPayloadSize(good.data() + good.size() - size, size), size);
  }
  EXPECT_EQ(verifier.check(kPolicyChannel, nullptr, 0, kT0, payload_size), Verdict::Unsigned);
  EXPECT_EQ(unsignedPayloadSize(nullptr, 0), 0);
  EXPECT_EQ(checkOf(verifier, good), Verdict::Ok);  // nothing above was accepted
}

// (6) A buffer too small.
TEST(Signing, TooSmallBuffer) {
  const Key key = testKey();
  Signer signer(key, 3);
  const Bytes payload = payloadOf(100);
  Bytes buf(payload);
  buf.resize(100 + kSignatureSize);
  const Bytes before = buf;
  EXPECT_EQ(signer.sign(kPolicyChannel, buf.data(), 100, 100 + kSignatureSize - 1), -1);
  EXPECT_EQ(signer.sign(kPolicyChannel, buf.data(), 100, 100), -1);
  EXPECT_EQ(signer.sign(kPolicyChannel, buf.data(), 100, 50), -1);
  EXPECT_EQ(signer.sign(kPolicyChannel, buf.data(), -1, 100), -1);
  EXPECT_EQ(signer.sign(kPolicyChannel, nullptr, 0, 100), -1);
  EXPECT_EQ(signer.signAt(kPolicyChannel, buf.data(), 100, 135, kT0), -1);
  EXPECT_EQ(buf, before);
  EXPECT_EQ(signer.lastTimestamp(), std::numeric_limits<std::int64_t>::min());
  EXPECT_EQ(signer.sign(kPolicyChannel, buf.data(), 100, 100 + kSignatureSize),
            100 + kSignatureSize);
  // A payload near INT_MAX: no overflow in the capacity check.
  EXPECT_EQ(signer.signAt(kPolicyChannel, buf.data(), std::numeric_limits<int>::max() - 10,
                          std::numeric_limits<int>::max(), kT0),
            -1);
}

// (7) Counters, and the first of each reason said once.
TEST(Signing, CountersAndSayOnce) {
  const Key key = testKey();
  const Signer signer(key, 3);
  const Bytes payload = payloadOf(80);
  Verifier verifier(key);
  for (int v = 0; v < kVerdicts; ++v) {
    EXPECT_FALSE(verifier.sayOnce(static_cast<Verdict>(v)));  // nothing counted yet
    EXPECT_NE(std::string(describe(static_cast<Verdict>(v))), "");
  }
  const Bytes good = signedAt(signer, payload, kT0);
  Bytes forged = signedAt(signer, payload, kT0 + 1);  // newer, then altered
  forged[0] ^= 0x80;
  const Bytes other = signedAt(Signer(testKey(50), 3), payload, kT0);
  EXPECT_EQ(checkOf(verifier, good), Verdict::Ok);
  EXPECT_EQ(checkOf(verifier, good), Verdict::Replayed);
  EXPECT_EQ(checkOf(verifier, good), Verdict::Replayed);
  EXPECT_EQ(checkOf(verifier, forged), Verdict::Forged);
  EXPECT_EQ(checkOf(verifier, payload), Verdict::Unsigned);
  EXPECT_EQ(checkOf(verifier, payload), Verdict::Unsigned);
  EXPECT_EQ(checkOf(verifier, payload), Verdict::Unsigned);
  EXPECT_EQ(checkOf(verifier, other), Verdict::WrongKey);
  EXPECT_EQ(checkOf(verifier, signedAt(signer, payload, kT0 - 10 * kSecond)), Verdict::Stale);
  EXPECT_EQ(checkOf(verifier, signedAt(signer, payload, kT0 + 10 * kSecond)), Verdict::Future);
  verifier.setSizes({0, 10, 1});
  EXPECT_EQ(checkOf(verifier, signedAt(signer, payload, kT0 + 1)), Verdict::Implausible);
  verifier.setSizes({});
  verifier.setNewSenderRate(1.0, 0.0);
  EXPECT_EQ(checkOf(verifier, signedAt(Signer(key, 4), payload, kT0 + 1)), Verdict::OverRate);
  const std::array<std::int64_t, kVerdicts> expected = {1, 3, 1, 1, 2, 1, 1, 1, 1};
  EXPECT_EQ(verifier.counters(), expected);
  for (int v = 0; v < kVerdicts; ++v) {
    EXPECT_TRUE(verifier.sayOnce(static_cast<Verdict>(v))) << v;
    EXPECT_FALSE(verifier.sayOnce(static_cast<Verdict>(v))) << v;
  }
  EXPECT_EQ(checkOf(verifier, payload), Verdict::Unsigned);
  EXPECT_FALSE(verifier.sayOnce(Verdict::Unsigned));
  EXPECT_EQ(verifier.count(Verdict::Unsigned), 4);
}

// (8) Key files.
class KeyFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    char pattern[] = "/tmp/stride_test_signing_XXXXXX";
    ASSERT_NE(::mkdtemp(pattern), nullptr);
    dir_ = pattern;
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  // A file of this content and mode.
  std::string file(const std::string& name, const std::string& content, mode_t mode) {
    const std::string path = dir_ + "/" + name;
    std::ofstream(path) << content;
    EXPECT_EQ(::chmod(path.c_str(), mode), 0);
    return path;
  }
  // The message loadKeyFile throws with ("" if it does not).
  static std::string loadError(const std::string& path) {
    try {
      loadKeyFile(path);
    } catch (const std::runtime_error& e) {
      return e.what();
    }
    return "";
  }

  std::string dir_;
};

const std::string kHex = "000102030405060708090a0b0c0d0e0f101112131415161718191a1b1c1d1e1f";

TEST_F(KeyFiles, GoodFileLoads) {
  for (const std::string& content :
       {kHex + "\n", kHex, "  \t" + kHex + "\r\n\n",
        std::string("000102030405060708090A0B0C0D0E0F") + "101112131415161718191A1B1C1D1E1F\n"}) {
    const Key key = loadKeyFile(file("key", content, 0600));
    EXPECT_EQ(key.bytes, testKey().bytes);
    EXPECT_EQ(key.id, 0x1c13aac1u);
    EXPECT_EQ(key.id, keyId(key.bytes));
    std::filesystem::remove(dir_ + "/key");
  }
  EXPECT_NO_THROW(loadKeyFile(file("owner_read_only", kHex, 0400)));
}

TEST_F(KeyFiles, TooOpenIsRefused) {
  const std::string path = file("key", kHex + "\n", 0644);
  EXPECT_EQ(loadError(path), "permissions 0644 for '" + path + "' are too open: chmod 600 " + path);
  for (mode_t mode : {0640, 0604, 0660, 0602, 0610}) {
    ASSERT_EQ(::chmod(path.c_str(), mode), 0);
    EXPECT_NE(loadError(path).find("are too open: chmod 600 " + path), std::string::npos) << mode;
  }
}

TEST_F(KeyFiles, BadContentIsRefused) {
  for (const std::string& content :
       {kHex.substr(0, 63) + "\n", kHex.substr(0, 40) + "x" + kHex.substr(41) + "\n", kHex + "ab\n",
        kHex.substr(0, 32) + " " + kHex.substr(32), std::string(""), std::string("\n"),
        std::string(10000, 'a')}) {
    const std::string path = file("key", content, 0600);
    const std::string error = loadError(path);
    EXPECT_NE(error.find("'" + path + "'"), std::string::npos) << error;
    EXPECT_NE(error.find("expected 64 hex digits"), std::string::npos) << error;
    std::filesystem::remove(path);
  }
}

TEST_F(KeyFiles, MissingFile) {
  const std::string path = dir_ + "/nothing";
  const std::string error = loadError(path);
  EXPECT_NE(error.find("cannot read key file '" + path + "'"), std::string::npos) << error;
  EXPECT_NE(loadError(dir_).find("'" + dir_ + "'"), std::string::npos);  // a directory
}

TEST_F(KeyFiles, WriteNewKeyFile) {
  const std::string path = dir_ + "/new.key";
  writeNewKeyFile(path);
  struct stat st {};
  ASSERT_EQ(::stat(path.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 07777, 0600u);
  std::ifstream in(path);
  const std::string content((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_EQ(content.size(), 65u);
  EXPECT_EQ(content.back(), '\n');
  for (int i = 0; i < 64; ++i) {
    EXPECT_TRUE((content[i] >= '0' && content[i] <= '9') ||
                (content[i] >= 'a' && content[i] <= 'f'))
        << i;
  }
  const Key key = loadKeyFile(path);
  EXPECT_EQ(key.id, keyId(key.bytes));
  EXPECT_EQ(hex(key.bytes) + "\n", content);

  // Never overwritten.
  try {
    writeNewKeyFile(path);
    ADD_FAILURE() << "a second writeNewKeyFile did not throw";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("'" + path + "' exists already"), std::string::npos)
        << e.what();
  }
  EXPECT_EQ(loadKeyFile(path).bytes, key.bytes);

  // Another key is another key.
  writeNewKeyFile(dir_ + "/other.key");
  EXPECT_NE(loadKeyFile(dir_ + "/other.key").bytes, key.bytes);
  EXPECT_THROW(writeNewKeyFile(dir_ + "/no/such/dir.key"), std::runtime_error);
}

TEST(Signing, RandomSenderIds) {
  std::set<std::uint32_t> ids;
  for (int i = 0; i < 100; ++i) {
    const std::uint32_t id = randomSenderId();
    EXPECT_NE(id, 0u);
    ids.insert(id);
  }
  EXPECT_GT(ids.size(), 90u);
}

// (9) No allocation in sign() and check(), on every path, from the first call.
TEST(Signing, NoAllocation) {
  // The counter counts (so that the zeros below mean something).
  EXPECT_EQ(stride::test_support::allocations([] {
              void* volatile p = std::malloc(100);
              std::free(p);
            }),
            1);
  const Key key = testKey();
  const Key other_key = testKey(77);
  for (int size : {600, 31000, 160000}) {
    Bytes buf = payloadOf(size);
    buf.resize(buf.size() + kSignatureSize);
    const Bytes plain = payloadOf(size);
    timespec wall{};
    clock_gettime(CLOCK_REALTIME, &wall);
    const std::int64_t now = static_cast<std::int64_t>(wall.tv_sec) * kSecond + wall.tv_nsec / 1000;
    Bytes other = signedAt(Signer(other_key, 1), plain, now);
    Bytes forged(buf);
    Signer signer(key, 2);
    Verifier verifier(key);
    int signed_size = 0, payload_size = 0;
    std::array<Verdict, 7> verdicts{};
    std::int64_t unsigned_size = 0;
    const long allocations = stride::test_support::allocations([&] {
      signed_size = signer.sign(kPolicyChannel, buf.data(), size, static_cast<int>(buf.size()));
      verdicts[0] = verifier.check(kPolicyChannel, buf.data(), signed_size, now, payload_size);
      verifier.accept();
      verdicts[1] = verifier.check(kPolicyChannel, buf.data(), signed_size, now, payload_size);
      verdicts[2] = verifier.check(kPolicyChannel, plain.data(), size, now, payload_size);
      verdicts[3] = verifier.check(kPolicyChannel, other.data(), signed_size, now, payload_size);
      // A newer message altered (an altered copy of the accepted one is refused as replayed,
      // before hashing).
      std::memcpy(forged.data(), buf.data(), buf.size());
      signer.sign(kPolicyChannel, forged.data(), size, static_cast<int>(forged.size()));
      forged[5] ^= 1;
      verdicts[4] = verifier.check(kPolicyChannel, forged.data(), signed_size, now, payload_size);
      signer.sign(kPolicyChannel, buf.data(), size, static_cast<int>(buf.size()));
      verdicts[5] = verifier.check(kPolicyChannel, buf.data(), signed_size, now, payload_size);
      verifier.accept();
      verdicts[6] = verifier.check(kPolicyChannel, buf.data(), signed_size, now + 3600 * kSecond,
                                   payload_size);
      unsigned_size = unsignedPayloadSize(buf.data(), signed_size);
    });
    EXPECT_EQ(allocations, 0) << size;
    EXPECT_EQ(signed_size, size + kSignatureSize);
    EXPECT_EQ(unsigned_size, size);
    const std::array<Verdict, 7> expected = {
        Verdict::Ok,     Verdict::Replayed, Verdict::Unsigned, Verdict::WrongKey,
        Verdict::Forged, Verdict::Ok,       Verdict::Stale};
    EXPECT_EQ(verdicts, expected) << size;
  }
}

// (10) sign()'s timestamps: the wall clock, strictly increasing.
TEST(Signing, TimestampsStrictlyIncrease) {
  const Key key = testKey();
  Signer signer(key, 4);
  Bytes buf(16 + kSignatureSize, 0);
  timespec now{};
  clock_gettime(CLOCK_REALTIME, &now);
  const std::int64_t start = static_cast<std::int64_t>(now.tv_sec) * kSecond + now.tv_nsec / 1000;
  std::int64_t previous = std::numeric_limits<std::int64_t>::min();
  Verifier verifier(key);
  for (int i = 0; i < 1000; ++i) {
    const int size = signer.sign(kPolicyChannel, buf.data(), 16, static_cast<int>(buf.size()));
    ASSERT_EQ(size, 16 + kSignatureSize);
    const std::int64_t t = trailerTimestamp(buf.data(), size);
    EXPECT_GT(t, previous) << i;
    EXPECT_EQ(t, signer.lastTimestamp());
    previous = t;
    int payload_size = 0;
    EXPECT_EQ(verifier.check(kPolicyChannel, buf.data(), size, t, payload_size), Verdict::Ok) << i;
    verifier.accept();
  }
  // The wall clock's microseconds (1000 quick calls may run ahead of it by at most 1000).
  EXPECT_GE(previous, start);
  EXPECT_LT(previous, start + 10 * kSecond);
  // signAt leaves the signer's own sequence alone.
  signer.signAt(kPolicyChannel, buf.data(), 16, static_cast<int>(buf.size()), 5);
  EXPECT_EQ(signer.lastTimestamp(), previous);
}

}  // namespace test_signing
}  // namespace stride::msg
