#include "controller/statistics.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace stride {

namespace {
// Sorted, without NaN: std::sort needs a strict weak order, which NaN breaks.
std::vector<double> sorted(std::vector<double> samples) {
  samples.erase(
      std::remove_if(samples.begin(), samples.end(), [](double x) { return std::isnan(x); }),
      samples.end());
  std::sort(samples.begin(), samples.end());
  return samples;
}
// The ceil(p n)-th smallest (1-based) of non-empty sorted samples. p n a hair above an integer is
// the product's rounding (0.07 * 100 is 7.000000000000001 in doubles), not a higher rank: it is
// shaved by a relative 1e-12 first.
double nearestRank(const std::vector<double>& s, double p) {
  const double pn = std::clamp(p, 0.0, 1.0) * static_cast<double>(s.size());
  const double rank = std::ceil(pn * (1.0 - 1e-12));
  const std::size_t i = rank < 1.0 ? 0 : static_cast<std::size_t>(rank) - 1;
  return s[std::min(i, s.size() - 1)];
}
}  // namespace

std::optional<double> percentile(std::vector<double> samples, double p) {
  const std::vector<double> s = sorted(std::move(samples));
  if (s.empty()) return std::nullopt;
  return nearestRank(s, p);
}

Percentiles percentiles(std::vector<double> samples) {
  const std::vector<double> s = sorted(std::move(samples));
  Percentiles out;
  out.count = static_cast<long>(s.size());
  if (s.empty()) return out;
  out.p50 = nearestRank(s, 0.50);
  out.p99 = nearestRank(s, 0.99);
  out.max = s.back();
  return out;
}

}  // namespace stride
