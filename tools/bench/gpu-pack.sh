#!/usr/bin/env bash
# Packs crackvis's programs for a machine that has none of their libraries:
# a lent GPU node (the device tool) whose image is not Debian 12. The pack
# holds crackvis, crackvis-data, crackvis-hdf5-worker and crackvis-render,
# every Debian library they load except glibc's own (the node's newer glibc
# runs them), and the development certificates. Each program's RPATH is set
# to ../lib, so the HDF5 workers, which crackvis-data starts with an
# environment of one variable, find their libraries without LD_LIBRARY_PATH.
# No EGL or OpenGL driver is packed: glvnd's dispatch libraries travel, the
# vendor library is the node's (NVIDIA's EGL, named by gpu-node.sh).
#
#   tools/bench/gpu-pack.sh OUT.tar.xz
#
# Needs patchelf and xz. Environment: CRACKVIS_BUILD (default build/release).
# Then, on the node: tools/bench/gpu-node.sh OUT.tar.xz RESULTS_DIR.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/../.." && pwd)
build=${CRACKVIS_BUILD:-$root/build/release}
pack=${1:?usage: gpu-pack.sh OUT.tar.xz}
mkdir -p "$(dirname "$pack")"
pack=$(cd "$(dirname "$pack")" && pwd)/$(basename "$pack")
export LC_ALL=C  # sort and join on the same collation
programs=(tools/crackvis dataservice/crackvis-data dataservice/crackvis-hdf5-worker
  server/app/crackvis-render)
for program in "${programs[@]}"; do
  [[ -x $build/$program ]] || { echo "gpu-pack.sh: $build/$program is missing: build first" >&2; exit 1; }
done
command -v patchelf >/dev/null || { echo "gpu-pack.sh: needs patchelf (apt-get install patchelf)" >&2; exit 1; }

stage=$(mktemp -d)
trap 'rm -rf "$stage"' EXIT
mkdir -p "$stage/crackvis/bin" "$stage/crackvis/lib" "$stage/crackvis/certs/generated"
for program in "${programs[@]}"; do
  cp "$build/$program" "$stage/crackvis/bin/"
done
# glibc's libraries stay behind: the loader and libc must come from one
# glibc, the node's.
glibc='/(ld-linux-x86-64|libc|libm|libdl|libpthread|librt|libresolv|libutil|libanl|libmvec)\.so'
for program in "${programs[@]}"; do ldd "$build/$program"; done |
  awk '$2 == "=>" && $3 ~ /^\// { print $3 }' | sort -u | grep -Ev "$glibc" |
  while read -r library; do cp -L "$library" "$stage/crackvis/lib/"; done

# Two libraries are a quarter of the pack and never run in crackvis: codec2
# (an audio codec libavcodec links) and ICU's data (libxml2's encodings,
# through libicuuc). The node's copy must stay under the device tool's 64 MiB,
# so each is replaced by a stub with its soname and the symbols the other
# libraries import from it (BIND_NOW needs them all): a function aborts if
# ever called, a data symbol is an empty blob ICU would refuse.
stub() {  # LIBRARY_FILE
  local library=$1 soname source
  soname=$(readelf -d "$library" | sed -n 's/.*(SONAME).*\[\(.*\)\]/\1/p')
  source=$stage/stub.c
  echo '#include <stdlib.h>' >"$source"
  nm -D --defined-only "$library" | awk '{ print $2, $3 }' | sort -k2 >"$stage/defined"
  # A versioned symbol would need its version node in the stub too.
  if grep -q @ "$stage/defined"; then
    echo "gpu-pack.sh: $(basename "$library") has versioned symbols: cannot stub it" >&2
    exit 1
  fi
  for other in "$stage"/crackvis/lib/* "$stage"/crackvis/bin/*; do
    [[ $other == "$library" ]] || nm -D --undefined-only "$other" 2>/dev/null | awk '{ print $2 }'
  done | sed 's/@.*//' | sort -u | join -1 2 -2 1 "$stage/defined" - |
    while read -r symbol type; do
      case $type in
        T | W | i) echo "void $symbol(void) { abort(); }" ;;
        *) echo "const char $symbol[64];" ;;
      esac
    done >>"$source"
  cc -shared -fPIC -O1 -Wl,-soname,"$soname" -o "$library" "$source"
  echo "gpu-pack.sh: $(basename "$library") is a stub of $(($(wc -l <"$source") - 1)) symbols" >&2
}
for name in libcodec2 libicudata; do
  matches=("$stage"/crackvis/lib/"$name".so.*)
  [[ -f ${matches[0]} ]] || { echo "gpu-pack.sh: no $name in the pack to stub" >&2; exit 1; }
  stub "${matches[0]}"
done

for program in "$stage"/crackvis/bin/*; do
  # DT_RPATH, not RUNPATH: it applies to the libraries' own dependencies too.
  patchelf --force-rpath --set-rpath '$ORIGIN/../lib' "$program"
done

cd "$root"
[[ -f certs/generated/crackvis-render.pem ]] || bash certs/make-dev-certs.sh --client crackvis-render >&2
cp certs/generated/* "$stage/crackvis/certs/generated/"
git -C "$root" log -1 --format='%H %cI' >"$stage/crackvis/commit" 2>/dev/null || true

XZ_OPT='-9 -T2' tar -C "$stage" -cJf "$pack" crackvis
echo "gpu-pack.sh: $(find "$stage/crackvis/lib" -type f | wc -l) libraries," \
  "$(du -sh "$stage/crackvis" | cut -f1) unpacked, $(du -h "$pack" | cut -f1) packed: $pack" >&2
