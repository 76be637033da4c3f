#!/usr/bin/env bash
# tools/drive/sweep.sh --config FILE (issue 34): a controller configuration outside config/, its
# robot beside it by a relative path (relative to the YAML's folder, and not where the shipped
# layout would find another: the sweep must resolve it from the file's own folder), swept at one
# speed (--no-push --speed-step 0.5 --max-speed 0.5: one 14 s lock-step drive). The input folder
# stays byte-identical (sha256 of every file, nothing added), the sweep's JSON exists and names
# the configuration. A path disguised as a robot's name (which once made sweep.sh write its
# temporary copy over the user's file) is a usage error that leaves the file alone.
#   sweep_config.sh BUILD_DIR ROOT
set -euo pipefail
build=$1 root=$2
export STRIDE_BUILD_DIR=$build
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT

# The user's files: ctrl/my_quad.yaml, its robot in ctrl/robot/ (another file name than the
# shipped one).
mkdir -p "$dir/user/ctrl/robot"
cp "$root/config/robots/stride_quad/stride_quad.urdf" "$dir/user/ctrl/robot/"
cp "$root/config/robots/stride_quad/stride_quad.yaml" "$dir/user/ctrl/robot/quad.yaml"
sed 's|^robot: .*|robot: robot/quad.yaml   # beside this file|' \
  "$root/config/controller/stride_quad.yaml" > "$dir/user/ctrl/my_quad.yaml"
grep -q '^robot: robot/quad.yaml' "$dir/user/ctrl/my_quad.yaml" || { echo "FAIL: test setup"; exit 1; }
listing() { (cd "$dir/user" && find . -printf '%p %s %m\n' | sort && find . -type f -print0 | sort -z | xargs -0 sha256sum); }
listing > "$dir/before.txt"
sha256sum "$dir/user/ctrl/my_quad.yaml"

# A path disguised as a name: refused before anything is written.
name_path="../../../..$dir/user/ctrl/my_quad"  # as the user of issue 34 passed it
status=0
"$root/tools/drive/sweep.sh" "$name_path" --no-push --out "$dir/out-bad" > "$dir/bad.txt" 2>&1 ||
  status=$?
cat "$dir/bad.txt"
[ "$status" = 2 ] && grep -q "no shipped robot" "$dir/bad.txt" ||
  { echo "FAIL: a path as the robot's name exited $status, not a usage error (2)"; exit 1; }

status=0
"$root/tools/drive/sweep.sh" --config "$dir/user/ctrl/my_quad.yaml" --no-push --speed-step 0.5 \
  --max-speed 0.5 --out "$dir/out" || status=$?
[ "$status" = 0 ] || { echo "FAIL: sweep.sh --config exited $status"; exit 1; }

sha256sum "$dir/user/ctrl/my_quad.yaml"
listing | diff "$dir/before.txt" - || { echo "FAIL: the sweep changed the input folder (above)"; exit 1; }
[ -s "$dir/out/sweep_my_quad.json" ] || { echo "FAIL: no $dir/out/sweep_my_quad.json"; ls -la "$dir/out"; exit 1; }
cat "$dir/out/sweep_my_quad.json"
python3 - "$dir/out/sweep_my_quad.json" "$dir/user/ctrl/my_quad.yaml" <<'PY'
import json, os, sys
s = json.load(open(sys.argv[1]))
assert s["robot"] == "my_quad", s
assert os.path.realpath(s["config"]) == os.path.realpath(sys.argv[2]), s
assert s["max_speed_mps"] == 0.5 and s["max_lateral_push_Ns"] is None, s
assert s["top_speed_mps"] in (0.0, 0.5), s
PY
echo "sweep.sh --config: input unchanged, results in sweep_my_quad.json"
