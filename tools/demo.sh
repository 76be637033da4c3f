#!/usr/bin/env bash
# README command 1: installs the packages, builds Release and runs the demo.
# Today the demo shows Stride's dynamics core on the in-house robots (models, contacts, and the
# cost of each algorithm); the closed-loop demo (mock robot + controller over LCM) replaces it
# when the controller lands.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/tools/install-deps.sh"
"$root/tools/build.sh"
build="${STRIDE_BUILD_DIR:-$root/build}"
exec "$build/tools/stride-dynamics-demo" "$@"
