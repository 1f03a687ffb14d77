#!/usr/bin/env bash
# Many users on one render node (issue 34 point 3): `crackvis bench render
# --sessions N` for each N given, in alternating order over R rounds, against
# one crackvis-render started fresh. Each session has its own connection,
# file (the --file list in turn) and view, and all drag together. Prints per
# N the sessions' event-to-frame p50 and p95 (the median session and the
# worst), their frame rate and reduction, the server's CPU and resident
# memory, and the ratio of each N's p50 to N = 1's.
# Figures: docs/benchmarks.md, "Many users on one render node".
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/../.." && pwd)
readonly here root
build=${CRACKVIS_BUILD:-$root/build/release}
readonly build

usage() {
  cat <<EOF
usage: tools/bench/sessions.sh --data DIR --file NAME [--file NAME ...] [--counts "1 2 4 8"]
                               [--rounds R] [--seconds S] [--size WxH] [--renders-at-once K]
                               [--out DIR]

Runs 'crackvis bench render --sessions N' for each N in --counts (default "1 2 4 8"), R rounds
(default 2), the order reversed every other round, against a crackvis-data over DIR and a
crackvis-render (--max-sessions: the largest N) started fresh from \$build (CRACKVIS_BUILD) on free
loopback ports with the development certificates. Each session drags for S seconds (default 5) at
WxH (default 1280x720) on the files NAME (relative to DIR) in turn. Prints each run with the load
beside it, then per N the medians over the rounds. --renders-at-once is passed on to crackvis-render
(default: its own, the hardware threads).
EOF
}

die() {
  echo "sessions.sh: $*" >&2
  exit 1
}

data=
files=()
counts="1 2 4 8"
rounds=2
seconds=5
size=1280x720
out=
render_options=()
while (($#)); do
  case $1 in
    -h | --help) usage; exit 0 ;;
    --data) data=${2:?--data needs a value}; shift 2 ;;
    --file) files+=("${2:?--file needs a value}"); shift 2 ;;
    --counts) counts=${2:?--counts needs a value}; shift 2 ;;
    --rounds) rounds=${2:?--rounds needs a value}; shift 2 ;;
    --seconds) seconds=${2:?--seconds needs a value}; shift 2 ;;
    --size) size=${2:?--size needs a value}; shift 2 ;;
    --renders-at-once) render_options+=(--renders-at-once "${2:?--renders-at-once needs a value}"); shift 2 ;;
    --out) out=${2:?--out needs a value}; shift 2 ;;
    *) die "unknown argument $1 (see --help)" ;;
  esac
done
[[ -d $data ]] || die "--data DIR is required and must be a folder"
((${#files[@]})) || die "give at least one --file"
for file in "${files[@]}"; do
  [[ -f $data/$file ]] || die "$data/$file does not exist"
done
[[ $rounds =~ ^[1-9][0-9]*$ ]] || die "--rounds $rounds: expected a positive integer"
largest=0
for n in $counts; do
  [[ $n =~ ^[1-9][0-9]*$ ]] || die "--counts: $n is not a positive integer"
  ((n > largest)) && largest=$n
done
for binary in tools/crackvis dataservice/crackvis-data server/app/crackvis-render; do
  [[ -x $build/$binary ]] || die "$build/$binary is missing: build the project first"
done
crackvis=$build/tools/crackvis

# shellcheck source=tools/bench/bench_services.sh
source "$here/bench_services.sh"
cd "$root"
bench_output "$out"
data_port=$(bench_free_port)
render_port=$(bench_free_port)
bench_background "$build/dataservice/crackvis-data" --root "$data" \
  --listen "127.0.0.1:$data_port" --access-log '' >"$out/crackvis-data.log" 2>&1
bench_background "$build/server/app/crackvis-render" --listen "127.0.0.1:$render_port" \
  --data-server "localhost:$data_port" --access-log '' --max-sessions "$((largest > 8 ? largest : 8))" \
  "${render_options[@]}" \
  >"$out/crackvis-render.log" 2>&1
render_pid=${bench_pids[-1]}
bench_wait_render "$render_port" "$out/crackvis-render.log"

file_args=()
for file in "${files[@]}"; do
  file_args+=(--file "$file")
done
read -r -a order <<<"$counts"
for r in $(seq "$rounds"); do
  if ((r % 2 == 0)); then
    reversed=()
    for ((k = ${#order[@]} - 1; k >= 0; k--)); do reversed+=("${order[k]}"); done
    run_order=("${reversed[@]}")
  else
    run_order=("${order[@]}")
  fi
  for n in "${run_order[@]}"; do
    echo "round $r of $rounds: $n session(s) (load $(cut -d' ' -f1-3 /proc/loadavg))" >&2
    "$crackvis" bench render --server "localhost:$render_port" "${file_args[@]}" --sessions "$n" \
      --server-pid "$render_pid" --size "$size" --seconds "$seconds" --json \
      >"$out/sessions-$n-$r.json" 2>"$out/sessions-$n-$r.log" ||
      die "bench render --sessions $n failed: $(tail -3 "$out/sessions-$n-$r.log")"
  done
done

python3 - "$out" "$rounds" "$counts" <<'EOF'
import json, statistics, sys
out, rounds, counts = sys.argv[1], int(sys.argv[2]), [int(n) for n in sys.argv[3].split()]
med = statistics.median
runs = {n: [json.load(open(f"{out}/sessions-{n}-{r}.json")) for r in range(1, rounds + 1)] for n in counts}
first = runs[counts[0]][0]
print(f"crackvis bench render --sessions N: {first['size']}, each session dragging {first['seconds']} s "
      f"at {first['event_rate']:.0f} events/s; {first['machine']}")
for n in counts:
    for r, run in enumerate(runs[n], 1):
        s = run["per_session"]
        print(f"  N={n} round {r}: p50 per session {[round(x['event_to_frame_ms']['p50'], 1) for x in s]} ms, "
              f"p95 {[round(x['event_to_frame_ms']['p95'], 1) for x in s]} ms, "
              f"fps {[round(x['fps'], 1) for x in s]}, reduction {[round(x['reduction_mean'], 2) for x in s]}, "
              f"coarse {[round(x.get('coarse_share', 0) * 100) for x in s]} %; "
              f"server {run['server']['cpu_cores']:.2f} cores, {run['server']['rss_peak_mib']:.0f} MiB peak; "
              f"load {run['load_before'][0]:.2f}")
base = med(run["p50_median_ms"] for run in runs[counts[0]])
print(f"\n{'N':>3} {'p50 median':>11} {'p50 worst':>10} {'p95 worst':>10} {'fps':>6} {'reduction':>9} "
      f"{'coarse':>6} {'cores':>6} {'RSS MiB':>8} {'p50 / N=' + str(counts[0]):>10}")
for n in counts:
    p50 = med(run["p50_median_ms"] for run in runs[n])
    worst = med(run["p50_max_ms"] for run in runs[n])
    p95 = med(run["p95_max_ms"] for run in runs[n])
    fps = med(x["fps"] for run in runs[n] for x in run["per_session"])
    reduction = med(x["reduction_mean"] for run in runs[n] for x in run["per_session"])
    coarse = med(x.get("coarse_share", 0) for run in runs[n] for x in run["per_session"])
    cores = med(run["server"]["cpu_cores"] for run in runs[n])
    rss = max(run["server"]["rss_peak_mib"] for run in runs[n])
    print(f"{n:>3} {p50:>11.1f} {worst:>10.1f} {p95:>10.1f} {fps:>6.1f} {reduction:>9.2f} {coarse * 100:>5.0f}% {cores:>6.2f} "
          f"{rss:>8.0f} {p50 / base:>10.2f}")
if 4 in counts and counts[0] == 1:
    ratio = med(run["p50_max_ms"] for run in runs[4]) / base
    print(f"goal N=4: each session's p50 <= 2x N=1's: worst session {ratio:.2f}x "
          f"({'met' if ratio <= 2 else 'NOT met'})")
if 8 in counts:
    p95 = max(run["p95_max_ms"] for run in runs[8])
    print(f"goal N=8: no session's p95 above 500 ms: largest {p95:.0f} ms ({'met' if p95 <= 500 else 'NOT met'})")
EOF
