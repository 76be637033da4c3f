#!/usr/bin/env bash
# lcm-spy with Stride's message types on the CLASSPATH, so it decodes every Stride channel (state,
# policy, status, plan, command, model; tests/messages/lcm_spy_decodes.sh checks it). Arguments go
# to lcm-spy (e.g. --lcm-url='udpm://...?ttl=0').
# Inside the demo's private network namespace: tools/demo.sh --spy starts it there.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
jar="${STRIDE_BUILD_DIR:-$here/build}/messages/stride_lcm_types.jar"
if [ ! -f "$jar" ]; then
  echo "lcm-spy.sh: $jar not built (needs a JDK: tools/install-deps.sh, then tools/build.sh)" >&2
  exit 1
fi
command -v lcm-spy >/dev/null || { echo "lcm-spy.sh: lcm-spy missing (liblcm-java)" >&2; exit 1; }
export CLASSPATH="$jar${CLASSPATH:+:$CLASSPATH}"
# Debian's wrapper passes -Xincgc, which Java 17 refuses: let the JVM ignore it.
export JAVA_TOOL_OPTIONS="-XX:+IgnoreUnrecognizedVMOptions${JAVA_TOOL_OPTIONS:+ $JAVA_TOOL_OPTIONS}"
exec lcm-spy "$@"
