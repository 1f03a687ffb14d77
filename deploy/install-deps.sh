#!/usr/bin/env bash
# Installs every Debian 12 package crackvis needs to build, test and run.
#
# Idempotent: packages already installed are skipped, and a machine that has
# everything returns in about a second without touching the network. Works as
# root with no terminal (CI); as another user it goes through sudo.
#
#   deploy/install-deps.sh                   # everything (build, test, run)
#   deploy/install-deps.sh --runtime         # only what the built services and CLI load
#   deploy/install-deps.sh --client          # only what the `client` preset builds with
#   deploy/install-deps.sh [--runtime] --list   # print the package list and exit
set -euo pipefail

# One package per line, grouped by the part of crackvis that needs it.
readonly PACKAGES=(
  # toolchain
  build-essential cmake ninja-build pkg-config git clang-format
  # dem/: HDF5 files and their command-line tools (h5dump, h5ls)
  libhdf5-dev hdf5-tools h5utils
  # CLI, logging, JSON, parallel loops
  libcli11-dev libspdlog-dev libfmt-dev nlohmann-json3-dev libtbb-dev
  # cracks/: kd-tree, global Voronoi baseline, VTK adapters
  libnanoflann-dev voro++-dev libvtk9-dev
  # cracks/: Delaunay and regular triangulations of packings that are no lattice
  libcgal-dev
  # dataservice/, server/: gRPC with TLS
  libgrpc++-dev libgrpc-dev protobuf-compiler protobuf-compiler-grpc libprotobuf-dev libssl-dev openssl
  # server/: off-screen rendering (EGL + Mesa llvmpipe), pipeline schemas, encoding
  libegl-dev libegl-mesa0 libgl1-mesa-dri libgles-dev libopengl-dev
  libxml2-dev libxml2-utils
  libavcodec-dev libavformat-dev libavutil-dev libswscale-dev libx264-dev ffmpeg
  # server/service: the web front door (Boost.Beast, header-only);
  # tests/web: the browser page driven in headless Chromium. node and npm
  # (web/'s build) are added below unless a node with npm is installed.
  libboost-dev chromium
  # client/: Qt6 thin client, headless screenshots
  qt6-base-dev qt6-base-dev-tools libqt6opengl6-dev xvfb
  # tests, benchmark and report plots; scipy counts fragments independently
  catch2 gnuplot-nox python3-scipy
  # fuzzing (tests/fuzz/): clang with libFuzzer and the sanitizer runtimes
  clang libclang-rt-14-dev
  # paraview-plugin/: what building against Debian's ParaView (unpacked by
  # deploy/paraview-prefix.sh, never installed) needs besides it: its Open MPI
  # HDF5 and MPI, and the Qt 5 tools that make the plugin's documentation
  libhdf5-openmpi-dev libopenmpi-dev openmpi-bin
  qtbase5-dev qttools5-dev qttools5-dev-tools qtxmlpatterns5-dev-tools
  # deploy/slurm/: its test submits the batch script to a single-node Slurm
  # (slurmctld and slurmd on loopback, started by the test)
  slurmctld slurmd slurm-client
)

# What crackvis-data, crackvis-render and the crackvis CLI load when they run
# on a machine that did not build them (container images, service nodes): the
# packages of their direct shared libraries (tests/deploy/runtime-packages.sh
# checks this against the binaries), plus Mesa's EGL and llvmpipe, which
# libglvnd loads at run time. apt brings each library's own dependencies.
readonly RUNTIME_PACKAGES=(
  libhdf5-103-1 libgrpc++1.51 libgrpc29 libabsl20220623 libprotobuf32 libssl3 libfmt9
  libtbb12 libvoro++1 libvtk9.1 libxml2 libgmp10
  libavcodec59 libavformat59 libavutil57 libswscale6
  libegl1 libegl-mesa0 libgl1-mesa-dri
)

# What the `client` preset (crackvis-client alone, docs/client.md) builds and
# tests with: no HDF5, CGAL, TBB or VTK. ffmpeg brings ffprobe, which the
# recorder's tests read MP4 files with.
readonly CLIENT_PACKAGES=(
  build-essential cmake ninja-build pkg-config libfmt-dev libssl-dev nlohmann-json3-dev
  libgrpc++-dev libgrpc-dev protobuf-compiler protobuf-compiler-grpc libprotobuf-dev
  libxml2-dev libavcodec-dev libavformat-dev libavutil-dev libswscale-dev
  qt6-base-dev qt6-base-dev-tools catch2 ffmpeg
)

selected=("${PACKAGES[@]}")
list_only=false
for argument in "$@"; do
  case "$argument" in
    --runtime) selected=("${RUNTIME_PACKAGES[@]}") ;;
    --client) selected=("${CLIENT_PACKAGES[@]}") ;;
    --list) list_only=true ;;
    -h | --help)
      sed -n '2,11p' "$0" | sed 's/^# \{0,1\}//'
      exit 0
      ;;
    *)
      echo "install-deps: unknown option '$argument' (try --help)" >&2
      exit 2
      ;;
  esac
done

if $list_only; then
  printf '%s\n' "${selected[@]}"
  exit 0
fi

is_installed() {
  [[ "$(dpkg-query -W -f='${db:Status-Status}' "$1" 2>/dev/null)" == "installed" ]]
}

missing=()
for package in "${selected[@]}"; do
  is_installed "$package" || missing+=("$package")
done
# web/ is built by npm from its lockfile. Debian's nodejs 18 and npm 9 do;
# a machine that already has a node with npm (NodeSource's nodejs, which
# conflicts with Debian's npm package) keeps its own.
if [[ "${selected[*]}" == "${PACKAGES[*]}" ]] && ! { command -v node && command -v npm; } >/dev/null; then
  missing+=(nodejs npm)
fi

# Debian's ParaView, unpacked into a private prefix for the plugin's build
# and tests (it conflicts with libvtk9-dev's python3-vtk9: never installed).
unpack_paraview() {
  [[ "${selected[*]}" == "${PACKAGES[*]}" ]] || return 0
  bash "$(dirname "$0")/paraview-prefix.sh" >/dev/null
}

if ((${#missing[@]} == 0)); then
  echo "install-deps: all ${#selected[@]} packages present"
  unpack_paraview
  exit 0
fi

as_root=()
if ((EUID != 0)); then
  command -v sudo >/dev/null || {
    echo "install-deps: not root and no sudo; install as root: ${missing[*]}" >&2
    exit 1
  }
  as_root=(sudo)
fi

echo "install-deps: installing ${#missing[@]} packages: ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
apt_get=("${as_root[@]}" apt-get -y -q -o Dpkg::Use-Pty=0 --no-install-recommends)
# The package lists of a fresh machine are empty or stale; refresh them once.
"${as_root[@]}" apt-get update -q
"${apt_get[@]}" install "${missing[@]}"
unpack_paraview
echo "install-deps: done"
