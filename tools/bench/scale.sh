#!/usr/bin/env bash
# The single-node cost curve (issue 19 point 3): for FCC blocks of about N
# particles with a planted through crack that opens (crackvis generate
# --planted-crack: the crack reaches the top at 3/4 of the steps, plus 0.2 %
# scattered breaks), per N:
#   - the time and peak memory of making the file;
#   - each method's time per step as a viewer runs it (incremental, reading
#     not timed, crackvis bench methods) with the bytes it keeps per particle;
#   - one 1280x720 snapshot of the last step (read, extract, render on llvmpipe);
#   - the reads through crackvis-data (crackvis bench transfer --views-only):
#     a view's first step (Describe + Read with the bond list) and a step
#     change (one Read);
#   - a live crackvis-render session at 1280x720 (crackvis bench render):
#     the interactive event-to-frame p50 while dragging, the full-resolution
#     event-to-frame p50 of still camera moves, and crackvis-render's peak
#     RSS so far (VmHWM: the largest N's session sets it).
# crackvis-data and crackvis-render run on loopback with the development
# certificates (certs/make-dev-certs.sh makes them when missing).
#
#   tools/bench/scale.sh OUT_DIR N [N ...]      # e.g. /tmp/scale 100000 1000000
#
# Prints a Markdown table (and OUT_DIR/scale.jsonl, a JSON object per N) and
# draws OUT_DIR/scale.png (gnuplot): the times against N, log-log. The files
# are kept in OUT_DIR (about 45 B per particle per saved step on disk).
# Environment: CRACKVIS_BUILD (default build/release), STEPS (planted-crack
# steps, default 10), THREADS (default: all cores), DRAG_SECONDS (default 5),
# STILL_FRAMES (default 10).
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/../.." && pwd)
build=${CRACKVIS_BUILD:-$root/build/release}
crackvis=$build/tools/crackvis
steps=${STEPS:-10}
threads=${THREADS:-$(nproc)}
drag_seconds=${DRAG_SECONDS:-5}
still_frames=${STILL_FRAMES:-10}
out=${1:?usage: scale.sh OUT_DIR N [N ...]}
shift
(($#)) || { echo "scale.sh: give at least one particle count" >&2; exit 2; }
for binary in tools/crackvis dataservice/crackvis-data server/app/crackvis-render; do
  [[ -x $build/$binary ]] || { echo "scale.sh: $build/$binary is missing: build first" >&2; exit 1; }
done
mkdir -p "$out"
out=$(cd "$out" && pwd)
: >"$out/scale.jsonl"

# crackvis-data serving OUT_DIR and crackvis-render reading through it.
cd "$root"
[[ -f certs/generated/crackvis-render.pem ]] || bash certs/make-dev-certs.sh --client crackvis-render >&2
free_port() {
  python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'
}
pids=()
trap 'for pid in "${pids[@]}"; do kill "$pid" 2>/dev/null || true; done; wait 2>/dev/null || true' EXIT
data_port=$(free_port)
render_port=$(free_port)
"$build/dataservice/crackvis-data" --root "$out" --listen "127.0.0.1:$data_port" --access-log '' \
  >"$out/crackvis-data.log" 2>&1 &
pids+=($!)
"$build/server/app/crackvis-render" --listen "127.0.0.1:$render_port" \
  --data-server "localhost:$data_port" --access-log '' >"$out/crackvis-render.log" 2>&1 &
render_pid=$!
pids+=("$render_pid")
for _ in $(seq 100); do
  "$crackvis" health "localhost:$render_port" >/dev/null 2>&1 && break
  sleep 0.2
done
"$crackvis" health "localhost:$render_port" >/dev/null ||
  { echo "scale.sh: crackvis-render did not start: $(tail -3 "$out/crackvis-render.log")" >&2; exit 1; }
peak_mb() { awk '/^VmHWM/ { printf "%.0f", $2 / 1024 }' "/proc/$1/status"; }

# Seconds and peak RSS (MB) of a command, as "S MB", its output discarded.
timed() {
  /usr/bin/time -f '%e %M' -o "$out/time.txt" "$@" >/dev/null 2>"$out/stderr.txt" || {
    tail -5 "$out/stderr.txt" >&2
    return 1
  }
  awk '{ printf "%s %.0f", $1, $2 / 1024 }' "$out/time.txt"
}

echo "machine: $(lscpu | sed -n 's/^Model name: *//p'), $(nproc) hardware threads; load before $(cut -d' ' -f1-3 /proc/loadavg)" >&2
echo "| particles | bonds | generate s / MB | cell attribute | cell cut | local Voronoi | cell centre | snapshot s / MB | crackvis-data: first view / step change | session: interactive p50 / full frame p50 / render server peak |"
echo "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
for n in "$@"; do
  # FCC with s site planes per axis holds about s^3 / 2 particles.
  sites=$(python3 -c "print(round((2 * $n) ** (1 / 3)))")
  file=$out/fcc-$n.h5
  made=$(timed "$crackvis" generate --sites "$sites" "$sites" "$sites" --planted-crack "$steps" -o "$file")
  sync  # the file's dirty pages written back now, not during the timings below
  "$crackvis" bench methods "$file" --voro-every 0 --runs 1 --threads "$threads" --json -q \
    >"$out/methods-$n.json"
  shot=$(timed "$crackvis" snapshot "$file" -s -1 -m local-voronoi --width 1280 --height 720 \
    -q -o "$out/fcc-$n.png")
  "$crackvis" bench transfer --server "localhost:$data_port" --file "fcc-$n.h5" --views-only \
    --repeat 5 --json >"$out/transfer-$n.json" 2>"$out/transfer-$n.log"
  "$crackvis" bench render --server "localhost:$render_port" --file "fcc-$n.h5" --size 1280x720 \
    --seconds "$drag_seconds" --still-frames "$still_frames" --json >"$out/render-$n.json" \
    2>"$out/render-$n.log"
  render_peak=$(peak_mb "$render_pid")
  python3 - "$out/methods-$n.json" "$n" "$made" "$shot" "$threads" "$out/transfer-$n.json" \
    "$out/render-$n.json" "$render_peak" >>"$out/scale.jsonl" <<'EOF'
import json, sys
path, n, made, shot, threads, transfer_path, render_path, render_peak = sys.argv[1:9]
transfer = json.load(open(transfer_path))
render = json.load(open(render_path))
report = json.load(open(path))
config = [c for c in report["configs"] if c.get("threads") == int(threads)] or report["configs"][-1:]
methods = config[0]["methods"]
row = {"requested": int(n), "particles": report.get("particles"), "bonds": report.get("bonds"),
       "generate_s": float(made.split()[0]), "generate_mb": int(made.split()[1]),
       "snapshot_s": float(shot.split()[0]), "snapshot_mb": int(shot.split()[1]),
       "threads": config[0].get("threads"),
       "methods": {name: {"max_ms": m["max_ms"], "median_ms": m["median_ms"]}
                   for name, m in methods.items()},
       "bytes_per_particle": {name: m.get("state_bytes_per_particle")
                              for name, m in report.get("methods", {}).items()},
       "data_first_view_ms": 1e3 * transfer["grpc_first_view"]["seconds_median"],
       "data_first_view_bytes": transfer["grpc_first_view"]["bytes"],
       "data_step_change_ms": 1e3 * transfer["grpc_warm_view"]["seconds_median"],
       "data_step_change_bytes": transfer["grpc_warm_view"]["bytes"],
       "session_interactive_p50_ms": render["event_to_frame_ms"]["p50"],
       "session_full_frame_p50_ms": render["full_resolution_event_to_frame_ms"]["p50"],
       "session_frame_kinds": render.get("frame_kinds"),
       "render_server_peak_mb": int(render_peak),
       "load_before": report.get("load_before"), "load_after": report.get("load_after"),
       "load_after_session": render.get("load_after")}
print(json.dumps(row))
EOF
  python3 - "$out/scale.jsonl" <<'EOF'
import json, sys
row = json.loads(open(sys.argv[1]).read().splitlines()[-1])
def cell(name):
    m = row["methods"][name]
    b = (row.get("bytes_per_particle") or {}).get(name)
    per = f", {b:.0f} B/p" if isinstance(b, (int, float)) else ""
    return f"{m['max_ms']:.1f} ms max, {m['median_ms']:.1f} ms median{per}"
print(f"| {row['particles']:,} | {row['bonds']:,} | {row['generate_s']:.1f} / {row['generate_mb']:,} "
      f"| {cell('cell-attribute')} | {cell('cell-cut')} | {cell('local-voronoi')} "
      f"| {cell('cell-centre')} | {row['snapshot_s']:.1f} / {row['snapshot_mb']:,} "
      f"| {row['data_first_view_ms']:,.0f} ms / {row['data_step_change_ms']:,.0f} ms "
      f"| {row['session_interactive_p50_ms']:,.0f} ms / {row['session_full_frame_p50_ms']:,.0f} ms "
      f"/ {row['render_server_peak_mb']:,} MB |")
EOF
done
echo "load after $(cut -d' ' -f1-3 /proc/loadavg)" >&2

# The plot: every time against N, log-log.
python3 - "$out/scale.jsonl" >"$out/scale.dat" <<'EOF'
import json, sys
print("# particles, largest step ms of cell-attribute cell-cut local-voronoi cell-centre, "
      "snapshot ms, crackvis-data step change ms, session interactive p50 ms, full frame p50 ms")
for line in open(sys.argv[1]):
    r = json.loads(line)
    m = r["methods"]
    print(r["particles"], *(m[k]["max_ms"] for k in ("cell-attribute", "cell-cut", "local-voronoi",
                                                      "cell-centre")),
          1e3 * r["snapshot_s"], r["data_step_change_ms"], r["session_interactive_p50_ms"],
          r["session_full_frame_p50_ms"])
EOF
gnuplot <<EOF
set terminal pngcairo size 900,560 font "sans,11"
set output "$out/scale.png"
set logscale xy
set grid
set key top left
set xlabel "particles"
set ylabel "milliseconds"
set title "crackvis on one node ($(nproc) threads, llvmpipe, 1280x720): cost against size"
plot "$out/scale.dat" using 1:2 with linespoints title "cell attribute, largest step", \\
     "" using 1:3 with linespoints title "cell cut, largest step", \\
     "" using 1:4 with linespoints title "local Voronoi, largest step", \\
     "" using 1:5 with linespoints title "cell centre, largest step", \\
     "" using 1:6 with linespoints title "snapshot (read, extract, render)", \\
     "" using 1:7 with linespoints title "crackvis-data step change (Read)", \\
     "" using 1:8 with linespoints title "session: interactive event-to-frame p50", \\
     "" using 1:9 with linespoints title "session: full-resolution frame p50"
EOF
echo "plot: $out/scale.png" >&2
