#!/usr/bin/env bash
# The time to the first picture with two settings of crackvis-render, A and B
# (extra arguments for each; optionally a crackvis-data or crackvis-render
# program for each, an older build's against this one's), alternating over R
# rounds on fresh services (the order reversed every other round). Each run:
# fresh crackvis-data and crackvis-render on loopback, then `crackvis bench
# render --first-pictures 3`: the first open is cold (nothing described,
# cached or touched in the fresh services; the file in the page cache), the
# later two warm. Prints each run's cold and warm times with their parts,
# crackvis-render's resident memory idle (2 s after it answers) and after the
# sessions (7 s later: the heap trimmed), and the load; then the medians.
# Figures: docs/benchmarks.md ("A heap kept touched for the first picture").
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/../.." && pwd)
readonly here root
build=${CRACKVIS_BUILD:-$root/build/release}
readonly build

usage() {
  cat <<EOF
usage: tools/bench/first-picture-ab.sh --data DIR --file NAME --a "ARGS" --b "ARGS"
                                       [--a-data PROGRAM] [--b-data PROGRAM]
                                       [--a-render PROGRAM] [--b-render PROGRAM]
                                       [--rounds R] [--size WxH] [--step S] [--gap SECONDS]
                                       [--out DIR]

Times the first picture of DIR/NAME (default: the last step, 1280x720) with crackvis-render
started with the extra arguments of --a and of --b in turn (e.g. --a "--heap-reserve-mb 0"
--b ""), fresh services each run, R rounds (default 4). --a-data and --b-data name the
crackvis-data each arm runs (default this build's; its HDF5 workers are the crackvis-hdf5-worker
beside it), e.g. a copy of an older build's to compare the two; --a-render and --b-render the
crackvis-render likewise. --gap pauses between one session's
close and the next open (default 0, the browser's pattern; 1.1 to 2: the next open meets the
heap trim and what follows it, see crackvis-render's HeapTrimmer). --out keeps each run's JSON
and logs.
EOF
}

die() {
  echo "first-picture-ab.sh: $*" >&2
  exit 1
}

data=
file=
rounds=4
size=1280x720
step=-1
gap=0
out=
args_a=
args_b=
data_a=
data_b=
render_a=
render_b=
given_a=
given_b=
while (($#)); do
  case $1 in
    -h | --help) usage; exit 0 ;;
    --data) data=${2:?--data needs a value}; shift 2 ;;
    --file) file=${2:?--file needs a value}; shift 2 ;;
    --a) args_a=${2?--a needs a value}; given_a=1; shift 2 ;;
    --b) args_b=${2?--b needs a value}; given_b=1; shift 2 ;;
    --a-data) data_a=${2:?--a-data needs a value}; shift 2 ;;
    --b-data) data_b=${2:?--b-data needs a value}; shift 2 ;;
    --a-render) render_a=${2:?--a-render needs a value}; shift 2 ;;
    --b-render) render_b=${2:?--b-render needs a value}; shift 2 ;;
    --rounds) rounds=${2:?--rounds needs a value}; shift 2 ;;
    --size) size=${2:?--size needs a value}; shift 2 ;;
    --step) step=${2:?--step needs a value}; shift 2 ;;
    --gap) gap=${2:?--gap needs a value}; shift 2 ;;
    --out) out=${2:?--out needs a value}; shift 2 ;;
    *) die "unknown argument $1 (see --help)" ;;
  esac
done
[[ -d $data ]] || die "--data DIR is required and must be a folder"
[[ -n $file && -f $data/$file ]] || die "--file NAME must name a file in $data"
[[ -n $given_a && -n $given_b ]] || die "--a and --b are both required (either may be \"\")"
[[ $rounds =~ ^[1-9][0-9]*$ ]] || die "--rounds $rounds: expected a positive integer"
[[ $gap =~ ^[0-9]+(\.[0-9]+)?$ ]] || die "--gap $gap: expected seconds, e.g. 1.2"
# An arm's crackvis-data: an absolute path (the runs start from the source
# tree), with its own HDF5 worker beside it (else crackvis-data would fall
# back to this build's worker, and the arm would mix two builds).
arm_program() {
  local program=$1
  [[ -z $program ]] && return 0
  [[ -x $program ]] || die "$program is not an executable crackvis-data"
  [[ -x $(dirname "$program")/crackvis-hdf5-worker ]] ||
    die "no crackvis-hdf5-worker beside $program: copy both programs"
  realpath -e -- "$program"
}
data_a=$(arm_program "$data_a")
data_b=$(arm_program "$data_b")
# An arm's crackvis-render, likewise absolute.
render_program() {
  local program=$1
  [[ -z $program ]] && return 0
  [[ -x $program ]] || die "$program is not an executable crackvis-render"
  realpath -e -- "$program"
}
render_a=$(render_program "$render_a")
render_b=$(render_program "$render_b")
for binary in tools/crackvis dataservice/crackvis-data server/app/crackvis-render; do
  [[ -x $build/$binary ]] || die "$build/$binary is missing: build the project first"
done

# shellcheck source=tools/bench/bench_services.sh
source "$here/bench_services.sh"
cd "$root"
bench_output "$out"
cat "$data/$file" >/dev/null # into the page cache

resident_kb() {
  awk '/^VmRSS/ {print $2}' "/proc/$1/status"
}

# run TAG ROUND ARGS DATA RENDER: one run on fresh services (DATA and RENDER:
# the arm's programs, empty for this build's), its figures in $out/TAG-ROUND.*
run() {
  local extra=$3 log=$out/$1-$2
  bench_data_program=$4
  bench_render_program=$5
  # shellcheck disable=SC2086 # the extra arguments are words
  bench_start_services "$data" "$log" $extra
  sleep 2
  resident_kb "$bench_render_pid" >"$log.idle"
  cut -d' ' -f1 /proc/loadavg >"$log.load"
  "$build/tools/crackvis" bench render --server "localhost:$bench_render_port" --file "$file" \
    --step "$step" --size "$size" --first-pictures 3 --first-picture-gap "$gap" --seconds 0.5 \
    --still-frames 0 --jumps 0 --playback-steps 0 --json >"$log.json" 2>"$log.log" ||
    die "bench render failed: $(tail -3 "$log.log")"
  sleep 7
  resident_kb "$bench_render_pid" >"$log.after"
  bench_stop_services
}

for r in $(seq "$rounds"); do
  order=(a b)
  ((r % 2 == 0)) && order=(b a)
  for tag in "${order[@]}"; do
    extra=$args_a program=$data_a renderer=$render_a
    [[ $tag == b ]] && extra=$args_b program=$data_b renderer=$render_b
    echo "round $r of $rounds: $tag ($extra${program:+, $program}${renderer:+, $renderer})" \
      "(load $(cut -d' ' -f1-3 /proc/loadavg))" >&2
    run "$tag" "$r" "$extra" "$program" "$renderer"
  done
done

python3 - "$out" "$rounds" "$file" "$args_a" "$args_b" "$gap" "$data_a" "$data_b" \
  "$render_a" "$render_b" <<'EOF'
import json, statistics, sys
out, rounds, name, args = sys.argv[1], int(sys.argv[2]), sys.argv[3], {"a": sys.argv[4], "b": sys.argv[5]}
gap = float(sys.argv[6])
programs = {"a": [sys.argv[7], sys.argv[9]], "b": [sys.argv[8], sys.argv[10]]}
def label(tag):
    words = [args[tag] or "defaults"]
    words += [program for program in programs[tag] if program]
    return ", ".join(words)
med = statistics.median
rows = {"a": [], "b": []}
for tag in rows:
    for r in range(1, rounds + 1):
        base = f"{out}/{tag}-{r}"
        pictures = json.load(open(f"{base}.json"))["first_picture"]
        read = lambda suffix: float(open(f"{base}.{suffix}").read())
        rows[tag].append({"cold": pictures["first"], "warm": pictures["later_median"],
                          "idle": read("idle") / 1024, "after": read("after") / 1024,
                          "load": read("load")})
parts = ["open_file_ms", "extract_ms", "render_ms", "encode_ms"]
print(f"first picture of {name}, fresh services each run, alternating (ms; resident MB); "
      f"warm: the later opens, {gap:g} s after the previous close")
print(f"{'run':>6} {'cold':>6} {'open':>5} {'extract':>8} {'render':>7} {'encode':>7} {'warm':>6} "
      f"{'idle MB':>8} {'after MB':>9}  load")
for tag in rows:
    for r, row in enumerate(rows[tag], 1):
        c = row["cold"]
        print(f"{tag + str(r):>6} {c['total_ms']:>6.0f} " +
              " ".join(f"{c['server'][p]:>{w}.0f}" for p, w in zip(parts, (5, 8, 7, 7))) +
              f" {row['warm']['total_ms']:>6.0f} {row['idle']:>8.0f} {row['after']:>9.0f}  {row['load']:.2f}")
for tag in rows:
    rs = rows[tag]
    print(f"{tag} ({label(tag)}): median cold {med(r['cold']['total_ms'] for r in rs):.0f} ms "
          f"(extract {med(r['cold']['server']['extract_ms'] for r in rs):.0f}, "
          f"render {med(r['cold']['server']['render_ms'] for r in rs):.0f}), "
          f"warm {med(r['warm']['total_ms'] for r in rs):.0f} ms, "
          f"resident idle {med(r['idle'] for r in rs):.0f} MB, after {med(r['after'] for r in rs):.0f} MB")
EOF
