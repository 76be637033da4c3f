#!/usr/bin/env bash
# How fast a robot walks and how hard it can be pushed, measured with stride-drive (lock-step, in
# one process, deterministic; tools/drive/README.md):
#   speed  the top forward speed it holds for 10 s: commands of increasing speed, each held 10 s
#          after the ramp; a speed counts when the robot did not fall and its mean forward velocity
#          over those 10 s is within 15% (or 0.05 m/s) of the command. The sweep stops at the first
#          speed that fails, or after the last step not above --max-speed V.
#   push   the largest lateral push it survives while walking forward at --push-speed: a 0.1 s
#          force on the base 4 s into the walk, increasing until the robot falls within the 6 s
#          after it (bisection to 0.1 N s). --push-at moves the push (default 6.0 s, 4 s into the
#          walk) to another instant of the gait cycle: the largest push depends on the phase.
#   tools/drive/sweep.sh ROBOT | --config FILE [--speed-step 0.1] [--max-speed V]
#                        [--push-speed 0.5] [--push-at 6.0] [--no-push] [--no-speed]
#                        [--robots-dir DIR]... [--out DIR]
# ROBOT is a shipped robot's name: config/controller/ROBOT.yaml (stride_quad, solo12, anymal_c,
# stride_humanoid, talos_reduced; never a path). --config FILE sweeps any controller
# configuration; the paths in it (robot:, gait.plan_file, lcm.key_file) are relative to its
# folder, as stride-mpc reads them. The stepping gait is trot (quadrupeds) or walk (bipeds). The
# drives run on a copy in a temporary folder (mktemp -d) with those paths made absolute and the
# command limits lifted for the speed sweep: the sweep never writes to the configuration, nor
# beside it. Prints one line per run and a summary; writes DIR/sweep_NAME.json (DIR default
# build/sweep; NAME the ROBOT, or FILE's name without .yaml).
set -euo pipefail
case "${1:-}" in -h|--help) sed -n '2,/^set -euo/{/^#/p}' "$0"; exit 0 ;; esac
root=$(cd "$(dirname "$0")/../.." && pwd)
build="${STRIDE_BUILD_DIR:-$root/build}"
robot="" input="" step=0.1 max_speed="" push_speed=0.5 push_at=6.0 do_push=1 do_speed=1
out="$build/sweep" dirs=()
need() { [ $# -ge 2 ] || { echo "sweep.sh: $1 needs a value (--help)" >&2; exit 2; }; }
while [ $# -gt 0 ]; do
  case "$1" in
    --config) need "$@"; input="$2"; shift 2 ;;
    --speed-step) need "$@"; step="$2"; shift 2 ;;
    --max-speed) need "$@"; max_speed="$2"; shift 2 ;;
    --push-speed) need "$@"; push_speed="$2"; shift 2 ;;
    --push-at) need "$@"; push_at="$2"; shift 2 ;;
    --no-push) do_push=0; shift ;;
    --no-speed) do_speed=0; shift ;;
    --robots-dir) need "$@"; dirs+=(--robots-dir "$2"); shift 2 ;;
    --out) need "$@"; out="$2"; shift 2 ;;
    -h|--help) sed -n '2,/^set -euo/{/^#/p}' "$0"; exit 0 ;;
    -*) echo "sweep.sh: unknown option '$1' (--help)" >&2; exit 2 ;;
    *)
      [ -z "$robot" ] || { echo "sweep.sh: one ROBOT only ('$robot', then '$1')" >&2; exit 2; }
      robot="$1"
      shift ;;
  esac
done
shipped() { (cd "$root/config/controller" && ls -- *.yaml | sed 's/\.yaml$//' | tr '\n' ' '); }
if [ -n "$robot" ] && [ -n "$input" ]; then
  echo "sweep.sh: ROBOT or --config FILE, not both" >&2
  exit 2
elif [ -n "$robot" ]; then
  # A shipped robot's name, never a path: `../../x/my_robot` once made the sweep write its
  # temporary copy over the user's own file (issue 34).
  if ! [[ "$robot" =~ ^[A-Za-z0-9_]+$ ]] || [ ! -f "$root/config/controller/$robot.yaml" ]; then
    echo "sweep.sh: no shipped robot '$robot' (config/controller/NAME.yaml); the robots: $(shipped)" >&2
    echo "  another configuration: sweep.sh --config FILE" >&2
    exit 2
  fi
  input="$root/config/controller/$robot.yaml"
elif [ -n "$input" ]; then
  [ -f "$input" ] && [ -r "$input" ] || { echo "sweep.sh: no configuration file '$input'" >&2; exit 2; }
  # The results' name: the file's, without .yaml, in characters safe in a file name.
  robot=$(basename -- "$input" | sed -E 's/\.ya?ml$//; s/[^A-Za-z0-9_.-]/_/g')
else
  echo "usage: sweep.sh ROBOT | --config FILE [options] (--help); the robots: $(shipped)" >&2
  exit 2
fi
for v in "$step" "$push_speed" "$push_at" ${max_speed:+"$max_speed"}; do
  awk -v v="$v" 'BEGIN { exit !(v ~ /^[0-9]*\.?[0-9]+([eE][-+]?[0-9]+)?$/) }' ||
    { echo "sweep.sh: '$v' is not a non-negative number" >&2; exit 2; }
done
awk -v s="$step" 'BEGIN { exit !(s + 0 > 0) }' || { echo "sweep.sh: --speed-step must be > 0" >&2; exit 2; }
[ -d "$build/robot_packages" ] && dirs+=(--robots-dir "$build/robot_packages")
drive="$build/tools/stride-drive"
[ -x "$drive" ] || { echo "sweep.sh: build first (tools/build.sh)" >&2; exit 1; }
mkdir -p "$out"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# The configuration's copy in the temporary folder (the input is only read): its paths made
# absolute, relative to the input's folder as stride-mpc resolves them (robot: at the top level,
# plan_file: and key_file: in their blocks), and the command limits lifted.
config="$work/config.yaml"
python3 "$root/tools/drive/config_copy.py" "$input" "$config" --lift-command-limits
gait=walk
if ! "$build/controller/stride-mpc" --config "$config" "${dirs[@]}" --print-model > "$work/model.txt" 2>&1; then
  cat "$work/model.txt" >&2
  echo "sweep.sh: cannot load '$input' (above; $config was its copy with absolute paths)" >&2
  exit 1
fi
grep -q '^gaits:.* trot' "$work/model.txt" && gait=trot

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
  # 4: the robot fell, 3: the simulation diverged (stride-drive's statuses): results, with a summary.
  if { [ "$status" != 0 ] && [ "$status" != 3 ] && [ "$status" != 4 ]; } || [ ! -s "$summary" ]; then
    cp "$work/drive.txt" "$out/sweep_${robot}_error.txt"
    echo "sweep.sh: stride-drive failed (exit $status): $out/sweep_${robot}_error.txt" >&2
    exit 1
  fi
  python3 - "$summary" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
a = s["segments"][-1]["achieved"]
print("fell" if s["fell"] or s.get("diverged") else "ok", "%.3f" % (a[0] if a else 0.0))
PY
}

speed_top=0
if [ "$do_speed" = 1 ]; then
  v=$step
  while :; do
    # A failed drive prints nothing (its message and exit are in the substitution's subshell).
    read -r fell got < <(drive_at "$v" 10) || exit 1
    ok=$(awk -v v="$v" -v g="$got" 'BEGIN { d = g - v; if (d < 0) d = -d; t = 0.15 * v; if (t < 0.05) t = 0.05; print (d <= t) ? 1 : 0 }')
    printf "%s speed %.2f m/s: %s, mean %.3f m/s%s\n" "$robot" "$v" "$fell" "$got" \
      "$([ "$ok" = 1 ] || echo ' (off the command)')"
    [ "$fell" = ok ] && [ "$ok" = 1 ] || break
    speed_top=$v
    v=$(awk -v v="$v" -v s="$step" 'BEGIN { printf "%.2f", v + s }')
    if [ -n "$max_speed" ] && awk -v v="$v" -v m="$max_speed" 'BEGIN { exit !(v > m + 1e-9) }'; then
      echo "$robot: next speed $v m/s above --max-speed $max_speed: stopped"
      break
    fi
  done
fi

push_top=0
if [ "$do_push" = 1 ]; then
  lo=0 hi=0.5
  # Grow until a fall, then bisect.
  while :; do
    read -r fell got < <(drive_at "$push_speed" 8 "$hi" "$push_at") || exit 1
    printf "%s push %.2f N s at %.2f m/s: %s\n" "$robot" "$hi" "$push_speed" "$fell"
    [ "$fell" = ok ] || break
    lo=$hi
    hi=$(awk -v h="$hi" 'BEGIN { print h * 2 }')
    [ "$(awk -v h="$hi" 'BEGIN { print (h > 1000) }')" = 1 ] && break
  done
  while [ "$(awk -v l="$lo" -v h="$hi" 'BEGIN { print (h - l > 0.1) }')" = 1 ]; do
    mid=$(awk -v l="$lo" -v h="$hi" 'BEGIN { printf "%.3f", (l + h) / 2 }')
    read -r fell got < <(drive_at "$push_speed" 8 "$mid" "$push_at") || exit 1
    printf "%s push %.2f N s at %.2f m/s: %s\n" "$robot" "$mid" "$push_speed" "$fell"
    if [ "$fell" = ok ]; then lo=$mid; else hi=$mid; fi
  done
  push_top=$lo
fi

speed_text="$speed_top m/s" push_text="$push_top N s"
[ "$do_speed" = 1 ] || { speed_top=null; speed_text="not measured"; }
[ "$do_push" = 1 ] || { push_top=null; push_text="not measured"; }
echo "$robot: top speed held 10 s: $speed_text; largest lateral push survived at $push_speed m/s: $push_text"
# config: the configuration swept (the input, not the temporary copy); max_speed_mps: --max-speed.
python3 - "$out/sweep_$robot.json" "$robot" "$(realpath -- "$input")" "$speed_top" "$push_speed" \
  "$push_top" "${max_speed:-null}" <<'PY'
import json, sys
path, robot, config, top, push_speed, push, max_speed = sys.argv[1:]
num = lambda x: None if x == "null" else float(x)
with open(path, "w") as f:
    json.dump({"robot": robot, "config": config, "top_speed_mps": num(top),
               "push_speed_mps": num(push_speed), "max_lateral_push_Ns": num(push),
               "max_speed_mps": num(max_speed)}, f)
    f.write("\n")
PY
