#!/usr/bin/env bash
# Checks that `deploy/install-deps.sh --runtime` names the Debian package of
# every shared library the given binaries link directly, so that a container
# image or service node with only the runtime packages can start them (apt
# brings each package's own dependencies). Fails with the missing packages.
#
#   runtime-packages.sh deploy/install-deps.sh BINARY...
set -euo pipefail

install_deps=$1
shift
mapfile -t runtime < <(bash "$install_deps" --runtime --list)
# Present on every Debian 12 system (essential, or needed by apt itself).
runtime+=(libc6 libgcc-s1 libstdc++6)

missing=0
declare -A path_of   # soname -> the file the dynamic loader resolves it to
declare -A users_of  # soname -> the binaries linking it
for binary in "$@"; do
  resolved=$(ldd "$binary")
  mapfile -t needed < <(readelf -d "$binary" | awk -F'[][]' '/\(NEEDED\)/ {print $2}')
  for soname in "${needed[@]}"; do
    path=$(awk -v so="$soname" '$1 == so && $2 == "=>" {print $3}' <<<"$resolved")
    if [[ -z "$path" || "$path" == "not" ]]; then
      echo "$binary: $soname is not found on this machine" >&2
      missing=1
      continue
    fi
    path_of[$soname]=$path
    users_of[$soname]+=" $(basename "$binary")"
  done
  echo "$(basename "$binary"): ${#needed[@]} direct libraries"
done

# One dpkg query for all of them: dpkg records some libraries under /lib,
# others under /usr/lib (usrmerge), so ask for both spellings.
queries=()
for path in "${path_of[@]}"; do
  queries+=("${path#/usr}" "/usr${path#/usr}")
done
declare -A package_of
while IFS= read -r line; do
  package=${line%%:*}
  package_of[$(basename "${line##*: }")]=$package
done < <(dpkg-query -S "${queries[@]}" 2>/dev/null || true)

for soname in "${!path_of[@]}"; do
  package=${package_of[$soname]:-}
  if [[ -z "$package" ]]; then
    echo "$soname (${path_of[$soname]}, for${users_of[$soname]}) belongs to no Debian package" >&2
    missing=1
  elif [[ " ${runtime[*]} " != *" $package "* ]]; then
    echo "$soname (for${users_of[$soname]}) comes from $package, which install-deps.sh --runtime lacks" >&2
    missing=1
  fi
done
echo "${#path_of[@]} libraries, from packages install-deps.sh --runtime installs: $([[ $missing == 0 ]] && echo yes || echo NO)"
exit "$missing"
