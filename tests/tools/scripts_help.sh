#!/usr/bin/env bash
# The scripts a user runs answer --help with their header and exit 0, doing nothing else (before,
# tools/bench/run.sh took --help for a filter and ran the whole suite, and the paper scripts
# plotted an empty folder after the program's help).
# Usage: scripts_help.sh ROOT
set -uo pipefail
root=$1
fail=0
for script in tools/demo.sh tools/test.sh tools/bench/run.sh tools/drive/sweep.sh \
              tools/paper/astronaut.sh tools/paper/large-stride.sh tools/viz.sh \
              tools/viz-screenshot.sh tools/soak.sh tools/faults.sh tools/drive/terrains.sh \
              tools/robustness.sh; do
  out=$(timeout 20 "$root/$script" --help 2>&1)
  status=$?
  if [ "$status" != 0 ] || [ "$(printf '%s\n' "$out" | head -n 1 | cut -c1)" != "#" ]; then
    echo "FAILED: $script --help: exit $status, first line '$(printf '%s\n' "$out" | head -n 1)'"
    fail=1
  fi
done
[ "$fail" = 0 ] && echo "every script answers --help"
exit "$fail"
