#!/usr/bin/env bash
# README command 2: installs the packages, builds Release, runs every test through ctest.
# The tests read ../shared (reference values and public robot models) beside the repository.
set -euo pipefail
case "${1:-}" in -h|--help) sed -n '2,/^set -euo/{/^#/p}' "$0"; exit 0 ;; esac
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/tools/install-deps.sh"
"$root/tools/build.sh"
build="${STRIDE_BUILD_DIR:-$root/build}"
cd "$build"
ctest --output-on-failure -j"$(nproc 2>/dev/null || echo 2)" --timeout 600
