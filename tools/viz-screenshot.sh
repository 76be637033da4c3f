#!/usr/bin/env bash
# Regenerates viz/screenshot.png, the README's picture of the browser viewer: the browser test
# (viz/web/test/browser_test.sh, headless Chromium) on a 5 s drive of the in-house quadruped,
# whose screenshot at mid-log (trotting forward) is copied into the source tree. The test's checks
# run too: a page that shows the wrong joint angles makes no picture.
#   tools/viz-screenshot.sh
set -euo pipefail
case "${1:-}" in
  -h|--help) sed -n '2,/^set -euo/{/^#/p}' "$0"; exit 0 ;;
  "") ;;
  *) echo "viz-screenshot.sh: no arguments (--help)" >&2; exit 2 ;;
esac
root=$(cd "$(dirname "$0")/.." && pwd)
build="${STRIDE_BUILD_DIR:-$root/build}"
modules="$build/viz/web/npm/node_modules"
[ -x "$build/viz/stride-viz" ] && [ -d "$modules/playwright-core" ] || "$root/tools/build.sh"
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
STRIDE_VIZ_LOG_DURATION=5 "$root/viz/web/test/browser_test.sh" "$build/viz/stride-viz" \
  "$build/tools/stride-drive" "$root/config" "$(command -v node)" "$modules" "$out"
cp "$out/viewer.png" "$root/viz/screenshot.png"
echo "viz-screenshot.sh: wrote viz/screenshot.png"
