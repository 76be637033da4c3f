#!/usr/bin/env bash
# The paper's large strides on flat ground (§V-A, Fig. 2-4) with one command: builds
# stride-paper-large-stride if it is missing, runs the IK baseline and KKT-DDP for each stride
# length, walks the DDP motion on the mock robot (closed loop), prints the table, writes the trajectories
# (CSV / JSON) and the plots (PNG) into --out DIR. Other options go to the program
# (stride-paper-large-stride --help), e.g. --lengths 0.8 1.0 --iterations 100.
#   tools/paper/large-stride.sh --out build/paper/large_stride
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
build="${STRIDE_BUILD_DIR:-$root/build}"
out="$build/paper/large_stride"
args=()
while [ $# -gt 0 ]; do
  case "$1" in
    --out) out="$2"; shift 2 ;;
    --out=*) out="${1#--out=}"; shift ;;
    *) args+=("$1"); shift ;;
  esac
done
bin="$build/tools/paper/stride-paper-large-stride"
if [ ! -x "$bin" ]; then
  nice -n 19 cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release >/dev/null
  nice -n 19 cmake --build "$build" -j1 --target stride-paper-large-stride >/dev/null
fi
mkdir -p "$out"
nice -n 19 "$bin" --out "$out" "${args[@]}"
# Debian's python3-matplotlib lives under /usr/bin/python3; a python3 earlier on PATH (pyenv,
# a venv) may not see it.
py=""
for candidate in python3 /usr/bin/python3; do
  if "$candidate" -c "import matplotlib" 2>/dev/null; then py="$candidate"; break; fi
done
if [ -n "$py" ]; then
  "$py" "$root/tools/paper/plot_large_stride.py" "$out"
else
  echo "large-stride.sh: python3-matplotlib missing (tools/install-deps.sh installs it): no plots" >&2
fi
