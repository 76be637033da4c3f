#!/usr/bin/env bash
# The CI version of issue 19's 10-minute soak: tools/soak.sh --minutes 1, the real-time closed loop
# of the quadruped (stride-sim and stride-mpc on their cores, lcm-logger on) through the soak's 30 s
# drive pattern twice (stand, trot, forward, turn, sidestep both ways). Passes on soak.sh's own
# verdict: the robot stayed up and neither program's memory grew by more than 8 MB; its report
# (falls, misses, fallbacks, lost messages, memory) is printed either way.
# Exit 77 (ctest: skipped) only when network namespaces are not permitted.
#   soak_60s.sh BUILD_DIR ROOT
set -euo pipefail
build=$1 root=$2
# shellcheck source=../private_netns.sh
source "$(dirname "$0")/../private_netns.sh"
private_netns "$@"
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
STRIDE_DEMO_NO_SETUP=1 STRIDE_BUILD_DIR="$build" "$root/tools/soak.sh" --minutes 1 --out "$dir"
