#!/usr/bin/env bash
# Builds and runs the consumer program (main.cpp) against Stride as a user gets it, without any
# flag of Stride's (no -march): `install` installs the build tree BUILD into a prefix under it and
# finds it with find_package(Stride 0.1); `subdir` adds the source tree ROOT with add_subdirectory
# (the libraries are compiled again; ccache makes that quick). The work stays in BUILD/consumer/.
# Usage: run.sh install|subdir BUILD ROOT
set -euo pipefail
mode=$1 build=$(cd "$2" && pwd) root=$(cd "$3" && pwd)
here=$(cd "$(dirname "$0")" && pwd)
work="$build/consumer/$mode"
mkdir -p "$build/consumer"
jobs=2  # the CI machines have two cores; other tests may be timing-sensitive
args=(-DCMAKE_BUILD_TYPE=Release)
if command -v ccache >/dev/null; then args+=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache); fi

step() { echo "== $*"; }
case "$mode" in
  install)
    prefix="$build/consumer/prefix"
    rm -rf "$prefix"
    step "cmake --install $build --prefix $prefix"
    cmake --install "$build" --prefix "$prefix" >"$build/consumer/install.log"
    # What the package promises besides the libraries.
    for f in bin/stride-mpc bin/stride-sim bin/stride-drive bin/stride-log-summary \
             include/stride/solver/multibody/rnea.hpp include/stride/config/robot_config.hpp \
             include/stride/locomotion/locomotion_problem.hpp include/stride/terrain/terrain.hpp \
             include/stride/robot_state_t.hpp lib/cmake/Stride/StrideTargets.cmake \
             share/stride/messages/robot_state_t.lcm \
             share/stride/config/robots/stride_quad/stride_quad.yaml \
             share/stride/config/controller/stride_quad.yaml; do
      [ -e "$prefix/$f" ] || { echo "FAILED: $f is not installed" >&2; exit 1; }
    done
    # Issue 34: the headers are <stride/...> only. The targets' include directory is include/
    # (not include/stride, where "config/robot_config.hpp" would be found), and the installed
    # headers include each other in that form (no quoted include, which would need another path).
    dirs=$(grep -ho 'INTERFACE_INCLUDE_DIRECTORIES "[^"]*"' "$prefix"/lib/cmake/Stride/StrideTargets.cmake |
           sed 's/^[^"]*"//; s/"$//' | tr ';' '\n' | sort -u)
    # shellcheck disable=SC2016  # the file's own text, not a shell variable
    if [ "$dirs" != '${_IMPORT_PREFIX}/include' ]; then
      echo "FAILED: the installed targets' include directories are not include/ alone:" >&2
      echo "$dirs" >&2
      exit 1
    fi
    if grep -rn '^[[:space:]]*#[[:space:]]*include[[:space:]]*"' "$prefix/include/stride"; then
      echo "FAILED: installed headers include with quotes (above), not <stride/...>" >&2
      exit 1
    fi
    args+=(-DCMAKE_PREFIX_PATH="$prefix")
    robot="$prefix/share/stride/config/robots/stride_quad/stride_quad.yaml"
    ;;
  subdir)
    args+=(-DSTRIDE_SOURCE_DIR="$root" -DSTRIDE_BUILD_TESTS=OFF -DSTRIDE_BUILD_BENCH=OFF)
    robot="$root/config/robots/stride_quad/stride_quad.yaml"
    ;;
  *)
    echo "usage: run.sh install|subdir BUILD ROOT" >&2
    exit 2
    ;;
esac

step "configure ($mode)"
cmake -S "$here" -B "$work" "${args[@]}" >"$work.configure.log" 2>&1 ||
  { cat "$work.configure.log"; exit 1; }
step "build ($mode)"
cmake --build "$work" -j"$jobs" >"$work.build.log" 2>&1 || { cat "$work.build.log"; exit 1; }
# The point of the test: the program itself was compiled without Stride's instruction-set flag.
if grep '"command":.*consumer/main\.cpp' "$work/compile_commands.json" | grep -q -- '-march'; then
  echo "FAILED: main.cpp was compiled with -march (from Stride's targets?)" >&2
  exit 1
fi
# And the in-tree short form does not compile for a user (found nowhere on the include path).
step "short include must fail ($mode)"
if cmake --build "$work" --target stride-consumer-short-include >"$work.short.log" 2>&1; then
  echo "FAILED: a consumer compiled #include \"config/robot_config.hpp\" (short form)" >&2
  exit 1
fi
if ! grep -Eq "config/robot_config\.hpp.*(No such file|not found)" "$work.short.log"; then
  cat "$work.short.log"
  echo "FAILED: short_include.cpp failed for another reason than the missing header (above)" >&2
  exit 1
fi
step "run ($mode)"
"$work/stride-consumer" "$robot"
