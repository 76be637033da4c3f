#!/usr/bin/env bash
# A stand-in for ssh in GNU parallel's --sshloginfile runs (tests/tools/robustness_hosts.sh): "ssh
# HOST -- COMMAND" runs COMMAND here, in a network namespace of its own (unshare -rn: a host with
# no network but its own loopback), with FAKE_HOST set to HOST.
host=$1
shift
[ "${1:-}" = -- ] && shift
exec unshare -rn env FAKE_HOST="$host" bash -c "$*"
