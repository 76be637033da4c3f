#!/usr/bin/env bash
# tools/robustness.sh spreads its cases over hosts with GNU parallel --sshloginfile: two hosts
# faked on this machine (tests/tools/fake_ssh.sh, each job in a network namespace of its own), one
# row of stride_quad's card (4 lock-step drives). Both hosts must have run cases, the card must
# show the row with a result per level, and --json must say the same.
#   robustness_hosts.sh BUILD_DIR
set -euo pipefail
build=$1
root=$(cd "$(dirname "$0")/../.." && pwd)
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
printf '1/host-a\n1/host-b\n' >"$dir/hosts"
STRIDE_BUILD_DIR="$build" "$root/tools/robustness.sh" stride_quad --only torque_latency_steps \
  --sshloginfile "$dir/hosts" --ssh "$root/tests/tools/fake_ssh.sh" --out "$dir/out" \
  --json "$dir/card.json" | tee "$dir/card.txt"
results="$dir/out/stride_quad/results.jsonl"
[ "$(wc -l <"$results")" = 4 ] || { echo "FAIL: expected 4 cases" >&2; exit 1; }
for h in host-a host-b; do
  grep -q "\"host\": \"$h\"" "$results" || { echo "FAIL: no case ran on $h" >&2; exit 1; }
done
grep -qE '^torque_latency_steps +1:(tracked|missed|fell) 2:' "$dir/card.txt" ||
  { echo "FAIL: the card has no torque_latency_steps row" >&2; exit 1; }
python3 - "$dir/card.json" <<'PY'
import json, sys
card = json.load(open(sys.argv[1]))
rows = {r["row"]: r for r in card["card"]}
levels = [c["level"] for c in rows["torque_latency_steps"]["levels"]]
assert levels == ["1", "2", "4", "8"], levels
assert all(c["result"] in ("tracked", "missed", "fell") for c in rows["torque_latency_steps"]["levels"])
print("robustness_hosts: OK,", [c["result"] for c in rows["torque_latency_steps"]["levels"]])
PY
