# Sourced by the benchmark scripts in tools/bench/: their output folder,
# free loopback ports, background services (crackvis-data, crackvis-render,
# followers) that are stopped on any exit, and the wait for a render server
# to answer. Needs $root (the source tree) and $build (the build tree).

# bench_output DIR: $out is DIR, or a temporary folder removed on exit when
# DIR is empty; the development certificates are made when missing.
bench_output() {
  out=$1
  bench_out_is_temp=
  if [[ -z $out ]]; then
    out=$(mktemp -d)
    bench_out_is_temp=1
  fi
  mkdir -p "$out"
  [[ -f $root/certs/generated/crackvis-render.pem ]] ||
    bash "$root/certs/make-dev-certs.sh" --client crackvis-render >&2
}

bench_free_port() {
  python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'
}

bench_pids=()
# bench_background COMMAND...: started in the background, stopped on exit.
bench_background() {
  "$@" &
  bench_pids+=($!)
}

bench_cleanup() {
  local pid
  for pid in "${bench_pids[@]}"; do
    kill "$pid" 2>/dev/null || true
  done
  wait 2>/dev/null || true
  if [[ -n ${bench_out_is_temp:-} ]]; then
    rm -rf "$out"
  fi
}
trap bench_cleanup EXIT

# bench_wait_render PORT LOG: until crackvis-render on PORT answers its
# health check (10 s), else the end of its LOG and exit 1.
bench_wait_render() {
  local port=$1 log=$2
  for _ in $(seq 50); do
    "$build/tools/crackvis" health "localhost:$port" >/dev/null 2>&1 && return 0
    sleep 0.2
  done
  echo "crackvis-render did not start: $(tail -3 "$log")" >&2
  exit 1
}
