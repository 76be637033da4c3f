#!/usr/bin/env bash
# Installs the Debian 12 packages Stride builds and runs with; runs `apt-get update` first only
# when something is missing. Needs root (or sudo). Used by tools/demo.sh and tools/test.sh.
#   (no argument)  everything tools/test.sh builds and runs: the programs, the tests, the
#                  benchmarks, the viewer and its browser test, lcm-spy's jar, the paper's plots
#   --sanitize     that, and clang 14 with its sanitizer and libFuzzer runtimes (test.sh --sanitize)
#   --demo         only what tools/demo.sh builds and runs: the compiler, the libraries and LCM
#                  (a newcomer's first walk waits for no browser, JDK or test framework)
#   --viz, --spy   with --demo: also the viewer's (Node.js, npm, socat) or lcm-spy's (a JDK) packages
set -euo pipefail

# What the demo's programs need to configure, build and run (tools/demo.sh).
demo=(
  build-essential cmake ninja-build ccache pkg-config
  libeigen3-dev            # linear algebra (3.4)
  liburdfdom-dev           # URDF parsing
  libtinyxml-dev           # SRDF parsing (urdfdom's own XML library)
  libyaml-cpp-dev          # configuration files
  libcli11-dev             # command lines
  nlohmann-json3-dev       # JSON the programs write (run summaries, experiment results)
  libsodium-dev            # message signing: HMAC-SHA256, random keys and sender ids
  libssl-dev               # message signing: SHA-256 of the payload (libcrypto)
  libomp-dev               # OpenMP (per-knot parallelism)
  liblcm-dev liblcm-bin    # LCM 1.3: messages, lcm-gen, lcm-logger, lcm-logplayer
  libboost-dev             # stride-viz: Boost.Beast (HTTP, WebSocket) and Asio, header-only
                           # (configured with the rest, so a later --viz only builds)
  iproute2 util-linux      # ip, unshare, taskset: the demo's private network namespace, pinning
)
viz=(
  nodejs npm               # viz/web: npm ci (the lock file's packages) and esbuild build stride-viz's page
  socat                    # demo.sh --viz: the viewer's port from the demo's namespace to the host
)
spy=(
  liblcm-java libjchart2d-java  # lcm-spy, and lcm.jar to compile our types for it
  openjdk-17-jdk-headless  # javac: the jar of our message types that lcm-spy decodes with
)
tests=(
  clang-format
  libgtest-dev libgmock-dev  # tests
  libbenchmark-dev         # tools/bench
  curl                     # tests: the viewer through demo.sh --viz's forward
  python3-matplotlib       # tools/paper: the experiments' plots
  parallel                 # tools/robustness.sh --jobs: GNU parallel runs the card's cases
  chromium                 # viz/web/test: the page's browser test, headless
)
sanitize=(
  clang-14                 # tools/test.sh --sanitize: the compiler (OpenMP: libomp-dev above)
  libclang-rt-14-dev       # AddressSanitizer, UndefinedBehaviorSanitizer and libFuzzer
  llvm-14                  # llvm-symbolizer-14: file and line in the sanitizers' reports
)

packages=("${demo[@]}")
profile=all
for a in "$@"; do
  case "$a" in
    -h|--help) sed -n '2,/^set -euo/{/^#/p}' "$0"; exit 0 ;;
    --demo) profile=demo ;;
    --viz) packages+=("${viz[@]}") ;;
    --spy) packages+=("${spy[@]}") ;;
    --sanitize) packages+=("${sanitize[@]}") ;;
    *) echo "install-deps: unknown argument '$a'" >&2; exit 2 ;;
  esac
done
[ "$profile" = all ] && packages+=("${viz[@]}" "${spy[@]}" "${tests[@]}")

missing=()
for p in "${packages[@]}"; do
  # A Node.js from elsewhere than Debian (NodeSource's nodejs) brings its own npm and conflicts
  # with Debian's npm package: an npm on the PATH is enough.
  if [ "$p" = npm ] && command -v npm >/dev/null; then continue; fi
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi
sudo=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "install-deps: need root to install: ${missing[*]}" >&2; exit 1; }
  sudo="sudo"
fi
echo "install-deps: installing ${missing[*]}"
# Another apt (unattended upgrades, a second checkout's install) may hold the lock: wait for it.
lock=(-o DPkg::Lock::Timeout=600)
$sudo apt-get "${lock[@]}" update -qq
DEBIAN_FRONTEND=noninteractive $sudo apt-get "${lock[@]}" install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "install-deps: done"
