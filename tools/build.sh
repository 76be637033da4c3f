#!/usr/bin/env bash
# Configures and builds Release into build/ (or $STRIDE_BUILD_DIR). Shared by demo.sh and test.sh.
#   tools/build.sh [--target NAME]... [CMAKE_CONFIGURE_ARGS]...
# --target (repeatable) builds only those targets and what they need (tools/demo.sh: the programs
# of the run); without, everything. Other arguments go to cmake's configure step.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build="${STRIDE_BUILD_DIR:-$root/build}"
jobs=$(nproc 2>/dev/null || echo 2)
targets=() configure=()
while [ $# -gt 0 ]; do
  case "$1" in
    --target) [ $# -ge 2 ] || { echo "build.sh: --target needs a name" >&2; exit 2; }
              targets+=(--target "$2"); shift 2 ;;
    *) configure+=("$1"); shift ;;
  esac
done
# ccache hashes paths relative to the repository: a fresh clone elsewhere reuses the objects.
export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$root}"
# Ninja for a new build folder: it keeps both cores busy across targets where make's recursion
# waits target by target, and its log (.ninja_log) times every step (tests/README.md, "CI's time").
# A folder configured before keeps its generator.
generator=()
[ -f "$build/CMakeCache.txt" ] || generator=(-G Ninja)
cmake -S "$root" -B "$build" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release "${configure[@]}" >/dev/null
cmake --build "$build" -j"$jobs" "${targets[@]}"
