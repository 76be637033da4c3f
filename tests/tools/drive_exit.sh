#!/usr/bin/env bash
# stride-drive's exit status and summary (issue 34): 0 and the timing figures for a robot that stood;
# 4 for a fall, with or without --check-tracking; 1 for a missed command only with --check-tracking.
# Usage: drive_exit.sh STRIDE_DRIVE CONFIG_DIR
set -uo pipefail
drive=$1 config=$2/controller/stride_quad.yaml
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "FAILED: $*"; exit 1; }
run() {  # expected-status script [options...]
  local want=$1 script=$2 status=0
  shift 2
  "$drive" --config "$config" --commands "$script" --summary "$work/s.json" "$@" > "$work/out.txt" 2>&1 ||
    status=$?
  [ "$status" = "$want" ] || { cat "$work/out.txt"; fail "stride-drive $* exited $status, not $want"; }
}
printf -- '- {at: 0.0, gait: stand}\n' > "$work/stand.yaml"
printf -- '- {at: 0.0, gait: stand, vx: 0.3}\n' > "$work/miss.yaml"

run 0 "$work/stand.yaml" --duration 2.6 --check-tracking
python3 - "$work/s.json" <<'PY' || fail "the summary's timing"
import json, sys
s = json.load(open(sys.argv[1]))
t = s["timing"]
assert not s["fell"] and s["tracked"], s
assert t["period_ms"] == 5.0 and t["ticks"] >= 500, t
for k in ("solve_ms", "prepare_ms", "tick_ms"):
    assert 0 < t[k]["p50"] <= t[k]["p99"] <= t[k]["max"], (k, t[k])
assert t["budget_share_p50"] > 0 and t["wall_s"] > 0 and t["robot_s_per_wall_s"] > 0, t
print("stood: tick p50 %.2f ms, budget %.0f%% of the period" %
      (t["tick_ms"]["p50"], 100 * t["budget_share_p50"]))
PY
grep -q "timing (lock-step, this host): tick p50" "$work/out.txt" || fail "no timing line"

run 4 "$work/stand.yaml" --duration 3 --push 1:0.1:0,3000,0
python3 -c "import json,sys; assert json.load(open(sys.argv[1]))['fell']" "$work/s.json" ||
  fail "exit 4 but the summary says no fall"
run 4 "$work/stand.yaml" --duration 3 --push 1:0.1:0,3000,0 --check-tracking
echo "fell: 4"

run 1 "$work/miss.yaml" --duration 2.5 --check-tracking
grep -q "segment 0: vx 0.000, commanded 0.300" "$work/out.txt" || fail "no miss said"
run 0 "$work/miss.yaml" --duration 2.5
echo "missed: 1 with --check-tracking, 0 without"

# A script gait the robot does not have: refused before the drive, naming the entry and the gaits.
printf -- '- {at: 0.0, gait: stand}\n- {at: 1.0, gait: trot, vx: 0.3}\n' > "$work/trot.yaml"
status=0
"$drive" --config "$2/controller/stride_humanoid.yaml" --commands "$work/trot.yaml" \
  > "$work/out.txt" 2>&1 || status=$?
[ "$status" = 2 ] || { cat "$work/out.txt"; fail "a trot on a biped exited $status, not 2"; }
grep -q "trot.yaml': entry 1 (at 1 s): gait 'trot': the robot of '.*stride_humanoid.yaml' walks with stand, walk, hop only" \
  "$work/out.txt" || { cat "$work/out.txt"; fail "the refusal does not say the entry and the gaits"; }
echo "a trot on a biped: refused"
