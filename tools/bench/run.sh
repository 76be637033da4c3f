#!/usr/bin/env bash
# Run stride-bench with repetitions; print the median of each benchmark and keep the JSON.
#   tools/bench/run.sh [FILTER] [--out FILE.json]
# FILTER is a regular expression on the names <algorithm>/<robot> (default: all).
set -euo pipefail
case "${1:-}" in
  -h|--help)
    sed -n '2,/^set -euo/{/^#/p}' "$0"
    echo "# Benchmarks' names: stride-bench --benchmark_list_tests (in the build's tools/bench/)."
    echo "# REPETITIONS (15) and MIN_TIME (0.05 s) in the environment change the runs."
    exit 0 ;;
esac
here=$(cd "$(dirname "$0")/../.." && pwd)
bench="${STRIDE_BUILD_DIR:-$here/build}/tools/bench/stride-bench"
filter="${1:-.}"
out="${here}/build/bench.json"
[ "${2:-}" = "--out" ] && out="$3"
if [ ! -x "$bench" ]; then
  echo "stride-bench not built: run tools/test.sh (or cmake --build build) first" >&2
  exit 1
fi
"$bench" --benchmark_filter="$filter" --benchmark_repetitions="${REPETITIONS:-15}" \
  --benchmark_min_time="${MIN_TIME:-0.05}" --benchmark_report_aggregates_only=true \
  --benchmark_out="$out" --benchmark_out_format=json --benchmark_format=console 2>&1 |
  grep --line-buffered -E '_median|^Benchmark|^-' | sed -u 's/_median//'
echo "JSON: $out"
