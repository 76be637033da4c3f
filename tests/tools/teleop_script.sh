#!/usr/bin/env bash
# stride-teleop --commands as a real process over LCM UDP multicast, in a private network namespace
# this test creates (only lo, multicast routed to it, ttl=0): a test robot publishes states at
# 200 Hz of robot time, twice as fast as the wall clock, and moves exactly as the newest command
# says; lcm-logger records. Then the log must hold one command per 50 ms of state stamps, each
# stamped with a state's utime and equal to the script's entry in force then, and
# stride-log-summary must find one segment per entry, each tracked. Also the usage errors (exit 2).
# Exit 77 (ctest: skipped) only when namespaces are not permitted.
#   teleop_script.sh STRIDE_TELEOP STRIDE_LOG_SUMMARY COMMAND_ROBOT
set -euo pipefail
teleop=$1 summary=$2 robot=$3
# shellcheck source=../private_netns.sh
source "$(dirname "$0")/../private_netns.sh"
private_netns "$@"
dir=$(mktemp -d)
pids=()
trap 'for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done; wait 2>/dev/null || true; rm -rf "$dir"' EXIT

# Usage errors first (no LCM traffic: they stop before opening LCM), each exit 2 with its reason.
expect_usage_error() {  # expected-message command...
  local want=$1 status=0
  shift
  "$@" > "$dir/err.txt" 2>&1 < /dev/null || status=$?
  if [ "$status" != 2 ] || ! grep -q -- "$want" "$dir/err.txt"; then
    echo "FAIL: '$*' exited $status (expected 2 and '$want'):"
    cat "$dir/err.txt"
    exit 1
  fi
}
printf -- '- {at: 0.0, gait: stand}\n- {at: 1.0, vx: fast}\n' > "$dir/bad.yaml"
printf -- '- {at: 0.0, gait: trot}\n' > "$dir/trot.yaml"
(
  unset LCM_DEFAULT_URL
  expect_usage_error "no LCM URL" "$teleop" --commands "$dir/trot.yaml"
)
expect_usage_error "bad.yaml': entry 1: vx must be a number" \
  "$teleop" --url memq:// --commands "$dir/bad.yaml"
expect_usage_error "entry 0 (at 0 s): gait 'trot': a biped (--gaits biped) walks with stand, walk, hop only" \
  "$teleop" --url memq:// --commands "$dir/trot.yaml" --gaits biped
expect_usage_error "stdin is not a terminal" "$teleop" --url memq://
expect_usage_error "rate" "$teleop" --url memq:// --rate 0

export LCM_DEFAULT_URL='udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304'
cat > "$dir/script.yaml" <<'EOF'
- {at: 0.0, gait: stand}
- {at: 1.0, gait: trot, vx: 0.3}
- {at: 2.5, yaw_rate: 0.8}
- {at: 3.5, vx: 0.0, vy: 0.2, yaw_rate: 0.0, body_height: 0.02}
EOF
duration=4.5  # the last entry + the 1 s hold

timeout 60 lcm-logger --quiet "$dir/session.lcmlog" &
logger_pid=$!
pids+=($logger_pid)
timeout 60 "$teleop" --commands "$dir/script.yaml" --duration "$duration" > "$dir/teleop.txt" 2>&1 &
teleop_pid=$!
pids+=($teleop_pid)
# The robot starts once the teleop listens (its first subscribe may take a while over udpm).
for _ in $(seq 100); do
  grep -q "waiting for states" "$dir/teleop.txt" && break
  sleep 0.1
done
sleep 0.3
timeout 60 "$robot" run --duration 5 --rate 200 --speed 2 > "$dir/robot.txt" 2>&1
status=0
wait "$teleop_pid" || status=$?
# Stop the logger before reading the log: it writes its last events on the way out.
sleep 0.3
kill -INT "$logger_pid"
wait "$logger_pid" || true
cat "$dir/teleop.txt" "$dir/robot.txt"
[ "$status" = 0 ] || { echo "FAIL: stride-teleop exited $status"; exit 1; }
grep -q "stopped at t = 4.500 s of robot time (--duration): 90 commands sent" "$dir/teleop.txt" || {
  echo "FAIL: stride-teleop did not stop at the duration after 90 commands"
  exit 1
}
[ "$(grep -c ' entry [0-9] (at [0-9.]* s): ' "$dir/teleop.txt")" = 4 ] || {
  echo "FAIL: stride-teleop did not print each of the 4 entries when it started"
  exit 1
}
"$robot" check "$dir/session.lcmlog" "$dir/script.yaml" --rate 20 --duration "$duration"
# The entries last 1-1.5 s: average from 0.2 s after each start, check them all.
"$summary" "$dir/session.lcmlog" --summary "$dir/summary.json" --check-tracking --settle 0.2 \
  --min-segment 0.5 | tee "$dir/log-summary.txt"
segments=$(grep -c '"t0"' "$dir/summary.json")
[ "$segments" = 4 ] || { echo "FAIL: $segments segments, expected one per script entry (4)"; exit 1; }
grep -q "tracking: every segment tracked its command (4 of 4" "$dir/log-summary.txt" || {
  echo "FAIL: not every segment was checked and tracked"
  exit 1
}
echo "PASS: stride-teleop --commands over udpm in a private namespace, one segment per entry"
