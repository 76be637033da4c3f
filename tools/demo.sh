#!/usr/bin/env bash
# README command 1: installs the packages, builds Release, then drives a robot in closed loop:
# stride-sim (the mock robot) and stride-mpc (the controller) as two processes talking LCM over UDP
# multicast, each pinned to one of the two cores, stride-teleop sending the velocity commands (a
# command script, or the keyboard) and lcm-logger recording the session. By default everything
# runs inside a private network namespace this script creates (only a loopback interface,
# multicast routed to it, ttl=0): nothing reaches the host's network.
#
#   tools/demo.sh [--robot NAME | --humanoid | --config FILE] [--no-setup]
#                 [--commands FILE | --teleop] [--duration S] [--realtime | --lockstep]
#                 [--robots-dir DIR]... [--check-tracking] [--host-network] [--out DIR]
#                 [--summary FILE] [--spy] [--viz [--viz-port P]]
#                 [--slow-host F] [--kill-controller T] [--pause-controller T D]
#                 [--kill-sim T] [--flood RATE] [--forged-flood RATE] [--future-junk RATE] [--replay-log FILE]
#                 [--rival | --rival-key]
#                 [--key-file F | --no-signing]
#                 [--terrain NAME|FILE [--map-rate HZ]]
#
#   --robot NAME      a shipped robot: stride_quad (default), solo12, anymal_c, stride_humanoid,
#                     talos_reduced: config/controller/NAME.yaml (a name, never a path: another
#                     configuration is --config FILE); solo12, anymal_c and talos_reduced need
#                     example-robot-data (--robots-dir, ROS_PACKAGE_PATH, or build/robot_packages,
#                     which the build makes from ../shared)
#   --humanoid        short for --robot stride_humanoid
#   --config FILE     drive any controller configuration (stride-mpc --config FILE): its paths
#                     (robot:, gait.plan_file, lcm.key_file) are relative to FILE's folder; only
#                     read, never written. Its name in the output is FILE's without .yaml; the
#                     default command script is NAME_commands.yaml beside a NAME_controller.yaml
#                     (stride-init's files), else the in-house robot's of its kind
#                     (config/commands/stride_quad.yaml for a robot that trots, else
#                     stride_humanoid.yaml; terrain_... with --terrain)
#   --no-setup        skip the set-up (tools/install-deps.sh --demo: apt-get; tools/build.sh: cmake
#                     and the build of this run's programs alone) and run on the build as it is;
#                     the same as STRIDE_DEMO_NO_SETUP=1
#   --terrain T       the world the robot walks in: a terrain file, or NAME for
#                     config/terrain/NAME.yaml (stairs_anymal_c, ramp_solo12, rough_stride_quad,
#                     step_talos_reduced, ...; format in terrain/README.md); default flat ground.
#                     The mock robot publishes elevation maps of it on STRIDE_TERRAIN (--viz
#                     draws them)
#   --map-rate HZ     the mock robot's elevation maps per second (default 10 with --terrain);
#                     0: none, the controller walks blind (controller/README.md, "Terrain")
#   --commands FILE   the command script stride-teleop plays on the robot's clock (default
#                     config/commands/NAME.yaml; with --terrain, config/commands/terrain_NAME.yaml:
#                     straight on at 0.2-0.4 m/s; format in tools/README.md, "stride-teleop");
#                     `--commands none`: no command source, the robot stands until you send
#                     commands yourself (the demo prints how; default duration 60 s)
#   --teleop          drive from the keyboard instead (real time, no time limit): arrows / WASD,
#                     Q/E turn, space stands, 1-7 gaits, x or Ctrl-C quits and ends the demo
#   --duration S      seconds of robot time (default: the script's last entry + 4 s)
#   --realtime        wall clock: the sim at 1 kHz, the controller at its rate, each on its own
#                     core (the default for every robot)
#   --lockstep        deterministic lock-step: the sim waits for every answer (the same bits on
#                     every run, as fast as the machine goes)
#   --robots-dir DIR  where example-robot-data is looked for (repeatable), before
#                     build/robot_packages and ROS_PACKAGE_PATH
#   --check-tracking  exit 1 when a command segment missed its command (a fall always exits 4,
#                     a diverged simulation 3: stride-sim's and stride-log-summary's statuses)
#                     With a fault (--kill-controller, --pause-controller, --kill-sim, --flood,
#                     --rival) the summary also says whether control came back (every segment
#                     starting 2 s after the fault's end tracked; issue 33), and exits 6 if not
#   --host-network    use the host's loopback instead of a private namespace (multicast with ttl=0
#                     on lo; for watching with lcm-spy from the host: tools/lcm-spy.sh)
#   --out DIR         where the log and summaries go (default build/demo)
#   --summary FILE    the summary as JSON (default DIR/summary.json)
#   --spy             also start lcm-spy (tools/lcm-spy.sh) on the demo's bus; needs a display
#   --viz             also start the browser viewer (stride-viz) on the demo's bus and print its
#                     address, http://127.0.0.1:P/ on this machine (from the private namespace, a
#                     socat pair forwards it through a Unix socket in DIR); afterwards
#                     tools/viz.sh DIR/session.lcmlog replays the session in the same page
#   --viz-port P      the viewer's port on the host's loopback (default 8765)
#   --rss             record the resident memory of stride-mpc and stride-sim every 10 s in
#                     DIR/rss.txt (t [s], kB, kB): tools/soak.sh reads it
#   --slow-host F     the controller's solver takes F times its time (busy), as on a host F times
#                     slower: shows how it sheds work when a period overruns (controller/README.md,
#                     "Overload")
#   --kill-controller T  SIGKILL stride-mpc T seconds after the robot starts and start a new one
#                     1 s later (issue 19: the robot stands down on its own meanwhile, sim/README.md
#                     "Controller loss"; the new controller takes over); its output in
#                     DIR/mpc-restarted.txt. tools/faults.sh runs it at 10 instants
#   --pause-controller T D  stop stride-mpc (SIGSTOP) T seconds after the robot starts, for D
#                     seconds, then let it go on (SIGCONT): a host stall, swapping, a debugger
#                     (issue 33: it must drive again within 2 s of waking); when it was stopped and
#                     woken in DIR/pause.txt. tools/faults.sh --pause runs it
#   --flood RATE      also publish RATE policies per second of another robot (44 kB each, another
#                     model hash) on the policy channel (stride-flood, on the side core at nice
#                     10): every receiver must refuse them cheaply and the robot walk on (issue
#                     19); stride-flood's line in DIR/flood.txt. tools/faults.sh --flood runs it
#   --forged-flood RATE  also publish RATE forged frames per second on the state and policy
#                     channels, in turn, for the whole run (issue 44): 60 kB of random bytes with a
#                     signature trailer that claims the run's key id, a fresh timestamp, a new
#                     sender each and a made-up mac (stride-flood --forged, at nice 10): what an
#                     attacker without the key can send. Needs signing (not --no-signing).
#                     tools/faults.sh --forged-flood runs it
#   --future-junk RATE  also publish RATE junk policies per second signed with the run's key under
#                     the live controller's sender id, stamped INT64_MAX, 1 h ahead and 0.3 s ahead
#                     in turn (issue 44: a key holder with a wrong clock, or a compromised one;
#                     stride-flood --future). Every one is refused (outside the window, or of no
#                     run) and none locks the live controller out. tools/faults.sh --future runs it
#   --replay-log FILE also replay FILE (an lcm-logger log of an earlier session, e.g. another demo's
#                     DIR/session.lcmlog signed with the same --key-file) on the bus from the
#                     robot's start, at its pace (lcm-logplayer): a recording replayed by an
#                     attacker without the key (issue 44: every message refused as stale or of
#                     another run). tools/faults.sh --replay runs it
#   --kill-sim T      SIGKILL stride-sim (the mock robot) T seconds after it starts and start a new
#                     one 1 s later, standing at the default posture at the origin, for the rest of
#                     the duration: the controller must take the new robot over as it is (issue
#                     19; real time, with a command script); its output in DIR/sim-restarted.txt.
#                     tools/faults.sh --kill-sim runs it
#   --key-file F      sign and check every message with this key (messages/README.md,
#                     "Signing"); by default each run makes a fresh one, DIR/key (stride-keygen),
#                     shared by the robot, the controller and the teleop
#   --no-signing      no key: the wire unauthenticated, as before signing (each program says so)
#   --rival-key       --rival, the rival given the key (a second controller of the operator's:
#                     the robot keeps the first while it speaks; messages/README.md, "Signing")
#   --rival           also run a second stride-mpc on the robot's channels with another plan (its
#                     commands from STRIDE_RIVAL_COMMAND, where nobody sends: it stands while the
#                     robot walks; on the side core at nice 10, from 3 s after the robot's
#                     controller): the robot must follow the first
#                     controller, refuse the rival's policies and say so, and both controllers
#                     must report the other (issue 19); its output in DIR/mpc-rival.txt.
#                     tools/faults.sh --rival runs it
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build="${STRIDE_BUILD_DIR:-$root/build}"

robot=stride_quad by_name=0 user_config="" no_setup=0 commands="" teleop=0 duration="" mode="" host_network=0 out="" summary=""
spy=0 check=0 slow_host="" viz=0 viz_port=8765 rss=0 kill_controller="" flood="" forged_flood="" future_junk="" replay_log="" kill_sim="" rival=0
pause_at="" pause_for="" terrain="" map_rate="" signing=1 key_file="" rival_key=0
robots_dirs=()
args=("$@")
need_value() { [ $# -ge 2 ] || { echo "demo.sh: $1 needs a value (--help)" >&2; exit 2; }; }
while [ $# -gt 0 ]; do
  case "$1" in
    --robot) need_value "$@"; robot="$2" by_name=1; shift 2 ;;
    --humanoid) robot=stride_humanoid by_name=1; shift ;;
    --config) need_value "$@"; user_config="$2"; shift 2 ;;
    --no-setup) no_setup=1; shift ;;
    --terrain) need_value "$@"; terrain="$2"; shift 2 ;;
    --map-rate) need_value "$@"; map_rate="$2"; shift 2 ;;
    --commands) need_value "$@"; commands="$2"; shift 2 ;;
    --teleop) teleop=1; shift ;;
    --duration) need_value "$@"; duration="$2"; shift 2 ;;
    --lockstep) mode=lockstep; shift ;;
    --realtime) mode=realtime; shift ;;
    --robots-dir) need_value "$@"; robots_dirs+=("$(cd "$2" 2>/dev/null && pwd || echo "$2")"); shift 2 ;;
    --check-tracking) check=1; shift ;;
    --host-network) host_network=1; shift ;;
    --out) need_value "$@"; out="$2"; shift 2 ;;
    --summary) need_value "$@"; summary="$2"; shift 2 ;;
    --spy) spy=1; shift ;;
    --viz) viz=1; shift ;;
    --viz-port) need_value "$@"; viz_port="$2"; shift 2 ;;
    --rss) rss=1; shift ;;
    --slow-host) need_value "$@"; slow_host="$2"; shift 2 ;;
    --kill-controller) need_value "$@"; kill_controller="$2"; shift 2 ;;
    --pause-controller)
      [ $# -ge 3 ] || { echo "demo.sh: --pause-controller needs T and D (--help)" >&2; exit 2; }
      pause_at="$2" pause_for="$3"; shift 3 ;;
    --flood) need_value "$@"; flood="$2"; shift 2 ;;
    --forged-flood) need_value "$@"; forged_flood="$2"; shift 2 ;;
    --future-junk) need_value "$@"; future_junk="$2"; shift 2 ;;
    --replay-log) need_value "$@"; replay_log=$(cd "$(dirname "$2")" && pwd)/$(basename "$2"); shift 2 ;;
    --kill-sim) need_value "$@"; kill_sim="$2"; shift 2 ;;
    --rival) rival=1; shift ;;
    --rival-key) rival=1 rival_key=1; shift ;;
    --key-file) need_value "$@"; key_file=$(realpath "$2"); shift 2 ;;
    --no-signing) signing=0; shift ;;
    -h|--help) sed -n '2,/^set -euo/{/^#/p}' "$0"; exit 0 ;;
    *) echo "demo.sh: unknown option '$1' (--help)" >&2; exit 2 ;;
  esac
done

[ "$by_name" = 1 ] && [ -n "$user_config" ] &&
  { echo "demo.sh: --robot/--humanoid or --config, not both" >&2; exit 2; }
if [ -n "$user_config" ]; then
  # The user's configuration, read where it is (stride-mpc resolves its paths from its folder).
  [ -f "$user_config" ] && [ -r "$user_config" ] ||
    { echo "demo.sh: no configuration file '$user_config'" >&2; exit 2; }
  config=$(realpath -- "$user_config")
  robot=$(basename -- "$config" | sed -E 's/\.ya?ml$//')
else
  # A shipped robot's name only, never a path (issue 34: a path disguised as a name).
  config="$root/config/controller/$robot.yaml"
  if ! [[ "$robot" =~ ^[A-Za-z0-9_]+$ ]] || [ ! -f "$config" ]; then
    echo "demo.sh: no robot '$robot' (config/controller/NAME.yaml); the robots:" \
      $(cd "$root/config/controller" && ls -- *.yaml | sed 's/\.yaml$//') >&2
    echo "  another configuration: --config FILE" >&2
    exit 2
  fi
fi
if [ -n "$terrain" ]; then
  if [ -f "$terrain" ]; then
    terrain=$(cd "$(dirname "$terrain")" && echo "$(pwd)/$(basename "$terrain")")
  elif [ -f "$root/config/terrain/$terrain.yaml" ]; then
    terrain="$root/config/terrain/$terrain.yaml"
  else
    echo "demo.sh: no terrain '$terrain' (a file, or config/terrain/NAME.yaml); the terrains:" \
      $(cd "$root/config/terrain" && ls *.yaml | sed 's/\.yaml$//') >&2
    exit 2
  fi
fi
# The command source, the duration and the mode; the default command script is the robot's
# (config/commands/NAME.yaml), for --config the in-house robot's of its kind, known once the
# model is loaded (below).
commands_and_duration() {
  if [ "$teleop" = 1 ]; then
    [ -n "$commands" ] && { echo "demo.sh: --teleop or --commands, not both" >&2; exit 2; }
    [ -n "$duration" ] && { echo "demo.sh: --teleop runs until you quit it (x); no --duration" >&2; exit 2; }
    [ "$mode" = lockstep ] && {
      echo "demo.sh: --teleop runs in real time (the keyboard's commands are on the wall clock)" >&2
      exit 2
    }
    mode=realtime
    [ -t 0 ] || { echo "demo.sh: --teleop reads the keyboard: stdin must be a terminal" >&2; exit 2; }
  elif [ "$commands" = none ]; then
    duration="${duration:-60}"
  else
    # On a terrain, the robot's slower walk over it (config/commands/terrain_NAME.yaml) if it has one.
    if [ -z "$commands" ] && [ -n "$terrain" ] && [ -f "$root/config/commands/terrain_$script_robot.yaml" ]; then
      commands="$root/config/commands/terrain_$script_robot.yaml"
    fi
    commands="${commands:-$root/config/commands/$script_robot.yaml}"
    [ -f "$commands" ] || { echo "demo.sh: no command script '$commands'" >&2; exit 2; }
    commands=$(cd "$(dirname "$commands")" && echo "$(pwd)/$(basename "$commands")")
    if [ -z "$duration" ]; then
      # The last entry's time (entries `- {at: T, ...}` or `- at: T`), comments stripped.
      last=$(sed 's/#.*//' "$commands" | grep -oE '(^|[{ ,-])at: *[-+0-9.eE]+' |
        sed 's/.*at: *//' | tail -n 1)
      [ -n "$last" ] || { echo "demo.sh: '$commands' has no entry with 'at:'" >&2; exit 2; }
      duration=$(awk -v t="$last" 'BEGIN { printf "%g", t + 4 }')
    fi
  fi
  awk -v d="$duration" 'BEGIN { exit !(d == "" || d + 0 > 0) }' ||
    { echo "demo.sh: --duration must be a positive number of seconds" >&2; exit 2; }
  [ -z "$mode" ] && mode=realtime
  if [ -n "$kill_sim" ]; then
    # A restarted mock robot in lock-step would stamp from 0 again, which the controller refuses as
    # stamps going back; with the keyboard or no commands the demo does not run the sim itself.
    { [ "$mode" = realtime ] && [ "$teleop" = 0 ] && [ "$commands" != none ]; } || {
      echo "demo.sh: --kill-sim needs real time and a command script" >&2
      exit 2
    }
    awk -v k="$kill_sim" -v d="$duration" 'BEGIN { exit !(k + 0 > 0 && k + 0 < d + 0) }' ||
      { echo "demo.sh: --kill-sim T must be within the duration" >&2; exit 2; }
  fi
  return 0
}
script_robot=$robot
defer_commands=0
# stride-init writes NAME_controller.yaml and NAME_commands.yaml side by side: the robot's own.
if [ -n "$user_config" ] && [ "$teleop" = 0 ] && [ -z "$commands" ] && [ -z "$terrain" ] &&
  [[ "$user_config" == *_controller.yaml ]] && [ -f "${user_config%_controller.yaml}_commands.yaml" ]; then
  commands="${user_config%_controller.yaml}_commands.yaml"
fi
if [ -n "$user_config" ] && [ "$teleop" = 0 ] && [ -z "$commands" ]; then
  defer_commands=1
else
  commands_and_duration
fi
out="${out:-$build/demo}"
summary="${summary:-$out/summary.json}"

# Set-up (skipped inside the namespace: the outer invocation did it; and with --no-setup or
# STRIDE_DEMO_NO_SETUP=1, as the tests do, which run on a tree already built).
if [ -z "${STRIDE_DEMO_INSIDE:-}" ] && [ -z "${STRIDE_DEMO_NO_SETUP:-}" ] && [ "$no_setup" = 0 ]; then
  # Only what this run starts: the tests, benchmarks and paper tools build with tools/test.sh.
  deps=(--demo) targets=(stride-mpc stride-sim stride-teleop stride-keygen stride-log-summary)
  [ -n "$flood$forged_flood$future_junk" ] && targets+=(stride-flood)
  [ "$viz" = 1 ] && deps+=(--viz) targets+=(stride-viz stride-viz-web)
  [ "$spy" = 1 ] && deps+=(--spy) targets+=(stride_lcm_jar)
  "$root/tools/install-deps.sh" "${deps[@]}"
  configure=()
  # A first configure leaves the tests and benchmarks out (their packages are test.sh's); a tree
  # that tools/test.sh configured keeps them.
  [ -f "$build/CMakeCache.txt" ] || configure=(-DSTRIDE_BUILD_TESTS=OFF -DSTRIDE_BUILD_BENCH=OFF)
  build_args=()
  for t in "${targets[@]}"; do build_args+=(--target "$t"); done
  STRIDE_BUILD_DIR="$build" "$root/tools/build.sh" "${configure[@]}" "${build_args[@]}"
fi
mkdir -p "$out"

# The robot's model, before anything starts: its URDF (public robots: example-robot-data through
# --robots-dir, the build's package view, ROS_PACKAGE_PATH), the robot YAML and its gaits.
[ -d "$build/robot_packages" ] && robots_dirs+=("$build/robot_packages")
dirs_args=()
for d in "${robots_dirs[@]}"; do dirs_args+=(--robots-dir "$d"); done
if ! model=$("$build/controller/stride-mpc" --config "$config" "${dirs_args[@]}" --print-model 2>&1); then
  echo "$model" >&2
  echo "demo.sh: cannot load the robot '$robot' (above)." >&2
  if echo "$model" | grep -q 'package://'; then
    echo "  Its URDF comes from example-robot-data (https://github.com/Gepetto/example-robot-data):" >&2
    echo "  pass the folder that holds that package with --robots-dir DIR (repeatable), add it to" >&2
    echo "  ROS_PACKAGE_PATH, or get the package (with ../shared beside the repository the build" >&2
    echo "  makes build/robot_packages)." >&2
  fi
  exit 1
fi
robot_yaml=$(echo "$model" | sed -n 's/^  yaml  //p')
gaits=biped
echo "$model" | grep -q '^gaits:.* trot' && gaits=quadruped
rate=$(sed -n 's/^rate_hz: *\([0-9.]*\).*/\1/p' "$config")  # lock-step: a state per tick
if [ "$defer_commands" = 1 ]; then
  script_robot=stride_humanoid
  [ "$gaits" = quadruped ] && script_robot=stride_quad
  commands_and_duration
  [ -z "${STRIDE_DEMO_INSIDE:-}" ] &&
    echo "demo: $robot ($config) plays $commands (the in-house robot's of its kind; --commands FILE)"
fi

if [ -z "${STRIDE_DEMO_INSIDE:-}" ] && [ "$host_network" = 0 ]; then
  # Re-run this script in a new network namespace (as root directly, else as a user namespace's
  # root). The namespace and everything in it disappear when the script ends.
  ns=(unshare --net)
  [ "$(id -u)" -ne 0 ] && ns=(unshare --user --map-root-user --net)
  if ! "${ns[@]}" true 2>/dev/null; then
    echo "demo.sh: cannot create a network namespace here; rerun with --host-network" >&2
    exit 1
  fi
  if [ "$viz" = 1 ]; then
    # The viewer serves inside the namespace, whose loopback the host cannot reach; a Unix socket
    # in the output folder can be reached from both sides: the host's end listens here, on the
    # host's loopback only, and the namespace's end (below) connects the socket to stride-viz.
    command -v socat > /dev/null || { echo "demo.sh: --viz needs socat (tools/install-deps.sh)" >&2; exit 1; }
    rm -f "$out/viz.sock"
    socat "TCP-LISTEN:$viz_port,bind=127.0.0.1,reuseaddr,fork" "UNIX-CONNECT:$out/viz.sock" \
      2> "$out/viz-forward.txt" &
    export STRIDE_DEMO_VIZ_FORWARD=$!
  fi
  STRIDE_DEMO_INSIDE=1 exec "${ns[@]}" "$0" "${args[@]}"
fi

if [ -n "${STRIDE_DEMO_INSIDE:-}" ]; then
  ip link set lo up
  ip route replace 224.0.0.0/4 dev lo
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

log="$out/session.lcmlog"
rm -f "$log" "$out/teleop.txt"
pids=()
rival_dir=""
cleanup() {
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
  # The host's end of the viewer's forward (started before the namespace: same user, so ours to
  # stop).
  [ -n "${STRIDE_DEMO_VIZ_FORWARD:-}" ] && kill "$STRIDE_DEMO_VIZ_FORWARD" 2>/dev/null || true
  wait 2>/dev/null || true
  [ -z "$rival_dir" ] || rm -rf "$rival_dir"
}
trap cleanup EXIT
# Waits up to $3 s for the pattern $2 in the file $1 while the process $4 lives.
wait_for() {
  local i
  for ((i = 0; i < $3 * 10; i++)); do
    grep -q "$2" "$1" 2>/dev/null && return 0
    kill -0 "$4" 2>/dev/null || return 1
    sleep 0.1
  done
  return 1
}
# wait_for, or show the program's output and stop the demo.
started() {  # FILE PATTERN PID NAME
  wait_for "$1" "$2" 30 "$3" && return 0
  cat "$1" >&2
  echo "demo.sh: $4 did not start" >&2
  exit 1
}

# Two cores: the controller on one, alone; the mock robot on the other, with lcm-logger and
# stride-teleop (light: floating, they sometimes landed on the controller's core and delayed a
# tick by up to 5 ms, 12 misses in a 60 s run). A wall-clock safety net on every process, except
# when driving by keyboard. The limit's SIGTERM is followed by SIGKILL 10 s later: a process stuck in
# its exit (LeakSanitizer's scan, tests/README.md) must not outlast it.
cpus=$(nproc)
mpc_cpu=$((cpus > 1 ? 1 : 0))
side=(taskset -c 0)
if [ "$teleop" = 1 ]; then
  limit=0  # timeout 0: none
  sim_duration=1e9
else
  # Lock-step runs as fast as the controller answers: slower than real time for the big robots.
  limit=$(awk -v d="$duration" -v m="$mode" 'BEGIN { printf "%d", d * (m == "lockstep" ? 30 : 4) + 120 }')
  sim_duration=$duration
fi
started=$(date +%s.%N)

timeout -k 10 "$limit" "${side[@]}" lcm-logger --quiet "$log" &
pids+=($!)
if [ "$spy" = 1 ]; then
  timeout -k 10 "$limit" "$root/tools/lcm-spy.sh" --lcm-url="$LCM_DEFAULT_URL" > "$out/lcm-spy.txt" 2>&1 &
  pids+=($!)
  sleep 3  # the JVM starts slowly
fi
if [ "$viz" = 1 ]; then
  # Another LCM subscriber, on the side core: it never slows the controller (a slow browser drops
  # frames in stride-viz, never in the loop). Inside the namespace it listens on the namespace's
  # loopback, joined to the host's by the forward above.
  timeout -k 10 "$limit" "${side[@]}" "$build/viz/stride-viz" --url "$LCM_DEFAULT_URL" \
    --robot "$robot_yaml" "${dirs_args[@]}" --port "$viz_port" > "$out/viz.txt" 2>&1 &
  viz_pid=$!
  pids+=($viz_pid)
  started "$out/viz.txt" "^stride-viz: http" "$viz_pid" stride-viz
  if [ -n "${STRIDE_DEMO_INSIDE:-}" ]; then
    timeout -k 10 "$limit" socat "UNIX-LISTEN:$out/viz.sock,fork,unlink-early" "TCP:127.0.0.1:$viz_port" \
      2> "$out/viz-forward-inside.txt" &
    pids+=($!)
  fi
  echo "demo: the viewer is at http://127.0.0.1:$viz_port/ (open it in a browser on this machine;"
  echo "  after the demo: tools/viz.sh $log)"
fi
mpc_args=(--config "$config" "${dirs_args[@]}" --summary "$out/mpc.json")
[ -n "$slow_host" ] && mpc_args+=(--emulate-slow-host "$slow_host")
sim_args=(--robot "$robot_yaml" "${dirs_args[@]}" --duration "$sim_duration"
  --summary "$out/sim.json")
[ -n "$terrain" ] && sim_args+=(--terrain "$terrain")
[ -n "$map_rate" ] && sim_args+=(--map-rate "$map_rate")
rm -f "$out/sim.json" "$out/sim-restarted.json" "$out/kill.txt" "$out/pause.txt" "$out/sim-restart.txt"
# Authenticated messages (messages/README.md, "Signing"): a fresh key for every run, unless one
# was given or signing was turned off. The robot, the controller and the teleop share it; the
# rival and the flood do not (--rival-key gives the rival the key).
key_args=()
if [ "$signing" = 1 ]; then
  if [ -z "$key_file" ]; then
    key_file="$out/key"
    rm -f "$key_file"
    "$build/tools/stride-keygen" "$key_file" > /dev/null
  fi
  key_args=(--key-file "$key_file")
fi
mpc_args+=("${key_args[@]}")
sim_args+=("${key_args[@]}")
if [ "$mode" = lockstep ]; then
  mpc_args+=(--lockstep)
  sim_args+=(--lockstep --rate "$rate")
else
  sim_args+=(--rate 1000)
fi
timeout -k 10 "$limit" taskset -c "$mpc_cpu" "$build/controller/stride-mpc" "${mpc_args[@]}" \
  > "$out/mpc.txt" 2>&1 &
mpc_pid=$!
pids+=($mpc_pid)
# The controller prints its line once subscribed (the first udpm subscribe can take seconds).
started "$out/mpc.txt" "^stride-mpc: .* mode" "$mpc_pid" stride-mpc
if [ "$rss" = 1 ]; then
  # VmRSS of the controller and of the mock robot (once it runs), on the side core, until the
  # controller stops: a leak shows as growth between the first and the last line.
  rm -f "$out/rss.txt"
  (
    t=0
    # The programs run under `timeout`, children of this script: found through it, never a
    # program of the same name elsewhere on the machine.
    program() { for p in $(pgrep -P $$); do pgrep -P "$p" -x "$1"; done | head -n 1; }
    rss_of() {
      local pid
      pid=$(program "$1")
      [ -n "$pid" ] && awk '/^VmRSS:/ { print $2 }' "/proc/$pid/status" 2>/dev/null || echo 0
    }
    while kill -0 "$mpc_pid" 2>/dev/null; do
      echo "$t $(rss_of stride-mpc) $(rss_of stride-sim)" >> "$out/rss.txt"
      sleep 10
      t=$((t + 10))
    done
  ) &
  pids+=($!)
fi
teleop_bin="$build/tools/stride-teleop"
if [ -n "$flood" ]; then
  # A rogue publisher on the robot's network: its own cost is small (it would run elsewhere);
  # what counts is every subscriber's, the kernel's delivery and the refusal on the raw bytes.
  timeout -k 10 "$limit" nice -n 10 "${side[@]}" "$build/tools/stride-flood" --rate "$flood" \
    > "$out/flood.txt" 2>&1 &
  pids+=($!)
fi
if [ -n "$forged_flood" ]; then
  [ "$signing" = 1 ] || { echo "demo: --forged-flood needs signing (not --no-signing)" >&2; exit 2; }
  # Frames claiming the run's key id (an attacker reads it off the wire; the key is not used).
  timeout -k 10 "$limit" nice -n 10 "${side[@]}" "$build/tools/stride-flood" \
    --rate "$forged_flood" --forged "$key_file" --size 60000 --channel STRIDE_STATE,STRIDE_POLICY \
    > "$out/flood.txt" 2>&1 &
  pids+=($!)
fi
if [ -n "$future_junk" ]; then
  [ "$signing" = 1 ] || { echo "demo: --future-junk needs signing (not --no-signing)" >&2; exit 2; }
  # Signed with the run's key: what a key holder with a wrong clock (or a compromised one) sends.
  timeout -k 10 "$limit" nice -n 10 "${side[@]}" "$build/tools/stride-flood" \
    --rate "$future_junk" --future "$key_file" --channel STRIDE_POLICY > "$out/flood.txt" 2>&1 &
  pids+=($!)
fi
if [ "$rival" = 1 ]; then
  # The rival's YAML, in a temporary folder (the robot's configuration is only read): the robot's,
  # with its paths made absolute (robot:, gait.plan_file, lcm.key_file: relative to the YAML's
  # folder) and the command channel moved where nobody sends.
  rival_dir=$(mktemp -d)
  rival_yaml="$rival_dir/rival.yaml"
  python3 "$root/tools/drive/config_copy.py" "$config" "$rival_dir/absolute.yaml"
  sed -e '/^  command: /d' -e '/^lcm:/a\  command: STRIDE_RIVAL_COMMAND' "$rival_dir/absolute.yaml" \
    > "$rival_yaml"
  grep -q '^lcm:' "$rival_yaml" || printf 'lcm:\n  command: STRIDE_RIVAL_COMMAND\n' >> "$rival_yaml"
  rival_args=(--config "$rival_yaml" "${dirs_args[@]}" --summary "$out/mpc-rival.json")
  [ "$rival_key" = 1 ] && rival_args+=("${key_args[@]}")
  [ "$mode" = lockstep ] && rival_args+=(--lockstep)
  # It starts 3 s after the robot's controller: a controller that comes up while the robot is
  # driven. Started together, the two start-up solves race for the robot's first policy, and the
  # rival, without commands, would win it now and then (a robot follows the first controller).
  ( sleep 3; exec timeout -k 10 "$limit" nice -n 10 "${side[@]}" "$build/controller/stride-mpc" \
    "${rival_args[@]}" ) > "$out/mpc-rival.txt" 2>&1 &
  rival_pid=$!
  pids+=($rival_pid)
fi
if [ -n "$kill_controller" ]; then
  # The controller killed (no chance to say goodbye) while the robot walks, a new one started a
  # second later on the same core with the same arguments. Timed from here: the sim starts next.
  (
    sleep "$kill_controller"
    pkill -KILL -P "$mpc_pid" -x stride-mpc || true
    echo "demo: killed stride-mpc at $(date +%s.%N)" > "$out/kill.txt"
    sleep 1
    echo "demo: started a new stride-mpc at $(date +%s.%N)" >> "$out/kill.txt"
    restarted=()
    for a in "${mpc_args[@]}"; do
      [ "$a" = "$out/mpc.json" ] && a="$out/mpc-restarted.json"
      restarted+=("$a")
    done
    exec timeout -k 10 "$limit" taskset -c "$mpc_cpu" "$build/controller/stride-mpc" "${restarted[@]}" \
      > "$out/mpc-restarted.txt" 2>&1
  ) &
  restart_pid=$!
  pids+=($restart_pid)
fi
if [ -n "$pause_at" ]; then
  # The controller stopped by the host (it cannot tell, nor clean up) and let go on: timed from
  # here, as the kill.
  (
    sleep "$pause_at"
    pid=$(pgrep -P "$mpc_pid" -x stride-mpc || true)
    [ -n "$pid" ] || exit 0
    kill -STOP "$pid"
    echo "demo: stopped stride-mpc at $(date +%s.%N)" > "$out/pause.txt"
    sleep "$pause_for"
    kill -CONT "$pid"
    echo "demo: woke stride-mpc at $(date +%s.%N)" >> "$out/pause.txt"
  ) &
  pids+=($!)
fi
robot_started=$(date +%s.%N)  # the faults that last the whole run start here
if [ -n "$replay_log" ]; then
  # The attacker's replay of a recording, at its pace, from the robot's start (issue 44).
  timeout -k 10 "$limit" nice -n 10 "${side[@]}" lcm-logplayer "$replay_log" \
    > "$out/replay.txt" 2>&1 &
  pids+=($!)
fi
if [ "$commands" = none ]; then
  # No command source: whoever joins the bus drives (the controller stands until then).
  join=""
  if [ -n "${STRIDE_DEMO_INSIDE:-}" ]; then
    join="nsenter --target $$ --net "
    command -v sudo > /dev/null && join="sudo $join"
    [ "$(awk '$1 == 0 { print $2 }' /proc/self/uid_map)" != 0 ] &&
      join="nsenter --target $$ --user --net --preserve-credentials "
  fi
  echo "demo: $robot, $mode, ${duration} s of robot time, no commands (the robot stands until you"
  echo "  send some); drive it from another terminal with"
  echo "  ${join}env LCM_DEFAULT_URL='$LCM_DEFAULT_URL' $teleop_bin --gaits $gaits ${key_args[*]}"
  echo "logging to $log"
  sim_status=0
  timeout -k 10 "$limit" taskset -c 0 "$build/sim/stride-sim" "${sim_args[@]}" > "$out/sim.txt" 2>&1 ||
    sim_status=$?
elif [ "$teleop" = 0 ]; then
  # The script's t = 0 is the first state the teleop receives: it listens before the sim starts.
  timeout -k 10 "$limit" "${side[@]}" "$teleop_bin" --commands "$commands" --gaits "$gaits" "${key_args[@]}" \
    > "$out/teleop.txt" 2>&1 &
  teleop_pid=$!
  pids+=($teleop_pid)
  started "$out/teleop.txt" "waiting for states" "$teleop_pid" stride-teleop
  echo "demo: $robot, $mode, ${duration} s of robot time, commands from $commands; logging to $log"
  sim_status=0
  if [ -n "$kill_sim" ]; then
    # The mock robot killed while it walks and a new one started a second later for the rest of
    # the duration: a robot whose state estimator restarted, found standing at the origin.
    timeout -k 10 "$limit" taskset -c 0 "$build/sim/stride-sim" "${sim_args[@]}" > "$out/sim.txt" 2>&1 &
    sim_pid=$!
    pids+=($sim_pid)
    sleep "$kill_sim"
    pkill -KILL -P "$sim_pid" -x stride-sim || true
    wait "$sim_pid" 2>/dev/null || true
    sleep 1
    date +%s.%N > "$out/sim-restart.txt"
    rest=$(awk -v d="$duration" -v k="$kill_sim" 'BEGIN { r = d - k - 1; printf "%.3f", (r > 1 ? r : 1) }')
    restarted=() prev=""
    for a in "${sim_args[@]}"; do
      [ "$prev" = --duration ] && a="$rest"
      [ "$prev" = --summary ] && a="$out/sim-restarted.json"
      restarted+=("$a")
      prev=$a
    done
    timeout -k 10 "$limit" taskset -c 0 "$build/sim/stride-sim" "${restarted[@]}" \
      > "$out/sim-restarted.txt" 2>&1 || sim_status=$?
  else
    timeout -k 10 "$limit" taskset -c 0 "$build/sim/stride-sim" "${sim_args[@]}" > "$out/sim.txt" 2>&1 ||
      sim_status=$?
  fi
  kill -TERM "$teleop_pid" 2>/dev/null || true
  wait "$teleop_pid" 2>/dev/null || true
else
  timeout -k 10 "$limit" taskset -c 0 "$build/sim/stride-sim" "${sim_args[@]}" > "$out/sim.txt" 2>&1 &
  sim_pid=$!
  pids+=($sim_pid)
  echo "demo: $robot, real time, driven from the keyboard until you quit (x); logging to $log"
  # The teleop reads the terminal in the foreground. When the sim stops first (the robot fell),
  # a watcher stops the teleop, which restores the terminal.
  pidfile="$out/teleop.pid"
  rm -f "$pidfile"
  (
    while kill -0 "$sim_pid" 2>/dev/null; do sleep 0.5; done
    [ -s "$pidfile" ] && kill -TERM "$(cat "$pidfile")" 2>/dev/null
  ) &
  pids+=($!)
  trap 'true' INT  # a stray SIGINT must not end the demo before its summary
  sim_status=0
  bash -c 'echo $$ > "$1"; shift; exec "$@"' teleop "$pidfile" \
    "${side[@]}" "$teleop_bin" --gaits "$gaits" "${key_args[@]}" || true
  trap - INT
  if ! kill -0 "$sim_pid" 2>/dev/null; then
    wait "$sim_pid" || sim_status=$?
    echo "demo: the sim stopped before the teleop (see below)"
  fi
  kill -TERM "$sim_pid" 2>/dev/null || true
  wait "$sim_pid" 2>/dev/null || true
fi
# Stop the controller at once: from now on its states go stale and it would (rightly) fall back.
kill -TERM "$mpc_pid" 2>/dev/null || true
wait "$mpc_pid" 2>/dev/null || true
if [ -n "$kill_controller" ]; then
  kill -TERM "$restart_pid" 2>/dev/null || true  # the restarted one's timeout passes it on
  wait "$restart_pid" 2>/dev/null || true
fi
if [ "$rival" = 1 ]; then
  kill -TERM "$rival_pid" 2>/dev/null || true
  wait "$rival_pid" 2>/dev/null || true
fi
# lcm-logger stopped before it has read the robot's last states would make a summary of a robot
# that fell say it did not (issue 33): wait until the log stops growing (up to 5 s). A loss that
# remains is measured and said by stride-log-summary (the robot's own last stamp, in sim.json).
size=-1
for ((i = 0; i < 50; i++)); do
  sleep 0.1
  now_size=$(stat -c %s "$log" 2>/dev/null || echo 0)
  [ "$now_size" = "$size" ] && break
  size=$now_size
done
cleanup
trap - EXIT
wall=$(awk -v a="$started" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }')

cat "$out/mpc.txt" "$out/sim.txt" | grep -E '^stride-(mpc|sim):' || true
if [ -n "$kill_controller" ]; then
  echo "demo: stride-mpc killed at $kill_controller s and restarted 1 s later; the restarted one:"
  grep -E '^stride-mpc:' "$out/mpc-restarted.txt" 2>/dev/null || echo "  (no output)"
fi
if [ -n "$kill_sim" ]; then
  echo "demo: stride-sim killed at $kill_sim s and restarted 1 s later; the restarted one:"
  grep -E '^stride-sim:' "$out/sim-restarted.txt" 2>/dev/null || echo "  (no output)"
fi
if [ "$rival" = 1 ]; then
  echo "demo: a rival stride-mpc ran on the same channels; the rival:"
  grep -E '^stride-mpc:' "$out/mpc-rival.txt" 2>/dev/null || echo "  (no output)"
fi
[ -n "$flood$forged_flood$future_junk" ] && { grep -E '^stride-flood: .* sent' "$out/flood.txt" || echo "demo: stride-flood said nothing ($out/flood.txt)"; }
[ -f "$out/teleop.txt" ] && grep -E '^stride-teleop: stopped' "$out/teleop.txt" || true
[ "$sim_status" = 124 ] && echo "demo: the sim was stopped by the safety net after $limit s"
echo
echo "== summary (from the log) =="
summary_args=("$log" --summary "$summary")
# The mock robot's own verdict (its terrain, trips, and a fall the logger may not have read).
sim_json="$out/sim.json"
[ -n "$kill_sim" ] && sim_json="$out/sim-restarted.json"
[ -f "$sim_json" ] && summary_args+=(--sim-summary "$sim_json")
[ "$check" = 1 ] && summary_args+=(--check-tracking)
# Whether control came back after a fault (issue 33): its end on the wall clock; a rival or a
# flood lasts the whole run, from the robot's start.
fault_end=""
[ -n "$kill_controller" ] && fault_end=$(sed -n 's/^demo: started a new stride-mpc at //p' "$out/kill.txt" 2>/dev/null)
[ -n "$pause_at" ] && fault_end=$(sed -n 's/^demo: woke stride-mpc at //p' "$out/pause.txt" 2>/dev/null)
[ -n "$kill_sim" ] && fault_end=$(cat "$out/sim-restart.txt" 2>/dev/null)
{ [ "$rival" = 1 ] || [ -n "$flood$forged_flood$future_junk$replay_log" ]; } && fault_end=$robot_started
if [ -n "$kill_controller$pause_at$kill_sim$flood$forged_flood$future_junk$replay_log" ] || [ "$rival" = 1 ]; then
  if [ -n "$fault_end" ]; then
    summary_args+=(--fault-end-wall "$fault_end")
  else
    echo "demo: the fault never ended (the run stopped first): recovery not judged"
  fi
fi
status=0
"$build/tools/stride-log-summary" "${summary_args[@]}" || status=$?
# The sim's own verdict counts too (its fall criterion is the summary's, on every physics step).
if [ "$status" = 0 ] && { [ "$sim_status" = 3 ] || [ "$sim_status" = 4 ]; }; then
  status=$sim_status
fi
echo
echo "wall time: $wall s ($mode)"
echo "log: $log (replay: $build/controller/stride-mpc --config $config ${dirs_args[*]} --replay $log)"
echo "summary: $summary"
exit "$status"
