#!/usr/bin/env bash
# The README's first command: install what is missing, build Release, and start the server on
# http://127.0.0.1:8080 with the heptane sample (a real simulation volume) loaded. Open that
# address in a browser. Ctrl-C stops it. PEAKCAST_PORT / PEAKCAST_BIND change where it listens.
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
bash "$PEAKCAST_ROOT/scripts/build.sh"
data="$PEAKCAST_ROOT/tests/data"
exec "$BUILD_DIR/server/peakcast" serve --port "${PEAKCAST_PORT:-8080}" --bind "${PEAKCAST_BIND:-127.0.0.1}" \
  --data "$data" --volume "$data/heptane_151.nrrd" --upload-dir "${PEAKCAST_UPLOAD_DIR:-$BUILD_DIR/uploads}" "$@"
