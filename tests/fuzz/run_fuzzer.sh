#!/usr/bin/env bash
# The ctest fuzz_messages: the libFuzzer binary for RUNS inputs from seed 1, on a copy of the seed
# corpus in WORK/corpus (libFuzzer adds the inputs that reach new code to it); a crashing input is
# written to WORK/artifacts/ (replay it with stride-fuzz-replay FILE). Exit 0 when no input failed.
#   run_fuzzer.sh FUZZER CORPUS WORK RUNS [libFuzzer flags...]
set -euo pipefail
fuzzer=$1 corpus=$2 work=$3 runs=$4
shift 4
rm -rf "$work"
mkdir -p "$work/corpus" "$work/artifacts"
cp "$corpus"/* "$work/corpus/"
exec "$fuzzer" -runs="$runs" -seed=1 -print_final_stats=1 -artifact_prefix="$work/artifacts/" \
  "$@" "$work/corpus"
