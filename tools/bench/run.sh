#!/usr/bin/env bash
# Run stride-bench with repetitions; print the median of each benchmark and keep the JSON.
#   tools/bench/run.sh [FILTER] [--out FILE.json] [--config FILE [--robots-dir DIR]...]
# FILTER is a regular expression on the names <algorithm>/<robot> (default: all). --config FILE
# adds the controller benchmarks on any controller configuration (stride-bench --config:
# controller_tick/config:NAME, tick_parts/config:NAME/*, reference_update/config:NAME; NAME is
# FILE's name without .yaml; FILTER 'config:' runs only those).
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
filter=. out="${here}/build/bench.json" config_args=()
need() { [ $# -ge 2 ] || { echo "run.sh: $1 needs a value (--help)" >&2; exit 2; }; }
while [ $# -gt 0 ]; do
  case "$1" in
    --out) need "$@"; out="$2"; shift 2 ;;
    --config | --robots-dir) need "$@"; config_args+=("$1" "$2"); shift 2 ;;
    -*) echo "run.sh: unknown option '$1' (--help)" >&2; exit 2 ;;
    *) filter="$1"; shift ;;
  esac
done
if [ ! -x "$bench" ]; then
  echo "stride-bench not built: run tools/test.sh (or cmake --build build) first" >&2
  exit 1
fi
"$bench" "${config_args[@]}" --benchmark_filter="$filter" --benchmark_repetitions="${REPETITIONS:-15}" \
  --benchmark_min_time="${MIN_TIME:-0.05}" --benchmark_report_aggregates_only=true \
  --benchmark_out="$out" --benchmark_out_format=json --benchmark_format=console 2>&1 |
  grep --line-buffered -E '_median|^Benchmark|^-' | sed -u 's/_median//'
echo "JSON: $out"
