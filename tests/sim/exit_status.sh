#!/usr/bin/env bash
# stride-sim's exit status tells how the run ended (sim/README.md): 0 upright, 4 fallen, 2 a usage
# error, 1 an error of its files (a terrain file that is refused, said with the file and the key:
# terrain/README.md, "Errors"). No controller: the hold PD keeps the quadruped up for a second at its default gains and
# lets it collapse at zero gains. In-process LCM (memq://): nothing goes on any network.
# Usage: exit_status.sh STRIDE_SIM ROBOT_YAML
set -euo pipefail
sim=$1 robot=$2
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
run() {  # expected-status name args...
  local expected=$1 name=$2 status=0
  shift 2
  "$sim" --robot "$robot" --url memq:// --summary "$out/$name.json" "$@" > "$out/$name.txt" 2>&1 ||
    status=$?
  if [ "$status" != "$expected" ]; then
    cat "$out/$name.txt"
    echo "FAILED: $name: stride-sim exited $status, expected $expected"
    exit 1
  fi
}
run 0 stands --duration 1
grep -q '"fell": false' "$out/stands.json" || { echo "FAILED: stands: summary"; exit 1; }
run 4 collapses --duration 3 --hold-kp 0 --hold-kd 0
grep -q 'stride-sim: the robot fell at t = ' "$out/collapses.txt" ||
  { cat "$out/collapses.txt"; echo "FAILED: collapses: no fall message"; exit 1; }
grep -q '"fell": true' "$out/collapses.json" || { echo "FAILED: collapses: summary"; exit 1; }
run 2 usage --duration 1 --push 1:2
printf 'stairs:\n  - {start: [1, 0], steps: 2, rise: 0.1, run: -0.25, width: 1}\n' > "$out/mine.yaml"
run 1 bad_terrain --duration 1 --terrain "$out/mine.yaml"
grep -qF "stride-sim: terrain file '$out/mine.yaml': stairs[0].run: must be > 0 (got -0.25)" \
  "$out/bad_terrain.txt" || { cat "$out/bad_terrain.txt"; echo "FAILED: bad_terrain: message"; exit 1; }
echo "stride-sim exit statuses: 0 standing, 4 fallen, 2 usage error, 1 a refused terrain file"
