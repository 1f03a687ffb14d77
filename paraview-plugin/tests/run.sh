#!/usr/bin/env bash
# The plugin's tests (ctest runs this): on a lattice and on a random packing,
# each with a planted through crack that opens, and on the cuboids A and C
# (scaled down), the plugin's reader and four filters inside pvbatch at 1 and
# 2 MPI ranks must give what `crackvis extract` gives for the last step, face
# for face, with every rank extracting its own slab; then the same from a
# pvpython client driving a 2-rank pvserver.
#
#   paraview-plugin/tests/run.sh CRACKVIS_CLI [PLUGIN]
#
# PLUGIN defaults to what paraview-plugin/build.sh built (build/paraview-plugin).
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/../.." && pwd)
crackvis=${1:?usage: run.sh CRACKVIS_CLI [PLUGIN]}
plugin=${2:-$(find "$root/build/paraview-plugin" -name Crackvis.so -path '*/plugins/*' 2>/dev/null | head -1)}
[[ -n $plugin && -f $plugin ]] ||
  { echo "run.sh: no plugin built; run paraview-plugin/build.sh first" >&2; exit 1; }
env_lines=$("$root/deploy/paraview-prefix.sh" --env)
eval "$env_lines"
pvbatch=$CRACKVIS_PARAVIEW_PREFIX/usr/bin/pvbatch
work=$(mktemp -d -t crackvis-plugin-test.XXXXXX)
trap 'rm -rf "$work"' EXIT

free_port() {
  python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'
}

# Waits (at most 60 s) until the server process PID logs to LOG that it takes
# connections, or dies.
wait_for_server() {
  local log=$1 pid=$2
  for _ in $(seq 600); do
    grep -q "Accepting connection" "$log" && return 0
    kill -0 "$pid" 2>/dev/null || return 1
    sleep 0.1
  done
  return 1
}

# Runs a pvpython client script; on failure prints its log and the server's.
client_passes() {
  local client_log=$1 server_log=$2
  shift 2
  "$@" 2>"$client_log" && return 0
  grep -v '^HDF5-DIAG\|^  ' "$client_log" | tail -20 >&2
  tail -20 "$server_log" >&2
  return 1
}

# make_case NAME generate|sim|import ARGS...: the data set and the CLI's extraction
# of its last step by each method.
make_case() {
  local name=$1
  shift
  mkdir -p "$work/$name"
  "$crackvis" "$@" -o "$work/$name/data.h5" >/dev/null 2>&1
  local method
  for method in cell-cut local-voronoi cell-centre; do
    "$crackvis" extract "$work/$name/data.h5" -m "$method" -s -1 -q -o "$work/$name/$method.vtp"
  done
  "$crackvis" extract "$work/$name/data.h5" -m cell-attribute -s -1 -q \
    -o "$work/$name/cell-attribute.vtu"
}

# Specimens long enough that each of 2 ranks holds a slab of its own beside
# the ghost layer (4 bond lengths), with a planted through crack on the cut
# between the ranks' slabs that opens over 6 steps. The dissertation's
# cuboids, scaled down, with their simulated cracks. And the notched bars
# Yade, ESyS-Particle and LAMMPS broke (tests/data), imported.
make_case lattice generate --sites 24 8 8 --planted-crack 6
make_case random generate --packing random --box 0.03 0.01 0.01 --radius 0.0005 --planted-crack 6
make_case cuboidA sim cuboid3d --set A --scale 0.4 -q
make_case cuboidC sim cuboid3d --set C --scale 0.3 -q
for code in yade esys lammps; do
  make_case "$code" import "$code" "$root/tests/data/$code/notched_bar"
done

failed=0
for name in lattice random cuboidA cuboidC yade esys lammps; do
  for ranks in 1 2; do
    echo "== $name, $ranks rank(s)"
    if ((ranks == 1)); then
      run=("$pvbatch" --no-mpi)
    else
      # Debian's ParaView is built against Open MPI: its mpiexec, which wants
      # --allow-run-as-root for root and --oversubscribe beyond the cores.
      run=(mpiexec --allow-run-as-root --oversubscribe -np "$ranks" -x LD_LIBRARY_PATH
           -x PYTHONPATH "$pvbatch")
    fi
    if ! "${run[@]}" "$here/plugin_matches_cli.py" "$plugin" "$work/$name/data.h5" \
      "$work/$name" 2>"$work/$name.log"; then
      grep -v '^HDF5-DIAG\|^  ' "$work/$name.log" | tail -20 >&2
      failed=1
    fi
  done
done
# ParaView's client/server mode: pvpython drives a pvserver (2 ranks) that
# loads the plugin from PV_PLUGIN_PATH and runs the pipeline.
echo "== random, pvserver with 2 ranks, pvpython client"
port=$(free_port)
PV_PLUGIN_PATH=$(dirname "$plugin") mpiexec --allow-run-as-root --oversubscribe -np 2 \
  -x LD_LIBRARY_PATH -x PYTHONPATH -x PV_PLUGIN_PATH \
  "$CRACKVIS_PARAVIEW_PREFIX/usr/bin/pvserver" --server-port="$port" >"$work/pvserver.log" 2>&1 &
server_pid=$!
wait_for_server "$work/pvserver.log" "$server_pid" || true
client_passes "$work/client.log" "$work/pvserver.log" "$CRACKVIS_PARAVIEW_PREFIX/usr/bin/pvpython" \
  "$here/plugin_matches_cli.py" "$plugin" "$work/random/data.h5" "$work/random" \
  "localhost:$port" || failed=1
kill "$server_pid" 2>/dev/null || true
wait "$server_pid" 2>/dev/null || true
# deploy/pvserver-beside-data.sh (its own Xvfb): the server renders the crack
# a pvpython client asks for.
echo "== random, deploy/pvserver-beside-data.sh renders for a pvpython client"
port=$(free_port)
env -u DISPLAY "$root/deploy/pvserver-beside-data.sh" --port "$port" >"$work/beside.log" 2>&1 &
beside_pid=$!
wait_for_server "$work/beside.log" "$beside_pid" || true
# The client draws nothing itself but still needs a display for its window.
client_passes "$work/beside-client.log" "$work/beside.log" \
  xvfb-run -a -s "-screen 0 1280x1024x24 -noreset" "$CRACKVIS_PARAVIEW_PREFIX/usr/bin/pvpython" \
  "$here/pvserver_renders.py" "$plugin" "$work/random/data.h5" "localhost:$port" \
  "$work/beside.png" || failed=1
kill "$beside_pid" 2>/dev/null || true
wait "$beside_pid" 2>/dev/null || true

# paraview-plugin/run.sh asks glibc for huge pages where THP is madvise, and
# not when told not to.
if grep -q '\[madvise\]' /sys/kernel/mm/transparent_hugepage/enabled 2>/dev/null; then
  echo "== paraview-plugin/run.sh sets the huge-pages tunable"
  printf 'import os\nprint("tunables=" + os.environ.get("GLIBC_TUNABLES", ""))\n' >"$work/env.py"
  with=$(env -u GLIBC_TUNABLES "$root/paraview-plugin/run.sh" pvpython "$work/env.py" 2>/dev/null)
  without=$(env -u GLIBC_TUNABLES CRACKVIS_HUGE_PAGES=0 "$root/paraview-plugin/run.sh" pvpython \
    "$work/env.py" 2>/dev/null)
  [[ $with == *"tunables=glibc.malloc.hugetlb=1"* ]] ||
    { echo "run.sh: expected the tunable, got: $with" >&2; failed=1; }
  [[ $without == *"tunables="* && $without != *hugetlb* ]] ||
    { echo "run.sh: CRACKVIS_HUGE_PAGES=0 still set it: $without" >&2; failed=1; }
fi
exit "$failed"
