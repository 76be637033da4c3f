#!/usr/bin/env bash
# stride-sim and stride-drive offer the mock robot's sensing, actuator and mismatch options with the
# same names, defaults and help (sim/command_line.hpp): their --help sections from "Sensing" to the
# end of "Model mismatch" are identical, and each group is there.
# Usage: mock_robot_options.sh STRIDE_SIM STRIDE_DRIVE
set -euo pipefail
groups() { "$1" --help | sed -n '/^Sensing (/,$p' | grep -v '^Exit status' | awk 'NF'; }
a=$(groups "$1")
b=$(groups "$2")
if [ "$a" != "$b" ]; then
  echo "FAILED: the mock robot's options differ between stride-sim and stride-drive:"
  diff <(printf '%s\n' "$a") <(printf '%s\n' "$b") || true
  exit 1
fi
for g in "Sensing (" "Actuators (" "Model mismatch ("; do
  printf '%s\n' "$a" | grep -q "^$g" || { echo "FAILED: no group '$g' in the help"; exit 1; }
done
for o in --sensor-latency --velocity-estimator --torque-bandwidth --velocity-limits --mass-scale \
         --payload --com-offset --torque-limit-scale --mu; do
  printf '%s\n' "$a" | grep -q -- "$o" || { echo "FAILED: no $o in the help"; exit 1; }
done
echo "stride-sim and stride-drive: the same $(printf '%s\n' "$a" | grep -c '^  --') mock robot options"
