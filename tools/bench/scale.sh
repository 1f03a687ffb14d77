#!/usr/bin/env bash
# The single-node cost curve (issue 19 point 3): for FCC blocks of about N
# particles with a planted through crack that opens (crackvis generate
# --planted-crack: the crack reaches the top at 3/4 of the steps, plus 0.2 %
# scattered breaks), the time and peak memory of making the file, each
# method's time per step as a viewer runs it (incremental, reading not timed,
# crackvis bench methods) with the bytes it keeps per particle, and one
# 1280x720 snapshot of the last step (read, extract, render on llvmpipe).
#
#   tools/bench/scale.sh OUT_DIR N [N ...]      # e.g. /tmp/scale 100000 1000000
#
# Prints a Markdown table (and OUT_DIR/scale.jsonl, a JSON object per N). The
# files are kept in OUT_DIR (about 170 B per particle per step on disk).
# Environment: CRACKVIS (the CLI, default build/release/tools/crackvis),
# STEPS (planted-crack steps, default 10), THREADS (default: all cores).
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/../.." && pwd)
crackvis=${CRACKVIS:-$root/build/release/tools/crackvis}
steps=${STEPS:-10}
threads=${THREADS:-$(nproc)}
out=${1:?usage: scale.sh OUT_DIR N [N ...]}
shift
(($#)) || { echo "scale.sh: give at least one particle count" >&2; exit 2; }
[[ -x $crackvis ]] || { echo "scale.sh: no crackvis CLI at $crackvis (build it, or set CRACKVIS)" >&2; exit 1; }
mkdir -p "$out"
: >"$out/scale.jsonl"

# Seconds and peak RSS (MB) of a command, as "S MB", its output discarded.
timed() {
  /usr/bin/time -f '%e %M' -o "$out/time.txt" "$@" >/dev/null 2>"$out/stderr.txt" || {
    tail -5 "$out/stderr.txt" >&2
    return 1
  }
  awk '{ printf "%s %.0f", $1, $2 / 1024 }' "$out/time.txt"
}

echo "machine: $(lscpu | sed -n 's/^Model name: *//p'), $(nproc) hardware threads; load before $(cut -d' ' -f1-3 /proc/loadavg)" >&2
echo "| particles | bonds | generate s / MB | cell attribute | cell cut | local Voronoi | cell centre | snapshot s / MB |"
echo "|---:|---:|---:|---:|---:|---:|---:|---:|"
for n in "$@"; do
  # FCC with s site planes per axis holds about s^3 / 2 particles.
  sites=$(python3 -c "print(round((2 * $n) ** (1 / 3)))")
  file=$out/fcc-$n.h5
  made=$(timed "$crackvis" generate --sites "$sites" "$sites" "$sites" --planted-crack "$steps" -o "$file")
  "$crackvis" bench methods "$file" --voro-every 0 --runs 1 --threads "$threads" --json -q \
    >"$out/methods-$n.json"
  shot=$(timed "$crackvis" snapshot "$file" -s -1 -m local-voronoi --width 1280 --height 720 \
    -q -o "$out/fcc-$n.png")
  python3 - "$out/methods-$n.json" "$n" "$made" "$shot" "$threads" >>"$out/scale.jsonl" <<'EOF'
import json, sys
path, n, made, shot, threads = sys.argv[1:6]
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
       "load_before": report.get("load_before"), "load_after": report.get("load_after")}
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
      f"| {cell('cell-centre')} | {row['snapshot_s']:.1f} / {row['snapshot_mb']:,} |")
EOF
done
echo "load after $(cut -d' ' -f1-3 /proc/loadavg)" >&2
