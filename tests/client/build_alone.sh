#!/usr/bin/env bash
# Builds and tests the `client` preset in a copy of the repository that holds
# only what the thin client needs (issue 30): no dem/, cracks/, server/,
# dataservice/ or any other server-side area, so the build cannot reach for
# them. Run as a ctest test of the full tree; the copy stays in WORK so a
# second run only rebuilds what changed.
#
#   build_alone.sh SOURCE_DIR WORK
set -euo pipefail

source_dir=$1
work=$2
tree=$work/crackvis-client-only

# What the client's tree is made of (CMakeLists.txt, CRACKVIS_CLIENT_ONLY).
areas=(CMakeLists.txt CMakePresets.json .clang-format cmake common vocabulary tls proto pipeline
       pipeline-schemas encode client tests/CMakeLists.txt tests/support tests/pipeline
       tests/encode tests/client)
mkdir -p "$tree/tests"
for area in "${areas[@]}"; do
  rm -rf "${tree:?}/$area"
  # -a keeps the times, so an unchanged file is not rebuilt on the next run.
  cp -a "$source_dir/$area" "$tree/$area"
done
for left_out in dem cracks dataservice rpcserver server importers tools; do
  if [[ -e "$tree/$left_out" ]]; then
    echo "the client's tree holds $left_out/" >&2
    exit 1
  fi
done

cd "$tree"
cmake --preset client
cmake --build --preset client
ctest --preset client
