#!/usr/bin/env bash
# crackvis's render server and ParaView 5.11 client/server on the same view,
# alternately: run k of `crackvis bench render` (real crackvis-data and
# crackvis-render on loopback, mutual TLS), then run k of paraview-peer.sh,
# for each k; then a table of the medians over the runs side by side, with
# the load average beside every run. Figures: docs/benchmarks.md.
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/../.." && pwd)
readonly here root
build=${CRACKVIS_BUILD:-$root/build/release}
readonly build

usage() {
  cat <<EOF
usage: tools/bench/render-vs-paraview.sh DATA_ROOT FILE [--runs R] [--size WxH] [--seconds S]
                                         [--frames N] [--max-reduction K] [--plugin] [--out DIR]

Alternates R runs (default 5) of 'crackvis bench render' and of tools/bench/paraview-peer.sh on
DATA_ROOT/FILE's last step at WxH (default 1280x720), then prints the medians side by side:
crackvis's full-resolution event-to-frame latency (a camera move answered by a full-resolution
frame) against ParaView's still render, and both interactive latencies.

  --runs R      alternating runs of each (default 5)
  --size WxH    view size (default 1280x720)
  --seconds S   length of crackvis's drag (default 5)
  --frames N    ParaView's timed frames and crackvis's still frames per run (default 20)
  --max-reduction K  crackvis-render's largest image reduction factor (default: the server's, 8)
  --plugin      ParaView as deploy/pvserver-beside-data.sh runs it: pvserver reads FILE itself
                through the crackvis plugin (reader + local Voronoi filter) instead of files
                crackvis exported beforehand
  --out DIR     keep every run's JSON and the summary there (default: a temporary folder)

Starts its own crackvis-data and crackvis-render from $build (CRACKVIS_BUILD) on free loopback
ports with the development certificates (certs/make-dev-certs.sh makes them when missing).
EOF
}

die() {
  echo "render-vs-paraview.sh: $*" >&2
  exit 1
}

runs=5
size=1280x720
seconds=5
frames=20
max_reduction=8
plugin=()
out=
positional=()
while (($#)); do
  case $1 in
    -h | --help) usage; exit 0 ;;
    --runs) runs=${2:?--runs needs a value}; shift 2 ;;
    --size) size=${2:?--size needs a value}; shift 2 ;;
    --seconds) seconds=${2:?--seconds needs a value}; shift 2 ;;
    --frames) frames=${2:?--frames needs a value}; shift 2 ;;
    --max-reduction) max_reduction=${2:?--max-reduction needs a value}; shift 2 ;;
    --out) out=${2:?--out needs a value}; shift 2 ;;
    --plugin) plugin=(--plugin); shift ;;
    -*) die "unknown option $1 (see --help)" ;;
    *) positional+=("$1"); shift ;;
  esac
done
((${#positional[@]} == 2)) || { usage >&2; exit 2; }
data_root=$(cd "${positional[0]}" && pwd) || die "no folder ${positional[0]}"
file=${positional[1]}
[[ -f $data_root/$file ]] || die "no file $data_root/$file"
[[ $runs =~ ^[1-9][0-9]*$ ]] || die "--runs $runs: expected a positive integer"
for binary in tools/crackvis dataservice/crackvis-data server/app/crackvis-render; do
  [[ -x $build/$binary ]] || die "$build/$binary is missing: build the project first"
done

# shellcheck source=tools/bench/bench_services.sh
source "$here/bench_services.sh"
cd "$root"
bench_output "$out"

data_port=$(bench_free_port)
render_port=$(bench_free_port)
bench_background "$build/dataservice/crackvis-data" --root "$data_root" \
  --listen "127.0.0.1:$data_port" --access-log '' >"$out/crackvis-data.log" 2>&1
bench_background "$build/server/app/crackvis-render" --listen "127.0.0.1:$render_port" \
  --data-server "localhost:$data_port" --max-reduction "$max_reduction" --access-log '' \
  >"$out/crackvis-render.log" 2>&1
bench_wait_render "$render_port" "$out/crackvis-render.log"

for k in $(seq "$runs"); do
  echo "run $k of $runs: crackvis (load $(cut -d' ' -f1-3 /proc/loadavg))" >&2
  "$build/tools/crackvis" bench render --server "localhost:$render_port" --file "$file" \
    --size "$size" --seconds "$seconds" --still-frames "$frames" --json \
    >"$out/crackvis-$k.json" 2>"$out/crackvis-$k.log" ||
    die "crackvis bench render failed: $(tail -3 "$out/crackvis-$k.log")"
  echo "run $k of $runs: ParaView (load $(cut -d' ' -f1-3 /proc/loadavg))" >&2
  CRACKVIS="$build/tools/crackvis" "$here/paraview-peer.sh" "$data_root/$file" --size "$size" \
    --frames "$frames" "${plugin[@]}" --json "$out/paraview-$k.json" >/dev/null \
    2>"$out/paraview-$k.log" ||
    die "paraview-peer.sh failed: $(tail -3 "$out/paraview-$k.log")"
done

python3 - "$out" "$runs" "$max_reduction" "${#plugin[@]}" <<'EOF'
import json, statistics, sys
out, runs, plugin = sys.argv[1], int(sys.argv[2]), sys.argv[4] == "1"
cv = [json.load(open(f"{out}/crackvis-{k}.json")) for k in range(1, runs + 1)]
pv = [json.load(open(f"{out}/paraview-{k}.json")) for k in range(1, runs + 1)]
med = lambda values: statistics.median(values)
rows = {
    "crackvis full-resolution event-to-frame p50 ms": med([c["full_resolution_event_to_frame_ms"]["p50"] for c in cv]),
    "crackvis full-resolution render p50 ms": med([c["full_resolution_render_ms"]["p50"] for c in cv]),
    "ParaView still render p50 ms": med([p["still_render_ms"]["p50"] for p in pv]),
    "ParaView load (read, extract) ms": med([p["load_ms"] for p in pv]),
    "ParaView first frame ms": med([p["first_frame_ms"] for p in pv]),
    "crackvis interactive event-to-frame p50 ms": med([c["event_to_frame_ms"]["p50"] for c in cv]),
    "ParaView interactive render p50 ms": med([p["interactive_ms"]["p50"] for p in pv]),
}
ratios = {
    "full_resolution_over_paraview_still": rows["crackvis full-resolution event-to-frame p50 ms"] / rows["ParaView still render p50 ms"],
    "interactive_over_paraview_interactive": rows["crackvis interactive event-to-frame p50 ms"] / rows["ParaView interactive render p50 ms"],
}
kinds = {}
for c in cv:
    for kind, count in c["frame_kinds"].items():
        kinds[kind] = kinds.get(kind, 0) + count
summary = {
    "runs": runs,
    "crackvis_max_reduction": int(sys.argv[3]),
    "paraview_data_path": pv[0].get("data_path"),
    "paraview_plugin": plugin,
    "size": cv[0]["size"],
    "particles": cv[0]["particles"],
    "medians": rows,
    "ratios": ratios,
    "crackvis_frame_kinds": kinds,
    "crackvis_interactive_spheres_at_most_2x": all(c["targets"]["interactive_spheres_at_most_2x_reduction"] for c in cv),
    "load": {"crackvis": [c["load_before"] for c in cv], "paraview": [p.get("loadavg_before") for p in pv]},
    "goals": {
        "full_resolution_over_paraview_still_le_0.5": ratios["full_resolution_over_paraview_still"] <= 0.5,
        "interactive_p50_le_40ms_spheres_at_most_2x": rows["crackvis interactive event-to-frame p50 ms"] <= 40.0
        and all(c["targets"]["interactive_spheres_at_most_2x_reduction"] for c in cv),
    },
}
json.dump(summary, open(f"{out}/summary.json", "w"), indent=2)
print(f"crackvis vs ParaView 5.11, {summary['size']}, {summary['particles']} particles, medians of {runs} alternating runs"
      f" (crackvis-render --max-reduction {summary['crackvis_max_reduction']})")
print(f"  ParaView's data: {summary['paraview_data_path']}")
for name, value in rows.items():
    print(f"  {name:<48} {value:9.1f}")
for name, value in ratios.items():
    print(f"  {name:<48} {value:9.2f}")
print("  crackvis frames drawn as:", ", ".join(f"{k} x{v}" for k, v in sorted(kinds.items())))
print("  load before each run (1 min): crackvis", [round(l[0], 2) for l in summary["load"]["crackvis"]],
      "ParaView", [round(l[0], 2) if l else None for l in summary["load"]["paraview"]])
print("  goals:", ", ".join(f"{k}={'met' if v else 'NOT met'}" for k, v in summary["goals"].items()))
print(json.dumps(summary))
EOF
