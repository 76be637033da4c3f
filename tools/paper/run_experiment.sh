#!/usr/bin/env bash
# What every experiment script of tools/paper does (sourced by astronaut.sh and large-stride.sh):
# builds its program if it is missing, runs it with --out DIR, its motions' LCM logs and the other
# options, then draws the plots with Debian's matplotlib. The snapshot figures are frames of
# stride-viz's page in headless Chromium (snapshots.py) when Chromium, node and the built viewer
# are there; otherwise stick figures, and one line says why.
#   run_experiment NAME PROGRAM PLOT_SCRIPT DEFAULT_OUT_SUBDIR "$@"
run_experiment() {
  local name="$1" program="$2" plot="$3" subdir="$4"
  shift 4
  local root build out args=() log_args=()
  root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
  build="${STRIDE_BUILD_DIR:-$root/build}"
  out="$build/paper/$subdir"
  local bin="$build/tools/paper/$program"
  while [ $# -gt 0 ]; do
    case "$1" in
      # The script's own header, then the program's options; nothing is solved or plotted.
      -h|--help)
        sed -n '2,/^set -euo/{/^#/p}' "$0"
        echo
        [ -x "$bin" ] && "$bin" --help
        return 0 ;;
      --out) out="$2"; shift 2 ;;
      --out=*) out="${1#--out=}"; shift ;;
      *) args+=("$1"); shift ;;
    esac
  done
  if [ ! -x "$bin" ]; then
    "$root/tools/build.sh" >/dev/null
  fi
  mkdir -p "$out"
  # The motions as LCM logs (stride-viz --log plays them; the snapshots are drawn from them).
  case "$program" in
    stride-paper-astronaut) log_args=(--log "$out/session.lcmlog") ;;
    stride-paper-large-stride) log_args=(--logs) ;;
  esac
  # One thread unless OMP_NUM_THREADS says otherwise (the README's timings are on one core).
  OMP_NUM_THREADS="${OMP_NUM_THREADS:-1}" "$bin" --out "$out" "${log_args[@]}" "${args[@]}"
  # Debian's python3-matplotlib lives under /usr/bin/python3; a python3 earlier on PATH (pyenv,
  # a venv) may not see it.
  local py="" candidate
  for candidate in python3 /usr/bin/python3; do
    if "$candidate" -c "import matplotlib" 2>/dev/null; then py="$candidate"; break; fi
  done
  if [ -n "$py" ]; then
    local viewer="$build/viz/stride-viz" modules="$build/viz/web/npm/node_modules" why
    local plot_args=(--viewer "$viewer" --node-modules "$modules")
    if ! why=$(cd "$root/tools/paper" && "$py" -c \
        'import sys, snapshots; print(snapshots.browser_missing(sys.argv[1], sys.argv[2]) or "")' \
        "$viewer" "$modules"); then
      why="snapshots.py does not load"
    fi
    if [ -n "$why" ]; then
      echo "$name: snapshots as stick figures: $why"
      plot_args=()
    fi
    "$py" "$root/tools/paper/$plot" "$out" "${plot_args[@]}"
  else
    echo "$name: python3-matplotlib missing (tools/install-deps.sh installs it): no plots" >&2
  fi
}
