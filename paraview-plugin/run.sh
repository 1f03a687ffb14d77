#!/usr/bin/env bash
# Runs Debian's ParaView 5.11 with the crackvis plugin loaded: unpacks
# ParaView into its private prefix and builds the plugin first when needed
# (deploy/paraview-prefix.sh, paraview-plugin/build.sh).
#
#   paraview-plugin/run.sh paraview [ARGS...]     # the GUI: File > Open a crackvis-dem .h5
#   paraview-plugin/run.sh pvpython [SCRIPT]      # Python: crackvisdemreader(FileName=...)
#   paraview-plugin/run.sh pvbatch SCRIPT         # batch
#   paraview-plugin/run.sh pvserver [ARGS...]     # a server for ParaView's client
#   paraview-plugin/run.sh --ranks R pvbatch SCRIPT   # pvbatch or pvserver on R MPI ranks
#
# The plugin is found through PV_PLUGIN_PATH, which ParaView loads at start.
# With --ranks, Open MPI's mpiexec starts R processes (more than the cores
# allowed) with the environment ParaView needs; each rank extracts its own
# slab of the specimen.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
ranks=1
if [[ ${1:-} == --ranks ]]; then
  ranks=${2:-}
  [[ $ranks =~ ^[1-9][0-9]*$ ]] || { echo "run.sh: --ranks needs a positive integer" >&2; exit 2; }
  shift 2
fi
tool=${1:-}
case $tool in
  paraview | pvpython | pvbatch | pvserver | pvdataserver | pvrenderserver) shift ;;
  -h | --help | "") sed -n '2,16p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
  *) echo "run.sh: unknown tool '$tool' (paraview, pvpython, pvbatch or pvserver)" >&2; exit 2 ;;
esac
if ((ranks > 1)) && [[ $tool != pvbatch && $tool != pvserver ]]; then
  echo "run.sh: --ranks is for pvbatch and pvserver, not $tool" >&2
  exit 2
fi
plugin=$("$root/paraview-plugin/build.sh")
env_lines=$("$root/deploy/paraview-prefix.sh" --env)
eval "$env_lines"
export PV_PLUGIN_PATH=$(dirname "$plugin")${PV_PLUGIN_PATH:+:$PV_PLUGIN_PATH}
binary=$CRACKVIS_PARAVIEW_PREFIX/usr/bin/$tool
# glibc's malloc asks for transparent huge pages where the kernel gives them
# only on request (deploy/huge-pages.sh). CRACKVIS_HUGE_PAGES=0 leaves it off.
source "$root/deploy/huge-pages.sh"
crackvis_huge_pages
if ((ranks > 1)); then
  command -v mpiexec >/dev/null || { echo "run.sh: --ranks needs mpiexec (openmpi-bin)" >&2; exit 1; }
  as_root=()
  ((EUID == 0)) && as_root=(--allow-run-as-root)  # Open MPI refuses root without it
  exported=(-x LD_LIBRARY_PATH -x PYTHONPATH -x PV_PLUGIN_PATH)
  [[ -n ${DISPLAY:-} ]] && exported+=(-x DISPLAY)
  exported+=(${crackvis_huge_pages_mpi[@]+"${crackvis_huge_pages_mpi[@]}"})
  exec mpiexec "${as_root[@]}" --oversubscribe -np "$ranks" "${exported[@]}" "$binary" "$@"
fi
exec "$binary" "$@"
