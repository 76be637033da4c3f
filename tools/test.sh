#!/usr/bin/env bash
# README command 2: installs the packages, builds Release, runs every test through ctest.
# The tests read ../shared (reference values and public robot models) beside the repository.
#   tools/test.sh              Release in build/ ($STRIDE_BUILD_DIR), every test
#   tools/test.sh --sanitize   clang-14 with AddressSanitizer and UndefinedBehaviorSanitizer and
#                              the message fuzzer (STRIDE_FUZZ) in build-sanitize/
#                              ($STRIDE_SANITIZE_BUILD_DIR): every test but the labels that cannot
#                              mean anything under a sanitizer, printed with why (tests/README.md,
#                              "Sanitizers")
set -euo pipefail
usage() { sed -n '2,/^set -euo/{/^#/p}' "$0"; }
sanitize=0
case "${1:-}" in
  -h|--help) usage; exit 0 ;;
  --sanitize) sanitize=1 ;;
  "") ;;
  *) echo "tools/test.sh: unknown argument '$1'" >&2; usage >&2; exit 2 ;;
esac
root=$(cd "$(dirname "$0")/.." && pwd)
jobs=$(nproc 2>/dev/null || echo 2)

if [ "$sanitize" = 0 ]; then
  "$root/tools/install-deps.sh"
  # Tests and benchmarks on, whatever an earlier tools/demo.sh configured (it builds without).
  "$root/tools/build.sh" -DSTRIDE_BUILD_TESTS=ON -DSTRIDE_BUILD_BENCH=ON
  cd "${STRIDE_BUILD_DIR:-$root/build}"
  exec ctest --output-on-failure -j"$jobs" --timeout 600
fi

"$root/tools/install-deps.sh" --sanitize
build="${STRIDE_SANITIZE_BUILD_DIR:-$root/build-sanitize}"
# -O3, Release's level: sanitized closed loops ran 1.1x faster than at -O2 and 1.4x than at -O1
# (tests/README.md, "Sanitizers"). Line tables: file and line in the reports, at a fraction of full
# debug information's size.
flags="-fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer"
flags+=" -gline-tables-only"
# With debug information ccache hashes the build folder too: without, a fresh clone elsewhere
# reuses the objects (CCACHE_BASEDIR, set by build.sh, makes their paths relative).
export CCACHE_NOHASHDIR=true
# Without tools/bench: its one test (bench_config) is left out below, so its nine files, slow to
# compile under the sanitizers, would be built for nothing.
# The harness (the tests' and the programs' own files) at -O0: the tests spend their time in the
# libraries, still at -O3, and the harness was most of this build's time at -O3 (tests/README.md,
# "CI's time").
STRIDE_BUILD_DIR="$build" "$root/tools/build.sh" \
  -DCMAKE_CXX_COMPILER=clang++-14 -DCMAKE_CXX_FLAGS="$flags" \
  -DCMAKE_CXX_FLAGS_RELEASE="-O3 -DNDEBUG" -DSTRIDE_HARNESS_CXX_FLAGS=-O0 -DSTRIDE_FUZZ=ON \
  -DSTRIDE_BUILD_TESTS=ON -DSTRIDE_BUILD_BENCH=OFF

# Tests whose question a sanitizer changes, excluded by label (tests/CMakeLists.txt).
excluded=(
  "realtime|real time against the wall clock: the sanitizers make the work 8-20x slower, so its deadlines are missed by design"
  "package|installs Stride and builds a consumer project against it: a build-system test, not about memory (and the consumer is not built with the sanitizers)"
  "openmp_alloc|counts allocations with 2 OpenMP threads: clang's libomp allocates in every parallel region, gcc's libgomp does not (tests/README.md)"
  "sanitize_slow|long runs of a path another test runs shorter here: the lock-step closed loops of the faults (Faults.*, ControllerLoss.*, ClosedLoop.WithSigning*, ClosedLoop.QuadrupedStandsThenTrots, ClosedLoop.ARivalController*, SignedReplay.AJunkMessage*, SignedReplay.ARestartedSender*, CommandsClosedLoop.*), whose faults Faults.EveryFaultInTurnInOneSignedDrive runs in turn in one drive (another model's policies: SimNode.StatesCarryTheModelHash* and the fuzz corpus; malformed commands: NodeCommands.RefusedCommands* and the corpus); the astronaut with its legs alone, the mirrored legs in Astronaut.Mirrored*; the terrain walks TerrainWithMap.*, TerrainBlind.*, whose paths BlindGroundOffset.* and TerrainMap.* run; two of the four blind ground offsets, anymal_c_lower_5cm and talos_reduced_higher_5cm, whose early and late touch-downs anymal_c_higher_5cm and talos_reduced_lower_5cm run; the robustness cards' drives robustness_*, whose sensing, actuator and mismatch paths test_sensing, test_sim_node and ClosedLoop.QuadrupedTrotsWithNoiseDelayAndDrops run; stride-init's six drives init_robots_drives, whose set-up init_robots runs with --no-drive; sweep_config's sweep and bench_config's benchmark, whose drive and tick drive_exit_status and ControllerNoAllocation.* run; the demo's runs demo_viz and demo_terrain, whose programs closed_loop_two_processes runs; paper_snapshots, whose solves Astronaut.Mirrored* and large_stride.* run and whose log playback viz_session_log runs: one to over 10 minutes each under the sanitizers (tests/README.md, \"Sanitizers\")"
)
labels=()
for e in "${excluded[@]}"; do
  label=${e%%|*}
  n=$(cd "$build" && ctest -N -L "^${label}\$" | sed -n 's/^Total Tests: //p')
  echo "test.sh --sanitize: excluded label '$label' (${n:-0} tests): ${e#*|}"
  labels+=("$label")
done
label_regex="^($(IFS='|'; echo "${labels[*]}"))\$"

# LeakSanitizer on; the reports symbolized; any finding fails its test.
export ASAN_OPTIONS="detect_leaks=1:check_initialization_order=1:strict_init_order=1:abort_on_error=0:halt_on_error=1:${ASAN_OPTIONS:-}"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:${UBSAN_OPTIONS:-}"
export ASAN_SYMBOLIZER_PATH="${ASAN_SYMBOLIZER_PATH:-$(command -v llvm-symbolizer-14 || true)}"
cd "$build"
exec ctest --output-on-failure -j"$jobs" --timeout 900 -LE "$label_regex"
