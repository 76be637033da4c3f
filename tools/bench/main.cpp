// stride-bench: every Stride benchmark, named <algorithm>/<robot>.
//   stride-bench --benchmark_filter='rnea/.*' --benchmark_format=json
// tools/bench/run.sh runs it with repetitions and prints the medians.

#include <benchmark/benchmark.h>

namespace stride::bench {
void registerMultibodyBenchmarks();
void registerContactBenchmarks();
}  // namespace stride::bench

int main(int argc, char** argv) {
  stride::bench::registerMultibodyBenchmarks();
  stride::bench::registerContactBenchmarks();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
