#!/usr/bin/env bash
# README command 1: installs the packages, builds Release, then runs the closed loop: stride-sim
# (the mock robot) and stride-mpc (the controller) as two processes talking LCM over UDP
# multicast, each pinned to one of the two cores, with lcm-logger recording the session. By
# default everything runs inside a private network namespace this script creates (only a loopback
# interface, multicast routed to it, ttl=0): nothing reaches the host's network.
#
#   tools/demo.sh [--duration S] [--humanoid] [--realtime | --lockstep] [--host-network]
#                 [--out DIR] [--summary FILE] [--spy]
#
#   --duration S     seconds of robot time (default 10: the quadruped stands 2 s, trots in place,
#                    walks forward from 5 s)
#   --humanoid       the in-house humanoid walking instead of the quadruped
#   --lockstep       deterministic lock-step: the sim waits for every answer (the quadruped's
#                    default: on a 2-core machine its 200 Hz tick does not fit the period yet when
#                    the sim shares the machine, see tools/bench/README.md)
#   --realtime       wall clock: the sim at 1 kHz, the controller at its rate (the humanoid's default)
#   --host-network   use the host's loopback instead of a private namespace (multicast with ttl=0
#                    on lo; for watching with lcm-spy from the host: tools/lcm-spy.sh)
#   --out DIR        where the log and summaries go (default build/demo)
#   --summary FILE   the summary as JSON (default DIR/summary.json)
#   --spy            also start lcm-spy (tools/lcm-spy.sh) on the demo's bus; needs a display
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build="${STRIDE_BUILD_DIR:-$root/build}"

duration=10 robot=quad mode="" host_network=0 out="" summary="" spy=0
args=("$@")
while [ $# -gt 0 ]; do
  case "$1" in
    --duration) duration="$2"; shift 2 ;;
    --humanoid) robot=humanoid; shift ;;
    --lockstep) mode=lockstep; shift ;;
    --realtime) mode=realtime; shift ;;
    --host-network) host_network=1; shift ;;
    --out) out="$2"; shift 2 ;;
    --summary) summary="$2"; shift 2 ;;
    --spy) spy=1; shift ;;
    -h|--help) sed -n '2,25p' "$0"; exit 0 ;;
    *) echo "demo.sh: unknown option '$1' (--help)" >&2; exit 2 ;;
  esac
done
out="${out:-$build/demo}"
[ -z "$mode" ] && { [ "$robot" = quad ] && mode=lockstep || mode=realtime; }
summary="${summary:-$out/summary.json}"

# Set-up (skipped inside the namespace: the outer invocation did it).
if [ -z "${STRIDE_DEMO_INSIDE:-}" ]; then
  "$root/tools/install-deps.sh"
  "$root/tools/build.sh"
  mkdir -p "$out"
  if [ "$host_network" = 0 ]; then
    # Re-run this script in a new network namespace (as root directly, else as a user namespace's
    # root). The namespace and everything in it disappear when the script ends.
    ns=(unshare --net)
    [ "$(id -u)" -ne 0 ] && ns=(unshare --user --map-root-user --net)
    if ! "${ns[@]}" true 2>/dev/null; then
      echo "demo.sh: cannot create a network namespace here; rerun with --host-network" >&2
      exit 1
    fi
    STRIDE_DEMO_INSIDE=1 exec "${ns[@]}" "$0" "${args[@]}"
  fi
fi

if [ -n "${STRIDE_DEMO_INSIDE:-}" ]; then
  ip link set lo up
  ip route add 224.0.0.0/4 dev lo
  # Refuse to run if anything but loopback is visible: this must be our private namespace.
  if [ "$(awk -F: 'NR > 2 { gsub(/ /, "", $1); print $1 }' /proc/net/dev | sort -u)" != "lo" ]; then
    echo "demo.sh: the namespace has interfaces other than lo; refusing to send multicast" >&2
    exit 1
  fi
else
  # Host network: loopback only, and multicast that never leaves the machine.
  ip route show 224.0.0.0/4 2>/dev/null | grep -q "dev lo" || {
    echo "demo.sh: --host-network needs a multicast route on lo:" >&2
    echo "  sudo ip route add 224.0.0.0/4 dev lo" >&2
    exit 1
  }
fi
export LCM_DEFAULT_URL='udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304'

if [ "$robot" = quad ]; then
  config="$root/config/controller/stride_quad.yaml"
  robot_yaml="$root/config/robots/stride_quad/stride_quad.yaml"
  hold=(--hold-kp 5 --hold-kd 0.1)  # the sim's PD until the first policy arrives
else
  config="$root/config/controller/stride_humanoid.yaml"
  robot_yaml="$root/config/robots/stride_humanoid/stride_humanoid.yaml"
  hold=(--hold-kp 300 --hold-kd 10)
fi
rate=$(sed -n 's/^rate_hz: *\([0-9.]*\).*/\1/p' "$config")  # lock-step: a state per tick
log="$out/session.lcmlog"
rm -f "$log"
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
  wait 2>/dev/null || true
}
trap cleanup EXIT

# Two cores: the controller on one, the mock robot on the other (lcm-logger is light and floats).
cpus=$(nproc)
mpc_cpu=$((cpus > 1 ? 1 : 0))
limit=$(awk -v d="$duration" 'BEGIN { printf "%d", d * 4 + 120 }')  # wall-clock safety net

timeout "$limit" lcm-logger --quiet "$log" &
pids+=($!)
if [ "$spy" = 1 ]; then
  timeout "$limit" "$root/tools/lcm-spy.sh" --lcm-url="$LCM_DEFAULT_URL" > "$out/lcm-spy.txt" 2>&1 &
  pids+=($!)
  sleep 3  # the JVM starts slowly
fi
mpc_args=(--config "$config" --summary "$out/mpc.json")
sim_args=(--robot "$robot_yaml" --duration "$duration" --summary "$out/sim.json" "${hold[@]}")
if [ "$mode" = lockstep ]; then
  mpc_args+=(--lockstep)
  sim_args+=(--lockstep --rate "$rate")
else
  sim_args+=(--rate 1000)
fi
timeout "$limit" taskset -c "$mpc_cpu" "$build/controller/stride-mpc" "${mpc_args[@]}" \
  > "$out/mpc.txt" 2>&1 &
mpc_pid=$!
pids+=($mpc_pid)
sleep 0.5  # the controller subscribes before the first estimate
echo "demo: $robot, $mode, ${duration} s of robot time; logging to $log"
timeout "$limit" taskset -c 0 "$build/sim/stride-sim" "${sim_args[@]}" > "$out/sim.txt" 2>&1
# Stop the controller at once: from now on its states go stale and it would (rightly) fall back.
kill -TERM "$mpc_pid" 2>/dev/null || true
wait "$mpc_pid" 2>/dev/null || true
sleep 0.2
cleanup
trap - EXIT

cat "$out/mpc.txt" "$out/sim.txt" | grep -E '^stride-(mpc|sim):' || true
echo
echo "== summary (from the log) =="
"$build/tools/stride-log-summary" "$log" --summary "$summary"
echo
echo "log: $log (replay: $build/controller/stride-mpc --config $config --replay $log)"
echo "summary: $summary"
