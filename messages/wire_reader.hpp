#pragma once
// The one reader of LCM's encoded bytes before they are decoded (issue 43): big-endian integers
// (LCM's encoding) read from bytes nobody vouched for, every read checked against the bytes
// there are. The wire checks (validate.cpp) read counts at fixed offsets with readInt32/readInt64;
// stride-viz's checks of the types with strings (viz/server/wire.cpp) walk a message front to back
// with WireReader. Header-only, allocation-free, never throws.

#include <cstdint>
#include <cstring>

namespace stride::msg {

// The big-endian int32 at byte offset `at` of buf[0, size); false (out untouched) when it does
// not fit.
inline bool readInt32(const void* buf, long size, long at, std::int32_t& out) {
  if (at < 0 || at + 4 > size) return false;
  const auto* b = static_cast<const unsigned char*>(buf) + at;
  const std::uint32_t u = (std::uint32_t(b[0]) << 24) | (std::uint32_t(b[1]) << 16) |
                          (std::uint32_t(b[2]) << 8) | std::uint32_t(b[3]);
  std::memcpy(&out, &u, 4);
  return true;
}

// The big-endian int64 at byte offset `at` (two int32, high first).
inline bool readInt64(const void* buf, long size, long at, std::int64_t& out) {
  std::int32_t hi, lo;
  if (!readInt32(buf, size, at, hi) || !readInt32(buf, size, at + 4, lo)) return false;
  const std::uint64_t u = (std::uint64_t(std::uint32_t(hi)) << 32) | std::uint32_t(lo);
  std::memcpy(&out, &u, 8);
  return true;
}

// Reads an encoded message front to back without trusting it: every read checks the bytes left
// and, when it fails, leaves the position where it was.
class WireReader {
 public:
  WireReader(const void* buf, long size)
      : b_(static_cast<const unsigned char*>(buf)), size_(size) {}
  bool skip(long n) {
    if (n < 0 || at_ + n > size_) return false;
    at_ += n;
    return true;
  }
  bool int32(std::int32_t& out) {
    if (!readInt32(b_, size_, at_, out)) return false;
    at_ += 4;
    return true;
  }
  bool int64(std::int64_t& out) {
    if (!readInt64(b_, size_, at_, out)) return false;
    at_ += 8;
    return true;
  }
  // A string: its length counts the NUL, which must be there (a length < 1 would make lcm-gen's
  // decoder construct a string of size_t(-1)).
  bool string() {
    std::int32_t len;
    if (!readInt32(b_, size_, at_, len) || len < 1 || at_ + 4 + len > size_ ||
        b_[at_ + 4 + len - 1] != 0)
      return false;
    at_ += 4 + len;
    return true;
  }
  // A count n >= 0 of elements of at least min_bytes_each that the bytes left can hold.
  bool count(std::int32_t& n, long min_bytes_each) {
    std::int32_t c;
    if (!readInt32(b_, size_, at_, c) || c < 0 ||
        static_cast<long>(c) * min_bytes_each > size_ - at_ - 4)
      return false;
    n = c;
    at_ += 4;
    return true;
  }
  long at() const { return at_; }

 private:
  const unsigned char* b_;
  long size_, at_ = 0;
};

}  // namespace stride::msg
