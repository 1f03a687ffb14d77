#!/usr/bin/env bash
# Plots broken bonds against saved step for the four benchmark data sets, like
# Fig. 3.6 of the dissertation: (a) plate2d, (b) cuboid3d A, B, C.
#
# usage: tools/plots/broken_bonds.sh [DATA_DIR] [OUTPUT.png]
#   DATA_DIR holds plate2d.h5 and cuboidA.h5, cuboidB.h5, cuboidC.h5 as written by
#   `crackvis sim` (default /tmp/crackvis-data); CRACKVIS names the CLI
#   (default build/release/tools/crackvis). Needs gnuplot (gnuplot-nox).
set -euo pipefail

data_dir=${1:-/tmp/crackvis-data}
output=${2:-docs/img/broken_bonds.png}
crackvis=${CRACKVIS:-build/release/tools/crackvis}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# `crackvis info --steps` prints "step time broken broken% new" rows.
for name in plate2d cuboidA cuboidB cuboidC; do
  "$crackvis" info "$data_dir/$name.h5" --steps |
    awk '/^ +[0-9]+ +[-0-9.e+]+ +[0-9]+ +[0-9.]+ +[0-9]+$/ { print $1, $4 }' >"$work/$name.dat"
  if [[ ! -s "$work/$name.dat" ]]; then
    echo "broken_bonds.sh: no steps read from $data_dir/$name.h5" >&2
    exit 1
  fi
done

gnuplot <<GNUPLOT
set terminal pngcairo size 1200,480 font ",11"
set output "$output"
set multiplot layout 1,2
set grid
set key left top
set xlabel "saved step"
set ylabel "broken bonds, % of all bonds"
set title "(a) 2D: plate2d (13,723 bonds)"
plot "$work/plate2d.dat" using 1:2 with lines lw 2 title "plate2d"
set title "(b) 3D: cuboid3d (267,674 bonds)"
plot "$work/cuboidA.dat" using 1:2 with lines lw 2 title "set A", \
     "$work/cuboidB.dat" using 1:2 with lines lw 2 title "set B", \
     "$work/cuboidC.dat" using 1:2 with lines lw 2 title "set C"
unset multiplot
GNUPLOT
echo "wrote $output"
