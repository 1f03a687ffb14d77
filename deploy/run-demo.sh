#!/usr/bin/env bash
# The main job, from a fresh Debian 12 machine to a live remote visualization:
# installs what is missing, builds crackvis, simulates the dissertation's
# cuboid A fracture benchmark (once), makes development certificates (once),
# starts crackvis-data and crackvis-render on loopback with mutual TLS, and
# opens crackvis-client on them. Without a display (or with DEMO_HEADLESS=1)
# the client runs a scripted session instead (rotate, step through the
# fracture, switch between the four crack methods) and writes demo.mp4 and
# demo.png. The services stop when the client ends. A second run reuses the
# build, the data and the certificates and starts in seconds.
#
#   deploy/run-demo.sh [OUT_DIR]          # default: demo-out/ (demo.mp4, demo.png, logs)
#   DEMO_SCALE=0.3 deploy/run-demo.sh     # a smaller specimen (default: full size)
#   DEMO_HEADLESS=1 deploy/run-demo.sh    # the scripted session even with a display
#   DEMO_PORT=50051 (data; render = +1; the browser page = +2; 0: ports the OS chooses)
#   DEMO_DATA=demo-data                   # where the simulated file is kept
#   DEMO_SKIP_INSTALL=1                   # skip deploy/install-deps.sh (tests)
#   DEMO_BUILD=DIR                        # use this build tree as it is (tests)
set -euo pipefail
cd "$(dirname "$0")/.."
out_dir="${1:-demo-out}"
data_dir="${DEMO_DATA:-demo-data}"
scale="${DEMO_SCALE:-1}"
data_port="${DEMO_PORT:-50051}"
render_port=$((data_port == 0 ? 0 : data_port + 1))
web_port=$((data_port == 0 ? 0 : data_port + 2))
build="${DEMO_BUILD:-build/release}"

say() { echo "run-demo: $*"; }
# The port a service printed it serves on ('event=serving address="127.0.0.1:PORT"').
port_of() { grep -o 'event=serving address="127\.0\.0\.1:[0-9]*' "$1" | head -1 | cut -d: -f2; }

if [[ -z "${DEMO_SKIP_INSTALL:-}" ]]; then
  bash deploy/install-deps.sh
fi
if [[ -z "${DEMO_BUILD:-}" ]]; then
  cmake --preset release >/dev/null
  cmake --build --preset release --target crackvis crackvis-data crackvis-render crackvis-client \
    crackvis-web
fi

mkdir -p "$data_dir" "$out_dir"
file="cuboidA-scale$scale.h5"
if ! "$build/tools/crackvis" info "$data_dir/$file" >/dev/null 2>&1; then
  say "simulating cuboid A (scale $scale) into $data_dir/$file"
  "$build/tools/crackvis" sim cuboid3d --set A --scale "$scale" -o "$data_dir/$file"
fi
certs=certs/generated
if [[ ! -f "$certs/crackvis-render.pem" || ! -f "$certs/client.pem" ]]; then
  bash certs/make-dev-certs.sh --client crackvis-render
fi

# The browser page signs in as a user: "demo", with a password made once
# and kept in $out_dir/web-password (mode 0600). The Qt client keeps its
# certificate (CN crackvis-client), a user of its own here.
users="$out_dir/render-users.json"
if [[ ! -s "$out_dir/web-password" || ! -s "$users" ]]; then
  (umask 077; "$build/dataservice/crackvis-data" new-token | awk '/^token /{print substr($2, 1, 16)}' >"$out_dir/web-password")
  hash=$(tr -d '\n' <"$out_dir/web-password" | "$build/dataservice/crackvis-data" hash-secret)
  cat >"$users" <<EOF
{"users": [
  {"name": "demo", "password_hash": "$hash", "folders": ["*"]},
  {"name": "client", "certificate_name": "crackvis-client", "folders": ["*"]}
]}
EOF
fi

# The page, where this build tree has it (the CMake option CRACKVIS_WEB).
web=()
if [[ -f "$build/web/dist/index.html" ]]; then
  web=(--users-from "$users" --web-listen "127.0.0.1:$web_port" --web-root "$build/web/dist")
fi

pids=()
stop_services() {
  for pid in "${pids[@]}"; do kill -TERM "$pid" 2>/dev/null || true; done
  for pid in "${pids[@]}"; do wait "$pid" 2>/dev/null || true; done
}
trap stop_services EXIT

# Waits until a service prints that it serves, or fails with its log.
await() {
  local log=$1 name=$2
  for _ in $(seq 1 300); do
    if grep -q "serving" "$log" 2>/dev/null; then return 0; fi
    sleep 0.1
  done
  say "$name did not start:"; cat "$log" >&2; exit 1
}

"$build/dataservice/crackvis-data" --root "$data_dir" --listen "127.0.0.1:$data_port" \
  --ca "$certs/ca.pem" --cert "$certs/server.pem" --key "$certs/server.key" \
  --access-log "$out_dir/data-access.log" >"$out_dir/crackvis-data.log" 2>&1 &
pids+=($!)
await "$out_dir/crackvis-data.log" crackvis-data
data_port=$(port_of "$out_dir/crackvis-data.log")
"$build/server/app/crackvis-render" --listen "127.0.0.1:$render_port" \
  --ca "$certs/ca.pem" --cert "$certs/server.pem" --key "$certs/server.key" \
  --data-server "localhost:$data_port" --data-ca "$certs/ca.pem" \
  --data-cert "$certs/crackvis-render.pem" --data-key "$certs/crackvis-render.key" \
  "${web[@]}" --access-log "$out_dir/render-access.log" >"$out_dir/crackvis-render.log" 2>&1 &
pids+=($!)
await "$out_dir/crackvis-render.log" crackvis-render
render_port=$(port_of "$out_dir/crackvis-render.log")
web_url=$(grep -o 'event=web_serving .*url="[^"]*' "$out_dir/crackvis-render.log" | sed 's/.*url="//' || true)
say "services on 127.0.0.1:$data_port (data) and 127.0.0.1:$render_port (render); logs in $out_dir/"
[[ -z "$web_url" ]] || say "in a browser: $web_url  (user demo, password in $out_dir/web-password; certificate: the development CA's)"
head -1 "$out_dir/crackvis-render.log"

client=("$build/client/app/crackvis-client" --connect "localhost:$render_port"
        --ca "$certs/ca.pem" --cert "$certs/client.pem" --key "$certs/client.key"
        --file "$file" --pipeline deploy/demo-view.xml)
if [[ -n "${DISPLAY:-}" && -z "${DEMO_HEADLESS:-}" ]]; then
  say "opening crackvis-client (close its window to stop the services)"
  "${client[@]}"
else
  say "no display: the scripted session writes $out_dir/demo.mp4 and $out_dir/demo.png"
  "${client[@]}" --demo "$out_dir" 2>&1 | grep -v '^\[libx264\|^\[mp4'
fi
