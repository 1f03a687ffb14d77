#!/usr/bin/env bash
# The time to the first picture, crackvis against ParaView 5.11 with the
# crackvis plugin, on one file in one run (issue 34 point 1). Alternates, over
# R rounds (the order reversed every other round):
#   crackvis  fresh crackvis-data and crackvis-render on loopback; `crackvis
#             bench render --first-pictures 3`: each session from OpenSession
#             to its first full-resolution frame, the first on the fresh
#             services (cold caches), then the median of the later (warm);
#   ParaView  tools/bench/paraview-peer.sh --plugin: a fresh pvserver (Xvfb,
#             llvmpipe) that reads the file with the crackvis-dem reader,
#             extracts the crack with the local Voronoi filter and renders
#             the first still frame for a pvpython client; its first picture
#             is that load plus that frame (pvserver's start and the connect
#             excluded, as crackvis's service start is).
# Both show the same step, view size, spheres and crack surface; the file is
# in the page cache for both. Prints each run with the load beside it, then
# the medians and crackvis's ratio to ParaView (goal: at most 0.2).
# Figures: docs/benchmarks.md, "Time to the first picture".
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/../.." && pwd)
readonly here root
build=${CRACKVIS_BUILD:-$root/build/release}
readonly build

usage() {
  cat <<EOF
usage: tools/bench/first-picture.sh --data DIR --file NAME [--rounds R] [--size WxH] [--step S]
                                    [--out DIR]

Times the first picture of DIR/NAME (default: the last step, 1280x720) in crackvis (services
started fresh from \$build, CRACKVIS_BUILD) and in ParaView 5.11 with the crackvis plugin
(tools/bench/paraview-peer.sh --plugin), alternating over R rounds (default 3). --out keeps
the JSON of every run.
EOF
}

die() {
  echo "first-picture.sh: $*" >&2
  exit 1
}

data=
file=
rounds=3
size=1280x720
step=-1
out=
while (($#)); do
  case $1 in
    -h | --help) usage; exit 0 ;;
    --data) data=${2:?--data needs a value}; shift 2 ;;
    --file) file=${2:?--file needs a value}; shift 2 ;;
    --rounds) rounds=${2:?--rounds needs a value}; shift 2 ;;
    --size) size=${2:?--size needs a value}; shift 2 ;;
    --step) step=${2:?--step needs a value}; shift 2 ;;
    --out) out=${2:?--out needs a value}; shift 2 ;;
    *) die "unknown argument $1 (see --help)" ;;
  esac
done
[[ -d $data ]] || die "--data DIR is required and must be a folder"
[[ -n $file && -f $data/$file ]] || die "--file NAME must name a file in $data"
[[ $rounds =~ ^[1-9][0-9]*$ ]] || die "--rounds $rounds: expected a positive integer"
for binary in tools/crackvis dataservice/crackvis-data server/app/crackvis-render; do
  [[ -x $build/$binary ]] || die "$build/$binary is missing: build the project first"
done
crackvis=$build/tools/crackvis

# shellcheck source=tools/bench/bench_services.sh
source "$here/bench_services.sh"
cd "$root"
bench_output "$out"
cat "$data/$file" >/dev/null # into the page cache, for both

# crackvis ROUND: fresh services, three first pictures, the services stopped.
run_crackvis() {
  local log=$out/crackvis-$1
  bench_start_services "$data" "$log"
  "$crackvis" bench render --server "localhost:$bench_render_port" --file "$file" \
    --step "$step" --size "$size" --first-pictures 3 --seconds 0.5 --still-frames 0 --jumps 0 \
    --playback-steps 0 --json >"$log.json" 2>"$log.log" ||
    die "bench render failed: $(tail -3 "$log.log")"
  bench_stop_services
}

run_paraview() {
  bash "$here/paraview-peer.sh" "$data/$file" --plugin --step "$step" --size "$size" --frames 2 \
    --json "$out/paraview-$1.json" >/dev/null 2>"$out/paraview-$1.log" ||
    die "paraview-peer.sh failed: $(tail -3 "$out/paraview-$1.log")"
}

for r in $(seq "$rounds"); do
  order=(crackvis paraview)
  ((r % 2 == 0)) && order=(paraview crackvis)
  for tool in "${order[@]}"; do
    echo "round $r of $rounds: $tool (load $(cut -d' ' -f1-3 /proc/loadavg))" >&2
    cut -d' ' -f1 /proc/loadavg >"$out/load-$tool-$r"
    "run_$tool" "$r"
  done
done

python3 - "$out" "$rounds" "$file" <<'EOF'
import json, statistics, sys
out, rounds, name = sys.argv[1], int(sys.argv[2]), sys.argv[3]
med = statistics.median
rows = []
for r in range(1, rounds + 1):
    c = json.load(open(f"{out}/crackvis-{r}.json"))["first_picture"]
    p = json.load(open(f"{out}/paraview-{r}.json"))
    load = {t: float(open(f"{out}/load-{t}-{r}").read()) for t in ("crackvis", "paraview")}
    rows.append({"cold": c["first"]["total_ms"], "warm": c["later_median"]["total_ms"],
                 "cold_parts": c["first"], "pv_load": p["load_ms"], "pv_frame": p["first_frame_ms"],
                 "pv": p["load_ms"] + p["first_frame_ms"], "load": load})
print(f"time to the first picture of {name}: crackvis (fresh services: first open, later opens' "
      f"median) against ParaView 5.11 + crackvis plugin (read + extract, first still frame)")
print(f"{'round':>5} {'crackvis cold':>14} {'crackvis warm':>14} {'ParaView':>9} "
      f"{'(read+extract':>14} {'+ frame)':>9} {'cold / PV':>10} {'warm / PV':>10}  load")
for r, row in enumerate(rows, 1):
    print(f"{r:>5} {row['cold']:>14.0f} {row['warm']:>14.0f} {row['pv']:>9.0f} {row['pv_load']:>14.0f} "
          f"{row['pv_frame']:>9.0f} {row['cold'] / row['pv']:>10.3f} {row['warm'] / row['pv']:>10.3f}  "
          f"{row['load']['crackvis']:.2f} / {row['load']['paraview']:.2f}")
cold = med(r["cold"] for r in rows)
warm = med(r["warm"] for r in rows)
pv = med(r["pv"] for r in rows)
print(f"{'p50':>5} {cold:>14.0f} {warm:>14.0f} {pv:>9.0f} {med(r['pv_load'] for r in rows):>14.0f} "
      f"{med(r['pv_frame'] for r in rows):>9.0f} {cold / pv:>10.3f} {warm / pv:>10.3f}")
ratio = cold / pv
print(f"goal: crackvis's first picture at most 0.2x ParaView's: cold {ratio:.3f}x, warm {warm / pv:.3f}x "
      f"({'met' if ratio <= 0.2 else 'NOT met'} cold)")
def part(key):
    """The median over the rounds of one part of crackvis's cold first picture."""
    return med(r["cold_parts"]["server"].get(key, 0.0) for r in rows)
print(f"crackvis cold, median parts: OpenSession {med(r['cold_parts']['open_session_ms'] for r in rows):.0f} ms, "
      f"file opened {part('open_file_ms'):.0f} (Describe {part('describe_ms'):.0f}), "
      f"extraction {part('extract_ms'):.0f}, "
      f"render {part('render_ms'):.0f}")
EOF
