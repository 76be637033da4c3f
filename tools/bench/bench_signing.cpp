// Message signing (messages/signing.hpp): what signing and checking a message costs, by payload
// size in bytes: 600 (a state), 31000 (stride_quad's policy, 8 knots), 160000 (talos_reduced's).
//   BM_SignPolicy/<bytes>          Signer::sign: SHA-256 of the payload, HMAC of the header
//   BM_CheckPolicy/<bytes>         Verifier::check of one signed message, checked again and again:
//                                  after the first it is Replayed, which costs the same (the mac
//                                  is verified before the replay table is read)
//   BM_SignAndCheckPolicy/<bytes>  both, each message new (every check Ok)
// Registered from a static initializer, so that main.cpp needs no change for this file.

#include <benchmark/benchmark.h>

#include <array>
#include <cstdint>
#include <vector>

#include "messages/signing.hpp"

namespace stride::bench {
namespace {

msg::Key benchKey() {
  std::array<std::uint8_t, msg::kKeySize> bytes{};
  for (int i = 0; i < msg::kKeySize; ++i) bytes[i] = static_cast<std::uint8_t>(3 * i + 1);
  return msg::makeKey(bytes);
}

// A payload of `size` bytes with room for the trailer.
std::vector<std::uint8_t> payload(int size) {
  std::vector<std::uint8_t> buf(static_cast<std::size_t>(size + msg::kSignatureSize));
  for (int i = 0; i < size; ++i) buf[i] = static_cast<std::uint8_t>(i * 7 + (i >> 9));
  return buf;
}

void BM_SignPolicy(benchmark::State& state) {
  const int size = static_cast<int>(state.range(0));
  std::vector<std::uint8_t> buf = payload(size);
  msg::Signer signer(benchKey(), 1);
  for (auto _ : state) {
    benchmark::DoNotOptimize(
        signer.sign("STRIDE_POLICY", buf.data(), size, static_cast<int>(buf.size())));
    benchmark::ClobberMemory();
  }
  state.SetBytesProcessed(state.iterations() * size);
}

void BM_CheckPolicy(benchmark::State& state) {
  const int size = static_cast<int>(state.range(0));
  const msg::Key key = benchKey();
  std::vector<std::uint8_t> buf = payload(size);
  msg::Signer signer(key, 1);
  const int signed_size =
      signer.sign("STRIDE_POLICY", buf.data(), size, static_cast<int>(buf.size()));
  msg::Verifier verifier(key);
  // The same message every time, never accepted (so never a replay): the whole check, the hash
  // included, each time; without the new senders' budget, which would refuse it unhashed.
  verifier.setNewSenderRate(0.0, 0.0);
  const std::int64_t now = signer.lastTimestamp();
  int payload_size = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(
        verifier.check("STRIDE_POLICY", buf.data(), signed_size, now, payload_size));
    benchmark::ClobberMemory();
  }
  if (verifier.count(msg::Verdict::Ok) != static_cast<std::int64_t>(state.iterations()))
    state.SkipWithError("the signed message was refused");
  state.SetBytesProcessed(state.iterations() * size);
}

void BM_SignAndCheckPolicy(benchmark::State& state) {
  const int size = static_cast<int>(state.range(0));
  const msg::Key key = benchKey();
  std::vector<std::uint8_t> buf = payload(size);
  msg::Signer signer(key, 1);
  msg::Verifier verifier(key);
  int payload_size = 0;
  for (auto _ : state) {
    const int signed_size =
        signer.sign("STRIDE_POLICY", buf.data(), size, static_cast<int>(buf.size()));
    benchmark::DoNotOptimize(verifier.check("STRIDE_POLICY", buf.data(), signed_size,
                                            signer.lastTimestamp(), payload_size));
    verifier.accept();
    benchmark::ClobberMemory();
  }
  if (verifier.count(msg::Verdict::Ok) != static_cast<std::int64_t>(state.iterations()))
    state.SkipWithError("a signed message was refused");
  state.SetBytesProcessed(state.iterations() * size);
}

BENCHMARK(BM_SignPolicy)->Arg(600)->Arg(31000)->Arg(160000);
BENCHMARK(BM_CheckPolicy)->Arg(600)->Arg(31000)->Arg(160000);
BENCHMARK(BM_SignAndCheckPolicy)->Arg(600)->Arg(31000)->Arg(160000);

}  // namespace
}  // namespace stride::bench
