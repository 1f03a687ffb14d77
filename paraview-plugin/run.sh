#!/usr/bin/env bash
# Runs Debian's ParaView 5.11 with the crackvis plugin loaded: unpacks
# ParaView into its private prefix and builds the plugin first when needed
# (deploy/paraview-prefix.sh, paraview-plugin/build.sh).
#
#   paraview-plugin/run.sh paraview [ARGS...]     # the GUI: File > Open a crackvis-dem .h5
#   paraview-plugin/run.sh pvpython [SCRIPT]      # Python: crackvisdemreader(FileName=...)
#   paraview-plugin/run.sh pvbatch SCRIPT         # batch; under mpiexec for several ranks
#   paraview-plugin/run.sh pvserver [ARGS...]     # a server for ParaView's client
#
# The plugin is found through PV_PLUGIN_PATH, which ParaView loads at start.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
tool=${1:-}
case $tool in
  paraview | pvpython | pvbatch | pvserver | pvdataserver | pvrenderserver) shift ;;
  -h | --help | "") sed -n '2,12p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
  *) echo "run.sh: unknown tool '$tool' (paraview, pvpython, pvbatch or pvserver)" >&2; exit 2 ;;
esac
plugin=$("$root/paraview-plugin/build.sh")
env_lines=$("$root/deploy/paraview-prefix.sh" --env)
eval "$env_lines"
export PV_PLUGIN_PATH=$(dirname "$plugin")${PV_PLUGIN_PATH:+:$PV_PLUGIN_PATH}
exec "$CRACKVIS_PARAVIEW_PREFIX/usr/bin/$tool" "$@"
