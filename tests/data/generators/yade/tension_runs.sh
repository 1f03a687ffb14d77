#!/bin/bash
# The coverage specimens of docs/methods.md ("Coverage on Yade's JCFpm tension runs"): a notched bar
# of ~8,000 bonded spheres in a regular hexagonal packing and in a random dense one, pulled apart
# with JCFpm (tension_bar.py), imported with `crackvis import yade`, and the main crack's coverage
# printed per method at the last step. Not committed (4 MB each): regenerated here in ~5 minutes
# (one core per run; both run at once). hull_cells.py then measures the triangulation's hull
# cells on the random run (docs/methods.md, "The triangulation's hull cells").
#     bash tests/data/generators/yade/tension_runs.sh [OUTDIR] [CRACKVIS]
set -euo pipefail
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
OUT="$(mkdir -p "${1:-/tmp/crackvis-yade-tension}" && cd "${1:-/tmp/crackvis-yade-tension}" && pwd)"
CRACKVIS="${2:-crackvis}"
YADE="${YADE:-yade}"
for packing in hexa random; do
  mkdir -p "$OUT/$packing"
  # JCFpm writes cracks_<Key>.txt into the working directory.
  (cd "$OUT/$packing" && "$YADE" -j1 -n -x "$HERE/tension_bar.py" "$packing" out > log.txt 2>&1) &
done
wait
for packing in hexa random; do
  cp "$OUT/$packing/cracks_tension_$packing.txt" "$OUT/$packing/out/"
  "$CRACKVIS" import yade "$OUT/$packing/out" -o "$OUT/$packing.h5" -q > /dev/null
  for decomposition in auto triangulation; do
    for method in local-voronoi cell-centre cell-cut; do
      printf '%-7s %-13s %-14s ' "$packing" "$decomposition" "$method"
      "$CRACKVIS" extract "$OUT/$packing.h5" -m "$method" -s -1 --decomposition "$decomposition" \
        --metrics 2> /dev/null | tail -1 | awk '{print "mapped", $(NF-2), "main area", $(NF-1), "cover", $NF}'
    done
  done
done
