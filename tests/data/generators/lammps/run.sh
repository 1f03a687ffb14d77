#!/usr/bin/env bash
# Regenerates tests/data/lammps/notched_bar/ from in.notched_bar with Debian 12's LAMMPS
# (package lammps 20220106.git7586adbb6a+ds1, binary lmp). One serial process; about 1 s.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
out="$(cd "$here/../.." && pwd)/lammps/notched_bar"
lmp_bin="${LMP:-lmp}"

command -v "$lmp_bin" >/dev/null || { echo "run.sh: '$lmp_bin' not found (apt-get install lammps)" >&2; exit 1; }

work="$(mktemp -d "${TMPDIR:-/tmp}/crackvis-lammps.XXXXXX")"
trap 'rm -rf "$work"' EXIT

cp "$here/in.notched_bar" "$work/"
(
  cd "$work"
  OMP_NUM_THREADS=1 "$lmp_bin" -nocite -in in.notched_bar -log log.lammps -screen none
)

# sanity: the run must have produced the expected dumps
for s in 0 1500 3000 4500 6000 6180 6220 6260 6400 7540 8000; do
  [[ -s "$work/atoms.$s.txt" && -s "$work/bonds.$s.txt" ]] || { echo "run.sh: missing dump for step $s" >&2; exit 1; }
done
[[ -s "$work/breaks.txt" && -s "$work/log.lammps" ]] || { echo "run.sh: missing breaks.txt or log.lammps" >&2; exit 1; }

mkdir -p "$out"
find "$out" -mindepth 1 -delete
cp "$work"/atoms.*.txt "$work"/bonds.*.txt "$work/breaks.txt" "$work/log.lammps" "$out/"
echo "run.sh: wrote $(ls "$out" | wc -l) files to $out ($(du -sh "$out" | cut -f1))"
