#!/usr/bin/env bash
# The browser page against the C++ clients on the same view, alternately: run k
# of `crackvis bench render` (a C++ gRPC client decoding with crackvis-client's
# decoder, libavcodec: its event-to-frame latency, before the decode), run k of
# crackvis-client itself (the Qt window, off screen: `--measure-latency`,
# event to painted frame), then run k of tools/bench/browser_latency.mjs
# (headless Chromium through the web front door: event to painted frame,
# decoded with WebCodecs and drawn on the canvas), for each k, with the load
# average beside every run; then the medians side by side. The issue's goal
# compares the browser with the Qt client. Figures: docs/benchmarks.md, "The
# browser page".
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/../.." && pwd)
readonly here root
build=${CRACKVIS_BUILD:-$root/build/release}
readonly build

usage() {
  cat <<EOF
usage: tools/bench/browser-vs-client.sh DATA_ROOT FILE [--runs R] [--size WxH] [--seconds S]
                                        [--stills N] [--pin] [--out DIR]

Alternates R runs (default 5) of 'crackvis bench render', of crackvis-client --measure-latency
(the Qt window, QT_QPA_PLATFORM=offscreen) and of the browser page in headless Chromium on
DATA_ROOT/FILE's last step at WxH (default 1280x720): a drag of S seconds (default 5) with rotate
moves at 60 Hz, then N (default 10) still camera moves answered at full resolution. Prints p50
and p95 of both latencies for the three clients, the browser's first frame after choosing the
file, the decode times, bitrate and each window's CPU time per painted frame.

--pin runs the services on CPU 0 and each client on CPU 1 (taskset), as a client on a machine of
its own would leave the server's CPU alone; without it all share every CPU.

Starts its own crackvis-data and crackvis-render (with --web-listen and a user for the page) from
$build (CRACKVIS_BUILD) on free loopback ports with the development certificates.
EOF
}

die() {
  echo "browser-vs-client.sh: $*" >&2
  exit 1
}

runs=5
size=1280x720
seconds=5
stills=10
out=
server_cpus=()
client_cpus=()
positional=()
while (($#)); do
  case $1 in
    -h | --help) usage; exit 0 ;;
    --runs) runs=${2:?--runs needs a value}; shift 2 ;;
    --size) size=${2:?--size needs a value}; shift 2 ;;
    --seconds) seconds=${2:?--seconds needs a value}; shift 2 ;;
    --stills) stills=${2:?--stills needs a value}; shift 2 ;;
    --out) out=${2:?--out needs a value}; shift 2 ;;
    --pin) server_cpus=(taskset -c 0); client_cpus=(taskset -c 1); shift ;;
    -*) die "unknown option $1 (see --help)" ;;
    *) positional+=("$1"); shift ;;
  esac
done
((${#positional[@]} == 2)) || { usage >&2; exit 2; }
data_root=$(cd "${positional[0]}" && pwd) || die "no folder ${positional[0]}"
file=${positional[1]}
[[ -f $data_root/$file ]] || die "no file $data_root/$file"
[[ $runs =~ ^[1-9][0-9]*$ ]] || die "--runs $runs: expected a positive integer"
for binary in tools/crackvis dataservice/crackvis-data server/app/crackvis-render \
  client/app/crackvis-client web/dist/index.html \
  web/node_modules/playwright-core/package.json; do
  [[ -e $build/$binary ]] || die "$build/$binary is missing: build the project (and crackvis-web) first"
done

# shellcheck source=tools/bench/bench_services.sh
source "$here/bench_services.sh"
cd "$root"
bench_output "$out"

# The page's user, and the C++ client's certificate as a user of its own.
password=$(openssl rand -hex 12)
hash=$(printf %s "$password" | "$build/dataservice/crackvis-data" hash-secret)
cat >"$out/users.json" <<EOF
{"users": [
  {"name": "bench", "password_hash": "$hash", "folders": ["*"]},
  {"name": "client", "certificate_name": "crackvis-client", "folders": ["*"]}
]}
EOF

data_port=$(bench_free_port)
render_port=$(bench_free_port)
web_port=$(bench_free_port)
bench_background "${server_cpus[@]}" "$build/dataservice/crackvis-data" --root "$data_root" \
  --listen "127.0.0.1:$data_port" --access-log '' >"$out/crackvis-data.log" 2>&1
bench_background "${server_cpus[@]}" "$build/server/app/crackvis-render" \
  --listen "127.0.0.1:$render_port" --data-server "localhost:$data_port" \
  --users-from "$out/users.json" --web-listen "127.0.0.1:$web_port" \
  --web-root "$build/web/dist" --access-log '' >"$out/crackvis-render.log" 2>&1
bench_wait_render "$render_port" "$out/crackvis-render.log"

for k in $(seq "$runs"); do
  echo "run $k of $runs: crackvis bench render (load $(cut -d' ' -f1-3 /proc/loadavg))" >&2
  cut -d' ' -f1 /proc/loadavg >"$out/client-$k.load"
  "${client_cpus[@]}" "$build/tools/crackvis" bench render --server "localhost:$render_port" --file "$file" \
    --size "$size" --seconds "$seconds" --still-frames "$stills" --json \
    >"$out/client-$k.json" 2>"$out/client-$k.log" ||
    die "crackvis bench render failed: $(tail -3 "$out/client-$k.log")"
  echo "run $k of $runs: crackvis-client (load $(cut -d' ' -f1-3 /proc/loadavg))" >&2
  cut -d' ' -f1 /proc/loadavg >"$out/qt-$k.load"
  QT_QPA_PLATFORM=offscreen "${client_cpus[@]}" "$build/client/app/crackvis-client" \
    --connect "localhost:$render_port" --file "$file" --measure-latency "$out/qt-$k.json" \
    --view-size "$size" --drag-seconds "$seconds" --still-moves "$stills" >"$out/qt-$k.log" 2>&1 ||
    die "crackvis-client --measure-latency failed: $(tail -3 "$out/qt-$k.log")"
  echo "run $k of $runs: browser (load $(cut -d' ' -f1-3 /proc/loadavg))" >&2
  cut -d' ' -f1 /proc/loadavg >"$out/browser-$k.load"
  CRACKVIS_WEB_URL="https://localhost:$web_port/" CRACKVIS_USER=bench \
    CRACKVIS_PASSWORD="$password" CRACKVIS_FILE="$file" \
    CRACKVIS_NODE_MODULES="$build/web/node_modules" BENCH_SIZE="$size" \
    BENCH_SECONDS="$seconds" BENCH_STILLS="$stills" \
    "${client_cpus[@]}" node "$here/browser_latency.mjs" >"$out/browser-$k.json" 2>"$out/browser-$k.log" ||
    die "browser_latency.mjs failed: $(tail -3 "$out/browser-$k.log")"
done

python3 - "$out" "$runs" <<'EOF'
import json, statistics, sys
out, runs = sys.argv[1], int(sys.argv[2])
client = [json.load(open(f"{out}/client-{k}.json")) for k in range(1, runs + 1)]
qt = [json.load(open(f"{out}/qt-{k}.json")) for k in range(1, runs + 1)]
page = [json.load(open(f"{out}/browser-{k}.json")) for k in range(1, runs + 1)]
load = lambda kind: [float(open(f"{out}/{kind}-{k}.load").read()) for k in range(1, runs + 1)]
def med(values):
    known = [v for v in values if v is not None]
    return statistics.median(known) if known else float("nan")
rows = [
    ("drag: event to frame, p50 ms", med(c["event_to_frame_ms"]["p50"] for c in client),
     med(q["drag_event_to_paint_ms"]["p50"] for q in qt), med(p["drag_event_to_paint_ms"]["p50"] for p in page)),
    ("drag: event to frame, p95 ms", med(c["event_to_frame_ms"]["p95"] for c in client),
     med(q["drag_event_to_paint_ms"]["p95"] for q in qt), med(p["drag_event_to_paint_ms"]["p95"] for p in page)),
    ("still move: event to full-resolution frame, p50 ms",
     med(c["full_resolution_event_to_frame_ms"]["p50"] for c in client),
     med(q["still_event_to_paint_ms"]["p50"] for q in qt), med(p["still_event_to_paint_ms"]["p50"] for p in page)),
    ("still move: event to full-resolution frame, p95 ms",
     med(c["full_resolution_event_to_frame_ms"]["p95"] for c in client),
     med(q["still_event_to_paint_ms"]["p95"] for q in qt), med(p["still_event_to_paint_ms"]["p95"] for p in page)),
    ("drag: the server's part (last event received to frame sent), p50 ms",
     med(c.get("server_event_to_send_ms", {}).get("p50") for c in client),
     med(q["server_event_to_send_ms"]["p50"] for q in qt),
     med(p.get("server_event_to_send_ms", {}).get("p50") for p in page)),
    ("decode p50 ms", med(c["client_decode_ms"]["p50"] for c in client), med(q["decode_ms"]["p50"] for q in qt),
     med(p["decode_ms"]["p50"] for p in page)),
    ("frames per second while dragging", med(c.get("interactive_fps") for c in client), med(q["drag_fps"] for q in qt),
     med(p["drag_fps"] for p in page)),
]
print(f"browser page vs crackvis-client (Qt window, off screen) and crackvis bench render (C++ gRPC "
      f"client, latency before its decode), {page[0]['size']}, medians of {runs} alternating runs ({page[0]['chromium']})")
print(f"  {'':<52} {'bench render':>12} {'Qt client':>10} {'browser':>9} {'browser - Qt':>13} {'browser - bench':>16}")
for name, c, q, p in rows:
    print(f"  {name:<52} {c:12.1f} {q:10.1f} {p:9.1f} {p - q:13.1f} {p - c:16.1f}")
print(f"  browser: first frame after choosing the file     {med(p['first_frame_ms'] for p in page):9.0f} ms"
      f"  (runs: {[round(p['first_frame_ms']) for p in page]}; the page's double click to its first frame painted)")
print(f"    with the harness's double click (Playwright)    {med(p.get('first_frame_wall_ms') for p in page):9.0f} ms")
print(f"  Qt client: first frame after the file's open      {med(q['first_frame_ms'] for q in qt):9.0f} ms")
print(f"  browser: bitrate while dragging                  {med(p['bitrate_mbps'] for p in page):9.2f} Mbit/s"
      f" (Qt client {med(q['bitrate_mbps'] for q in qt):.2f})")
print(f"  browser: Chromium's CPU time per painted frame   {med(p['browser_cpu_ms_per_frame'] for p in page):9.2f} ms (all its processes)")
by_process = {}
for p in page:
    for kind, ms in (p.get("browser_cpu_ms_per_frame_by_process") or {}).items():
        if kind != "all" and ms is not None:
            by_process.setdefault(kind, []).append(ms)
print("  browser: of which, by Chromium's process type   " +
      ", ".join(f"{kind} {statistics.median(ms):.2f}" for kind, ms in sorted(by_process.items())) + " ms")
print(f"  Qt client: its CPU time per painted frame        {med(q['client_cpu_ms_per_frame'] for q in qt):9.2f} ms")
print(f"  load before each run (1 min): bench render {load('client')}, Qt client {load('qt')}, browser {load('browser')}")
goal = rows[0][3] <= rows[0][2] + 5 and rows[2][3] <= rows[2][2] + 5
print(f"  goal browser p50 <= Qt client p50 + 5 ms (drag and still): {'met' if goal else 'NOT met'}; "
      f"first frame <= 1 s: {'met' if med(p['first_frame_ms'] for p in page) <= 1000 else 'NOT met'}")
json.dump({"client": client, "qt": qt, "browser": page,
           "load": {"client": load("client"), "qt": load("qt"), "browser": load("browser")}},
          open(f"{out}/summary.json", "w"), indent=1)
EOF
