#!/usr/bin/env bash
# Graceful overload: the closed loop in real time (tools/demo.sh, in a private network namespace
# this test creates) with the controller's solver emulating a host F times slower (--slow-host F:
# every solver phase busy for F times its duration, in chunks of knots), so that a period's work
# (~2.2 ms of the 5 ms on this machine) reaches or outgrows the period. The controller must shed
# work in its documented order (controller/README.md, "Overload"): misses stay isolated (never two
# periods in a row, unless the host stalled it), every tick that runs with a state sends a policy,
# the robot is never left without one, and it trots on without falling. Exit 77 only when
# namespaces are not permitted.
# Timing-sensitive: ctest runs it alone (RUN_SERIAL).
#   tests/controller/overload.sh build . F
set -euo pipefail
build=$1 root=$2 slow=$3
# shellcheck source=../private_netns.sh
source "$(dirname "$0")/../private_netns.sh"
private_netns "$@"
export LCM_DEFAULT_URL='udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304'
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
printf -- '- {at: 0.0, gait: stand}\n- {at: 1.0, gait: trot, vx: 0.3}\n' > "$dir/drive.yaml"
# One run of the loop; exit status 3 when only the misses' criterion failed (see below).
run() {
rm -rf "$dir/demo"
status=0
STRIDE_DEMO_INSIDE=1 STRIDE_BUILD_DIR="$build" timeout 150 "$root/tools/demo.sh" \
  --robot stride_quad --slow-host "$slow" --commands "$dir/drive.yaml" --duration 10 \
  --out "$dir/demo" > "$dir/demo.txt" 2>&1 || status=$?
cat "$dir/demo.txt"
[ "$status" = 0 ] || { echo "FAIL: tools/demo.sh exited $status"; exit 1; }
value() { sed -n "s/.*\"$1\": \([0-9]*\).*/\1/p" "$2" | head -n 1; }
mpc="$dir/demo/mpc.json" sim="$dir/demo/sim.json"
cat "$mpc" "$sim"
grep -q '"fell": false' "$sim" || { echo "FAIL: the robot fell"; exit 1; }
# Misses the controller's own work made stay isolated. A run of misses in which the host kept the
# controller off its core for over 1 ms (wall time beyond CPU time, or a late wake-up) is the
# host's: a stall longer than a period misses two deadlines whatever the controller does.
in_a_row=$(value max_misses_in_a_row "$mpc") own=$(value max_own_misses_in_a_row "$mpc")
stalls=$(value host_stalls "$mpc")
echo "overload: own misses in a row $own, with host stalls $in_a_row, host stalls $stalls," \
  "shed $(value full_step_only "$mpc") + $(value previous_policy_ticks "$mpc")," \
  "deadline misses $(value deadline_misses "$mpc"), late ticks $(value late_ticks "$mpc")"
[ "$own" -le 1 ] ||
  { echo "FAIL: $own periods in a row missed their deadline, with no host stall"; return 3; }
shed=$(($(value full_step_only "$mpc") +
  $(value previous_policy_ticks "$mpc")))
[ "$shed" -gt 0 ] || { echo "FAIL: no work was shed: was the host slow enough?"; exit 1; }
# Every tick that ran with a state answered, but start-up solves too slow to send (made again on
# a newer state: controller/README.md, "Start-up"), and the robot always had a policy to apply
# (none ran out, never on the hold PD after the first; the sim may end before the last ones
# arrive).
ticks=$(value ticks "$mpc") without=$(value ticks_without_state "$mpc")
resolves=$(value startup_resolves "$mpc")
published=$(value policies "$mpc") received=$(value policies "$sim")
[ "$published" = $((ticks - without - resolves)) ] ||
  { echo "FAIL: $ticks ticks ($without without a state, $resolves start-up solves made again)," \
      "$published policies published"; exit 1; }
# (0.1 s of policies may still be on their way when the robot stops.)
[ "$received" -ge $((published - 20)) ] ||
  { echo "FAIL: $published policies published, $received received"; exit 1; }
[ "$(value exhausted_steps "$sim")" = 0 ] && [ "$(value hold_steps "$sim")" = 0 ] ||
  { echo "FAIL: the robot ran past its policies or on its hold controller"; exit 1; }
echo "PASS: ${slow}x slower solver in real time: $shed periods shed work, at most $own miss in" \
  "a row of its own ($in_a_row counting host stalls; $stalls periods stalled by the host)," \
  "$published policies for $ticks ticks ($received received), no fall"
}
# A host stall the controller cannot see: on a virtual machine whose hypervisor takes the CPU
# away without reporting steal time (this kind reports none), the lost time counts as the
# controller's own, and a run of misses looks like its own overrun. One run may fail the misses'
# criterion for that reason; two runs in a row may not. Every other criterion holds on each run.
status=0
run || status=$?
if [ "$status" = 3 ]; then
  echo "overload: the misses' criterion failed once; running again (tests/README.md, \"Timing\")"
  run
elif [ "$status" != 0 ]; then
  exit "$status"
fi
