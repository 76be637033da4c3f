#!/usr/bin/env bash
# Opens any Stride log in the browser viewer: stride-viz --log LOG serves the page on loopback and
# prints its address (http://127.0.0.1:PORT/); play, pause, speed and scrub in the page. Builds
# first when stride-viz is missing. Stops with Ctrl-C.
#   tools/viz.sh LOG [--port P] [--robot YAML] [--robots-dir DIR]... [--open]
#   LOG            an lcm-logger log of a session (tools/demo.sh writes build/demo/session.lcmlog)
#   --port P       default 8765; 0 picks a free port
#   --robot YAML   the robot, when the log's robot_model_t names one stride-viz cannot find
#   --robots-dir   where package:// URIs are looked for (default: build/robot_packages if present)
#   --open         also open the address in the default browser (xdg-open), when there is a display
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build="${STRIDE_BUILD_DIR:-$root/build}"
case "${1:-}" in
  -h|--help) sed -n '2,/^set -euo/{/^#/p}' "$0"; exit 0 ;;
  "") echo "usage: tools/viz.sh LOG [--port P] [--robot YAML] [--robots-dir DIR]... [--open]" >&2; exit 2 ;;
esac
log=$1
shift
port=8765 open=0
args=()
while [ $# -gt 0 ]; do
  case "$1" in
    --port) port="$2"; shift 2 ;;
    --robot|--robots-dir) args+=("$1" "$2"); shift 2 ;;
    --open) open=1; shift ;;
    *) echo "viz.sh: unknown option '$1' (--help)" >&2; exit 2 ;;
  esac
done
[ -f "$log" ] || { echo "viz.sh: no log '$log'" >&2; exit 1; }
[ -x "$build/viz/stride-viz" ] || "$root/tools/build.sh"
[ -d "$build/robot_packages" ] && args+=(--robots-dir "$build/robot_packages")
if [ "$open" = 1 ] && [ -n "${DISPLAY:-}${WAYLAND_DISPLAY:-}" ] && command -v xdg-open > /dev/null; then
  (sleep 1 && xdg-open "http://127.0.0.1:$port/" > /dev/null 2>&1) &
fi
exec "$build/viz/stride-viz" --log "$log" --port "$port" "${args[@]}"
