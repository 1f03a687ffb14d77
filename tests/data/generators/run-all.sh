#!/usr/bin/env bash
# Regenerates every importer test data set from the real DEM codes Debian 12
# ships (apt-get install lammps esys-particle yade): tests/data/lammps,
# tests/data/esys, tests/data/yade. Each run is deterministic; a few minutes
# in all on one core. The importer tests then check the new outputs against
# each code's own record of breaks, so a changed code shows up there.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
for code in lammps esys yade; do
  echo "== $code"
  bash "$here/$code/run.sh"
done
du -sh "$here/../lammps" "$here/../esys" "$here/../yade"
