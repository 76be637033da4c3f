#!/usr/bin/env bash
# The paper's astronaut reorientation (§V-B, Fig. 5-6) with one command: builds
# stride-paper-astronaut if it is missing, solves, prints the table, writes the trajectories
# (CSV / JSON) and the plots (PNG) into --out DIR. Other options go to the program
# (stride-paper-astronaut --help), e.g. --knots 4500 --waypoints 36. One thread unless
# OMP_NUM_THREADS says otherwise (the README's timings are on one core).
#   tools/paper/astronaut.sh --out build/paper/astronaut
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
build="${STRIDE_BUILD_DIR:-$root/build}"
out="$build/paper/astronaut"
args=()
while [ $# -gt 0 ]; do
  case "$1" in
    --out) out="$2"; shift 2 ;;
    --out=*) out="${1#--out=}"; shift ;;
    *) args+=("$1"); shift ;;
  esac
done
bin="$build/tools/paper/stride-paper-astronaut"
if [ ! -x "$bin" ]; then
  "$root/tools/build.sh" >/dev/null
fi
mkdir -p "$out"
OMP_NUM_THREADS="${OMP_NUM_THREADS:-1}" "$bin" --out "$out" "${args[@]}"
# Debian's python3-matplotlib lives under /usr/bin/python3; a python3 earlier on PATH (pyenv,
# a venv) may not see it.
py=""
for candidate in python3 /usr/bin/python3; do
  if "$candidate" -c "import matplotlib" 2>/dev/null; then py="$candidate"; break; fi
done
if [ -n "$py" ]; then
  "$py" "$root/tools/paper/plot_astronaut.py" "$out"
else
  echo "astronaut.sh: python3-matplotlib missing (tools/install-deps.sh installs it): no plots" >&2
fi
