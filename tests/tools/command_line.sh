#!/usr/bin/env bash
# Every program keeps the command-line conventions (config/command_line.hpp): `--version` prints
# "<name> <version>" and exits 0, `--help` exits 0, and an unknown option exits 2 with the usage
# line on stderr.
# Usage: command_line.sh VERSION PROGRAM...
set -uo pipefail
version=$1
shift
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
fail=0
for program in "$@"; do
  name=$(basename "$program")
  v=$("$program" --version 2>&1)
  status=$?
  if [ "$status" != 0 ] || [ "$v" != "$name $version" ]; then
    echo "FAILED: $name --version: exit $status, printed '$v' (expected '$name $version')"
    fail=1
  fi
  "$program" --help > "$out/help" 2>&1
  status=$?
  if [ "$status" != 0 ] || ! grep -q -- "--version" "$out/help"; then
    echo "FAILED: $name --help: exit $status"
    fail=1
  fi
  "$program" --no-such-option > "$out/err" 2>&1
  status=$?
  if [ "$status" != 2 ] || ! grep -q "^Usage: $name" "$out/err"; then
    echo "FAILED: $name --no-such-option: exit $status (expected 2 and the usage line):"
    cat "$out/err"
    fail=1
  fi
done
[ "$fail" = 0 ] && echo "$# programs: --version, --help, usage errors exit 2"
exit "$fail"
