#!/usr/bin/env bash
# Every shipped terrain a robot has (config/terrain/*_ROBOT.yaml, plus flat and step_up_down),
# driven with the robot's default command script by stride-drive (lock-step, deterministic;
# tools/drive/README.md): did it fall, and when; how far it got along x; its feet's trips on
# vertical faces; its touch-downs closer than 2 cm to an edge of the true terrain, of all its
# touch-downs; did it track every segment. Prints one markdown row per run; writes
# DIR/terrains_ROBOT.json.
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
echo "| robot | terrain | fell | distance x [m] | final base z above terrain [m] | trips | edge footholds | tracked |"
echo "| --- | --- | --- | --- | --- | --- | --- | --- |"
for robot in "${robots[@]}"; do
  config="$root/config/controller/$robot.yaml"
  [ -f "$config" ] || { echo "terrains.sh: no robot '$robot'" >&2; exit 2; }
  terrains=(flat step_up_down)
  for f in "$root"/config/terrain/*_"$robot".yaml; do
    [ -f "$f" ] && terrains+=("$(basename "$f" .yaml)")
  done
  rows=()
  for t in "${terrains[@]}"; do
    json="$out/${robot}_$t.json"
    "$build/tools/stride-drive" --config "$config" --commands "$root/config/commands/$robot.yaml" \
      "${dirs[@]}" --terrain "$t" --summary "$json" > "$out/${robot}_$t.txt" 2>&1 || {
      echo "terrains.sh: stride-drive failed on $robot / $t ($out/${robot}_$t.txt)" >&2
      exit 1
    }
    row=$(python3 - "$json" "$robot" "$t" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
fell = ("diverged" if j.get("diverged") else "fell") + " at %.1f s" % j["duration_s"] if j["fell"] else "no"
print("| %s | %s | %s | %.2f | %.3f | %d | %d / %d | %s |" % (sys.argv[2], sys.argv[3], fell,
      j["final_base"][0], j["base_height_above_terrain_m"], j["trips"], j["edge_footholds"],
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
