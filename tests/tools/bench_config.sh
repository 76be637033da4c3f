#!/usr/bin/env bash
# stride-bench --config FILE (issue 34): the controller's tick benchmark on a configuration given
# by path (outside config/, its robot beside it by a relative path), a short run; Google
# Benchmark's own flags still work, and an unknown flag or a missing file are refused.
#   bench_config.sh STRIDE_BENCH ROOT
set -euo pipefail
bench=$1 root=$2
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
mkdir -p "$dir/ctrl/robot"
cp "$root/config/robots/stride_quad/stride_quad.urdf" "$dir/ctrl/robot/"
cp "$root/config/robots/stride_quad/stride_quad.yaml" "$dir/ctrl/robot/quad.yaml"
sed 's|^robot: .*|robot: robot/quad.yaml|' "$root/config/controller/stride_quad.yaml" \
  > "$dir/ctrl/bench_quad.yaml"
before=$(sha256sum "$dir/ctrl/bench_quad.yaml")

"$bench" --config "$dir/ctrl/bench_quad.yaml" --benchmark_list_tests > "$dir/list.txt"
for name in controller_tick/config:bench_quad tick_parts/config:bench_quad/derivatives \
            reference_update/config:bench_quad; do
  grep -q "^$name" "$dir/list.txt" || { cat "$dir/list.txt"; echo "FAIL: $name not listed"; exit 1; }
done

status=0
"$bench" --config "$dir/ctrl/bench_quad.yaml" --benchmark_filter='^controller_tick/config:bench_quad' \
  --benchmark_min_time=0.01 --benchmark_format=json --benchmark_out="$dir/out.json" \
  --benchmark_out_format=json > "$dir/run.txt" 2>&1 || status=$?
[ "$status" = 0 ] || { cat "$dir/run.txt"; echo "FAIL: stride-bench exited $status"; exit 1; }
python3 - "$dir/out.json" "$dir/ctrl/bench_quad.yaml" <<'PY'
import json, os, sys
out = json.load(open(sys.argv[1]))
assert os.path.realpath(out["context"]["stride_config"]) == os.path.realpath(sys.argv[2]), out["context"]
runs = [b for b in out["benchmarks"] if b["name"].startswith("controller_tick/config:bench_quad")]
assert len(runs) == 1, [b["name"] for b in out["benchmarks"]]
b = runs[0]
assert not b.get("error_occurred"), b
assert b["iterations"] == 400 and b["real_time"] > 0 and b["prepare_ms"] > 0, b
print("%s: tick %.3f ms, preparation %.3f ms, period share %.2f" %
      (b["name"], b["real_time"], b["prepare_ms"], b["period_share"]))
PY
[ "$(sha256sum "$dir/ctrl/bench_quad.yaml")" = "$before" ] || { echo "FAIL: the configuration changed"; exit 1; }

# The environment variable does the same; usage errors.
STRIDE_BENCH_CONFIG="$dir/ctrl/bench_quad.yaml" "$bench" --benchmark_list_tests |
  grep -q '^controller_tick/config:bench_quad' || { echo "FAIL: STRIDE_BENCH_CONFIG"; exit 1; }
status=0
"$bench" --config "$dir/missing.yaml" --benchmark_list_tests > /dev/null 2>&1 || status=$?
[ "$status" = 2 ] || { echo "FAIL: a missing configuration exited $status, not 2"; exit 1; }
status=0
"$bench" --benchmark_no_such_flag > /dev/null 2>&1 || status=$?
[ "$status" != 0 ] || { echo "FAIL: an unknown flag was accepted"; exit 1; }
echo "stride-bench --config: OK"
