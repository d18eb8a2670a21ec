#!/usr/bin/env bash
# The README's second command: install what is missing, build, run every CTest label
# (unit, gpu, numeric, net, browser). Exits non-zero on any failure.
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
install_packages "${PEAKCAST_PACKAGES[@]}" "${PEAKCAST_TEST_PACKAGES[@]}"
install_node_modules
build_peakcast Release
cd "$BUILD_DIR"
ctest --output-on-failure -j"$(nproc)" --timeout 900 "$@"
