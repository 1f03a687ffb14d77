#!/usr/bin/env bash
# The folder rules of docs/architecture.md, checked on the sources:
#  1. each library's headers sit under a prefix (include/crackvis/NAME/) that
#     no other library uses;
#  2. rpcserver/ and server/ include nothing of dataservice/ but
#     dataservice_client's headers;
#  3. no header of a network library or of the client compiles <hdf5.h>.
#
#   include_rules.sh SOURCE_DIR BUILD_DIR
set -euo pipefail

source_dir=$1
build_dir=$2
cd "$source_dir"
status=0

# 1. One library per prefix.
mapfile -t prefixes < <(find . -path ./build -prune -o -path '*/include/crackvis/*' -type f -print |
  sed -E 's|^(.*/include/crackvis/[^/]+)/.*|\1|' | sort -u)
duplicates=$(printf '%s\n' "${prefixes[@]}" | sed -E 's|.*/include/crackvis/||' | sort | uniq -d)
for prefix in $duplicates; do
  echo "crackvis/$prefix/ is the prefix of more than one library:" >&2
  printf '%s\n' "${prefixes[@]}" | grep "/include/crackvis/$prefix$" >&2
  status=1
done
echo "${#prefixes[@]} include prefixes, each of one library"

# 2. rpcserver/ and server/ reach dataservice/ only through its client.
if grep -rn -E '#include <crackvis/dataservice_(h5|config|service|protocol)/' rpcserver server; then
  echo "rpcserver/ or server/ includes the data service's own headers (above)" >&2
  status=1
fi

# 3. No <hdf5.h> behind a network or client header: a translation unit that
# includes all of them and stops at HDF5's version macro (tests/CMakeLists.txt).
if ! cmake --build "$build_dir" --target crackvis_network_headers_check; then
  echo "a network or client header compiles <hdf5.h> (the #error above)" >&2
  status=1
fi
exit $status
