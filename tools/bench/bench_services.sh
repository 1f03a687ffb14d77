# Sourced by the benchmark scripts in tools/bench/: their output folder,
# free loopback ports, background services (crackvis-data, crackvis-render,
# followers) that are stopped on any exit, the wait for a render server to
# answer, and a fresh pair of services for one run. Needs $root (the source
# tree) and $build (the build tree).

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

# bench_start_services DATA LOG [RENDER_ARGS...]: fresh crackvis-data serving
# DATA and crackvis-render on free loopback ports, logging to LOG-data.log and
# LOG-render.log, with RENDER_ARGS added to crackvis-render's; returns once
# crackvis-render answers. crackvis-data is $bench_data_program when set (an
# older build's, for an A/B; its HDF5 workers are the program beside it), and
# crackvis-render $bench_render_program when set.
# Sets bench_render_port, bench_data_pid and bench_render_pid.
bench_start_services() {
  local data=$1 log=$2
  shift 2
  local data_port
  data_port=$(bench_free_port)
  bench_render_port=$(bench_free_port)
  "${bench_data_program:-$build/dataservice/crackvis-data}" --root "$data" --listen "127.0.0.1:$data_port" \
    --access-log '' >"$log-data.log" 2>&1 &
  bench_data_pid=$!
  "${bench_render_program:-$build/server/app/crackvis-render}" \
    --listen "127.0.0.1:$bench_render_port" \
    --data-server "localhost:$data_port" --access-log '' "$@" >"$log-render.log" 2>&1 &
  bench_render_pid=$!
  bench_pids+=("$bench_data_pid" "$bench_render_pid")
  bench_wait_render "$bench_render_port" "$log-render.log"
}

# bench_stop_services: stops the pair bench_start_services started last.
bench_stop_services() {
  kill "$bench_render_pid" "$bench_data_pid"
  wait "$bench_render_pid" "$bench_data_pid" 2>/dev/null || true
}
