#!/usr/bin/env bash
# Every shipped terrain a robot has (config/terrain/*_ROBOT.yaml, plus flat and step_up_down),
# driven with the robot's terrain script (config/commands/terrain_ROBOT.yaml, what `tools/demo.sh
# --terrain` plays; the default script when there is none) by stride-drive (lock-step,
# deterministic; tools/drive/README.md). With a map at 10 Hz, except blind (--map-rate 0): the
# rough_blind_* terrains, the humanoids' rough ground, and flat ground 5 cm above and below the
# nominal (`--ground`). Per run: did it fall, and when; how far it got along x; the mean forward
# speed over the longest commanded segment against its command; its feet's trips on vertical
# faces; its touch-downs closer than 2 cm to an edge of the true terrain, of all its touch-downs;
# did it track every segment. Prints one markdown row per run (the table of controller/README.md,
# "Terrain"); writes DIR/terrains_ROBOT.json.
#   tools/drive/terrains.sh [ROBOT...] [--robots-dir DIR] [--out DIR]
# ROBOT: names of config/controller/ROBOT.yaml (default: the five shipped robots).
set -euo pipefail
case "${1:-}" in -h|--help) sed -n '2,/^set -euo/{/^#/p}' "$0"; exit 0 ;; esac
root=$(cd "$(dirname "$0")/../.." && pwd)
build="${STRIDE_BUILD_DIR:-$root/build}"
robots=() dirs=() out="$build/terrains"
while [ $# -gt 0 ]; do
  case "$1" in
    --robots-dir) [ $# -ge 2 ] || { echo "terrains.sh: --robots-dir needs a value" >&2; exit 2; }
      dirs+=(--robots-dir "$2"); shift 2 ;;
    --out) [ $# -ge 2 ] || { echo "terrains.sh: --out needs a value" >&2; exit 2; }
      out="$2"; shift 2 ;;
    -*) echo "terrains.sh: unknown option '$1'" >&2; exit 2 ;;
    *) robots+=("$1"); shift ;;
  esac
done
[ ${#robots[@]} -gt 0 ] || robots=(stride_quad solo12 anymal_c stride_humanoid talos_reduced)
[ -d "$build/robot_packages" ] && dirs+=(--robots-dir "$build/robot_packages")
mkdir -p "$out"
echo "| robot | terrain | map | fell | x at the end [m] | speed / command | trips | edge footholds | tracked |"
echo "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"
for robot in "${robots[@]}"; do
  config="$root/config/controller/$robot.yaml"
  [ -f "$config" ] || { echo "terrains.sh: no robot '$robot'" >&2; exit 2; }
  commands="$root/config/commands/terrain_$robot.yaml"
  [ -f "$commands" ] || commands="$root/config/commands/$robot.yaml"
  # NAME|ARGS: a terrain and how the run sees it.
  runs=("flat|--terrain flat" "step_up_down|--terrain step_up_down")
  for f in "$root"/config/terrain/*_"$robot".yaml; do
    [ -f "$f" ] || continue
    t=$(basename "$f" .yaml)
    case "$t" in
      rough_blind_*) runs+=("$t|--terrain $t --map-rate 0") ;;
      rough_*) # A robot with a blind rough terrain of its own walks this one on the map.
        if [ -f "$root/config/terrain/rough_blind_$robot.yaml" ]; then
          runs+=("$t|--terrain $t")
        else
          runs+=("$t|--terrain $t --map-rate 0")
        fi ;;
      *) runs+=("$t|--terrain $t") ;;
    esac
  done
  runs+=("ground +5 cm|--ground 0.05 --map-rate 0" "ground -5 cm|--ground -0.05 --map-rate 0")
  rows=()
  for run in "${runs[@]}"; do
    t=${run%%|*}
    read -r -a args <<< "${run#*|}"
    key=$(printf '%s' "$t" | tr -c 'A-Za-z0-9_+-' '_')
    json="$out/${robot}_$key.json"
    status=0
    "$build/tools/stride-drive" --config "$config" --commands "$commands" "${dirs[@]}" \
      "${args[@]}" --summary "$json" > "$out/${robot}_$key.txt" 2>&1 || status=$?
    # 4: the robot fell (a row of the table, not a failure of the tool).
    if [ "$status" != 0 ] && [ "$status" != 4 ]; then
      echo "terrains.sh: stride-drive failed on $robot / $t (exit $status;" \
        "$out/${robot}_$key.txt)" >&2
      exit 1
    fi
    map=map
    [[ " ${args[*]} " == *" --map-rate 0 "* ]] && map=blind
    row=$(python3 - "$json" "$robot" "$t" "$map" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
fell = ("diverged" if j.get("diverged") else "fell") + " at %.1f s" % j["duration_s"] if j["fell"] else "no"
moving = [s for s in j["segments"] if s["achieved"] and abs(s["command"][0]) > 0]
speed = "-"
if moving:
    s = max(moving, key=lambda s: s["t1"] - s["t0"])
    speed = "%.3f / %.2f" % (s["achieved"][0], s["command"][0])
print("| %s | %s | %s | %s | %.2f | %s | %d | %d / %d | %s |" % (sys.argv[2], sys.argv[3],
      sys.argv[4], fell, j["final_base"][0], speed, j["trips"], j["edge_footholds"],
      j["footholds"], "yes" if j["tracked"] else "no"))
PY
)
    echo "$row"
    rows+=("$json")
  done
  python3 - "$out/terrains_$robot.json" "${rows[@]}" <<'PY'
import json, os, sys
runs = {os.path.basename(p)[:-5]: json.load(open(p)) for p in sys.argv[2:]}
json.dump(runs, open(sys.argv[1], "w"), indent=1)
PY
done
