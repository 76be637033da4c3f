#!/usr/bin/env bash
# The paper's snapshot figures end to end (issue 18): short runs of both experiments through their
# own scripts (tools/paper/astronaut.sh, large-stride.sh: the programs write their motions as LCM
# logs, stride-viz plays them in headless Chromium, snapshots.py composes the frames), then
# snapshots_check.mjs reads the logs itself and checks what the page showed at every frame: the
# state stamped at the frame's time, its joint angles (within 1e-6), the astronaut's locked joints
# at their default angles, stride_humanoid's model hash, the strides' planned forces. The figures
# must exist and not be blank (snapshots.py refuses a blank frame or figure).
#   snapshots_test.sh ROOT BUILD_DIR NODE
# Exit 77 (skipped) when there is no Chromium (tools/install-deps.sh installs Debian's).
set -euo pipefail
root=$1 build=$2 node=$3
chromium=${CHROMIUM:-/usr/bin/chromium}
if [ ! -x "$chromium" ]; then
  echo "paper_snapshots: no Chromium at $chromium (apt-get install chromium): skipped"
  exit 77
fi
for f in "$build/viz/stride-viz" "$build/tools/paper/stride-paper-astronaut" \
         "$build/tools/paper/stride-paper-large-stride" "$build/viz/web/dist/index.html" \
         "$build/viz/web/npm/node_modules/playwright-core"; do
  [ -e "$f" ] || { echo "paper_snapshots: $f missing (build first)" >&2; exit 1; }
done
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
export STRIDE_BUILD_DIR="$build" CHROMIUM="$chromium" PATH="$(dirname "$node"):$PATH"

# The astronaut: 5 s of motion, one DDP solve (the figure needs a motion, not the 360°).
"$root/tools/paper/astronaut.sh" --out "$dir/astronaut" --knots 250 --waypoints 2 --window 0 \
  --window-step 0 --iterations 20 > "$dir/astronaut.txt" 2>&1 || { cat "$dir/astronaut.txt"; exit 1; }
# One 100 cm stride, a few DDP iterations, no mock robot.
"$root/tools/paper/large-stride.sh" --out "$dir/strides" --lengths 1.0 --strides 1 \
  --iterations 5 --no-sim > "$dir/strides.txt" 2>&1 || { cat "$dir/strides.txt"; exit 1; }
grep -h "snapshots" "$dir/astronaut.txt" "$dir/strides.txt"

fail=0
for png in "$dir/astronaut/astronaut_snapshots.png" "$dir/strides/large_stride_100_snapshots.png"; do
  [ -s "$png" ] || { echo "FAIL  no figure $png"; fail=1; }
  [ -s "${png%.png}.json" ] || { echo "FAIL  no ${png%.png}.json: the figure is not stride-viz's"; fail=1; }
done
[ "$fail" = 0 ] || exit 1
# stride_humanoid's model hash, as stride-sim prints it for the robot's own YAML.
hash=$("$build/sim/stride-sim" --robot "$root/config/robots/stride_humanoid/stride_humanoid.yaml" \
  --print-model | sed -n 's/.*model hash \([0-9a-f]\{16\}\).*/\1/p' | head -1)
[ -n "$hash" ] || { echo "FAIL  no model hash from stride-sim --print-model"; exit 1; }
"$node" "$root/tests/paper/snapshots_check.mjs" "$dir/astronaut/astronaut_snapshots.json" \
  --locked "$dir/astronaut/summary.json" --hash "$hash" || fail=1
"$node" "$root/tests/paper/snapshots_check.mjs" "$dir/strides/large_stride_100_snapshots.json" \
  --hash "$hash" --forces || fail=1
exit "$fail"
