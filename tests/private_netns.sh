# Sourced by the tests that run programs as separate processes over LCM UDP multicast:
#   source "$(dirname "$0")/../private_netns.sh"; private_netns "$@"
# re-runs the calling script in a network namespace of its own (as root, or as a user namespace's
# root) with only lo, brought up, and multicast routed to it, so nothing reaches the host's
# network (with ttl=0 in the LCM URL). Exits 77 (ctest: skipped) only when namespaces are not
# permitted, and 1 when an interface other than lo is visible.
private_netns() {
  if [ -z "${STRIDE_NETNS:-}" ]; then
    local ns=(unshare --net)
    [ "$(id -u)" -ne 0 ] && ns=(unshare --user --map-root-user --net)
    if ! "${ns[@]}" true 2>/dev/null; then
      echo "SKIPPED: network namespaces are not permitted here (unshare --net failed)"
      exit 77
    fi
    STRIDE_NETNS=1 exec "${ns[@]}" "$0" "$@"
  fi
  ip link set lo up
  ip route add 224.0.0.0/4 dev lo
  [ "$(awk -F: 'NR > 2 { gsub(/ /, "", $1); print $1 }' /proc/net/dev | sort -u)" = lo ] || {
    echo "not a private namespace: refusing to multicast" >&2
    exit 1
  }
}
