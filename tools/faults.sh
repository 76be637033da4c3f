#!/usr/bin/env bash
# The controller killed and restarted in real time (issue 19): tools/demo.sh, in its private
# network namespace, walks the robot forward and SIGKILLs stride-mpc at N instants spread over
# one gait cycle (one run each), a new stride-mpc starting 1 s after each kill. The robot stands
# down on its own meanwhile (sim/README.md, "Controller loss") and the new controller walks it on.
# Prints one line per run and the falls; the lock-step version is ctest's ControllerLoss.*.
# Instead of the controller kills, one other fault per run:
#   --flood RATE   another robot's policies on the policy channel at RATE per second all along
#                  (tools/demo.sh --flood; lock-step: Faults.AFloodOf...)
#   --forged-flood RATE  forged frames on the state and policy channels at RATE per second all
#                  along: 60 kB claiming the run's key id, fresh timestamps, a new sender each, a
#                  made-up mac (issue 44: refused before hashing; tools/demo.sh --forged-flood;
#                  ctest forged_flood_real_time)
#   --future RATE  junk policies signed with the run's key under the live controller's sender id,
#                  stamped INT64_MAX, 1 h ahead and 0.3 s ahead in turn, RATE per second all along:
#                  a key holder with a wrong clock, or a compromised one (issue 44: each refused,
#                  none locks the live controller out; tools/demo.sh --future-junk; lock-step:
#                  SignedReplay.AJunkMessageFromTheFutureLocksNobodyOut)
#   --replay       a recording of a signed session (a first demo walking the same script, its
#                  session.lcmlog) replayed with lcm-logplayer at a new robot and controller with
#                  the same key, from their start (issue 44: every message refused as stale, or of
#                  another run; tools/demo.sh --replay-log; lock-step: SignedReplay.*)
#   --rival        a second stride-mpc on the same channels, standing while the robot walks
#                  (tools/demo.sh --rival; lock-step: ClosedLoop.ARivalController...)
#   --kill-sim     stride-sim killed at the same instants and a new one started 1 s later, the
#                  robot standing at the origin (tools/demo.sh --kill-sim; lock-step:
#                  Faults.TheMockRobotRestarted...)
#   --pause D      stride-mpc stopped (SIGSTOP) at the same instants for D seconds, then let go on
#                  (a host stall, swapping, a debugger: tools/demo.sh --pause-controller)
# Surviving is not recovering (issue 33): each run walks forward, then turns from 2.5 s after the
# fault's end and walks forward again 3 s later, and reports whether control came back (every
# segment starting 2 s after the fault's end tracked: stride-log-summary --fault-end) and when
# the command was first tracked.
#   tools/faults.sh [--robot stride_quad|stride_humanoid] [--runs N] [--out DIR]
#                   [--flood RATE | --forged-flood RATE | --future RATE | --replay | --rival | --kill-sim |
#                    --pause D]
#   --robot NAME   stride_quad (default: trots at 0.5 m/s) or stride_humanoid (walks at 0.2 m/s)
#   --runs N       kills (or runs with the other fault), one run each (default 10)
#   --out DIR      each run's demo folder (default build/faults/ROBOT, build/flood/ROBOT,
#                  build/rival/ROBOT, build/sim-restart/ROBOT, build/pause/ROBOT,
#                  build/forged-flood/ROBOT, build/future/ROBOT, build/replay/ROBOT)
# Exit status: 0 no fall and control back in every run; 4 the robot fell in some run; 6 control
# did not come back in some run; 1 another failure.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build="${STRIDE_BUILD_DIR:-$root/build}"
robot=stride_quad runs=10 out="" flood="" fault=kill pause=""
while [ $# -gt 0 ]; do
  case "$1" in
    --robot) robot="$2"; shift 2 ;;
    --runs) runs="$2"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    --flood) flood="$2" fault=flood; shift 2 ;;
    --forged-flood) flood="$2" fault=forged-flood; shift 2 ;;
    --future) flood="$2" fault=future; shift 2 ;;
    --replay) fault=replay; shift ;;
    --rival) fault=rival; shift ;;
    --kill-sim) fault=kill-sim; shift ;;
    --pause) pause="$2" fault=pause; shift 2 ;;
    -h|--help) sed -n '2,/^set -euo/{/^#/p}' "$0"; exit 0 ;;
    *) echo "faults.sh: unknown option '$1' (--help)" >&2; exit 2 ;;
  esac
done
case "$robot" in
  stride_quad) gait=trot vx=0.5 yaw=0.5 cycle=0.4 ;;
  stride_humanoid) gait=walk vx=0.2 yaw=0.2 cycle=1.0 ;;
  *) echo "faults.sh: --robot stride_quad or stride_humanoid" >&2; exit 2 ;;
esac
case "$fault" in
  kill) out="${out:-$build/faults/$robot}" ;;
  flood) out="${out:-$build/flood/$robot}" ;;
  forged-flood) out="${out:-$build/forged-flood/$robot}" ;;
  future) out="${out:-$build/future/$robot}" ;;
  replay) out="${out:-$build/replay/$robot}" ;;
  rival) out="${out:-$build/rival/$robot}" ;;
  kill-sim) out="${out:-$build/sim-restart/$robot}" ;;
  pause) out="${out:-$build/pause/$robot}" ;;
esac
mkdir -p "$out"
out=$(cd "$out" && pwd)
script="$out/commands.yaml"

falls=0 lost=0
for ((i = 0; i < runs; i++)); do
  # Walking at vx from 3.5 s; the faults cover one gait cycle, off the controller's period too.
  kill_at=$(awk -v i="$i" -v n="$runs" -v c="$cycle" 'BEGIN { printf "%.4f", 3.5 + c * i / n + 0.0013 * i }')
  # When the fault ends (a flood or a rival lasts the whole run: the walk's schedule of a kill).
  case "$fault" in
    pause) fault_end=$(awk -v k="$kill_at" -v d="$pause" 'BEGIN { printf "%.1f", k + d }') ;;
    *) fault_end=$(awk -v k="$kill_at" 'BEGIN { printf "%.1f", k + 1 }') ;;
  esac
  # Forward until 2.5 s after the fault's end, a turn for 3 s, forward again for 3 s: two
  # segments that start after the fault, whatever the start-up took.
  turn_at=$(awk -v f="$fault_end" 'BEGIN { printf "%.1f", f + 2.5 }')
  printf -- '- {at: 0.0, gait: stand}\n- {at: 1.0, gait: %s}\n- {at: 2.0, vx: %s}\n' "$gait" "$vx" > "$script"
  printf -- '- {at: %s, vx: 0.0, yaw_rate: %s}\n- {at: %s, vx: %s, yaw_rate: 0.0}\n' "$turn_at" "$yaw" \
    "$(awk -v t="$turn_at" 'BEGIN { printf "%.1f", t + 3 }')" "$vx" >> "$script"
  duration=$(awk -v t="$turn_at" 'BEGIN { printf "%.1f", t + 6 }')
  dir="$out/run$i"
  status=0
  case "$fault" in
    kill) args=(--kill-controller "$kill_at") ;;
    flood) args=(--flood "$flood") ;;
    forged-flood) args=(--forged-flood "$flood") ;;
    future) args=(--future-junk "$flood") ;;
    replay)
      # The recording: the same walk, signed with the key the attacked runs use.
      if [ ! -f "$out/recorded/session.lcmlog" ]; then
        rm -f "$out/key"
        "$build/tools/stride-keygen" "$out/key" > /dev/null
        "$root/tools/demo.sh" --robot "$robot" --commands "$script" --duration "$duration" \
          --realtime --key-file "$out/key" --out "$out/recorded" > "$out/recorded.txt" 2>&1 || true
      fi
      args=(--replay-log "$out/recorded/session.lcmlog" --key-file "$out/key") ;;
    rival) args=(--rival) ;;
    kill-sim) args=(--kill-sim "$kill_at") ;;
    pause) args=(--pause-controller "$kill_at" "$pause") ;;
  esac
  "$root/tools/demo.sh" --robot "$robot" --commands "$script" --duration "$duration" --realtime \
    "${args[@]}" --out "$dir" > "$dir.txt" 2>&1 || status=$?
  # A flooded session's log holds every foreign policy (44 MB a second): the summaries are kept.
  case "$fault" in flood|forged-flood) rm -f "$dir/session.lcmlog" ;; esac
  line=$(python3 - "$dir" "$fault" <<'EOF'
import json, os, sys
d, fault = sys.argv[1], sys.argv[2]
def load(name):
    return json.load(open(os.path.join(d, name)))
def recovery():
    # Whether control came back (stride-log-summary --fault-end, in the session's summary).
    r = load("summary.json").get("recovery")
    if r is None:
        return "; recovery: NOT judged (the fault did not end in the run)"
    when = ("its command tracked %.2f s after" % r["time_to_tracking_s"]
            if r["time_to_tracking_s"] is not None else "its command never tracked after")
    return "; %s: %d of %d segments after the fault tracked, %s the fault's end" % (
        "recovered" if r["recovered"] else "NOT recovered",
        r["segments_after"] - r["missed_after"], r["segments_after"], when)
if fault == "kill-sim":
    # The killed mock robot wrote no summary: the session's (from the log, both robots) and the
    # new robot's own.
    g, n = load("summary.json"), load("sim-restarted.json")
    print("fell" if g["fell"] or n["fell"] else "up",
          "the session: tilt max %.1f deg, base %.3f..%.3f m; the new robot: %s, tilt max %.1f deg, "
          "base %.3f..%.3f m, walked %.2f m, %d policies taken, %d steps on the hold PD before the "
          "first" % (g["max_tilt_deg"], g["base_height_min_m"], g["base_height_max_m"],
                     "fell" if n["fell"] else "up", n["max_tilt_deg"], n["base_height_min_m"],
                     n["base_height_max_m"], n["distance_m"], n["policies"], n["waiting_steps"])
          + recovery())
    sys.exit(0)
s = load("sim.json")
line = ("tilt max %.1f deg, base %.3f..%.3f m, walked %.2f m; %d stand-downs (%d steps standing "
        "down), %d past a policy's end, %d controller switches; %d policies taken, %d of another "
        "model refused, %d not signed with the key refused"
        % (s["max_tilt_deg"], s["base_height_min_m"], s["base_height_max_m"], s["distance_m"],
           s["stand_downs"], s["stand_down_steps"], s["exhausted_steps"], s["source_switches"],
           s["policies"], s["policies_wrong_model"], s["policies_unauthenticated"]))
if fault in ("forged-flood", "future", "replay"):
    m = load("mpc.json")
    u = m.get("unauthenticated") or {}
    line += ("; the robot refused %d policies of another run; the controller refused %s, and %d "
             "states of another run" % (s.get("policies_other_session", 0),
                                        ", ".join("%d %s" % (n, k) for k, n in u.items() if n),
                                        m.get("other_session_states", 0)))
if fault == "rival":
    m, r = load("mpc.json"), load("mpc-rival.json")
    line += ("; %d of the rival refused; the controller saw %d of the rival's policies, the rival "
             "%d of the controller's" % (s["policies_rival"], m["rival_policies"],
                                         r["rival_policies"]))
print("fell" if s["fell"] else "up", line + recovery())
EOF
  ) || line="no summary (demo exit $status: see $dir.txt)"
  case "$line" in fell*|no\ summary*) falls=$((falls + 1)) ;; esac
  case "$line" in *"NOT recovered"*|*"NOT judged"*|no\ summary*) lost=$((lost + 1)) ;; esac
  case "$fault" in
    kill) echo "faults: $robot run $i, stride-mpc killed at $kill_at s: $line" ;;
    flood) echo "faults: $robot run $i, $flood foreign policies/s: $line" ;;
    forged-flood) echo "faults: $robot run $i, $flood forged 60 kB frames/s: $line" ;;
    future) echo "faults: $robot run $i, $flood signed junk policies/s from the future: $line" ;;
    replay) echo "faults: $robot run $i, a recorded session replayed: $line" ;;
    rival) echo "faults: $robot run $i, a rival stride-mpc: $line" ;;
    kill-sim) echo "faults: $robot run $i, stride-sim killed at $kill_at s: $line" ;;
    pause) echo "faults: $robot run $i, stride-mpc stopped at $kill_at s for $pause s: $line" ;;
  esac
done
case "$fault" in
  kill) what="kills and restarts" ;;
  flood) what="runs under $flood foreign policies/s" ;;
  forged-flood) what="runs under $flood forged frames/s" ;;
  future) what="runs under $flood signed junk policies/s from the future" ;;
  replay) what="runs with a recorded session replayed" ;;
  rival) what="runs with a rival controller" ;;
  kill-sim) what="mock-robot kills and restarts" ;;
  pause) what="pauses of $pause s" ;;
esac
echo "faults: $robot: $falls falls and $lost runs where control did not come back in $runs $what (in $out)"
[ "$falls" = 0 ] || exit 4
[ "$lost" = 0 ] || exit 6
