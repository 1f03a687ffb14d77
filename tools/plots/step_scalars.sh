#!/usr/bin/env bash
# Plots one step scalar of a crackvis-dem v1.1 file against another (or
# against time), with the broken bonds on the second axis: the load-
# displacement curve of an imported run beside its cracking.
#
# usage: tools/plots/step_scalars.sh FILE.h5 X Y [OUTPUT.png]
#   X and Y name step scalars as `crackvis info FILE` lists them, or `time`,
#   `step`, `broken`; e.g. `displacement load`. With CRACKS=METHOD (e.g.
#   local-voronoi) they may also name the crack's numbers that `crackvis info
#   --steps --cracks METHOD` adds: `area`, `main_area`, `front_extent`,
#   `fragments`, `largest_fragment_share`, `tension_breaks`, `shear_breaks`;
#   e.g. `CRACKS=local-voronoi ... load main_area` plots crack area against
#   load. CRACKVIS names the CLI (default build/release/tools/crackvis).
#   Needs gnuplot and python3.
set -euo pipefail

if [[ $# -lt 3 ]]; then
  sed -n '2,15p' "$0" >&2
  exit 2
fi
file=$1
x=$2
y=$3
output=${4:-${file%.h5}-$y.png}
crackvis=${CRACKVIS:-build/release/tools/crackvis}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

"$crackvis" info "$file" --steps ${CRACKS:+--cracks "$CRACKS"} --json >"$work/info.json"
python3 - "$work/info.json" "$x" "$y" >"$work/curve.dat" <<'PYTHON'
import json, sys
info = json.load(open(sys.argv[1]))
def value(row, name):
    if name in ("time", "step", "broken"):
        return row[name]
    scalars = dict(row.get("scalars", {}))
    scalars.update({k: v for k, v in row.get("cracks", {}).items() if k != "front_axis"})
    if name not in scalars:
        cracks = list(row.get("cracks", {}).keys())
        known = ", ".join(["time", "step", "broken"] + info["step_scalars"] + cracks)
        sys.exit(f"step_scalars.sh: step {row['step']} has no scalar '{name}' (known: {known})")
    return scalars[name]
for row in info["per_step"]:
    print(value(row, sys.argv[2]), value(row, sys.argv[3]), row["broken"])
PYTHON

gnuplot <<GNUPLOT
set terminal pngcairo size 900,560 font ",11"
set output "$output"
set grid
set key left top
set xlabel "$x"
set ylabel "$y"
set y2label "broken bonds"
set y2tics
set ytics nomirror
set title "$(basename "$file")"
plot "$work/curve.dat" using 1:2 with linespoints lw 2 title "$y", \
     "$work/curve.dat" using 1:3 axes x1y2 with steps lw 1 title "broken bonds"
GNUPLOT
echo "wrote $output"
