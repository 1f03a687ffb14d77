#!/usr/bin/env bash
# The main job, from a fresh Debian 12 machine: installs what is missing,
# builds crackvis, simulates the dissertation's cuboid A fracture benchmark,
# and extracts its crack surfaces with the four methods as ParaView series.
# (Later issues grow this into the full client-server demo.)
#
#   deploy/run-demo.sh [DATA_DIR]        # default: demo-data/
#   DEMO_SCALE=0.3 deploy/run-demo.sh    # a smaller specimen, seconds instead of a minute
# A second run reuses the simulated file.
set -euo pipefail
cd "$(dirname "$0")/.."
data_dir="${1:-demo-data}"
scale="${DEMO_SCALE:-1}"

bash deploy/install-deps.sh
cmake --preset release >/dev/null
cmake --build --preset release --target crackvis
crackvis=build/release/tools/crackvis

mkdir -p "$data_dir"
run="$data_dir/cuboidA-scale$scale.h5"
if [[ ! -f "$run" ]] || ! "$crackvis" info "$run" >/dev/null 2>&1; then
  "$crackvis" sim cuboid3d --set A --scale "$scale" -o "$run"
fi
"$crackvis" info "$run"

# Every 10th step of the fracture, each method; open the .pvd files in ParaView.
for method in cell-attribute cell-cut local-voronoi cell-centre; do
  "$crackvis" extract "$run" --method "$method" --steps 0:-1:10 -o "$data_dir/$method.pvd"
done
echo
echo "Crack metrics at the last step (local Voronoi):"
"$crackvis" extract "$run" --method local-voronoi --steps -1 --metrics --quiet
echo
echo "ParaView series in $data_dir/: cell-attribute.pvd cell-cut.pvd local-voronoi.pvd cell-centre.pvd"
