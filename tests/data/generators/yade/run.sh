#!/bin/bash
# Regenerates tests/data/yade/notched_bar/ with Debian's yade (2023.02a): bash tests/data/generators/yade/run.sh
# One OpenMP thread (-j1): the run is then deterministic (fixed packing seed) and light on the machine.
set -euo pipefail
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
DEST="$(cd "$HERE/../.." && pwd)/yade/notched_bar"
YADE="${YADE:-yade}"
TMP="$(mktemp -d)"
trap 'rm -rf "$TMP"' EXIT
cp "$HERE/notched_bar.py" "$TMP/"
# JCFpm writes cracks_<Key>.txt into the working directory, so run inside the temp dir.
(cd "$TMP" && "$YADE" -j1 -n -x notched_bar.py out) 2>&1 | tee "$TMP/log.txt"
grep -q 'ends still connected: False' "$TMP/log.txt" || { echo "run.sh: the bar did not separate" >&2; exit 1; }
mkdir -p "$DEST"
find "$DEST" -mindepth 1 -delete
cp "$TMP"/out/* "$DEST/"
cp "$TMP/cracks_notched_bar.txt" "$DEST/"
ls -l "$DEST"
