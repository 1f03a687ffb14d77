#!/usr/bin/env bash
# Debian 12's ParaView 5.11 (paraview, python3-paraview, paraview-dev)
# unpacked into a private prefix, with the libraries it loads installed.
#
# ParaView must never be installed with apt or dpkg -i here: `paraview`
# conflicts with python3-vtk9, which libvtk9-dev (the VTK the rest of crackvis
# builds on) depends on, so installing it would remove that VTK. dpkg -x
# unpacks the packages without installing them; their Depends that are
# ordinary libraries are installed with apt when that removes nothing.
#
#   deploy/paraview-prefix.sh            # make sure the prefix exists; print its path
#   deploy/paraview-prefix.sh --env      # the same, then print the exports that run it:
#                                        #   eval "$(deploy/paraview-prefix.sh --env)"
#
# The prefix lives in ${CRACKVIS_PARAVIEW_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/crackvis/paraview-5.11}
# (/prefix); the first run downloads ~83 MB of .debs. Used by
# deploy/install-deps.sh (the plugin's build environment, paraview-plugin/),
# tools/bench/paraview-peer.sh and the plugin's tests.
set -euo pipefail

readonly pv_version=5.11
readonly pv_packages=(paraview python3-paraview paraview-dev)
# Depends of those packages that neither pvserver, pvpython nor a plugin
# build loads: Tcl wrapping, ParaViewWeb (twisted, autobahn), and ParaView
# itself (unpacked here).
readonly pv_unneeded_depends=" paraview tclsh python3-autobahn python3-twisted "
readonly cache=${CRACKVIS_PARAVIEW_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/crackvis/paraview-$pv_version}
readonly prefix=$cache/prefix

die() {
  echo "paraview-prefix.sh: $*" >&2
  exit 1
}

say() {
  echo "paraview-prefix.sh: $*" >&2
}

is_installed() {
  [[ $(dpkg-query -W -f='${db:Status-Status}' "$1" 2>/dev/null) == installed ]]
}

apt_download() {
  # As root, apt drops to the _apt user for downloads, which cannot write to
  # a folder under /root; downloading as the caller avoids the warning.
  apt-get -q -o APT::Sandbox::User="$(id -un)" download "$@" >&2
}

# Downloads and unpacks the packages into $prefix once; the .unpacked stamp
# (naming the packages) is written last, so an interrupted run starts over.
unpack_paraview() {
  [[ -f $prefix/.unpacked && $(cat "$prefix/.unpacked") == "${pv_packages[*]}" ]] && return 0
  if ! apt-cache show paraview >/dev/null 2>&1; then
    ((EUID == 0)) || die "apt does not know the paraview package; run 'apt-get update' as root"
    say "apt-get update (the package lists lack paraview)"
    apt-get update -qq >&2 || die "apt-get update failed"
  fi
  local version
  version=$(apt-cache policy paraview | awk '/Candidate:/ { print $2 }')
  [[ $version == $pv_version.* ]] ||
    die "apt offers paraview '$version', not $pv_version.x (this script expects Debian 12)"
  say "downloading ${pv_packages[*]} $version into $cache/debs (~83 MB, once)"
  mkdir -p "$cache/debs"
  rm -f "$cache/debs/"*.deb
  (cd "$cache/debs" && apt_download "${pv_packages[@]/%/=$version}") ||
    die "apt-get download ${pv_packages[*]} failed"
  say "unpacking into $prefix (dpkg -x: nothing is installed)"
  rm -rf "$prefix" "$prefix.partial"
  mkdir -p "$prefix.partial"
  local deb
  for deb in "$cache/debs/"*.deb; do
    dpkg -x "$deb" "$prefix.partial" || die "dpkg -x $deb failed"
    dpkg-deb -f "$deb" Depends >>"$prefix.partial/.depends"
  done
  echo "$version" >"$prefix.partial/.version"
  mv "$prefix.partial" "$prefix"
  echo "${pv_packages[*]}" >"$prefix/.unpacked"
}

# The packages' Depends that are not installed: installed with apt when that
# removes nothing (they are ordinary libraries), else unpacked into $prefix.
ensure_depends() {
  # Checked once per change of the installed packages (dpkg's status file).
  [[ $prefix/.depends-ok -nt /var/lib/dpkg/status ]] && return 0
  local group alternative missing=()
  while read -r group; do
    local satisfied=0 first=""
    for alternative in ${group//|/ }; do
      alternative=${alternative%%:*}
      [[ -z $first ]] && first=$alternative
      [[ $pv_unneeded_depends == *" $alternative "* ]] && satisfied=1
      is_installed "$alternative" && satisfied=1
    done
    ((satisfied)) || missing+=("$first")
  done < <(tr ',' '\n' <"$prefix/.depends" | sed 's/([^)]*)//g; s/^ *//; s/ *$//' | sort -u)
  if ((${#missing[@]} == 0)); then
    touch "$prefix/.depends-ok"
    return 0
  fi
  say "ParaView needs these packages: ${missing[*]}"
  if ((EUID == 0)) && ! apt-get install -s --no-install-recommends "${missing[@]}" 2>&1 |
    grep -q '^Remv'; then
    say "installing them with apt-get (the simulation removes nothing)"
    DEBIAN_FRONTEND=noninteractive apt-get install -y -q -o Dpkg::Use-Pty=0 \
      --no-install-recommends "${missing[@]}" >&2 || die "apt-get install ${missing[*]} failed"
  else
    say "not installable without removing packages (or not root): unpacking them into $prefix"
    (cd "$cache/debs" && apt_download "${missing[@]}") || die "apt-get download ${missing[*]} failed"
    local name
    for name in "${missing[@]}"; do
      dpkg -x "$cache/debs/${name}_"*.deb "$prefix" || die "dpkg -x $name failed"
    done
  fi
}

print_env() {
  local libdir multiarch
  libdir=$(dirname "$(find "$prefix/usr/lib" -name "libvtkRemotingCore-pv$pv_version.so.1" | head -1)")
  [[ -d $libdir && $libdir != . ]] || die "no ParaView libraries under $prefix (remove it to unpack again)"
  multiarch=$(basename "$libdir")
  # ParaView's vtkmodules must come before /usr/lib/python3/dist-packages,
  # where python3-vtk9's live.
  cat <<EOF
export CRACKVIS_PARAVIEW_PREFIX='$prefix'
export ParaView_DIR='$libdir/cmake/paraview-$pv_version'
export LD_LIBRARY_PATH='$libdir:$prefix/lib/$multiarch'\${LD_LIBRARY_PATH:+:\$LD_LIBRARY_PATH}
export PYTHONPATH='$prefix/usr/lib/python3/dist-packages'\${PYTHONPATH:+:\$PYTHONPATH}
EOF
}

case ${1:-} in
  "") unpack_paraview; ensure_depends; echo "$prefix" ;;
  --env) unpack_paraview; ensure_depends; print_env ;;
  -h | --help) sed -n '2,19p' "$0" | sed 's/^# \{0,1\}//' ;;
  *) die "unknown option '$1' (try --help)" ;;
esac
