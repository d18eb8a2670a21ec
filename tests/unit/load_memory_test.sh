#!/usr/bin/env bash
# Loading streams into the final buffer: peak RSS of `peakcast info` on a 96 MiB volume must
# stay within 1.1x the voxel bytes + one slice over the RSS of loading a tiny volume.
set -euo pipefail
peakcast=$1
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
"$peakcast" make-volume ramp --dims 8 8 8 --type uint16 -o "$dir/tiny.nrrd" --gzip >/dev/null
"$peakcast" make-volume ramp --dims 512 384 256 --type uint16 -o "$dir/big.nrrd" --gzip >/dev/null
"$peakcast" make-volume ramp --dims 512 384 256 --type uint16 -o "$dir/big.raw" >/dev/null
rss() { "$peakcast" info "$1" | awk '/peak RSS/ {print $3}'; }
base=$(rss "$dir/tiny.nrrd")
for f in big.nrrd big.raw; do
  big=$(rss "$dir/$f")
  awk -v b="$base" -v g="$big" -v f="$f" 'BEGIN {
    bytes = 512*384*256*2/1048576; slice = 512*384*2/1048576; limit = 1.1*bytes + slice + 2;
    printf "%s: baseline %.1f MiB, load %.1f MiB, delta %.1f MiB, voxels %.1f MiB, limit %.1f MiB\n", f, b, g, g-b, bytes, limit;
    exit (g - b <= limit) ? 0 : 1 }'
done
