#!/usr/bin/env bash
# Issue 33, in real time (tools/demo.sh in a private network namespace this test creates): with
# signing on, a second stride-mpc WITHOUT the key on the same channels changes nothing on the
# robot (every segment tracked, its policies refused unread, no controller switch); a second one
# WITH the key is the source rule's case (refused as a rival while the first speaks, no switch).
# Exit 77 only when namespaces are not permitted.
#   tests/controller/rival_signed.sh BUILD_DIR ROOT
set -euo pipefail
build=$1 root=$2
# shellcheck source=../private_netns.sh
source "$(dirname "$0")/../private_netns.sh"
private_netns "$@"
export LCM_DEFAULT_URL='udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304'
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
printf -- '- {at: 0.0, gait: stand}\n- {at: 1.0, gait: trot}\n- {at: 2.0, vx: 0.5}\n- {at: 5.0, vx: 0.0, yaw_rate: 0.5}\n' \
  > "$dir/drive.yaml"
for rival in --rival --rival-key; do
  status=0
  STRIDE_DEMO_INSIDE=1 STRIDE_BUILD_DIR="$build" timeout 150 "$root/tools/demo.sh" \
    --robot stride_quad --realtime --commands "$dir/drive.yaml" --duration 8 --check-tracking \
    "$rival" --out "$dir/demo$rival" > "$dir/demo$rival.txt" 2>&1 || status=$?
  cat "$dir/demo$rival.txt"
  python3 - "$dir/demo$rival" "$rival" "$status" <<'PY'
import json, os, sys
d, rival, status = sys.argv[1], sys.argv[2], int(sys.argv[3])
s = json.load(open(os.path.join(d, "summary.json")))
sim = json.load(open(os.path.join(d, "sim.json")))
assert status == 0, "tools/demo.sh exited %d (0: no fall, every segment tracked)" % status
assert not s["fell"] and s["tracked"], "the robot fell or missed a segment"
assert sim["source_switches"] == 0, "the robot switched to the rival"
if rival == "--rival":
    assert sim["policies_unauthenticated"] > 100, sim["policies_unauthenticated"]
    assert sim["policies_rival"] == 0, sim["policies_rival"]
    what = "%d of its policies refused unread" % sim["policies_unauthenticated"]
else:
    assert sim["policies_rival"] > 100, sim["policies_rival"]
    assert sim["policies_unauthenticated"] == 0, sim["policies_unauthenticated"]
    what = "%d of its policies refused by the source rule" % sim["policies_rival"]
print("PASS %s: every segment tracked, no switch, %s" % (rival, what))
PY
done
