#!/usr/bin/env bash
# tools/demo.sh --terrain (issue 30), lock-step in the demo's own private namespace: anymal_c on its
# stairs. Checks the plumbing, not the climb (a blind controller may fall here; issue 31): the
# mock robot walked on the named terrain, its elevation maps are in the session's log, and the
# summary has the terrain, the final base, the trips, the footholds near edges and the base's
# height above the terrain.
# An unknown terrain is a usage error that lists the shipped ones.
#   demo_terrain.sh BUILD_DIR ROOT
set -euo pipefail
build=$1 root=$2
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
export STRIDE_DEMO_NO_SETUP=1 STRIDE_BUILD_DIR=$build

status=0
"$root/tools/demo.sh" --terrain no_such_terrain > "$dir/bad.txt" 2>&1 || status=$?
cat "$dir/bad.txt"
[ "$status" = 2 ] && grep -q "no terrain 'no_such_terrain'" "$dir/bad.txt" &&
  grep -q "stairs_anymal_c" "$dir/bad.txt" || { echo "FAIL: an unknown terrain is not a usage error"; exit 1; }

status=0
"$root/tools/demo.sh" --robot anymal_c --terrain stairs_anymal_c --lockstep --duration 6 \
  --out "$dir/demo" > "$dir/demo.txt" 2>&1 || status=$?
cat "$dir/demo.txt"
if [ "$status" = 1 ] && grep -q "cannot create a network namespace" "$dir/demo.txt"; then
  exit 77  # no namespaces here (ctest: skipped)
fi
# 0 (walked, even if segments missed their commands: no --check-tracking) or 4 (fell).
[ "$status" = 0 ] || [ "$status" = 4 ] || { echo "FAIL: demo.sh exited $status"; exit 1; }
grep -q "terrain 'stairs_anymal_c'" "$dir/demo/sim.txt" || { echo "FAIL: the sim's terrain"; exit 1; }
python3 - "$dir/demo/summary.json" "$dir/demo/sim.json" <<'PY'
import json, math, sys
s = json.load(open(sys.argv[1]))
sim = json.load(open(sys.argv[2]))
def check(ok, what):
    if not ok:
        print("FAIL:", what, json.dumps(s, indent=1)[:2000])
        sys.exit(1)
check(s["terrain"] == "stairs_anymal_c", "summary terrain")
fb = s["final_base"]
check(isinstance(fb, list) and len(fb) == 3 and all(math.isfinite(x) for x in fb), "final_base")
check(abs(fb[0] - sim["final_base"][0]) < 0.05, "final_base agrees with the sim's")
check(isinstance(s["trips"], int) and s["trips"] == sim["trips"], "trips from the sim")
# The feet's touch-downs near the stairs' edges (sim/README.md, "Footholds near edges").
check(isinstance(sim["footholds"], int) and sim["footholds"] >= 4, "the sim's footholds")
check(isinstance(sim["edge_footholds"], int) and 0 <= sim["edge_footholds"] <= sim["footholds"],
      "the sim's edge footholds")
check(sim["min_edge_distance_m"] is None or sim["min_edge_distance_m"] >= 0.0,
      "the sim's nearest edge")
for key in ("footholds", "edge_footholds", "min_edge_distance_m"):
    check(s[key] == sim[key], key + " from the sim")
check(s["terrain_maps"] >= 10, "elevation maps in the log (10 Hz)")
# The robot walked towards the stairs (1.5 m ahead, 17 cm steps): a 2 m map around it shows some.
check(s["terrain_map_top_m"] is not None and s["terrain_map_top_m"] >= 0.169, "the maps show the stairs")
above = s["base_height_above_terrain_m"]
check(abs(above - sim["base_height_above_terrain_m"]) < 0.05, "height above the terrain")
check(s["fell"] == sim["fell"], "the summary's fall is the sim's")
print("summary OK: final base", fb, "above terrain %.3f" % above, "trips", s["trips"],
      "edge footholds", s["edge_footholds"], "of", s["footholds"], "maps", s["terrain_maps"],
      "fell", s["fell"])
PY
