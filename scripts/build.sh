#!/usr/bin/env bash
# Install what building needs (Debian 12) and build the Release server: the first half of the
# README's demo command, and the container's build stage (docker/Dockerfile runs this file).
#   bash scripts/build.sh              install missing build packages, build everything
#   bash scripts/build.sh --deps-only  only install (a cached container layer of its own)
# PEAKCAST_BUILD_DIR, PEAKCAST_TARGETS (e.g. "peakcast") and PEAKCAST_CMAKE_ARGS (e.g.
# "-DPEAKCAST_BUILD_TESTS=OFF") narrow the build; PEAKCAST_CMAKE_ARGS applies when the build
# directory is first configured (an existing one keeps its cache: remove it to change them).
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
install_packages "${PEAKCAST_BUILD_PACKAGES[@]}"
[[ ${1:-} == --deps-only ]] && exit 0
# shellcheck disable=SC2086  # PEAKCAST_CMAKE_ARGS is a list of arguments
build_peakcast Release "$BUILD_DIR" ${PEAKCAST_CMAKE_ARGS:-}
