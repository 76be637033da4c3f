#!/usr/bin/env bash
# How fast a robot walks and how hard it can be pushed, measured with stride-drive (lock-step, in
# one process, deterministic; tools/drive/README.md):
#   speed  the top forward speed it holds for 10 s: commands of increasing speed, each held 10 s
#          after the ramp; a speed counts when the robot did not fall and its mean forward velocity
#          over those 10 s is within 15% (or 0.05 m/s) of the command. The sweep stops at the first
#          speed that fails.
#   push   the largest lateral push it survives while walking forward at --push-speed: a 0.1 s
#          force on the base 4 s into the walk, increasing until the robot falls within the 6 s
#          after it (bisection to 0.1 N s). --push-at moves the push (default 6.0 s, 4 s into the
#          walk) to another instant of the gait cycle: the largest push depends on the phase.
#   tools/drive/sweep.sh ROBOT [--speed-step 0.1] [--push-speed 0.5] [--push-at 6.0] [--no-push]
#                        [--no-speed] [--robots-dir DIR] [--out DIR]
# ROBOT names config/controller/ROBOT.yaml; its stepping gait is trot (quadrupeds) or walk
# (bipeds). The command limits of the configuration are lifted for the speed sweep. Prints one line
# per run and a summary; writes DIR/sweep_ROBOT.json.
set -euo pipefail
case "${1:-}" in -h|--help) sed -n '2,/^set -euo/{/^#/p}' "$0"; exit 0 ;; esac
root=$(cd "$(dirname "$0")/../.." && pwd)
build="${STRIDE_BUILD_DIR:-$root/build}"
robot="${1:?usage: sweep.sh ROBOT [options]}"
shift
step=0.1 push_speed=0.5 push_at=6.0 do_push=1 do_speed=1 out="$build/sweep" dirs=()
need() { [ $# -ge 2 ] || { echo "sweep.sh: $1 needs a value" >&2; exit 2; }; }
while [ $# -gt 0 ]; do
  case "$1" in
    --speed-step) need "$@"; step="$2"; shift 2 ;;
    --push-speed) need "$@"; push_speed="$2"; shift 2 ;;
    --push-at) need "$@"; push_at="$2"; shift 2 ;;
    --no-push) do_push=0; shift ;;
    --no-speed) do_speed=0; shift ;;
    --robots-dir) need "$@"; dirs+=(--robots-dir "$2"); shift 2 ;;
    --out) need "$@"; out="$2"; shift 2 ;;
    *) echo "sweep.sh: unknown option '$1'" >&2; exit 2 ;;
  esac
done
[ -d "$build/robot_packages" ] && dirs+=(--robots-dir "$build/robot_packages")
drive="$build/tools/stride-drive"
[ -x "$drive" ] || { echo "sweep.sh: build first (tools/build.sh)" >&2; exit 1; }
mkdir -p "$out"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# The configuration with its robot path made absolute and the command limits lifted.
config="$work/$robot.yaml"
sed -e "s#^robot: *\(.*\)#robot: $root/config/controller/\1#" \
    -e "s#^\( *max_velocity:\).*#\1 [5.0, 2.0, 3.0]#" "$root/config/controller/$robot.yaml" > "$config"
grep -q "max_velocity" "$config" || printf 'command: {max_velocity: [5.0, 2.0, 3.0]}\n' >> "$config"
gait=walk
"$build/controller/stride-mpc" --config "$config" "${dirs[@]}" --print-model |
  grep -q '^gaits:.* trot' && gait=trot

# One drive: stand, step in place, then `speed` from 2 s for `hold` s after a ramp; optional push.
drive_at() {  # speed hold [push_impulse push_time] -> prints "fell achieved"
  local speed=$1 hold=$2 impulse=${3:-0} at=${4:-0}
  local script="$work/script.yaml" summary="$work/summary.json"
  cat > "$script" <<EOF
- {at: 0.0, gait: stand}
- {at: 1.0, gait: $gait}
- {at: 2.0, vx: $speed}
EOF
  local ramp
  ramp=$(awk -v v="$speed" 'BEGIN { printf "%.1f", v / 0.5 + 1.0 }')  # reached at >= 0.5 m/s²
  local duration
  duration=$(awk -v r="$ramp" -v h="$hold" 'BEGIN { print 2.0 + r + h }')
  local push=()
  if [ "$impulse" != 0 ]; then
    push=(--push "$at:0.1:0,$(awk -v i="$impulse" 'BEGIN { print i / 0.1 }'),0")
  fi
  # The segment's mean velocity over the hold: it settles for the ramp first.
  rm -f "$summary"
  local status=0
  "$drive" --config "$config" --commands "$script" "${dirs[@]}" --duration "$duration" \
    --settle "$ramp" "${push[@]}" --summary "$summary" > "$work/drive.txt" 2>&1 || status=$?
  if [ "$status" != 0 ] || [ ! -s "$summary" ]; then
    cp "$work/drive.txt" "$out/sweep_${robot}_error.txt"
    echo "sweep.sh: stride-drive failed (exit $status): $out/sweep_${robot}_error.txt" >&2
    exit 1
  fi
  python3 - "$summary" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
a = s["segments"][-1]["achieved"]
print("fell" if s["fell"] else "ok", "%.3f" % (a[0] if a else 0.0))
PY
}

speed_top=0
if [ "$do_speed" = 1 ]; then
  v=$step
  while :; do
    read -r fell got < <(drive_at "$v" 10)
    ok=$(awk -v v="$v" -v g="$got" 'BEGIN { d = g - v; if (d < 0) d = -d; t = 0.15 * v; if (t < 0.05) t = 0.05; print (d <= t) ? 1 : 0 }')
    printf "%s speed %.2f m/s: %s, mean %.3f m/s%s\n" "$robot" "$v" "$fell" "$got" \
      "$([ "$ok" = 1 ] || echo ' (off the command)')"
    [ "$fell" = ok ] && [ "$ok" = 1 ] || break
    speed_top=$v
    v=$(awk -v v="$v" -v s="$step" 'BEGIN { printf "%.2f", v + s }')
  done
fi

push_top=0
if [ "$do_push" = 1 ]; then
  lo=0 hi=0.5
  # Grow until a fall, then bisect.
  while :; do
    read -r fell got < <(drive_at "$push_speed" 8 "$hi" "$push_at")
    printf "%s push %.2f N s at %.2f m/s: %s\n" "$robot" "$hi" "$push_speed" "$fell"
    [ "$fell" = ok ] || break
    lo=$hi
    hi=$(awk -v h="$hi" 'BEGIN { print h * 2 }')
    [ "$(awk -v h="$hi" 'BEGIN { print (h > 1000) }')" = 1 ] && break
  done
  while [ "$(awk -v l="$lo" -v h="$hi" 'BEGIN { print (h - l > 0.1) }')" = 1 ]; do
    mid=$(awk -v l="$lo" -v h="$hi" 'BEGIN { printf "%.3f", (l + h) / 2 }')
    read -r fell got < <(drive_at "$push_speed" 8 "$mid" "$push_at")
    printf "%s push %.2f N s at %.2f m/s: %s\n" "$robot" "$mid" "$push_speed" "$fell"
    if [ "$fell" = ok ]; then lo=$mid; else hi=$mid; fi
  done
  push_top=$lo
fi

speed_text="$speed_top m/s" push_text="$push_top N s"
[ "$do_speed" = 1 ] || { speed_top=null; speed_text="not measured"; }
[ "$do_push" = 1 ] || { push_top=null; push_text="not measured"; }
echo "$robot: top speed held 10 s: $speed_text; largest lateral push survived at $push_speed m/s: $push_text"
printf '{"robot": "%s", "top_speed_mps": %s, "push_speed_mps": %s, "max_lateral_push_Ns": %s}\n' \
  "$robot" "$speed_top" "$push_speed" "$push_top" > "$out/sweep_$robot.json"
