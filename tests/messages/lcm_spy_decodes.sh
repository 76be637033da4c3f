#!/usr/bin/env bash
# lcm-spy decodes every Stride channel, signed or not (issue 17: the model message shows, state
# and policy stay decodable; issue 33: signed): a short in-process drive (on a terrain: its elevation maps too) writes a log of all
# channels, and LcmSpyDecodes.java looks
# each message's class up by fingerprint the way lcm-spy does, from stride_lcm_types.jar. The
# elevation map (terrain_t) also from a map with unknown (NaN) cells the C++ encoder wrote, and the
# horizon (horizon_t) from one with chosen footholds (issue 31): the fuzzer's seed corpus (its
# ctest fuzz_corpus_current keeps it current).
#   lcm_spy_decodes.sh STRIDE_DRIVE JAR CONFIG_DIR
set -euo pipefail
drive=$1 jar=$2 config=$3
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
lcm_jar=/usr/share/java/lcm.jar
"$drive" --config "$config/controller/stride_quad.yaml" \
  --commands "$config/commands/stride_quad.yaml" --terrain step_up_down --duration 1.5 \
  --log "$dir/session.lcmlog" > /dev/null
javac -nowarn -cp "$lcm_jar" -d "$dir" "$(dirname "$0")/LcmSpyDecodes.java"
# jchart2d: lcm-spy's charts, which the class scan loads with lcm.jar.
java -cp "$jar:$lcm_jar:/usr/share/java/jchart2d.jar:$dir" LcmSpyDecodes "$dir/session.lcmlog" STRIDE_STATE=robot_state_t \
  STRIDE_POLICY=policy_t STRIDE_STATUS=mpc_status_t STRIDE_MODEL=robot_model_t STRIDE_COMMAND=command_t \
  STRIDE_TERRAIN=terrain_t STRIDE_HORIZON=horizon_t \
  "corpus:$(dirname "$0")/../fuzz/corpus/viz_terrain-box_step=terrain_t" \
  "corpus:$(dirname "$0")/../fuzz/corpus/viz_horizon-standing=horizon_t"
# Signed messages (issue 33: a signature trailer after the LCM bytes) decode the same: lcm-spy reads
# from the front. A session with signing on, its key made here (mode 0600, as stride-keygen's).
python3 -c "import os, sys; fd = os.open(sys.argv[1], os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600); os.write(fd, (os.urandom(32).hex() + '\n').encode())" "$dir/key"
"$drive" --config "$config/controller/stride_quad.yaml" \
  --commands "$config/commands/stride_quad.yaml" --terrain step_up_down --duration 1.5 \
  --key-file "$dir/key" --log "$dir/signed.lcmlog" > /dev/null
java -cp "$jar:$lcm_jar:/usr/share/java/jchart2d.jar:$dir" LcmSpyDecodes "$dir/signed.lcmlog" STRIDE_STATE=robot_state_t \
  STRIDE_POLICY=policy_t STRIDE_STATUS=mpc_status_t STRIDE_MODEL=robot_model_t STRIDE_COMMAND=command_t \
  STRIDE_TERRAIN=terrain_t STRIDE_HORIZON=horizon_t
