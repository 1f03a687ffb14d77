#!/usr/bin/env bash
# Builds the crackvis ParaView plugin (paraview-plugin/README.md) against
# Debian's ParaView 5.11, unpacked by deploy/paraview-prefix.sh, in its own
# tree (default build/paraview-plugin), and prints the plugin's path.
#
#   paraview-plugin/build.sh            # then: pvpython, pvbatch or paraview with
#                                       # LoadPlugin('<printed path>')
#
# Environment: CRACKVIS_PLUGIN_BUILD_DIR (default build/paraview-plugin),
# CRACKVIS_PLUGIN_JOBS (default 2), and those of deploy/paraview-prefix.sh.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${CRACKVIS_PLUGIN_BUILD_DIR:-$root/build/paraview-plugin}
jobs=${CRACKVIS_PLUGIN_JOBS:-2}
env_lines=$("$root/deploy/paraview-prefix.sh" --env)
eval "$env_lines"
if [[ ! -f $build/CMakeCache.txt ]]; then
  cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release \
    -DCRACKVIS_PARAVIEW_PLUGIN=ON -DCRACKVIS_BUILD_TESTS=OFF -DParaView_DIR="$ParaView_DIR" \
    >"$build.configure.log" 2>&1 || {
    cat "$build.configure.log" >&2
    echo "paraview-plugin/build.sh: configuring failed (log above)" >&2
    exit 1
  }
fi
cmake --build "$build" -j "$jobs" >&2
plugin=$(find "$build" -name Crackvis.so -path '*/plugins/*' | head -1)
[[ -n $plugin ]] || { echo "paraview-plugin/build.sh: no Crackvis.so under $build" >&2; exit 1; }
echo "$plugin"
