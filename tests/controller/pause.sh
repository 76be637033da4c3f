#!/usr/bin/env bash
# Issue 33: a controller stopped by the host (SIGSTOP for 1.5 s in the middle of a trot, then
# SIGCONT: a host stall, swapping, a debugger) drives again. tools/demo.sh in real time, in a
# private network namespace this test creates, signing on: no fall, and control came back (every
# segment starting 2 s after the wake-up tracked; stride-log-summary --fault-end-wall) with its
# command tracked within 2 s of waking. Exit 77 only when namespaces are not permitted.
#   tests/controller/pause.sh BUILD_DIR ROOT
set -euo pipefail
build=$1 root=$2
# shellcheck source=../private_netns.sh
source "$(dirname "$0")/../private_netns.sh"
private_netns "$@"
export LCM_DEFAULT_URL='udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304'
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
# Trot forward; stopped at 3.5 s for 1.5 s; a turn from 2.5 s after waking, then forward again.
printf -- '- {at: 0.0, gait: stand}\n- {at: 1.0, gait: trot}\n- {at: 2.0, vx: 0.5}\n- {at: 7.5, vx: 0.0, yaw_rate: 0.5}\n- {at: 10.5, vx: 0.5, yaw_rate: 0.0}\n' \
  > "$dir/drive.yaml"
status=0
STRIDE_DEMO_INSIDE=1 STRIDE_BUILD_DIR="$build" timeout 150 "$root/tools/demo.sh" \
  --robot stride_quad --realtime --commands "$dir/drive.yaml" --duration 13.5 \
  --pause-controller 3.5 1.5 --out "$dir/demo" > "$dir/demo.txt" 2>&1 || status=$?
cat "$dir/demo.txt"
python3 - "$dir/demo/summary.json" "$status" <<'PY'
import json, sys
s, status = json.load(open(sys.argv[1])), int(sys.argv[2])
r = s.get("recovery")
assert not s["fell"], "the robot fell"
assert r is not None, "the pause did not end in the run: recovery not judged"
assert r["segments_after"] >= 1, r
assert r["recovered"], "control did not come back: %s" % r
assert r["time_to_tracking_s"] is not None and r["time_to_tracking_s"] <= 2.0, r
assert status == 0, "tools/demo.sh exited %d" % status
print("PASS: stopped 1.5 s; %d of %d segments after it tracked, its command tracked %.2f s after "
      "waking" % (r["segments_after"] - r["missed_after"], r["segments_after"], r["time_to_tracking_s"]))
PY
