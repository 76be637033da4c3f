#!/usr/bin/env bash
# tools/demo.sh's options about what it runs on (issue 34), all refused or printed before any
# set-up: --help documents --no-setup and --config; --robot takes a shipped robot's name only (a
# path disguised as a name is a usage error), --config a file that exists, not both.
#   demo_options.sh ROOT
set -uo pipefail
root=$1
demo="$root/tools/demo.sh"
fail=0
help=$("$demo" --help) || { echo "FAIL: --help exited $?"; fail=1; }
for option in --no-setup --config STRIDE_DEMO_NO_SETUP; do
  printf '%s\n' "$help" | grep -q -- "$option" || { echo "FAIL: --help does not mention $option"; fail=1; }
done
usage_error() {  # EXPECTED_TEXT ARGS...
  local text=$1 out status=0
  shift
  out=$(STRIDE_DEMO_NO_SETUP=1 timeout 20 "$demo" "$@" 2>&1) || status=$?
  if [ "$status" != 2 ] || ! printf '%s\n' "$out" | grep -q -- "$text"; then
    echo "FAIL: demo.sh $*: exit $status, '$out'"
    fail=1
  fi
}
usage_error "no robot '../config/controller/stride_quad'" --robot ../config/controller/stride_quad
usage_error "no robot 'stride_quad.yaml'" --robot stride_quad.yaml
usage_error "no configuration file" --config "$root/no/such/file.yaml"
usage_error "not both" --robot solo12 --config "$root/config/controller/solo12.yaml"
usage_error "needs a value" --config
[ "$fail" = 0 ] && echo "demo.sh: --help documents --no-setup and --config; bad robots refused"
exit "$fail"
