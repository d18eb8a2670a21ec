// Reading a box of voxels out of a volume file (each MPI rank reads only its brick).
// The payload is the full volume's bytes in x-fastest order, possibly split over several files
// (NRRD LIST, printf data files) and possibly compressed. The region is a list of rows (one per
// y and z of the box), each a contiguous run of the payload; only those bytes land in the volume.
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <memory>

#include "core/volume_io_detail.h"

namespace fs = std::filesystem;

namespace peakcast::detail {
namespace {

struct Rows {
  int64_t nx, ny, x0, y0, z0, rx, ry, rz, bpv;
  int64_t count() const { return ry * rz; }
  int64_t bytes() const { return rx * bpv; }
  int64_t start(int64_t k) const {  // payload byte offset of row k (y fastest, then z)
    const int64_t y = y0 + k % ry, z = z0 + k / ry;
    return ((z * ny + y) * nx + x0) * bpv;
  }
};

// Copies the part of payload bytes [c0, c0 + n) that falls into rows, from row `k` on; advances k
// past rows that are complete.
void copy_rows(const Rows& rows, int64_t& k, int64_t c0, const uint8_t* chunk, int64_t n, uint8_t* dst) {
  for (int64_t r = k; r < rows.count(); ++r) {
    const int64_t s = rows.start(r), e = s + rows.bytes();
    if (s >= c0 + n) break;
    const int64_t a = std::max(s, c0), b = std::min(e, c0 + n);
    if (a < b) std::copy(chunk + (a - c0), chunk + (b - c0), dst + r * rows.bytes() + (a - s));
    if (e <= c0 + n && r == k) ++k;
  }
}

// Raw payload: each row by pread from the file(s) that hold it.
void read_raw_rows(const PayloadSpec& payload, int64_t total, const Rows& rows, uint8_t* dst) {
  struct Part {
    fs::path path;
    int64_t begin, end, file_offset;  // payload bytes [begin, end) at file_offset in the file
  };
  std::vector<Part> parts;
  int64_t at = 0;
  for (const DataPart& p : payload.parts) {  // resolved by the reader: offsets and sizes checked
    parts.push_back({p.path, at, at + p.bytes, p.offset});
    at += p.bytes;
  }
  for (size_t i = 0; payload.parts.empty() && i < payload.files.size() && at < total; ++i) {
    std::error_code ec;
    const int64_t size = int64_t(fs::file_size(payload.files[i], ec));
    int64_t skip = i == 0 ? payload.byte_skip : 0;
    if (skip < 0) skip = std::max<int64_t>(0, size - total);  // the data is the last bytes
    const int64_t n = std::min(std::max<int64_t>(size - skip, 0), total - at);
    parts.push_back({payload.files[i], at, at + n, skip});
    at += n;
  }
  const int64_t first = rows.start(0), last = rows.start(rows.count() - 1) + rows.bytes();
  for (const Part& p : parts) {
    if (p.end <= first || p.begin >= last) continue;  // a slice file outside the region
    const File f = open_file(p.path);
    const int fd = fileno(f.get());
    for (int64_t r = 0; r < rows.count(); ++r) {
      const int64_t s = rows.start(r), e = s + rows.bytes();
      const int64_t a = std::max(s, p.begin), b = std::min(e, p.end);
      for (int64_t got = 0; a + got < b;) {
        const ssize_t n = ::pread(fd, dst + r * rows.bytes() + (a - s) + got, size_t(b - a - got),
                                  off_t(p.file_offset + (a - p.begin) + got));
        if (n <= 0) throw VolumeError(p.path, "read failed (the file shrank or could not be read)");
        got += n;
      }
    }
  }
}

// Compressed or text payload: decode in chunks, keep the rows' bytes, stop after the last row.
void read_compressed_rows(const PayloadSpec& payload, const Rows& rows, uint8_t* dst) {
  const int64_t last_byte = rows.start(rows.count() - 1) + rows.bytes();
  int64_t at = 0, k = 0;
  auto keep = [&](const uint8_t* chunk, size_t n) {
    copy_rows(rows, k, at, chunk, int64_t(n), dst);
    at += int64_t(n);
    return at < last_byte;
  };
  for (size_t i = 0; i < payload.parts.size() && at < last_byte; ++i)
    stream_part(payload.parts[i], payload.encoding, payload.text_type, keep);
  for (size_t i = 0; payload.parts.empty() && i < payload.files.size() && at < last_byte; ++i)
    inflate_file(payload.files[i], i == 0 ? payload.byte_skip : 0, payload.encoding, keep);
  if (at < last_byte)
    throw VolumeError(payload.files.back(), "truncated: the region ends at data byte " + std::to_string(last_byte) +
                                                ", the data holds " + std::to_string(at));
}

}  // namespace

Volume read_payload_region(const fs::path& header_file, const VolumeHeader& h, const PayloadSpec& payload,
                           const LoadOptions& options) {
  const VoxelRegion& region = *options.region;
  VolumeHeader rh = h;
  for (int a = 0; a < 3; ++a) {
    if (region.lo[a] < 0 || region.hi[a] > h.dims[a] || region.lo[a] >= region.hi[a])
      throw VolumeError(header_file, "region [" + std::to_string(region.lo[a]) + ", " + std::to_string(region.hi[a]) +
                                         ") on axis " + std::to_string(a) + " is not inside the volume's " +
                                         std::to_string(h.dims[a]) + " voxels");
    rh.dims[a] = region.hi[a] - region.lo[a];
    rh.origin[a] = h.origin[a] + double(region.lo[a]) * h.spacing[a];
  }
  LoadOptions local = options;
  local.region.reset();
  check_header(header_file, rh, local);  // the region's own voxel limit
  const int64_t bpv = int64_t(source_bytes(h.source));
  const int64_t total = h.voxel_count() * bpv;
  const Rows rows{h.dims[0],  h.dims[1],  region.lo[0], region.lo[1], region.lo[2],
                  rh.dims[0], rh.dims[1], rh.dims[2],   bpv};
  Volume v(rh);
  if (payload.encoding == Encoding::Raw)
    read_raw_rows(payload, total, rows, v.data());
  else
    read_compressed_rows(payload, rows, v.data());
  finish_volume(header_file, v, h.big_endian, local);
  v.source_dims = h.dims;
  v.region_lo = region.lo;
  return v;
}

Volume read_time_point(const fs::path& path, const VolumeHeader& h, int64_t times, const PayloadSpec& payload,
                       const LoadOptions& options) {
  const int64_t t = options.time_point, Z = h.dims[2];
  if (t < 0 || t >= times)
    throw VolumeError(path, "time point " + std::to_string(t) + " is outside 0.." + std::to_string(times - 1));
  VolumeHeader series = h;
  if (__builtin_mul_overflow(Z, times, &series.dims[2])) throw VolumeError(path, "sizes overflow 64-bit voxel count");
  series.time_point = t;
  series.time_points = times;
  LoadOptions o = options;
  VoxelRegion r = options.region.value_or(VoxelRegion{{0, 0, 0}, h.dims});
  if (r.hi[2] > Z) throw VolumeError(path, "region past the volume's " + std::to_string(Z) + " slices");
  r.lo[2] += t * Z;
  r.hi[2] += t * Z;
  o.region = r;
  Volume v = read_payload(path, series, payload, o);
  v.origin.z = h.origin.z + double(r.lo[2] - t * Z) * h.spacing.z;
  if (options.region) {
    v.source_dims = h.dims;
    v.region_lo[2] -= t * Z;
  } else {
    v.source_dims = {0, 0, 0};
    v.region_lo = {0, 0, 0};
  }
  return v;
}

}  // namespace peakcast::detail
