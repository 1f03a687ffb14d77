#!/usr/bin/env bash
# The crackvis ParaView plugin under MPI, per rank (issue 34 point 4): each
# rank's peak memory, and the wall time of the first update and of each
# following step (read + extract, then render + composite across ranks),
# through pvbatch at R ranks, on one file. Alternates the rank counts over
# the rounds (the order reversed every other round) and prints each run
# with the load beside it, then per rank count the medians, the speed-up
# over 1 rank, and the memory goal: a rank's data part (its peak less the
# fixed part, the peak of a rank that only loaded the plugin and rendered an
# empty view at the same R) at most 1.3 x the single rank's data part / R.
# Figures: docs/benchmarks.md, "Per-rank memory and speed under MPI".
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/../.." && pwd)
readonly here root

usage() {
  cat <<EOF
usage: tools/bench/mpi-ranks.sh --file FILE [--ranks "1 2 4"] [--rounds R] [--first S]
                                [--count C] [--size WxH] [--ghost-width W] [--out DIR]

pvbatch with the crackvis plugin on FILE at each rank count (default "1 2"), R rounds
(default 2): the first update at step S (default: 5 steps before the last), its frame, then
C more steps (default 4), each updated and rendered (default 1280x720, llvmpipe on a private
Xvfb). --ghost-width sets the reader's GhostWidth (default: the reader's, 4 longest bonds).
--out keeps every run's JSON, log and /usr/bin/time output. After the summary, each rank's
update of a later step by stage (the reader's prepare, read and fill; the filter's lattice,
piece, extract, opening, whole_set and output), timed in the process itself.
EOF
}

die() {
  echo "mpi-ranks.sh: $*" >&2
  exit 1
}

file=
rank_counts="1 2"
rounds=2
first=-5
count=4
size=1280x720
ghost=default
out=
while (($#)); do
  case $1 in
    -h | --help) usage; exit 0 ;;
    --file) file=${2:?--file needs a value}; shift 2 ;;
    --ranks) rank_counts=${2:?--ranks needs a value}; shift 2 ;;
    --rounds) rounds=${2:?--rounds needs a value}; shift 2 ;;
    --first) first=${2:?--first needs a value}; shift 2 ;;
    --count) count=${2:?--count needs a value}; shift 2 ;;
    --size) size=${2:?--size needs a value}; shift 2 ;;
    --ghost-width) ghost=${2:?--ghost-width needs a value}; shift 2 ;;
    --out) out=${2:?--out needs a value}; shift 2 ;;
    *) die "unknown argument $1 (see --help)" ;;
  esac
done
[[ -f $file ]] || die "--file FILE is required and must exist"
file=$(realpath "$file")
[[ $rounds =~ ^[1-9][0-9]*$ ]] || die "--rounds $rounds: expected a positive integer"
for r in $rank_counts; do
  [[ $r =~ ^[1-9][0-9]*$ ]] || die "--ranks: $r is not a positive integer"
done
[[ $size =~ ^[0-9]+x[0-9]+$ ]] || die "--size $size: expected WIDTHxHEIGHT"
[[ $ghost == default || $ghost =~ ^[0-9]+(\.[0-9]+)?$ ]] || die "--ghost-width $ghost: expected a number"
[[ -x /usr/bin/time ]] || die "needs GNU time (/usr/bin/time, package time)"
command -v Xvfb >/dev/null || die "needs Xvfb (Debian's ParaView renders through GLX)"

plugin=$(find "$root/build/paraview-plugin" -name Crackvis.so -path '*/plugins/*' 2>/dev/null | head -1)
[[ -n $plugin ]] || die "no plugin built: run paraview-plugin/build.sh first"
env_lines=$("$root/deploy/paraview-prefix.sh" --env) || die "no ParaView prefix"
eval "$env_lines"
pvbatch=$CRACKVIS_PARAVIEW_PREFIX/usr/bin/pvbatch
# As paraview-plugin/run.sh: glibc's malloc asks for huge pages where THP is
# madvise, unless CRACKVIS_HUGE_PAGES=0 (deploy/huge-pages.sh).
source "$root/deploy/huge-pages.sh"
crackvis_huge_pages

work=$(mktemp -d -t crackvis-mpi-ranks.XXXXXX)
[[ -n $out ]] || out=$work
mkdir -p "$out"
xvfb_pid=
cleanup() {
  [[ -n $xvfb_pid ]] && kill "$xvfb_pid" 2>/dev/null
  rm -rf "$work"
}
trap cleanup EXIT
# -displayfd: Xvfb picks a free display number and writes it to fd 3.
Xvfb -displayfd 3 -screen 0 1920x1080x24 -noreset -nolisten tcp 3>"$work/display" \
  2>"$work/xvfb.log" &
xvfb_pid=$!
for _ in $(seq 100); do
  [[ -s $work/display ]] && break
  sleep 0.1
done
[[ -s $work/display ]] || die "Xvfb did not start: $(tail -1 "$work/xvfb.log")"
DISPLAY=:$(head -1 "$work/display")
export DISPLAY
cat "$file" >/dev/null # into the page cache for every run
# Each reader and filter update prints its stages (crack_filter_state.h, StageLog).
export CRACKVIS_VTK_TIMINGS=1

# run TAG RANKS FILE|baseline: one pvbatch run; /usr/bin/time appends each
# rank's peak RSS (KiB) and wall seconds to $out/TAG.rss.
run() {
  local tag=$1 ranks=$2 input=$3
  local timed=(/usr/bin/time -a -o "$out/$tag.rss" -f "%M %e")
  rm -f "$out/$tag.rss"
  local script=("$here/mpi_ranks.py" "$plugin" "$input" "first=$first" "$count" "$size" "$out/$tag.json"
    "ghost=$ghost")
  if ((ranks == 1)); then
    "${timed[@]}" "$pvbatch" --no-mpi "${script[@]}" >"$out/$tag.log" 2>&1
  else
    mpiexec --allow-run-as-root --oversubscribe -np "$ranks" -x LD_LIBRARY_PATH -x PYTHONPATH \
      -x DISPLAY -x CRACKVIS_VTK_TIMINGS ${crackvis_huge_pages_mpi[@]+"${crackvis_huge_pages_mpi[@]}"} "${timed[@]}" "$pvbatch" "${script[@]}" >"$out/$tag.log" 2>&1
  fi || die "$tag failed: $(grep -v '^HDF5-DIAG\|^  ' "$out/$tag.log" | tail -3)"
  cut -d' ' -f1 /proc/loadavg >"$out/$tag.load"
}

for ranks in $rank_counts; do
  echo "baseline at $ranks rank(s) (load $(cut -d' ' -f1-3 /proc/loadavg))" >&2
  run "baseline-$ranks" "$ranks" baseline
done
read -r -a order <<<"$rank_counts"
for r in $(seq "$rounds"); do
  counts=("${order[@]}")
  if ((r % 2 == 0)); then
    counts=()
    for ((k = ${#order[@]} - 1; k >= 0; k--)); do counts+=("${order[k]}"); done
  fi
  for ranks in "${counts[@]}"; do
    echo "round $r of $rounds: $ranks rank(s) (load $(cut -d' ' -f1-3 /proc/loadavg))" >&2
    run "run-$ranks-$r" "$ranks" "$file"
  done
done

python3 - "$out" "$rounds" "$file" "$rank_counts" <<'EOF'
import json, statistics, sys
out, rounds, name, counts = sys.argv[1], int(sys.argv[2]), sys.argv[3], [int(r) for r in sys.argv[4].split()]
med = statistics.median

def peaks(tag):
    """Each rank's peak RSS in MiB."""
    return [int(line.split()[0]) / 1024 for line in open(f"{out}/{tag}.rss") if line.strip()]

rows = {}
print(f"crackvis plugin under MPI on {name}: pvbatch, local Voronoi, per rank count")
print(f"{'ranks':>5} {'round':>5} {'first update':>13} {'first frame':>12} {'step update':>12} "
      f"{'step frame':>11} {'rank peaks (MiB)':>24}  load")
for ranks in counts:
    rows[ranks] = []
    for r in range(1, rounds + 1):
        run = json.load(open(f"{out}/run-{ranks}-{r}.json"))
        steps = run["steps"]
        row = {"first": run["first_update_ms"], "frame": run["first_frame_ms"],
               "update": med(s["update_ms"] for s in steps) if steps else float("nan"),
               "step_frame": med(s["frame_ms"] for s in steps) if steps else float("nan"),
               "peaks": peaks(f"run-{ranks}-{r}"), "cells": run["cells"],
               "load": float(open(f"{out}/run-{ranks}-{r}.load").read())}
        rows[ranks].append(row)
        print(f"{ranks:>5} {r:>5} {row['first']:>13.0f} {row['frame']:>12.0f} {row['update']:>12.0f} "
              f"{row['step_frame']:>11.0f} {' '.join(f'{p:.0f}' for p in sorted(row['peaks'])):>24}  "
              f"{row['load']:.2f}")
print()
print(f"{'ranks':>5} {'first update':>13} {'speed-up':>9} {'step (upd+frame)':>17} {'speed-up':>9} "
      f"{'max rank peak':>14} {'fixed':>6} {'data part':>10} {'goal <=':>8}  cells")
single = None
for ranks in counts:
    rs = rows[ranks]
    fixed = max(peaks(f"baseline-{ranks}"))
    first = med(r["first"] for r in rs)
    step = med(r["update"] + r["step_frame"] for r in rs)
    peak = med(max(r["peaks"]) for r in rs)
    data = peak - fixed
    if single is None:
        single = {"first": first, "step": step, "data": data, "ranks": ranks}
    goal = 1.3 * single["data"] * single["ranks"] / ranks
    met = "met" if data <= goal else "NOT met"
    print(f"{ranks:>5} {first:>13.0f} {single['first'] / first:>9.2f} {step:>17.0f} "
          f"{single['step'] / step:>9.2f} {peak:>14.0f} {fixed:>6.0f} {data:>10.0f} {goal:>8.0f}  "
          f"{rs[0]['cells']} ({met})")
print("times in ms, medians over the rounds (a step: the median of its steps); memory in MiB: "
      "peak RSS by /usr/bin/time; fixed: a rank that only loaded the plugin and rendered an empty view")

def stage_lines(tag):
    """Per process, by its MPI rank (or pid order without one), its timing lines after the
    first update's, as (what, {stage: ms})."""
    by_process = {}
    for line in open(f"{out}/{tag}.log"):
        if not line.startswith("crackvis-vtk-timings "):
            continue
        fields = dict(f.split("=", 1) for f in line.split()[1:] if "=" in f)
        what = next(f for f in line.split()[1:] if "=" not in f)
        stages = {k[:-3]: float(v) for k, v in fields.items() if k.endswith("_ms")}
        rank = fields.get("rank", "-")
        key = (int(rank) if rank.isdigit() else 0, int(fields["pid"]))
        by_process.setdefault(key, []).append((fields.get("time"), what, stages))
    # The first update of each process (the piece's preparation), at the first time it
    # saw, is not a step.
    return [[(what, stages) for time, what, stages in lines if time != lines[0][0]]
            for _, lines in sorted(by_process.items())]

print()
print("a later step's update by stage, per rank (medians over the steps and rounds, ms):")
for ranks in counts:
    per_rank = {}
    for r in range(1, rounds + 1):
        for k, lines in enumerate(stage_lines(f"run-{ranks}-{r}")):
            for what, stages in lines:
                kind = "reader" if what.startswith("reader") else "filter"
                for stage, ms in stages.items():
                    per_rank.setdefault((kind, stage), {}).setdefault(k, []).append(ms)
    if not per_rank:
        print(f"  {ranks} rank(s): no timing lines (a plugin built before StageLog?)")
        continue
    print(f"  {ranks} rank(s): " + "  ".join(f"{'rank ' + str(k):>8}" for k in range(ranks)))
    for (kind, stage), values in per_rank.items():
        cells = "  ".join(f"{med(values[k]):>8.1f}" if k in values else f"{'-':>8}" for k in range(ranks))
        print(f"    {kind + ' ' + stage:<18} {cells}")
    # Rank 0's update clock against the plugin's work in it: from the first
    # reader's start to the last filter's end over the ranks (one clock,
    # CLOCK_MONOTONIC), and what lies outside that (ParaView's own work).
    inside, outside = [], []
    for r in range(1, rounds + 1):
        spans = [(float(f["start"]), float(f["end"]))
                 for line in open(f"{out}/run-{ranks}-{r}.log")
                 if line.startswith("crackvis-vtk-timings ")
                 for f in [dict(x.split("=", 1) for x in line.split()[1:] if "=" in x)]
                 if "start" in f]
        for step in json.load(open(f"{out}/run-{ranks}-{r}.json"))["steps"]:
            lo, hi = step.get("update_span", (0.0, 0.0))
            within = [sp for sp in spans if sp[0] >= lo - 1.0 and sp[1] <= hi + 1.0]
            if within:
                plugin = max(e for _, e in within) - min(b for b, _ in within)
                inside.append(plugin)
                outside.append(hi - lo - plugin)
    if inside:
        print(f"    rank 0's update clock: {med(inside):.1f} in the plugin (first reader start to "
              f"last filter end), {med(outside):.1f} outside it (ParaView)")
    # Where each rank's peak memory was reached: its peak after the first update's read,
    # after its first extraction, and at its last line (round 1).
    peaks = {}
    for line in open(f"{out}/run-{ranks}-1.log"):
        if line.startswith("crackvis-vtk-timings ") and "peak_mib=" in line:
            f = dict(x.split("=", 1) for x in line.split()[1:] if "=" in x)
            peaks.setdefault((f.get("rank", "-"), int(f["pid"])), []).append(float(f["peak_mib"]))
    for (rank, _), values in sorted(peaks.items()):
        if len(values) >= 2:
            print(f"    rank {rank} peak (MiB, round 1): {values[0]:.0f} after the first read, "
                  f"{values[1]:.0f} after the first extraction, {values[-1]:.0f} at the end")
EOF
