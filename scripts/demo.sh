#!/usr/bin/env bash
# The README's first command: install what is missing, build Release, run the demo.
# Renders the heptane sample (a real volume) with a near-Dirac red peak and a smooth blue
# feature, and prints where the PNG is.
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
install_packages "${PEAKCAST_PACKAGES[@]}"
build_peakcast Release
out=${PEAKCAST_DEMO_OUT:-$PEAKCAST_ROOT/out}
mkdir -p "$out"
"$BUILD_DIR/server/peakcast" render "$PEAKCAST_ROOT/scripts/demo/heptane.json" -o "$out/demo.png" --stats "$out/demo_stats.json"
echo "peakcast: demo image at $out/demo.png (stats: $out/demo_stats.json)"
