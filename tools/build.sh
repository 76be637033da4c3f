#!/usr/bin/env bash
# Configures and builds Release into build/ (or $STRIDE_BUILD_DIR). Shared by demo.sh and test.sh;
# extra arguments go to cmake's configure step.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build="${STRIDE_BUILD_DIR:-$root/build}"
jobs=$(nproc 2>/dev/null || echo 2)
# ccache hashes paths relative to the repository: a fresh clone elsewhere reuses the objects.
export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$root}"
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release "$@" >/dev/null
cmake --build "$build" -j"$jobs"
