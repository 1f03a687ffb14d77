#!/usr/bin/env bash
# ParaView peer of crackvis's render benchmark: renders the scene crackvis's
# render server shows (one step's particles as spheres plus its crack surface,
# reset camera) with ParaView 5.11 in client/server mode (pvserver renders,
# pvpython receives the images) and prints ParaView's frame times as JSON.
#
# ParaView comes from Debian 12's packages, unpacked into a private prefix:
# python3-paraview conflicts with python3-vtk9, which libvtk9-dev (this
# project's VTK) depends on, so it must never be installed with apt or dpkg -i.
# See tools/bench/README.md.
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/../.." && pwd)
readonly here root
readonly pv_version=5.11
crackvis=${CRACKVIS:-$root/build/release/tools/crackvis}

usage() {
  cat <<EOF
usage: tools/bench/paraview-peer.sh FILE.h5 [--step S] [--size WxH] [--frames N] [--json OUT]
                                   [--colour-by solid|radius] [--fxaa] [--ranks R]
                                   [--plugin] [--screenshot PNG] [--keep]

Times ParaView $pv_version client/server (Debian's packages) on the scene crackvis's
render server shows for FILE.h5 at step S, and prints one JSON object on stdout.

  --step S        step to show; negative counts from the end (default -1, the last)
  --size WxH      view size (default 1280x720)
  --frames N      timed frames per measurement, after 2 warm-up frames (default 20)
  --json OUT      also write the JSON to OUT
  --colour-by X   particles solid #b0b0b0 like crackvis's default (default), or by radius
  --fxaa          keep ParaView's FXAA on (crackvis renders without it)
  --ranks R       pvserver's MPI ranks (default 1, like crackvis's one process). ParaView
                  renders at 1/ImageReductionFactor during interaction only with R >= 2
                  (its IceT compositor); one rank renders every frame at full size
  --plugin        pvserver beside the data: it loads the crackvis plugin (paraview-plugin/,
                  built into build/paraview-plugin) and reads FILE.h5 itself with the
                  crackvis-dem reader and the local Voronoi filter, instead of files that
                  crackvis export and extract wrote beforehand (the load time then includes
                  the extraction)
  --screenshot P  save ParaView's first still frame as PNG P (to compare with crackvis's)
  --keep          keep the temporary folder (exported data, pvserver log)

Environment: CRACKVIS (the CLI, default build/release/tools/crackvis),
CRACKVIS_PARAVIEW_CACHE (default \${XDG_CACHE_HOME:-\$HOME/.cache}/crackvis/paraview-$pv_version),
LP_NUM_THREADS (llvmpipe's render threads, passed on to pvserver).
The first run downloads ~83 MB of .debs (deploy/paraview-prefix.sh) into the cache.
EOF
}

die() {
  echo "paraview-peer.sh: $*" >&2
  exit 1
}

say() {
  echo "paraview-peer.sh: $*" >&2
}

# --- options ---------------------------------------------------------------
file=""
step=-1
size=1280x720
frames=20
json_out=""
colour_by=solid
fxaa=()
ranks=1
screenshot=()
keep=0
plugin=""
while (($#)); do
  case $1 in
    -h | --help) usage; exit 0 ;;
    --step) step=${2:?--step needs a value}; shift 2 ;;
    --size) size=${2:?--size needs a value}; shift 2 ;;
    --frames) frames=${2:?--frames needs a value}; shift 2 ;;
    --json) json_out=${2:?--json needs a value}; shift 2 ;;
    --colour-by) colour_by=${2:?--colour-by needs a value}; shift 2 ;;
    --fxaa) fxaa=(--fxaa); shift ;;
    --ranks) ranks=${2:?--ranks needs a value}; shift 2 ;;
    --screenshot) screenshot=(--screenshot "$(realpath -m "${2:?--screenshot needs a value}")"); shift 2 ;;
    --keep) keep=1; shift ;;
    --plugin)
      plugin=$(find "$root/build/paraview-plugin" -name Crackvis.so -path '*/plugins/*' 2>/dev/null | head -1)
      [[ -n $plugin ]] || die "--plugin: no plugin built; run paraview-plugin/build.sh first"
      shift ;;
    -*) die "unknown option $1 (see --help)" ;;
    *) [[ -z $file ]] || die "one FILE.h5 only (see --help)"; file=$1; shift ;;
  esac
done
[[ -n $file ]] || { usage >&2; exit 2; }
[[ -r $file ]] || die "cannot read $file"
[[ $step =~ ^-?[0-9]+$ ]] || die "--step must be an integer, not '$step'"
[[ $size =~ ^[0-9]+x[0-9]+$ ]] || die "--size must be WxH, not '$size'"
if ! [[ $frames =~ ^[1-9][0-9]*$ ]]; then die "--frames must be a positive integer"; fi
if ! [[ $ranks =~ ^[1-9][0-9]*$ ]]; then die "--ranks must be a positive integer"; fi
[[ $colour_by == solid || $colour_by == radius ]] || die "--colour-by must be solid or radius"
[[ -x $crackvis ]] || die "no crackvis CLI at $crackvis (build it, or set CRACKVIS)"

# --- processes, cleaned up on any exit --------------------------------------
work=$(mktemp -d -t crackvis-paraview-peer.XXXXXX)
xvfb_pid=""
pvserver_pid=""
client_pid=""
cleanup() {
  local pid
  for pid in $client_pid $pvserver_pid $xvfb_pid; do
    if kill -0 "$pid" 2>/dev/null; then
      kill "$pid" 2>/dev/null || true
      wait "$pid" 2>/dev/null || true
    fi
  done
  if ((keep)); then say "kept $work"; else rm -rf "$work"; fi
}
trap cleanup EXIT
trap 'exit 130' INT TERM

# --- the scene's data, converted by our CLI -------------------------------
steps=$("$crackvis" info "$file" --json | sed -n 's/^ *"steps": *\([0-9]*\),*$/\1/p') ||
  die "crackvis info could not read $file"
[[ -n $steps ]] || die "crackvis info gave no step count for $file"
((step < 0)) && step=$((steps + step))
((step >= 0 && step < steps)) || die "step $step is outside 0..$((steps - 1)) of $file"
if [[ -n $plugin ]]; then
  # pvserver reads the file itself through the plugin.
  scene=(--h5 "$(realpath "$file")" --plugin "$plugin")
  export PV_PLUGIN_PATH
  PV_PLUGIN_PATH=$(dirname "$plugin")
else
  say "exporting step $step of $file"
  "$crackvis" export "$file" --particles -s "$step" -q -o "$work/particles.pvd" >&2 ||
    die "crackvis export failed"
  "$crackvis" extract "$file" -m local-voronoi -s "$step" -q -o "$work/crack.vtp" >&2 ||
    die "crackvis extract failed"
  scene=(--particles "$work/particles.pvd" --crack "$work/crack.vtp")
fi

# --- ParaView, unpacked on the first run -----------------------------------
# The private prefix (deploy/paraview-prefix.sh), unpacked on the first run.
env_lines=$("$root/deploy/paraview-prefix.sh" --env) || die "no ParaView prefix (see above)"
eval "$env_lines"
prefix=$CRACKVIS_PARAVIEW_PREFIX
libdir=$(dirname "$ParaView_DIR")
libdir=$(dirname "$libdir")
pvserver=$prefix/usr/bin/pvserver
pvpython=$prefix/usr/bin/pvpython
unresolved=$(ldd "$pvserver" "$pvpython" | awk '/not found/ { print $1 }' | sort -u | tr '\n' ' ')
[[ -z $unresolved ]] || die "libraries not found for pvserver/pvpython: $unresolved"

# --- a display, if this ParaView build renders through X -------------------
# Debian's build has only vtkXOpenGLRenderWindow (GLX): no EGL, no OSMesa, so
# pvserver needs an X server even offscreen. A private Xvfb (-noreset: it must
# outlive the first client) with Mesa's GLX gives llvmpipe.
opengl_lib=$libdir/libvtkRenderingOpenGL2-pv$pv_version.so.1
if grep -q -a -e vtkEGLRenderWindow -e vtkOSOpenGLRenderWindow "$opengl_lib"; then
  render_path="EGL/OSMesa build (no X server)"
else
  command -v Xvfb >/dev/null || die "this ParaView renders through GLX: install xvfb"
  width=${size%x*} height=${size#*x}
  # -displayfd: Xvfb picks a free display number and writes it to fd 3.
  Xvfb -displayfd 3 -screen 0 "$((width > 1920 ? width : 1920))x$((height > 1080 ? height : 1080))x24" \
    -noreset -nolisten tcp 3>"$work/display" 2>"$work/xvfb.log" &
  xvfb_pid=$!
  for _ in $(seq 100); do
    [[ -s $work/display ]] && break
    kill -0 "$xvfb_pid" 2>/dev/null || die "Xvfb failed: $(tail -1 "$work/xvfb.log")"
    sleep 0.1
  done
  [[ -s $work/display ]] || die "Xvfb did not report a display in 10 s"
  DISPLAY=:$(head -1 "$work/display")
  export DISPLAY
  render_path="GLX on a private Xvfb $DISPLAY, offscreen framebuffer"
fi

# --- pvserver on a free port -----------------------------------------------
port=$(python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
# --disable-registry: no user settings change the defaults measured.
server_options=(--disable-registry --force-offscreen-rendering --server-port="$port")
if ((ranks == 1)); then
  # One process needs no MPI (and then has no IceT compositor either).
  "$pvserver" --no-mpi "${server_options[@]}" >"$work/pvserver.log" 2>&1 &
else
  command -v mpiexec >/dev/null || die "--ranks $ranks needs mpiexec (openmpi-bin)"
  # Debian's ParaView is built against Open MPI: its mpiexec, which wants
  # --allow-run-as-root for root and --oversubscribe for more ranks than cores.
  mpi_env=(-x LD_LIBRARY_PATH -x PYTHONPATH)
  [[ -n ${PV_PLUGIN_PATH:-} ]] && mpi_env+=(-x PV_PLUGIN_PATH)
  [[ -n ${DISPLAY:-} ]] && mpi_env+=(-x DISPLAY)
  [[ -n ${LP_NUM_THREADS:-} ]] && mpi_env+=(-x LP_NUM_THREADS)
  mpiexec --allow-run-as-root --oversubscribe -np "$ranks" "${mpi_env[@]}" \
    "$pvserver" "${server_options[@]}" >"$work/pvserver.log" 2>&1 &
fi
pvserver_pid=$!
for _ in $(seq 600); do
  grep -q "Accepting connection" "$work/pvserver.log" && break
  kill -0 "$pvserver_pid" 2>/dev/null || die "pvserver failed: $(tail -3 "$work/pvserver.log")"
  sleep 0.1
done
grep -q "Accepting connection" "$work/pvserver.log" || die "pvserver did not listen within 60 s"
say "pvserver ($ranks rank(s)) on port $port ($render_path)"

# --- the measurement -------------------------------------------------------
# The client renders nothing but pastes the server's images: offscreen too.
# In the background with `wait`, so that a signal reaches the trap at once.
"$pvpython" --no-mpi --disable-registry --force-offscreen-rendering \
  "$here/paraview_peer.py" --port "$port" "${scene[@]}" --work "$work" \
  --step "$step" --size "$size" --frames "$frames" \
  --colour-by "$colour_by" "${fxaa[@]}" "${screenshot[@]}" --ranks "$ranks" \
  --render-path "$render_path" \
  --package-version "$(cat "$prefix/.version")" --json-out "$work/result.json" >&2 &
client_pid=$!
if ! wait "$client_pid"; then
  say "pvserver log: $(tail -5 "$work/pvserver.log" | tr '\n' ' ')"
  die "the ParaView client failed (see above)"
fi
[[ -s $work/result.json ]] || die "the ParaView client wrote no result"
cat "$work/result.json"
if [[ -n $json_out ]]; then
  cp "$work/result.json" "$json_out" || die "cannot write $json_out"
fi
