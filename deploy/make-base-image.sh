#!/usr/bin/env bash
# Makes the `debian:12` Docker image the Dockerfiles start from out of
# Debian's own archive, for machines that reach deb.debian.org but not Docker
# Hub (air-gapped clusters with a Debian mirror). Where Docker Hub is
# reachable, `docker pull debian:12` does the same job.
#
#   deploy/make-base-image.sh [MIRROR]   MIRROR defaults to http://deb.debian.org/debian
#
# Needs root, debootstrap and a running Docker daemon; about a minute.
set -euo pipefail

mirror=${1:-http://deb.debian.org/debian}
security=${mirror%/debian}/debian-security
command -v debootstrap >/dev/null || { echo "make-base-image: apt-get install debootstrap" >&2; exit 1; }
command -v docker >/dev/null || { echo "make-base-image: apt-get install docker.io" >&2; exit 1; }

rootfs=$(mktemp -d /tmp/crackvis-debian12.XXXXXX)
trap 'rm -rf "$rootfs" "$rootfs.log"' EXIT

echo "make-base-image: debootstrap bookworm from $mirror"
debootstrap --variant=minbase bookworm "$rootfs" "$mirror" >"$rootfs.log" 2>&1 || {
  tail -20 "$rootfs.log" >&2
  exit 1
}

# The same sources as Debian's official image: the release, its updates and
# the security archive, so images get the same fixed package versions.
rm -f "$rootfs/etc/apt/sources.list"
cat >"$rootfs/etc/apt/sources.list.d/debian.sources" <<SOURCES
Types: deb
URIs: $mirror
Suites: bookworm bookworm-updates
Components: main
Signed-By: /usr/share/keyrings/debian-archive-keyring.gpg

Types: deb
URIs: $security
Suites: bookworm-security
Components: main
Signed-By: /usr/share/keyrings/debian-archive-keyring.gpg
SOURCES
rm -rf "$rootfs"/var/lib/apt/lists/* "$rootfs"/var/cache/apt/archives/*.deb

tar -C "$rootfs" -c . | docker import -c 'CMD ["bash"]' - debian:12
docker image ls debian:12
