#!/usr/bin/env bash
# Watching a running simulation (issue 32): a writer produces cuboid A with
# `crackvis sim --live`, alone and followed by render sessions, alternately.
# Reports how soon a written step is on the client (`crackvis bench follow`:
# the step's commit to its first frame, p50 and p95), the writer's throughput
# with 0 and with N followers, and the sessions' incremental extraction per new
# step beside `crackvis bench methods`' offline figure for the same method.
# Figures: docs/benchmarks.md, "Following a running simulation".
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/../.." && pwd)
readonly here root
build=${CRACKVIS_BUILD:-$root/build/release}
readonly build

usage() {
  cat <<EOF
usage: tools/bench/live-follow.sh [--runs R] [--scale S] [--steps K] [--sessions N] [--size WxH]
                                  [--method M] [--no-pin] [--out DIR]

Alternates R pairs (default 3) of runs of 'crackvis sim cuboid3d --set A --live' (scale S, default
1: full size; K saved steps, default 200; one solver thread): the writer alone, then the writer
followed by N sessions (default 2) of 'crackvis bench follow' at WxH (default 1280x720) with crack
method M (default local-voronoi). Prints per run the writer's throughput (saved steps per second
from its first commit to its last) with the load beside it, their medians and ratio, the
step-to-frame p50 and p95, and the extraction per new step beside 'crackvis bench methods'.

By default the writer runs on CPU 0 and crackvis-data, crackvis-render and the followers on CPU 1
(taskset), as the simulation would run on a cluster node and the viewers elsewhere: the ratio then
shows what following costs the writer through the file (SWMR), not the two cores it would share
on this machine. --no-pin lets everything share both CPUs.

Starts its own crackvis-data and crackvis-render from $build (CRACKVIS_BUILD) on free loopback
ports with the development certificates, over a data root in DIR (default: a temporary folder).
EOF
}

die() {
  echo "live-follow.sh: $*" >&2
  exit 1
}

runs=3
scale=1
steps=200
sessions=2
size=1280x720
method=local-voronoi
out=
writer_cpus=(taskset -c 0)
viewer_cpus=(taskset -c 1)
while (($#)); do
  case $1 in
    -h | --help) usage; exit 0 ;;
    --runs) runs=${2:?--runs needs a value}; shift 2 ;;
    --scale) scale=${2:?--scale needs a value}; shift 2 ;;
    --steps) steps=${2:?--steps needs a value}; shift 2 ;;
    --sessions) sessions=${2:?--sessions needs a value}; shift 2 ;;
    --size) size=${2:?--size needs a value}; shift 2 ;;
    --method) method=${2:?--method needs a value}; shift 2 ;;
    --out) out=${2:?--out needs a value}; shift 2 ;;
    --no-pin) writer_cpus=(); viewer_cpus=(); shift ;;
    *) die "unknown argument $1 (see --help)" ;;
  esac
done
[[ $runs =~ ^[1-9][0-9]*$ ]] || die "--runs $runs: expected a positive integer"
for binary in tools/crackvis dataservice/crackvis-data server/app/crackvis-render; do
  [[ -x $build/$binary ]] || die "$build/$binary is missing: build the project first"
done
crackvis=$build/tools/crackvis

# shellcheck source=tools/bench/bench_services.sh
source "$here/bench_services.sh"
cd "$root"
bench_output "$out"
mkdir -p "$out/data"
data_port=$(bench_free_port)
render_port=$(bench_free_port)
bench_background "${viewer_cpus[@]}" "$build/dataservice/crackvis-data" --root "$out/data" \
  --listen "127.0.0.1:$data_port" --access-log '' >"$out/crackvis-data.log" 2>&1
bench_background "${viewer_cpus[@]}" "$build/server/app/crackvis-render" \
  --listen "127.0.0.1:$render_port" --data-server "localhost:$data_port" --access-log '' \
  >"$out/crackvis-render.log" 2>&1
bench_wait_render "$render_port" "$out/crackvis-render.log"

# One run of the writer; with followers when $2 is "followed".
write() {
  local k=$1 kind=$2 name="live-$1-$2.h5"
  rm -f "$out/data/$name"
  cut -d' ' -f1 /proc/loadavg >"$out/$kind-$k.load"
  local follower=
  if [[ $kind == followed ]]; then
    "${viewer_cpus[@]}" "$crackvis" bench follow --server "localhost:$render_port" --file "$name" \
      --step-log "$out/$kind-$k.steps" --sessions "$sessions" --size "$size" -m "$method" --json \
      >"$out/follow-$k.json" 2>"$out/follow-$k.log" &
    follower=$!
  fi
  "${writer_cpus[@]}" "$crackvis" sim cuboid3d --set A --scale "$scale" --steps "$steps" --threads 1 \
    --live --quiet --step-log "$out/$kind-$k.steps" -o "$out/data/$name" ||
    die "the writer failed (run $k, $kind)"
  if [[ -n $follower ]]; then
    wait "$follower" || die "crackvis bench follow failed: $(tail -3 "$out/follow-$k.log")"
  fi
}

for k in $(seq "$runs"); do
  for kind in alone followed; do
    echo "run $k of $runs, writer $kind (load $(cut -d' ' -f1-3 /proc/loadavg))" >&2
    write "$k" "$kind"
  done
done
echo "crackvis bench methods on the last followed file (load $(cut -d' ' -f1-3 /proc/loadavg))" >&2
"${viewer_cpus[@]}" "$crackvis" bench methods "$out/data/live-$runs-followed.h5" --runs 1 --threads 1 \
  --json -q >"$out/methods.json"

python3 - "$out" "$runs" "$sessions" "$method" "$scale" "$steps" <<'EOF'
import json, statistics, sys
out, runs, sessions, method, scale, steps = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4], sys.argv[5], sys.argv[6]
def throughput(kind, k):
    times = [float(line.split()[1]) for line in open(f"{out}/{kind}-{k}.steps")]
    return (len(times) - 1) / (times[-1] - times[0])
load = lambda kind, k: float(open(f"{out}/{kind}-{k}.load").read())
alone = [throughput("alone", k) for k in range(1, runs + 1)]
followed = [throughput("followed", k) for k in range(1, runs + 1)]
follow = [json.load(open(f"{out}/follow-{k}.json")) for k in range(1, runs + 1)]
methods = json.load(open(f"{out}/methods.json"))
offline = methods["configs"][0]["methods"][method]["median_ms"]
med = statistics.median
print(f"following cuboid A (scale {scale}, {steps} saved steps, 1 solver thread) with {sessions} "
      f"session(s), {follow[0]['size']}, {method}; {follow[0]['machine']}")
for k in range(runs):
    print(f"  run {k + 1}: writer alone {alone[k]:6.2f} steps/s (load {load('alone', k + 1):.2f}), "
          f"followed {followed[k]:6.2f} steps/s (load {load('followed', k + 1):.2f}); "
          f"step to frame p50 {follow[k]['step_to_frame_p50_ms']:.0f} ms, "
          f"p95 {follow[k]['step_to_frame_p95_ms']:.0f} ms, "
          f"steps shown {[s['steps_shown'] for s in follow[k]['per_session']]}")
ratio = med(followed) / med(alone)
p95 = med(f["step_to_frame_p95_ms"] for f in follow)
print(f"  writer throughput, median: alone {med(alone):.2f}, followed {med(followed):.2f} steps/s: "
      f"ratio {ratio:.3f} (goal >= 0.90: {'met' if ratio >= 0.9 else 'NOT met'})")
print(f"  step committed -> first frame on the client: p50 {med(f['step_to_frame_p50_ms'] for f in follow):.0f} ms, "
      f"p95 {p95:.0f} ms (goal p95 <= 1000 ms: {'met' if p95 <= 1000 else 'NOT met'})")
print(f"  session's extraction per new step, median {med(f['extract_ms_per_new_step']['p50'] for f in follow):.3f} ms "
      f"(read through crackvis-data {med(f['load_ms_per_new_step']['p50'] for f in follow):.1f} ms); "
      f"crackvis bench methods, {method}, incremental per step, 1 thread: {offline:.3f} ms")
json.dump({"alone": alone, "followed": followed, "follow": follow, "offline_ms": offline},
          open(f"{out}/summary.json", "w"), indent=1)
EOF
