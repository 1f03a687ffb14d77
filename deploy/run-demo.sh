#!/usr/bin/env bash
# The main job, from a fresh Debian 12 machine: installs what is missing,
# builds crackvis, generates a sample data set and describes it.
# (Later issues grow this into the full client-server demo.)
#
#   deploy/run-demo.sh [DATA_DIR]     # default: demo-data/
set -euo pipefail
cd "$(dirname "$0")/.."
data_dir="${1:-demo-data}"

bash deploy/install-deps.sh
cmake --preset release >/dev/null
cmake --build --preset release --target crackvis
crackvis=build/release/tools/crackvis

mkdir -p "$data_dir"
sample="$data_dir/sample-fcc.h5"
# A jittered FCC block of 10 x 10 x 10 cubic cells, 2 mm spheres.
"$crackvis" generate --lattice fcc --sites 21 21 21 --radius 0.002 --jitter 0.05 -o "$sample"
"$crackvis" info "$sample"
