#!/bin/bash
# Regenerates tests/data/esys/notched_bar/ with ESyS-Particle 2.3.5
# (Debian 12 package esys-particle): 1 master + 1 worker MPI process.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
dest="$(cd "$here/../.." && pwd)/esys/notched_bar"

# Open MPI refuses to run as root unless told; yield instead of busy-polling
# while idle so the two processes leave some CPU to others.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_mpi_yield_when_idle=1

work="$(mktemp -d "${TMPDIR:-/tmp}/esys_notched_bar.XXXXXX")"
trap 'rm -rf "$work"' EXIT

cp "$here/notched_bar.py" "$work/"
cd "$work"
start=$(date +%s)
nice -n 10 timeout 300 mpirun -np 2 esysparticle notched_bar.py > run.log 2>&1 || {
    echo "esysparticle failed; log:" >&2; cat run.log >&2; exit 1; }
echo "simulation took $(( $(date +%s) - start )) s"
grep -E '^(packed|created)' run.log || true

ls snap_t=*_0.txt > /dev/null   # fail if no snapshot was written

mkdir -p "$dest"
find "$dest" -mindepth 1 -delete
cp snap_t=*.txt bond_count.dat grip_force_left.dat grip_force_right.dat \
   grip_disp_left.dat grip_disp_right.dat "$dest/"
echo "copied $(ls "$dest" | wc -l) files to $dest ($(du -sh "$dest" | cut -f1))"
echo "intact bonds per save:"; cat "$dest/bond_count.dat"
