#!/usr/bin/env bash
# A robot's robustness card: its drive (config/commands/ROBOT.yaml) run by stride-drive in
# lock-step (deterministic) under one disturbance of the mock robot at a time, at increasing
# levels, and under the combined "hardware" rows (everything at once: controller/README.md,
# "Robustness"). Each run is "tracked" (no fall, every segment of 2 s or more within its
# tolerance: stride-drive --check-tracking), "missed" or "fell"; a row's threshold is the first
# level that is not tracked.
#   tools/robustness.sh ROBOT [--jobs N] [--sshloginfile FILE] [--json FILE] [--out DIR]
#                             [--only ROW]... [--config YAML] [--commands YAML] [--seed N]
# --config, --commands  another controller configuration or drive for ROBOT (default:
#                    config/controller/ROBOT.yaml, config/commands/ROBOT.yaml)
# --jobs N           runs N cases at once through GNU parallel (default: the number of cores)
# --sshloginfile F   spreads the cases over the hosts in F (GNU parallel's format, e.g.
#                    "2/user@host"); every host needs this repository, built, at the same path.
#                    PARALLEL_SSH (or --ssh CMD) replaces ssh, e.g. for hosts faked on one machine
# --json FILE        writes the card as JSON
# --only ROW         runs only this row (repeatable; the names in the first column)
# --seed N           every case's noise, drift and drop seed (1)
# Prints the table; exits 0 when every hardware row was tracked, 1 otherwise, 2 on bad arguments.
# The cases are independent runs: tools/robustness.sh --list ROBOT prints the job list, one case
# per line (row, level, stride-drive's options), and --case runs one line of it.
# tools/robustness.sh --markdown CARD.json... prints cards written by --json side by side, each
# cell the first level not tracked (controller/README.md's table).
set -euo pipefail
case "${1:-}" in -h|--help) sed -n '2,/^set -euo/{/^#/p}' "$0"; exit 0 ;; esac
root=$(cd "$(dirname "$0")/.." && pwd)
build="${STRIDE_BUILD_DIR:-$root/build}"
drive="$build/tools/stride-drive"

# The total mass [kg] of the robot of a controller YAML (stride-sim --print-model says it).
robot_mass() {
  "$build/sim/stride-sim" --robot "$(robot_yaml "$1")" --robots-dir "$build/robot_packages" \
    --print-model | sed -n 's/.*total mass \([0-9.]*\) kg.*/\1/p' | head -1
}
robot_yaml() {  # the controller YAML's robot:, relative to it
  local yaml
  yaml=$(sed -n 's/^robot: *//p' "$1" | sed 's/ *#.*//')
  case "$yaml" in /*) echo "$yaml" ;; *) echo "$(dirname "$1")/$yaml" ;; esac
}

# The job list: row<TAB>level<TAB>options. The hardware rows: what a robot's sensors and motors
# give (issue 32): joint velocity noise 0.1 rad/s, joint position 0.005 rad, base orientation
# 5 mrad, position 5 mm, velocity 0.05 m/s (the legs' odometry, through a 5 Hz complementary
# filter with an accelerometer of 0.05 m/s²: sim/README.md, "Sensing"), gyro 0.02 rad/s, 3 ms
# sensing latency, 20 % of the estimates dropped, ±20 % base mass (the trunk: batteries,
# computers, cabling; the legs' masses come from CAD), a payload of 10 % of the mass 3 cm off the
# base's centre (scaled by the robot's size), torque limits × 0.8, μ 0.4 known to the controller.
jobs_for() {
  local config=$1 mass size payload
  mass=$(robot_mass "$config")
  [ -n "$mass" ] || { echo "robustness.sh: cannot read the mass of $config's robot" >&2; exit 1; }
  # Sizes scale with the cube root of the mass: 3 cm on a 50 kg robot, 1.1 cm on a 2.5 kg one.
  size=$(awk -v m="$mass" 'BEGIN { printf "%.4f", (m / 50) ^ (1 / 3) }')
  payload() { awk -v m="$mass" -v f="$1" -v s="$size" 'BEGIN { printf "%.3f %.4f 0 0", f * m, 0.03 * s }'; }
  local hw="--joint-velocity-noise 0.1 --noise-q 0.005 --orientation-noise 0.005 \
--base-position-noise 0.005 --base-velocity-noise 0.05 --velocity-estimator 5 --accel-noise 0.05 \
--gyro-noise 0.02 --sensor-latency 3 --drop 0.2 --payload $(payload 0.1) \
--torque-limit-scale 0.8 --mu 0.4 --controller-mu 0.4"
  # A row: its name, its options with {} for the level, the levels.
  row() { local name=$1 fmt=$2; shift 2; for l in "$@"; do printf '%s\t%s\t%s\n' "$name" "$l" "${fmt//\{\}/$l}"; done; }
  row joint_velocity_noise "--joint-velocity-noise {}" 0.05 0.1 0.2 0.4
  row joint_position_noise "--noise-q {}" 0.0025 0.005 0.01 0.02
  row orientation_noise "--orientation-noise {}" 0.0025 0.005 0.01 0.02
  row gyro_noise "--gyro-noise {}" 0.02 0.05 0.1 0.2
  row gyro_bias_walk "--gyro-bias-walk {}" 0.001 0.003 0.01 0.03
  row base_position_noise "--base-position-noise {}" 0.0025 0.005 0.01 0.02
  row base_velocity_noise "--base-velocity-noise {}" 0.025 0.05 0.1 0.2
  row base_velocity_noise_estimated "--base-velocity-noise {} --velocity-estimator 5 --accel-noise 0.05" 0.025 0.05 0.1 0.2
  row base_drift "--base-drift {}" 0.01 0.03 0.1 0.3
  row encoder_resolution "--encoder-resolution {}" 0.0015 0.006 0.025 0.1
  row sensor_latency_steps "--sensor-latency {}" 3 6 12 24
  row estimate_drops "--drop {}" 0.1 0.2 0.4 0.6
  row estimate_delay_periods "--delay {}" 1 2 3 5
  row base_mass_scale "--mass-scale base:{}" 0.8 1.2 1.5 2.0
  row mass_scale "--mass-scale {}" 0.8 1.2 1.5 2.0
  for f in 0.1 0.2 0.3 0.5; do printf 'payload_mass_fraction\t%s\t--payload %s\n' "$f" "$(payload "$f")"; done
  row torque_limit_scale "--torque-limit-scale {}" 0.8 0.6 0.5 0.4
  row torque_latency_steps "--torque-latency {}" 1 2 4 8
  row torque_bandwidth_hz "--torque-bandwidth {}" 100 50 25 12
  row velocity_limits "--velocity-limits" on
  row ground_mu_known "--mu {} --controller-mu {}" 0.5 0.4 0.3 0.2
  row ground_mu_unknown "--mu {}" 0.5 0.4 0.3 0.2
  printf 'hardware\tbase_mass_x0.8\t%s --mass-scale base:0.8\n' "$hw"
  printf 'hardware\tbase_mass_x1.2\t%s --mass-scale base:1.2\n' "$hw"
}

# One case: prints one JSON line {row, level, result, ...}.
run_case() {
  local config=$1 commands=$2 name=$3 level=$4 args=$5 out=$6
  local summary="$out/${name}_${level}.json" log="$out/${name}_${level}.txt" status=0
  # shellcheck disable=SC2086  # the options are words
  "$drive" --config "$config" --commands "$commands" --robots-dir "$build/robot_packages" \
    --check-tracking --summary "$summary" $args >"$log" 2>&1 || status=$?
  python3 - "$name" "$level" "$args" "$summary" "$status" "${PARALLEL_SSHHOST:-local}" <<'EOF'
import json, sys
name, level, args, path, status, host = sys.argv[1:]
r = {"row": name, "level": level, "options": args, "host": host}
try:
    s = json.load(open(path))
    r["result"] = "fell" if s["fell"] else ("tracked" if s["tracked"] else "missed")
    r["fallbacks"] = s["fallbacks"]
    r["why"] = s.get("why")
except Exception as e:  # no summary: stride-drive refused the options or crashed
    r["result"] = "error"
    r["why"] = "stride-drive exited %s without a summary" % status
print(json.dumps(r))
EOF
}

if [ "${1:-}" = --case ]; then  # --case CONFIG COMMANDS OUT ROW LEVEL OPTIONS (one job)
  run_case "$2" "$3" "$5" "$6" "$7" "$4"
  exit 0
fi
if [ "${1:-}" = --markdown ]; then  # --markdown CARD.json... : the cards side by side (README)
  shift
  python3 - "$@" <<'EOF'
import json, sys
cards = [json.load(open(p)) for p in sys.argv[1:]]
robots = [c["robot"] for c in cards]
rows = []
for c in cards:
    for r in c["card"]:
        if r["row"] not in rows:
            rows.append(r["row"])
print("| disturbance | levels | " + " | ".join(robots) + " |")
print("| --- | --- | " + " | ".join("---" for _ in robots) + " |")
for name in rows:
    levels, cells = None, []
    for c in cards:
        r = next((x for x in c["card"] if x["row"] == name), None)
        if r is None:
            cells.append("")
            continue
        levels = levels or ", ".join(x["level"] for x in r["levels"])
        bad = [x for x in r["levels"] if x["result"] != "tracked"]
        if name == "hardware":
            cells.append("tracked" if not bad else ", ".join(f"{x['level']} {x['result']}" for x in bad))
        else:
            cells.append("all tracked" if not bad else f"{bad[0]['level']} ({bad[0]['result']})")
    print(f"| {name} | {levels} | " + " | ".join(cells) + " |")
EOF
  exit 0
fi
if [ "${1:-}" = --list ]; then
  jobs_for "$root/config/controller/${2:?usage: robustness.sh --list ROBOT}.yaml"
  exit 0
fi

robot="${1:?usage: tools/robustness.sh ROBOT [options]}"
shift
jobs=$(nproc 2>/dev/null || echo 2) json="" out="$build/robustness" sshlogin=() only=()
config="$root/config/controller/$robot.yaml" commands="$root/config/commands/$robot.yaml" seed=1
need() { [ $# -ge 2 ] || { echo "robustness.sh: $1 needs a value" >&2; exit 2; }; }
while [ $# -gt 0 ]; do
  case "$1" in
    --jobs) need "$@"; jobs="$2"; shift 2 ;;
    --sshloginfile) need "$@"; sshlogin=(--sshloginfile "$2"); shift 2 ;;
    --ssh) need "$@"; export PARALLEL_SSH="$2"; shift 2 ;;
    --json) need "$@"; json="$2"; shift 2 ;;
    --out) need "$@"; out="$2"; shift 2 ;;
    --only) need "$@"; only+=("$2"); shift 2 ;;
    --seed) need "$@"; seed="$2"; shift 2 ;;
    --config) need "$@"; config=$(realpath "$2"); shift 2 ;;
    --commands) need "$@"; commands=$(realpath "$2"); shift 2 ;;
    *) echo "robustness.sh: unknown option '$1'" >&2; exit 2 ;;
  esac
done
[ -f "$config" ] || { echo "robustness.sh: no controller configuration '$config'" >&2; exit 2; }
[ -f "$commands" ] || { echo "robustness.sh: no command script '$commands'" >&2; exit 2; }
[ -x "$drive" ] || { echo "robustness.sh: build first (tools/build.sh)" >&2; exit 1; }
command -v parallel >/dev/null || { echo "robustness.sh: needs GNU parallel (tools/install-deps.sh)" >&2; exit 1; }
out="$out/$robot"
mkdir -p "$out"
list="$out/jobs.tsv"
jobs_for "$config" | sed "s/\$/ --seed $seed/" >"$list"
if [ ${#only[@]} -gt 0 ]; then
  pattern=$(printf '^%s\t|' "${only[@]}")
  grep -E "${pattern%|}" "$list" >"$list.only" || true
  mv "$list.only" "$list"
fi
echo "robustness.sh: $robot, $(wc -l <"$list") cases, $jobs at a time${sshlogin:+ over ${sshlogin[1]}}" >&2
results="$out/results.jsonl"
# GNU parallel runs remote jobs through $SHELL: without it (a CI's bare environment) a
# --sshloginfile run does nothing and exits 0.
export SHELL="${SHELL:-/bin/bash}"
# Each job: this script's --case on one line of the list (on a remote host: the same path).
parallel --jobs "$jobs" "${sshlogin[@]}" --colsep '\t' --keep-order \
  "$root/tools/robustness.sh" --case "$config" "$commands" "$out" {1} {2} {3} <"$list" >"$results"
# Never a card with cases silently missing.
if [ "$(grep -c . "$results")" != "$(grep -c . "$list")" ]; then
  echo "robustness.sh: $(grep -c . "$list") cases, $(grep -c . "$results") results: a host did not" \
    "run its jobs (GNU parallel's --sshloginfile, ssh, this repository at the same path?)" >&2
  exit 1
fi
python3 - "$robot" "$results" "$json" <<'EOF'
import json, sys
robot, path, out = sys.argv[1:]
cases = [json.loads(line) for line in open(path) if line.strip()]
rows = {}
for c in cases:
    rows.setdefault(c["row"], []).append(c)
print(f"robustness card: {robot} (lock-step, its drive config/commands/{robot}.yaml)")
print(f"{'disturbance':24} {'levels: result':62} first fails at")
card = []
for name, cs in rows.items():
    cells = " ".join(f"{c['level']}:{c['result']}" for c in cs)
    first = next((c["level"] for c in cs if c["result"] != "tracked"), None)
    print(f"{name:24} {cells:62} {first if first else '-'}")
    card.append({"row": name, "levels": cs, "first_failure": first})
hardware = [c for c in cases if c["row"] == "hardware"]
ok = bool(hardware) and all(c["result"] == "tracked" for c in hardware)
for c in cases:
    if c["result"] != "tracked" and c.get("why"):
        print(f"  {c['row']} {c['level']}: {c['why']}")
if hardware:
    print(f"hardware rows: {'tracked' if ok else 'NOT tracked'}")
if out:
    with open(out, "w") as f:
        json.dump({"robot": robot, "card": card, "hardware_tracked": ok}, f, indent=2)
sys.exit(0 if ok or not hardware else 1)
EOF
