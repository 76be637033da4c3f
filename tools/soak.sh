#!/usr/bin/env bash
# A long real-time run of the closed loop (issue 19): tools/demo.sh in its private network
# namespace with lcm-logger, driving the quadruped through a 30 s pattern repeated for the whole
# run (stand, trot, forward 0.5 m/s, turn at 1 rad/s, sidestep left and right, stand), then a
# report: falls, deadline misses, fallbacks, lost messages, and the resident memory of stride-mpc
# and stride-sim at the start and at the end.
#   tools/soak.sh [--minutes N] [--robot NAME] [--out DIR] [--max-growth-mb M]
#   --minutes N          length of the run (default 10)
#   --robot NAME         a quadruped of config/controller/ (default stride_quad)
#   --out DIR            the log, the summaries and rss.txt (default build/soak)
#   --max-growth-mb M    fail when either program's memory grew more than M MB (default 8)
# Exit status: 0 upright and flat memory; 4 the robot fell; 1 memory grew, or another failure.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build="${STRIDE_BUILD_DIR:-$root/build}"
minutes=10 robot=stride_quad out="" max_growth=8
while [ $# -gt 0 ]; do
  case "$1" in
    --minutes) minutes="$2"; shift 2 ;;
    --robot) robot="$2"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    --max-growth-mb) max_growth="$2"; shift 2 ;;
    -h|--help) sed -n '2,/^set -euo/{/^#/p}' "$0"; exit 0 ;;
    *) echo "soak.sh: unknown option '$1' (--help)" >&2; exit 2 ;;
  esac
done
awk -v m="$minutes" 'BEGIN { exit !(m + 0 > 0) }' || { echo "soak.sh: --minutes must be > 0" >&2; exit 2; }
out="${out:-$build/soak}"
mkdir -p "$out"
out=$(cd "$out" && pwd)
duration=$(awk -v m="$minutes" 'BEGIN { printf "%d", m * 60 }')

# The pattern, repeated to cover the run; the teleop repeats the last entry (a stand) after it.
script="$out/commands.yaml"
{
  echo "# tools/soak.sh: a 30 s drive pattern repeated for $minutes min"
  for ((t0 = 0; t0 < duration; t0 += 30)); do
    echo "- {at: $t0, gait: stand, vx: 0.0, vy: 0.0, yaw_rate: 0.0}"
    echo "- {at: $((t0 + 2)), gait: trot}"
    echo "- {at: $((t0 + 4)), vx: 0.5}"
    echo "- {at: $((t0 + 10)), vx: 0.0, yaw_rate: 1.0}"
    echo "- {at: $((t0 + 16)), yaw_rate: 0.0, vy: 0.25}"
    echo "- {at: $((t0 + 20)), vy: -0.25}"
    echo "- {at: $((t0 + 24)), vy: 0.0}"
  done
} > "$script"

status=0
"$root/tools/demo.sh" --robot "$robot" --commands "$script" --duration "$duration" --realtime \
  --rss --out "$out" > "$out/demo.txt" 2>&1 || status=$?
grep -E '^(stride-mpc|stride-sim):|^session|^controller:|^lost:|^tracking|wall time' "$out/demo.txt" || true

# From the sample at 10 s: the first is taken as the controller starts, before the first state
# builds its problem. (The controller's tick latencies fill a reserved buffer, 4 B a tick: 0.5 MB
# in 10 min at 200 Hz, bounded at 4 MB.)
first=$(awk '$1 >= 10 { print; exit }' "$out/rss.txt" 2>/dev/null)
# The last sample with both programs running (the one taken after the run may find one gone).
last=$(awk '$2 > 0 && $3 > 0 { l = $0 } END { print l }' "$out/rss.txt" 2>/dev/null)
read -r t0 mpc0 sim0 <<< "${first:-0 0 0}"
read -r t1 mpc1 sim1 <<< "${last:-0 0 0}"
echo "soak: $minutes min of $robot in real time; memory (VmRSS) stride-mpc ${mpc0:-0} -> ${mpc1:-0} kB," \
  "stride-sim ${sim0:-0} -> ${sim1:-0} kB (samples at ${t0:-0} s and ${t1:-0} s); $(wc -l < "$out/rss.txt" 2>/dev/null || echo 0) samples in $out/rss.txt"
grown=$(awk -v a="${mpc0:-0}" -v b="${mpc1:-0}" -v c="${sim0:-0}" -v d="${sim1:-0}" -v m="$max_growth" \
  'BEGIN { print (b - a > m * 1024 || d - c > m * 1024) ? 1 : 0 }')
if [ "$status" != 0 ]; then
  echo "soak: the run ended with status $status (4: the robot fell; $out/demo.txt)"
  exit "$status"
fi
if [ "$grown" = 1 ]; then
  echo "soak: memory grew by more than $max_growth MB"
  exit 1
fi
echo "soak: upright, memory flat"
