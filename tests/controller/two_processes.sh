#!/usr/bin/env bash
# The closed loop as two processes over LCM UDP multicast, in a private network namespace this test
# creates (only lo, multicast routed to it, ttl=0): stride-sim --lockstep and stride-mpc --lockstep,
# with lcm-logger recording, no commands; then the log must show a quadruped that stood (the
# deadman's stand) without falling, every tick answered. Then the demo's drive, tools/demo.sh itself in this namespace: stride-teleop plays
# a command script (stand 1 s, trot forward at 0.3 m/s for 5 s) in lock-step, and
# `stride-log-summary --check-tracking` (demo.sh --check-tracking) must find the trot tracked.
# Exit 77 (ctest: skipped) only when namespaces are not permitted.
#   two_processes.sh BUILD_DIR CONFIG_DIR
set -euo pipefail
build=$1 config=$2
# Under the sanitizers (tools/test.sh --sanitize) the loop runs 15-20x slower: the guards scale.
scale=${STRIDE_TEST_TIME_SCALE:-1}
# shellcheck source=../private_netns.sh
source "$(dirname "$0")/../private_netns.sh"
private_netns "$@"
export LCM_DEFAULT_URL='udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304'
dir=$(mktemp -d)
pids=()
trap 'for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done; wait 2>/dev/null || true; rm -rf "$dir"' EXIT

timeout $((120 * scale)) lcm-logger --quiet "$dir/session.lcmlog" &
logger=$!
pids+=($logger)
# No command source here: the controller's deadman keeps the robot standing.
sed -e "s|^robot: .*|robot: $config/robots/stride_quad/stride_quad.yaml|" \
  "$config/controller/stride_quad.yaml" > "$dir/quad.yaml"
timeout $((120 * scale)) "$build/controller/stride-mpc" --config "$dir/quad.yaml" --lockstep > "$dir/mpc.txt" 2>&1 &
mpc=$!
pids+=($mpc)
sleep 0.5
timeout $((120 * scale)) "$build/sim/stride-sim" --robot "$config/robots/stride_quad/stride_quad.yaml" \
  --lockstep --rate 200 --duration 3 --summary "$dir/sim.json" > "$dir/sim.txt" 2>&1
kill -TERM "$mpc"
wait "$mpc" || true
sleep 0.3
cat "$dir/mpc.txt" "$dir/sim.txt"
"$build/tools/stride-log-summary" "$dir/session.lcmlog" --summary "$dir/summary.json" \
  --windows 0.2 | tee "$dir/log-summary.txt"
cat "$dir/summary.json"
# The per-window lines (--windows; windows of the log's wall-clock stamps, and lock-step runs 3 s
# of robot time in about 1 s) account for every tick with a policy and every miss.
answered=$(sed -n 's/^solver: [0-9]* of \([0-9]*\) ticks.*/\1/p' "$dir/log-summary.txt")
misses=$(sed -n 's/.*"deadline_misses": \([0-9]*\).*/\1/p' "$dir/summary.json")
read -r windows window_ticks window_misses < <(awk '/^by 0.2 s window/ { on = 1; next }
  on && NF == 9 { n++; t += $2; m += $3 } END { print n + 0, t + 0, m + 0 }' "$dir/log-summary.txt")
[ "$windows" -ge 2 ] && [ "$window_ticks" = "$answered" ] && [ "$window_misses" = "$misses" ] || {
  echo "FAIL: $windows windows with $window_ticks ticks, $window_misses misses; the log has $answered, $misses"
  exit 1
}
grep -q '"fell": false' "$dir/summary.json" || { echo "FAIL: the robot fell"; exit 1; }
grep -q '"lockstep_timeouts": 0' "$dir/sim.json" || { echo "FAIL: unanswered states"; exit 1; }
ticks=$(sed -n 's/.*"ticks": \([0-9]*\).*/\1/p' "$dir/summary.json")
[ "$ticks" -ge 590 ] || { echo "FAIL: $ticks ticks logged, expected about 600"; exit 1; }
policies=$(sed -n 's/.*"policies": \([0-9]*\).*/\1/p' "$dir/sim.json")
[ "$policies" -ge 600 ] || { echo "FAIL: the sim received $policies policies"; exit 1; }
echo "PASS: two processes over udpm in a private namespace, $ticks ticks"
kill -INT "$logger"
wait "$logger" || true

# The demo's drive. STRIDE_DEMO_INSIDE tells demo.sh it already runs in its private namespace (this
# one): it skips the packages, the build and its own namespace, and checks that only lo is here.
printf -- '- {at: 0.0, gait: stand}\n- {at: 1.0, gait: trot, vx: 0.3}\n' > "$dir/drive.yaml"
status=0
STRIDE_DEMO_INSIDE=1 STRIDE_BUILD_DIR="$build" timeout $((120 * scale)) "$config/../tools/demo.sh" \
  --robot stride_quad --lockstep --commands "$dir/drive.yaml" --duration 4.5 --out "$dir/demo" \
  --check-tracking > "$dir/demo.txt" 2>&1 || status=$?
cat "$dir/demo.txt"
[ "$status" = 0 ] || { echo "FAIL: tools/demo.sh exited $status"; exit 1; }
grep -q '"fell": false' "$dir/demo/summary.json" || { echo "FAIL: the robot fell"; exit 1; }
segments=$(grep -c '"t0"' "$dir/demo/summary.json")
[ "$segments" = 2 ] || { echo "FAIL: $segments segments, expected 2 (stand, trot)"; exit 1; }
grep -q "tracking: every segment tracked its command (1 of 2 segments" "$dir/demo.txt" || {
  echo "FAIL: the trot segment was not checked and tracked"
  exit 1
}
echo "PASS: tools/demo.sh drove the quadruped with a command script, the trot at 0.3 m/s tracked"
