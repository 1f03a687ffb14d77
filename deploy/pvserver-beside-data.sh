#!/usr/bin/env bash
# ParaView's server with the crackvis plugin, on the node that holds the data
# (issue 19 point 4): for users who prefer ParaView's client to
# crackvis-client. pvserver reads crackvis-dem files straight from storage
# through the plugin's reader and renders off-screen; ParaView's client
# connects to it (File > Connect, or pvpython's Connect()) and must load the
# plugin too (paraview-plugin/run.sh paraview does).
#
#   deploy/pvserver-beside-data.sh [--port P] [--ranks R]
#
#   --port P        the port pvserver listens on (default 11111, ParaView's)
#   --ranks R       MPI ranks (default 1); R >= 2 gives ParaView's parallel
#                   rendering and compositing, each rank reading and
#                   extracting its own slab (paraview-plugin/README.md)
#
# pvserver listens on every interface, and ParaView's connection is neither
# encrypted nor authenticated (unlike crackvis's mutual TLS): firewall the
# port and reach it through an SSH tunnel (ssh -L 11111:localhost:11111).
#
# Debian's ParaView renders through GLX only, so the script starts a private
# Xvfb (Mesa's llvmpipe) when no DISPLAY is set. It runs until stopped
# (Ctrl-C or SIGTERM), then stops pvserver and Xvfb; a client that
# disconnects ends only its pvserver, and a new one takes the next client.
# docs/deploy.md has more.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
port=11111
ranks=1

die() {
  echo "pvserver-beside-data.sh: $*" >&2
  exit 1
}

while (($#)); do
  case $1 in
    -h | --help) sed -n '2,24p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    --port) port=${2:?--port needs a value}; shift 2 ;;
    --ranks) ranks=${2:?--ranks needs a value}; shift 2 ;;
    *) die "unknown option $1 (see --help)" ;;
  esac
done
if ! [[ $port =~ ^[0-9]+$ ]] || ((port < 1 || port > 65535)); then
  die "--port must be 1-65535, not '$port'"
fi
[[ $ranks =~ ^[1-9][0-9]*$ ]] || die "--ranks must be a positive integer, not '$ranks'"

plugin=$("$root/paraview-plugin/build.sh")
env_lines=$("$root/deploy/paraview-prefix.sh" --env)
eval "$env_lines"
PV_PLUGIN_PATH=$(dirname "$plugin")
export PV_PLUGIN_PATH
# Huge pages for pvserver's arrays where THP is madvise; CRACKVIS_HUGE_PAGES=0
# leaves them off (deploy/huge-pages.sh).
source "$root/deploy/huge-pages.sh"
crackvis_huge_pages

xvfb_pid=""
server_pid=""
cleanup() {
  local pid
  rm -f "${run_log:-}"
  for pid in $server_pid $xvfb_pid; do
    kill "$pid" 2>/dev/null || true
    wait "$pid" 2>/dev/null || true
  done
}
trap cleanup EXIT
trap 'exit 0' INT TERM

if [[ -z ${DISPLAY:-} ]]; then
  command -v Xvfb >/dev/null || die "no DISPLAY and no Xvfb (deploy/install-deps.sh installs xvfb)"
  display_file=$(mktemp)
  # -displayfd: Xvfb picks a free display and writes its number to fd 3;
  # -noreset: it must outlive the first client.
  Xvfb -displayfd 3 -screen 0 1920x1080x24 -noreset -nolisten tcp 3>"$display_file" 2>/dev/null &
  xvfb_pid=$!
  for _ in $(seq 100); do
    [[ -s $display_file ]] && break
    kill -0 "$xvfb_pid" 2>/dev/null || die "Xvfb failed to start"
    sleep 0.1
  done
  [[ -s $display_file ]] || die "Xvfb did not report a display in 10 s"
  DISPLAY=:$(head -1 "$display_file")
  export DISPLAY
  rm -f "$display_file"
fi

server=("$CRACKVIS_PARAVIEW_PREFIX/usr/bin/pvserver" --server-port="$port" --force-offscreen-rendering
        --disable-registry)
# Starts pvserver; what it prints goes to our output and to $run_log.
run_log=$(mktemp)
start_server() {
  : >"$run_log"
  if ((ranks == 1)); then
    "${server[@]}" --no-mpi > >(tee -a "$run_log") 2>&1 &
  else
    # Debian's ParaView is built against Open MPI: its mpiexec, which wants
    # --allow-run-as-root for root and --oversubscribe beyond the cores.
    mpiexec --allow-run-as-root --oversubscribe -np "$ranks" -x LD_LIBRARY_PATH -x PYTHONPATH \
      -x PV_PLUGIN_PATH -x DISPLAY ${crackvis_huge_pages_mpi[@]+"${crackvis_huge_pages_mpi[@]}"} "${server[@]}" > >(tee -a "$run_log") 2>&1 &
  fi
  server_pid=$!
}

echo "pvserver-beside-data.sh: pvserver ($ranks rank(s), plugin $plugin) on port $port, DISPLAY=$DISPLAY" >&2
# pvserver ends when its client disconnects (its --multi-clients mode is
# deprecated): a new one takes the next client, so the server lasts until it
# is stopped. One that ends without a client failed (it exits with status 0
# even when its port is taken): that ends the script.
while true; do
  start_server
  status=0
  wait "$server_pid" || status=$?
  server_pid=""
  if ! grep -q "Client connected" "$run_log"; then
    rm -f "$run_log"
    die "pvserver ended (status $status) before a client connected; its output is above"
  fi
  echo "pvserver-beside-data.sh: the client left; pvserver starts again for the next" >&2
done
