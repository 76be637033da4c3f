#!/usr/bin/env bash
# Issue 44, in real time (tools/faults.sh --forged-flood in a private network namespace this test
# creates): 60 kB frames claiming the run's key id, with fresh timestamps, a new sender each and a
# made-up mac, at 4000 per second on the state and policy channels for the whole run. Every
# receiver refuses them before hashing (a size no state or policy of the robot has): the robot
# does not fall, never stands down, and control is there after the flood's start (faults.sh's
# recovery). Before the cheap refusals, 4000/s for 5 s cost 4.4 s of stand-downs.
# Exit 77 only when namespaces are not permitted.
#   tests/controller/forged_flood.sh BUILD_DIR ROOT
set -euo pipefail
build=$1 root=$2
# shellcheck source=../private_netns.sh
source "$(dirname "$0")/../private_netns.sh"
private_netns "$@"
export LCM_DEFAULT_URL='udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304'
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
status=0
STRIDE_DEMO_INSIDE=1 STRIDE_BUILD_DIR="$build" "$root/tools/faults.sh" --robot stride_quad \
  --runs 1 --forged-flood 4000 --out "$dir" > "$dir/faults.txt" 2>&1 || status=$?
cat "$dir/faults.txt"
python3 - "$dir/run0" "$status" <<'PY'
import json, os, sys
d, status = sys.argv[1], int(sys.argv[2])
sim = json.load(open(os.path.join(d, "sim.json")))
mpc = json.load(open(os.path.join(d, "mpc.json")))
flood = open(os.path.join(d, "flood.txt")).read()
print(flood.strip())
assert "forged frames sent" in flood, "the flood did not run"
assert status == 0, "tools/faults.sh exited %d (0: no fall, control back)" % status
assert not sim["fell"], "the robot fell"
assert sim["stand_downs"] == 0, "%d stand-downs" % sim["stand_downs"]
u = mpc["unauthenticated"]
refused = u["impossible_size"] + sim["policies_unauthenticated"]
assert u["impossible_size"] > 1000, u
assert u["forged"] == 0, "hashed %d forged frames" % u["forged"]
print("PASS: no fall, no stand-down; the controller refused %d frames of an impossible size, the "
      "robot %d policies unread" % (u["impossible_size"], sim["policies_unauthenticated"]))
PY
