#pragma once
// Percentiles of a run's samples (tick latencies, solve and preparation times, a period's work),
// for the summaries the programs print and write at their end: stride-mpc, stride-log-summary,
// stride-bench. One definition for all of them, so that their figures compare. Not for the
// real-time tick: every call copies and sorts its samples.

#include <optional>
#include <vector>

namespace stride {

// The nearest-rank p-th percentile of the samples, p in [0, 1]: the smallest sample x such that at
// least a share p of the samples is <= x, i.e. the ceil(p n)-th smallest of n samples (p = 0 gives
// the smallest, p = 1 the largest). Always one of the samples, never an interpolation between two.
// NaN samples are left out (they have no rank). Empty when no sample is left: "no data", which the
// summaries write as JSON null, never as 0.
std::optional<double> percentile(std::vector<double> samples, double p);

// What the summaries report of a set of samples: how many, the median, the 99th percentile and the
// largest, as percentile() defines them (empty when count is 0).
struct Percentiles {
  long count = 0;
  std::optional<double> p50, p99, max;
};
Percentiles percentiles(std::vector<double> samples);

}  // namespace stride
