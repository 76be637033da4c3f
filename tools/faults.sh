#!/usr/bin/env bash
# The controller killed and restarted in real time (issue 19): tools/demo.sh, in its private
# network namespace, walks the robot forward and SIGKILLs stride-mpc at N instants spread over
# one gait cycle (one run each), a new stride-mpc starting 1 s after each kill. The robot stands
# down on its own meanwhile (sim/README.md, "Controller loss") and the new controller walks it on.
# Prints one line per run and the falls; the lock-step version is ctest's ControllerLoss.*.
# With --flood RATE the runs kill nothing: another robot's policies arrive on the policy channel
# at RATE per second all along (tools/demo.sh --flood; lock-step: Faults.AFloodOf...).
#   tools/faults.sh [--robot stride_quad|stride_humanoid] [--runs N] [--out DIR] [--flood RATE]
#   --robot NAME   stride_quad (default: trots at 0.5 m/s) or stride_humanoid (walks at 0.2 m/s)
#   --runs N       kills (or flooded runs), one run each (default 10)
#   --out DIR      each run's demo folder (default build/faults/ROBOT, build/flood/ROBOT)
#   --flood RATE   a flood of RATE foreign policies per second instead of the kills
# Exit status: 0 no fall; 4 the robot fell in some run; 1 another failure.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build="${STRIDE_BUILD_DIR:-$root/build}"
robot=stride_quad runs=10 out="" flood=""
while [ $# -gt 0 ]; do
  case "$1" in
    --robot) robot="$2"; shift 2 ;;
    --runs) runs="$2"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    --flood) flood="$2"; shift 2 ;;
    -h|--help) sed -n '2,/^set -euo/{/^#/p}' "$0"; exit 0 ;;
    *) echo "faults.sh: unknown option '$1' (--help)" >&2; exit 2 ;;
  esac
done
case "$robot" in
  stride_quad) gait=trot vx=0.5 cycle=0.4 ;;
  stride_humanoid) gait=walk vx=0.2 cycle=1.0 ;;
  *) echo "faults.sh: --robot stride_quad or stride_humanoid" >&2; exit 2 ;;
esac
if [ -n "$flood" ]; then out="${out:-$build/flood/$robot}"; else out="${out:-$build/faults/$robot}"; fi
mkdir -p "$out"
out=$(cd "$out" && pwd)
script="$out/commands.yaml"
printf -- '- {at: 0.0, gait: stand}\n- {at: 1.0, gait: %s}\n- {at: 2.0, vx: %s}\n' "$gait" "$vx" \
  > "$script"

falls=0
for ((i = 0; i < runs; i++)); do
  # Walking at vx from 3.5 s; the kills cover one gait cycle, off the controller's period too.
  kill_at=$(awk -v i="$i" -v n="$runs" -v c="$cycle" 'BEGIN { printf "%.4f", 3.5 + c * i / n + 0.0013 * i }')
  duration=$(awk -v k="$kill_at" 'BEGIN { printf "%.1f", k + 1 + 4 }')
  dir="$out/run$i"
  status=0
  fault=(--kill-controller "$kill_at")
  [ -n "$flood" ] && fault=(--flood "$flood")
  "$root/tools/demo.sh" --robot "$robot" --commands "$script" --duration "$duration" --realtime \
    "${fault[@]}" --out "$dir" > "$dir.txt" 2>&1 || status=$?
  # A flooded session's log holds every foreign policy (44 MB a second): the summaries are kept.
  [ -n "$flood" ] && rm -f "$dir/session.lcmlog"
  line=$(python3 - "$dir" <<'EOF'
import json, sys
d = sys.argv[1]
s = json.load(open(d + "/sim.json"))
print("fell" if s["fell"] else "up",
      "tilt max %.1f deg, base %.3f..%.3f m, walked %.2f m; %d steps standing down, %d past a "
      "policy's end, %d controller switches; %d policies taken, %d of another model refused"
      % (s["max_tilt_deg"], s["base_height_min_m"], s["base_height_max_m"], s["distance_m"],
      s["stand_down_steps"], s["exhausted_steps"], s["source_switches"], s["policies"],
      s["policies_wrong_model"]))
EOF
  ) || line="no summary (demo exit $status: see $dir.txt)"
  case "$line" in fell*|no\ summary*) falls=$((falls + 1)) ;; esac
  if [ -n "$flood" ]; then
    echo "faults: $robot run $i, $flood foreign policies/s: $line"
  else
    echo "faults: $robot run $i, stride-mpc killed at $kill_at s: $line"
  fi
done
if [ -n "$flood" ]; then
  echo "faults: $robot: $falls falls in $runs runs under $flood foreign policies/s (summaries in $out)"
else
  echo "faults: $robot: $falls falls in $runs kills and restarts (logs in $out)"
fi
[ "$falls" = 0 ] || exit 4
