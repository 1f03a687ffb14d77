#!/usr/bin/env bash
# The render benchmarks on a GPU node (issue 34 point 6, issue 17 point 4):
# unpacks a pack made by gpu-pack.sh, points glvnd at NVIDIA's EGL, makes
# full-size cuboid A (crackvis sim) and a 1e6-particle FCC block with a planted
# crack (crackvis generate), starts crackvis-data and crackvis-render on
# loopback with mutual TLS, and runs crackvis bench render:
#   - cuboid A at 1920x1080, a drag at 60 and at 120 events/s (frames per
#     second with libx264 in the loop, full-resolution still frames, the time
#     to the first picture, jumps and playback);
#   - the 1e6 block at 1920x1080 and 1280x720 (the frame time at 1e6);
#   - N = 1, 4 and 8 sessions at once on cuboid A at 1280x720;
#   - occlusion culling on the CPU (CRACKVIS_OCCLUSION_CULLING=on, a second
#     crackvis-render) against the GPU default (off), alternating, on both
#     files at 1080p.
# Results: RESULTS_DIR/results.jsonl (one line per run: {"run": name,
# "report": bench render's JSON}), gpu-node.log (the machine, the tables, the
# services' logs) and a 1080p picture of each file from crackvis snapshot.
#
#   tools/bench/gpu-node.sh PACK.tar.xz RESULTS_DIR
#
# Environment: SECONDS_PER_DRAG (default 5), SKIP_1E6=1 to leave out the 1e6
# block, EGL_VENDOR=system for a dry run with the system's EGL (Mesa).
set -uo pipefail
pack=${1:?usage: gpu-node.sh PACK.tar.xz RESULTS_DIR}
results=${2:?usage: gpu-node.sh PACK.tar.xz RESULTS_DIR}
drag=${SECONDS_PER_DRAG:-5}
mkdir -p "$results"
results=$(cd "$results" && pwd)
pack=$(cd "$(dirname "$pack")" && pwd)/$(basename "$pack")
log=$results/gpu-node.log
say() { echo "[$(date +%T)] $*" | tee -a "$log" >&2; }

work=$(mktemp -d /tmp/crackvis-gpu.XXXXXX)
trap 'rm -rf "$work"' EXIT
tar -xJf "$pack" -C "$work" || { say "cannot unpack $pack"; exit 1; }
cv=$work/crackvis
data=$work/data
mkdir -p "$data"
cd "$cv"  # the certificates' default paths are relative: certs/generated/...

say "pack: $(cat commit 2>/dev/null)"
{
  nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.max.sm --format=csv,noheader
  grep PRETTY_NAME /etc/os-release
  ldd --version | head -1
  lscpu | sed -n 's/^Model name: *//p'
  echo "$(nproc) hardware threads, $(awk '/MemTotal/ { printf "%.0f GiB", $2 / 1048576 }' /proc/meminfo)"
} 2>&1 | tee -a "$log" >&2

# NVIDIA's EGL vendor library through the packed glvnd (libEGL.so.1).
# EGL_VENDOR=system keeps the system's vendors (a dry run on a CPU node).
if [[ ${EGL_VENDOR:-nvidia} == nvidia ]]; then
  vendor=$(find /usr/local/nvidia /usr/share/glvnd /etc/glvnd -path '*egl_vendor.d*' -name '*nvidia*.json' \
    2>/dev/null | head -1)
  egl=$(find /usr/local/nvidia /usr/lib /usr/lib64 -name 'libEGL_nvidia.so.0' 2>/dev/null | head -1)
  [[ -n $vendor && -n $egl ]] || { say "no NVIDIA EGL here (vendor file '$vendor', library '$egl')"; exit 1; }
  export __EGL_VENDOR_LIBRARY_FILENAMES=$vendor
  export LD_LIBRARY_PATH=$(dirname "$egl")
  say "EGL vendor: $vendor; library: $egl"
fi

bin=$cv/bin
missing=$(ldd "$bin"/* 2>&1 | grep 'not found' | sort -u)
[[ -z $missing ]] || { say "libraries not found: $missing"; exit 1; }
timed() {  # NAME COMMAND...: runs it, logs its wall seconds
  local start=$EPOCHREALTIME
  "${@:2}" >>"$log" 2>&1
  local rc=$?
  say "$1: rc $rc, $(python3 -c "print(round($EPOCHREALTIME - $start, 2))") s"
  return $rc
}
timed "sim cuboid A" "$bin/crackvis" sim cuboid3d --set A -q -o "$data/cuboidA.h5" || exit 1
if [[ ${SKIP_1E6:-0} != 1 ]]; then
  timed "generate 1e6" "$bin/crackvis" generate --sites 126 126 126 --planted-crack 10 \
    -o "$data/fcc-1e6.h5" || exit 1
fi
sync

timed "snapshot cuboid A 1080p" "$bin/crackvis" snapshot "$data/cuboidA.h5" -s -1 -m local-voronoi \
  --width 1920 --height 1080 -o "$results/cuboidA-1080p.png"

port() { python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'; }
data_port=$(port)
render_port=$(port)
"$bin/crackvis-data" --root "$data" --listen "127.0.0.1:$data_port" --access-log '' \
  >"$results/services.log" 2>&1 &
data_pid=$!
"$bin/crackvis-render" --listen "127.0.0.1:$render_port" --data-server "localhost:$data_port" \
  --access-log '' >>"$results/services.log" 2>&1 &
render_pid=$!
# A second render server that culls hidden spheres on the CPU as on
# llvmpipe (the GPU default is off), to compare in the same run.
culling_port=$(port)
CRACKVIS_OCCLUSION_CULLING=on "$bin/crackvis-render" --listen "127.0.0.1:$culling_port" \
  --data-server "localhost:$data_port" --access-log '' >>"$results/services.log" 2>&1 &
culling_pid=$!
trap 'kill $data_pid $render_pid $culling_pid 2>/dev/null; wait 2>/dev/null; rm -rf "$work"' EXIT
for p in $render_port $culling_port; do
  for _ in $(seq 100); do
    "$bin/crackvis" health "localhost:$p" >/dev/null 2>&1 && break
    sleep 0.2
  done
  "$bin/crackvis" health "localhost:$p" >>"$log" 2>&1 || {
    say "crackvis-render on $p did not start"
    cat "$results/services.log" >>"$log"
    exit 1
  }
done
head -c 4000 "$results/services.log" >>"$log"

# NAME ARGS...: one bench render, its JSON appended to results.jsonl;
# SERVER_PORT picks the render server (default: the GPU default's).
bench() {
  local name=$1
  shift
  say "bench render $name: $*"
  "$bin/crackvis" bench render --server "localhost:${SERVER_PORT:-$render_port}" "$@" --json \
    >"$work/report.json" 2>>"$log"
  local rc=$?
  python3 - "$name" "$work/report.json" "$rc" >>"$results/results.jsonl" <<'EOF'
import json, sys
name, path, rc = sys.argv[1], sys.argv[2], int(sys.argv[3])
try:
    report = json.load(open(path))
except Exception as error:  # a failed run still leaves a line
    report = {"error": str(error)}
print(json.dumps({"run": name, "rc": rc, "report": report}))
EOF
  python3 - "$work/report.json" >>"$log" 2>&1 <<'EOF'
import json, sys
r = json.load(open(sys.argv[1]))
def get(*keys):
    v = r
    for k in keys:
        v = v.get(k, {}) if isinstance(v, dict) else {}
    return v if v != {} else None
print(json.dumps({k: r.get(k) for k in ("backend", "interactive_fps", "interactive_bitrate_mbps", "reduction",
                                        "frame_kinds", "load_before", "load_after", "p50_max_ms",
                                        "p50_median_ms", "p95_max_ms", "failed", "server")}, default=str)[:1500])
for key in ("event_to_frame_ms", "full_resolution_event_to_frame_ms", "render_full_ms", "render_reduced_ms",
            "full_resolution_render_ms", "encode_ms", "full_frame_after_idle_ms", "server_event_to_send_ms"):
    if isinstance(r.get(key), dict):
        print(key, {k: round(v, 1) for k, v in r[key].items() if k in ("count", "p50", "p95", "mean")})
for key in ("first_picture", "playback"):
    if key in r:
        print(key, json.dumps(r[key], default=str)[:700])
if isinstance(r.get("jumps"), dict):
    print("jumps", {k: {q: round(v.get(q, 0), 1) for q in ("count", "p50", "p95")}
                    for k, v in r["jumps"].items() if isinstance(v, dict)})
if "per_session" in r:
    print("per_session", json.dumps(r["per_session"], default=str)[:900])
EOF
  return $rc
}

a=cuboidA.h5
bench "A-1080p-60Hz" --file $a --size 1920x1080 --seconds "$drag" --event-rate 60 --still-frames 20 \
  --first-pictures 5 --jumps 30 --playback-steps 100
bench "A-1080p-120Hz" --file $a --size 1920x1080 --seconds "$drag" --event-rate 120 --still-frames 10 \
  --first-pictures 0 --jumps 0 --playback-steps 0
bench "A-720p-60Hz" --file $a --size 1280x720 --seconds "$drag" --event-rate 60 --still-frames 20 \
  --first-pictures 3 --jumps 30 --playback-steps 0
if [[ ${SKIP_1E6:-0} != 1 ]]; then
  bench "1e6-1080p" --file fcc-1e6.h5 --size 1920x1080 --seconds "$drag" --still-frames 10 \
    --first-pictures 2 --jumps 10 --playback-steps 0
  bench "1e6-720p" --file fcc-1e6.h5 --size 1280x720 --seconds "$drag" --still-frames 10 \
    --first-pictures 0 --jumps 0 --playback-steps 0
  # Occlusion culling on the CPU (llvmpipe's default) against the GPU
  # default (off), alternating, twice each.
  for round in 1 2; do
    SERVER_PORT=$culling_port bench "1e6-1080p-culling-on-$round" --file fcc-1e6.h5 --size 1920x1080 \
      --seconds 3 --still-frames 10 --first-pictures 0 --jumps 0 --playback-steps 0
    bench "1e6-1080p-culling-off-$round" --file fcc-1e6.h5 --size 1920x1080 \
      --seconds 3 --still-frames 10 --first-pictures 0 --jumps 0 --playback-steps 0
  done
fi
for round in 1 2; do
  SERVER_PORT=$culling_port bench "A-1080p-culling-on-$round" --file $a --size 1920x1080 \
    --seconds 3 --still-frames 10 --first-pictures 0 --jumps 0 --playback-steps 0
  bench "A-1080p-culling-off-$round" --file $a --size 1920x1080 \
    --seconds 3 --still-frames 10 --first-pictures 0 --jumps 0 --playback-steps 0
done
for n in 1 4 8; do
  bench "A-720p-sessions-$n" --file $a --size 1280x720 --seconds "$drag" --sessions "$n" \
    --server-pid "$render_pid"
done
say "render server peak RSS: $(awk '/^VmHWM/ { print $2 / 1024 " MB" }' /proc/$render_pid/status)"
nvidia-smi --query-gpu=utilization.gpu,memory.used --format=csv >>"$log" 2>&1
cat "$results/services.log" | tail -40 >>"$log"
say "done"
