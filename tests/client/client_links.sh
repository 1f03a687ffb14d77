#!/usr/bin/env bash
# Checks that the thin client runs without the server stack: no library of
# HDF5, TBB, VTK or CGAL anywhere among what the dynamic loader resolves for
# crackvis-client, and none that crackvis-client asks for itself of CGAL's
# (GMP, MPFR: CGAL is header-only) or of EGL. Two come in legitimately
# through others on Debian, so only the client's own needs are checked for
# them: libEGL through Qt6Gui (its OpenGL contexts), libgmp through
# libavformat (GnuTLS). The test names who pulls libEGL in.
#
#   client_links.sh path/to/crackvis-client
set -euo pipefail

client=$1
resolved=$(ldd "$client")
mapfile -t needed < <(readelf -d "$client" | awk -F'[][]' '/\(NEEDED\)/ {print $2}')
echo "crackvis-client needs: ${needed[*]}"

status=0
server_stack='libhdf5|libCGAL|libmpfr|libtbb|libvtk'
if grep -E "^\s*($server_stack)" <<<"$resolved"; then
  echo "crackvis-client loads the libraries above of the server stack" >&2
  status=1
fi
for soname in "${needed[@]}"; do
  if [[ "$soname" =~ ^lib(EGL|gmp|mpfr|hdf5|tbb|vtk|CGAL) ]]; then
    echo "crackvis-client itself needs $soname" >&2
    status=1
  fi
done
# Where libEGL comes from, if anywhere: it must be Qt's.
if grep -q "libEGL" <<<"$resolved"; then
  qt_gui=$(awk '$1 ~ /^libQt6Gui/ {print $3}' <<<"$resolved")
  if [[ -z "$qt_gui" ]] || ! readelf -d "$qt_gui" | grep -q 'NEEDED.*libEGL'; then
    echo "libEGL is loaded, but not as Qt6Gui's dependency" >&2
    status=1
  else
    echo "libEGL comes with $qt_gui"
  fi
fi
exit $status
