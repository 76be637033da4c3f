#!/usr/bin/env bash
# The wire contract live (issue 17): an ANYmal C controller fed by a Solo-12 mock robot. Both have
# nq 19 and nv 18, so only the model hash tells them apart. Two real-time processes over LCM UDP
# multicast in a private network namespace this test creates (only lo, ttl=0), lcm-logger on.
# The controller must refuse every state, say once what it expected and what came, publish its
# robot_model_t, and exit 1 ("accepted none"); the robot gets no policy and stays on its hold PD.
# Exit 77 (ctest: skipped) only when namespaces are not permitted.
#   wrong_robot.sh BUILD_DIR CONFIG_DIR ROBOT_PACKAGES
set -euo pipefail
build=$1 config=$2 packages=$3
# shellcheck source=../private_netns.sh
source "$(dirname "$0")/../private_netns.sh"
private_netns "$@"
export LCM_DEFAULT_URL='udpm://239.255.76.67:7667?ttl=0'
dir=$(mktemp -d)
pids=()
trap 'for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done; wait 2>/dev/null || true; rm -rf "$dir"' EXIT

timeout 60 lcm-logger --quiet "$dir/session.lcmlog" &
pids+=($!)
timeout 60 "$build/controller/stride-mpc" --config "$config/controller/anymal_c.yaml" \
  --robots-dir "$packages" --duration 3 > "$dir/mpc.out" 2> "$dir/mpc.err" &
mpc=$!
pids+=($mpc)
sleep 0.5
sim_rc=0
timeout 60 "$build/sim/stride-sim" --robot "$config/robots/solo12/solo12.yaml" \
  --robots-dir "$packages" --duration 2 > "$dir/sim.out" 2>&1 || sim_rc=$?
mpc_rc=0
wait "$mpc" || mpc_rc=$?
cat "$dir/mpc.out" "$dir/mpc.err" "$dir/sim.out"

hash_of() {  # the model hash --print-model shows
  "$build/controller/stride-mpc" --config "$1" --robots-dir "$packages" --print-model |
    sed -n 's/^model hash \([0-9a-f]*\) .*/\1/p'
}
anymal=$(hash_of "$config/controller/anymal_c.yaml")
solo=$(hash_of "$config/controller/solo12.yaml")
[ -n "$anymal" ] && [ -n "$solo" ] && [ "$anymal" != "$solo" ] || {
  echo "FAIL: --print-model's hashes: anymal_c '$anymal', solo12 '$solo'"; exit 1; }

fail=0
[ "$mpc_rc" -eq 1 ] || { echo "FAIL: stride-mpc exited $mpc_rc, expected 1"; fail=1; }
expected="stride-mpc: refused a state on 'STRIDE_STATE': expected hash $anymal (anymal_c, nq 19, nv 18), got hash $solo: the same sizes, another robot or joint order"
grep -qF "$expected" "$dir/mpc.err" || { echo "FAIL: no line '$expected'"; fail=1; }
[ "$(grep -c 'refused a state' "$dir/mpc.err")" -eq 1 ] || { echo "FAIL: the cause must be said once"; fail=1; }
grep -qE "stride-mpc: the run accepted none of the [0-9]+ states on 'STRIDE_STATE': [0-9]+ another robot's model \(hash or sizes\); the model expects nq 19, nv 18 \(anymal_c, hash $anymal\)" \
  "$dir/mpc.err" || { echo "FAIL: no 'accepted none' summary"; fail=1; }
# The robot got no policy: it stood on its hold PD, and exits 0 (upright).
[ "$sim_rc" -eq 0 ] || { echo "FAIL: stride-sim exited $sim_rc"; fail=1; }
grep -q ' 0 policies (0 rejected, ' "$dir/sim.out" || { echo "FAIL: the robot should have had no policy"; fail=1; }
# The controller's model is on the bus (and in the log) for a robot or lcm-spy to check.
kill -INT "${pids[0]}" 2>/dev/null || true
sleep 0.3
grep -qa STRIDE_MODEL "$dir/session.lcmlog" || { echo "FAIL: no STRIDE_MODEL in the log"; fail=1; }
[ "$fail" -eq 0 ] && echo "PASS: the wrong robot was refused, said once, exit 1"
exit "$fail"
