#!/usr/bin/env bash
# Build the peakcast image from docker/Dockerfile.
#   bash docker/build-image.sh
# With a Docker engine (`docker info` answers) it runs `docker build`. Otherwise it uses buildah
# with vfs storage and chroot isolation, which need no daemon and no kernel overlay support. When
# the base image cannot be pulled (no registry reachable), it makes a Debian 12 base from Debian's
# packages with `debootstrap --variant=minbase bookworm`, adds it to a FROM-scratch image
# (localhost/peakcast-base:bookworm) and builds on that.
# Environment:
#   PEAKCAST_IMAGE          the tag to build (default localhost/peakcast:latest)
#   BASE_IMAGE              the base (default docker.io/library/debian:bookworm-slim)
#   PEAKCAST_DEBIAN_MIRROR  the mirror for debootstrap (default: this host's, else deb.debian.org)
#   PEAKCAST_IMAGE_LAYERS   set: buildah caches layers (fast rebuilds, many GB under vfs)
#   PEAKCAST_IMAGE_NO_CCACHE set: do not lend the host's ccache ($CCACHE_DIR) to the build stage
# Prints the image size and the build time at the end. The debootstrap base is made once and kept.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
tag=${PEAKCAST_IMAGE:-localhost/peakcast:latest}
base=${BASE_IMAGE:-docker.io/library/debian:bookworm-slim}
start=$SECONDS

if command -v docker >/dev/null && docker info >/dev/null 2>&1; then
  docker build -f "$root/docker/Dockerfile" --build-arg BASE_IMAGE="$base" -t "$tag" "$root"
  echo "build-image: $tag built by docker in $((SECONDS - start)) s," \
    "$(docker image inspect -f '{{.Size}}' "$tag" | awk '{printf "%.0f MB", $1 / 1e6}')"
  exit 0
fi
command -v buildah >/dev/null || {
  echo "build-image: neither a Docker engine nor buildah is available (apt-get install buildah)" >&2
  exit 1
}
buildah=(buildah --storage-driver vfs)
have_image() { "${buildah[@]}" inspect --type image "$1" >/dev/null 2>&1; }

# The host's Debian mirror, so that the base sees the same archive (and versions) as the host.
host_mirror() {
  local uri
  uri=$(grep -hE '^(URIs:|deb )' /etc/apt/sources.list.d/*.sources /etc/apt/sources.list 2>/dev/null |
    grep -vE 'security' | head -1 | sed -E 's/^URIs: *//; s/^deb +(\[[^]]*\] +)?//; s/ .*//' || true)
  echo "${uri:-http://deb.debian.org/debian}"
}

make_debootstrap_base() {
  local mirror=${PEAKCAST_DEBIAN_MIRROR:-$(host_mirror)}
  command -v debootstrap >/dev/null || {
    echo "build-image: $base cannot be pulled and debootstrap is missing (apt-get install debootstrap)" >&2
    exit 1
  }
  # Global, not local: the EXIT trap runs after this function has returned (set -u).
  work=$(mktemp -d)
  trap 'rm -rf "${work:-}"' EXIT
  echo "build-image: no registry base; debootstrap --variant=minbase bookworm from $mirror"
  debootstrap --variant=minbase bookworm "$work/rootfs" "$mirror" >"$work/debootstrap.log" 2>&1 || {
    tail -20 "$work/debootstrap.log" >&2
    exit 1
  }
  # The same suites as a Debian image: the release, its updates and security fixes (the host's
  # security source when it has one).
  local security
  # (|| true: grep fails on a missing sources.list, which a deb822-only host does not have.)
  security=$(grep -hE '^(URIs:|deb )' /etc/apt/sources.list.d/*.sources /etc/apt/sources.list 2>/dev/null |
    grep -E 'security' | head -1 | sed -E 's/^URIs: *//; s/^deb +(\[[^]]*\] +)?//; s/ .*//' || true)
  security=${security:-http://deb.debian.org/debian-security}
  cat >"$work/rootfs/etc/apt/sources.list" <<SOURCES
deb $mirror bookworm main
deb $mirror bookworm-updates main
deb $security bookworm-security main
SOURCES
  rm -rf "$work/rootfs/var/cache/apt/archives/"*.deb "$work/rootfs/var/lib/apt/lists/"*
  tar -C "$work/rootfs" -cf "$work/rootfs.tar" .
  printf 'FROM scratch\nADD rootfs.tar /\nCMD ["bash"]\n' >"$work/Containerfile"
  "${buildah[@]}" bud --isolation chroot --format docker -f "$work/Containerfile" -t "$1" "$work" >/dev/null
  rm -rf "$work"
  trap - EXIT
}

if ! have_image "$base" && ! "${buildah[@]}" pull -q "$base" >/dev/null 2>&1; then
  echo "build-image: cannot pull $base"
  base=localhost/peakcast-base:bookworm
  have_image "$base" || make_debootstrap_base "$base"
fi
# --format docker: OCI images have no HEALTHCHECK field. Layer caching is off by default: vfs
# stores every layer as a full copy of the file system (six cached builds took 34 GB here), so a
# build keeps only its result and the base; PEAKCAST_IMAGE_LAYERS=1 caches layers anyway.
layers=()
[[ -n ${PEAKCAST_IMAGE_LAYERS:-} ]] && layers=(--layers)
# The host's ccache, lent to the build stage's RUN steps (a bind mount, not part of any layer):
# the sources the host just built compile from the cache (scripts/common.sh sets the same keys).
cache=()
ccache_dir=${CCACHE_DIR:-$HOME/.cache/ccache}
[[ -z ${PEAKCAST_IMAGE_NO_CCACHE:-} && -d $ccache_dir ]] && cache=(--volume "$ccache_dir:/ccache")
"${buildah[@]}" bud --isolation chroot --format docker "${layers[@]}" "${cache[@]}" \
  -f "$root/docker/Dockerfile" --build-arg BASE_IMAGE="$base" -t "$tag" "$root"
[[ -n ${PEAKCAST_IMAGE_LAYERS:-} ]] || "${buildah[@]}" rmi --prune >/dev/null 2>&1 || true  # the build stage, a replaced image
size=$("${buildah[@]}" inspect --type image --format '{{.Docker.Size}}' "$tag" 2>/dev/null || echo 0)
if [[ $size == 0 ]]; then  # vfs does not fill Size: sum the layers' uncompressed sizes
  size=$("${buildah[@]}" images --format '{{.Size}}' "$tag" | head -1)
else
  size="$((size / 1000000)) MB"
fi
echo "build-image: $tag built by buildah on $base in $((SECONDS - start)) s, $size"
