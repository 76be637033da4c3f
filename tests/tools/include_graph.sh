#!/usr/bin/env bash
# ctest include_graph: the modules include one another in one direction only (README.md, "Layout
# and dependency direction"): solver ← locomotion ← controller, terrain on a floor of its own.
#   solver/      includes none of terrain/ locomotion/ controller/ config/ messages/ sim/ viz/ tools/
#                (the numerical core: no I/O, no planner, no world);
#   terrain/     includes nothing of Stride's but terrain/ (read by the sim, the planner, the viewer);
#   config/, messages/  the solver only (and not each other: a robot's file and the wire);
#   locomotion/  includes none of controller/ sim/ viz/ tools/ (the planner under the controller);
#   controller/, sim/, viz/  none of each other nor tools/ (three processes that share the wire).
# A link order in CMake does not catch a header that reaches up: a header-only use compiles as
# long as some target puts the folder on the path (the repository root is on every target's), so
# the sources themselves are read. Every #include "..." is resolved as the compiler would (beside
# the file first, then from the repository root) and `#include <stride/...>` as the public view
# of the same path; an LCM type ("stride/TYPE.hpp") is messages/. Exit 1 with each offending line.
# Usage: include_graph.sh ROOT
set -euo pipefail
[ $# -eq 1 ] || { echo "usage: include_graph.sh ROOT" >&2; exit 2; }
root=$(cd "$1" && pwd)

# What each module must not include.
declare -A forbidden=(
  [solver]="terrain locomotion controller config messages sim viz tools"
  [terrain]="solver locomotion controller config messages sim viz tools tests"
  [config]="terrain locomotion controller messages sim viz tools"
  [messages]="terrain locomotion controller config sim viz tools"
  [locomotion]="controller sim viz tools"
  [controller]="sim viz tools"
  [sim]="locomotion controller viz tools"
  [viz]="locomotion controller sim tools"
)
# Stride's top-level folders: an include that resolves under none of them is not Stride's.
modules="solver locomotion terrain controller config messages sim viz tools tests cmake"

# Sets `target` to the path an include names, from the root ("" when it is none of Stride's
# files). No subshell per include: the script reads every include of three modules.
resolve() {
  local file=$1 kind=$2 name=$3 dir rest first
  target=""
  dir=${file%/*}
  if [ "$kind" = '"' ] && [ -e "$root/$dir/$name" ]; then
    target=$(realpath -ms --relative-to="$root" "$root/$dir/$name")
    return
  fi
  # <Eigen/Core>, <vector>: not Stride's; <stride/...> is the public view of the tree's path.
  if [ "$kind" = '<' ]; then case "$name" in stride/*) ;; *) return ;; esac; fi
  rest=${name#stride/}
  first=${rest%%/*}
  if [ "$first" != "$rest" ] && [[ " $modules " == *" $first "* ]]; then
    target=$rest
  elif [ "$rest" != "$name" ] && [ "$first" = "$rest" ]; then
    target=messages/$rest  # an LCM type, which messages/ generates as stride/TYPE.hpp
  fi
}

violations=0
for module in "${!forbidden[@]}"; do
  [ -d "$root/$module" ] || continue
  while IFS= read -r file; do
    rel=${file#"$root"/}
    while IFS=: read -r line text; do
      [[ "$text" =~ ^[[:space:]]*#[[:space:]]*include[[:space:]]*([\"\<])([^\"\>]+)[\"\>] ]] || continue
      resolve "$rel" "${BASH_REMATCH[1]}" "${BASH_REMATCH[2]}"
      [ -n "$target" ] || continue
      to=${target%%/*}
      [[ " ${forbidden[$module]} " == *" $to "* ]] || continue
      echo "$rel:$line: includes $target: $module/ must not include $to/" >&2
      violations=$((violations + 1))
    done < <(grep -n '^[[:space:]]*#[[:space:]]*include' "$file" || true)
  done < <(find "$root/$module" -type f \( -name '*.hpp' -o -name '*.cpp' -o -name '*.h' \
                                          -o -name '*.cc' -o -name '*.inl' \) | sort)
done

if [ $violations -gt 0 ]; then
  echo "include_graph: $violations include(s) against the dependency direction (above)" >&2
  exit 1
fi
echo "include_graph: ${!forbidden[*]} include only what is below them"
