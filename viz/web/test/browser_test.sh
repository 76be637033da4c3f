#!/usr/bin/env bash
# stride-viz's page in headless Chromium on a fresh log (viz/web/README.md, "Test"): stride-drive
# drives the quadruped for 3 s in one process and logs every channel, terrain_log.mjs adds
# elevation maps of a made-up world around the robot (STRIDE_TERRAIN, 10 Hz) and gives the
# horizons' chosen footholds every source in turn, then browser_test.mjs
# runs `stride-viz --log` on it and checks the page against its own reading of the log.
#   browser_test.sh STRIDE_VIZ STRIDE_DRIVE CONFIG_DIR NODE NODE_MODULES OUT_DIR
# Exit 77 (skipped) when there is no Chromium (tools/install-deps.sh installs Debian's).
set -euo pipefail
viz=$1 drive=$2 config=$3 node=$4 modules=$5 out=$6
chromium=${CHROMIUM:-/usr/bin/chromium}
if [ ! -x "$chromium" ]; then
  echo "browser_test: no Chromium at $chromium (apt-get install chromium): skipped"
  exit 77
fi
if [ ! -d "$modules/playwright-core" ]; then
  echo "browser_test: no playwright-core in $modules (build the stride-viz-web target first)" >&2
  exit 1
fi
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
"$drive" --config "$config/controller/stride_quad.yaml" \
  --commands "$config/commands/stride_quad.yaml" --duration "${STRIDE_VIZ_LOG_DURATION:-3}" \
  --log "$dir/session.lcmlog" \
  > "$dir/drive.txt" || { cat "$dir/drive.txt"; exit 1; }
"$node" "$(dirname "$0")/terrain_log.mjs" "$dir/session.lcmlog" "$dir/terrain.lcmlog"
mkdir -p "$out"
STRIDE_VIZ_NODE_MODULES="$modules" CHROMIUM="$chromium" \
  "$node" "$(dirname "$0")/browser_test.mjs" "$viz" "$dir/terrain.lcmlog" "$out"
