#!/usr/bin/env bash
# tools/demo.sh --viz end to end (issue 18): inside a private network namespace this test creates
# (standing in for the host), the demo makes its own namespace for the closed loop and the viewer,
# and forwards the viewer's port to this one's loopback through a Unix socket (socat pair). The
# page and the viewer's counters must answer on 127.0.0.1 while the robot runs, with the robot's
# states arriving, and the demo must end cleanly (no forward left behind).
# Exit 77 (ctest: skipped) only when namespaces are not permitted.
#   demo_viz.sh BUILD_DIR ROOT
set -euo pipefail
build=$1 root=$2
# Under the sanitizers (tools/test.sh --sanitize) the loop runs 15-20x slower: the guards scale.
scale=${STRIDE_TEST_TIME_SCALE:-1}
# shellcheck source=../private_netns.sh
source "$(dirname "$0")/../private_netns.sh"
private_netns "$@"
dir=$(mktemp -d)
port=18765
trap 'kill $demo 2>/dev/null || true; wait 2>/dev/null || true; rm -rf "$dir"' EXIT
# A trot at 0.3 m/s: what this test checks is the viewer's forward, not the walk (the walks are
# the closed-loop tests').
printf -- '- {at: 0.0, gait: stand}\n- {at: 1.0, gait: trot, vx: 0.3}\n' > "$dir/drive.yaml"
STRIDE_DEMO_NO_SETUP=1 STRIDE_BUILD_DIR="$build" timeout $((150 * scale)) "$root/tools/demo.sh" --viz \
  --viz-port "$port" --lockstep --commands "$dir/drive.yaml" --duration 8 --out "$dir/demo" \
  > "$dir/demo.txt" 2>&1 &
demo=$!
code=000
for _ in $(seq 1 120); do
  code=$(curl -s -o "$dir/page.html" -w '%{http_code}' "http://127.0.0.1:$port/" || true)
  [ "$code" = 200 ] && break
  kill -0 "$demo" 2>/dev/null || break
  sleep 0.5
done
fail=0
[ "$code" = 200 ] || { echo "FAIL: the page did not answer through the forward (HTTP $code)"; fail=1; }
grep -q '<script' "$dir/page.html" 2>/dev/null || { echo "FAIL: not the viewer's page"; fail=1; }
sleep 2
curl -s "http://127.0.0.1:$port/api/info" > "$dir/info.json" || true
python3 - "$dir/info.json" <<'PY' || fail=1
import json, sys
info = json.load(open(sys.argv[1]))
n = info["messages"]["channels"]["STRIDE_STATE"]["accepted"]
print(f"stride-viz through the forward: {n} states accepted, mode {info['mode']}")
sys.exit(0 if info["mode"] == "live" and n > 0 else 1)
PY
status=0
wait "$demo" || status=$?
cat "$dir/demo.txt" | grep -E '^demo:|viewer|^stride-viz' || true
[ "$status" = 0 ] || { echo "FAIL: tools/demo.sh exited $status"; cat "$dir/demo.txt"; fail=1; }
if pgrep -f "TCP-LISTEN:$port" > /dev/null; then echo "FAIL: the forward outlived the demo"; fail=1; fi
[ "$fail" = 0 ] && echo "PASS: demo.sh --viz served the live viewer on this namespace's loopback"
exit "$fail"
