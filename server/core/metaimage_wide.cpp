// MetaImage element types peakcast does not keep, converted when read, by a stated rule
// (docs/scenes.md, "Volumes"): MET_DOUBLE to float32, refused when a finite value does not fit
// (as the Python client's uploads do); the 32- and 64-bit integers to the narrowest kept type that
// holds every value (uint8, uint16 from 0 up; int8, int16 with negatives), else float32 when every
// value is exact in it (|v| <= 2^24), else refused with the range.
#include <algorithm>
#include <bit>
#include <cfloat>
#include <cmath>
#include <cstring>

#include "core/volume_io_detail.h"

namespace fs = std::filesystem;

namespace peakcast::detail {
namespace {

template <typename T>
T element(const uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return v;
}

// Every value, as a double, for the scan and the conversion (64-bit integers past 2^53 lose
// digits here, and are then refused as not exact in float32 nor held by a kept integer type).
double value_at(const WideType& w, const uint8_t* p) {
  if (w.floating) return element<double>(p);
  if (w.bytes == 4) return w.is_signed ? double(element<int32_t>(p)) : double(element<uint32_t>(p));
  return w.is_signed ? double(element<int64_t>(p)) : double(element<uint64_t>(p));
}

SourceType target_type(const fs::path& path, const WideType& w, double lo, double hi) {
  auto range = [&] { return std::to_string(lo) + ".." + std::to_string(hi); };
  if (w.floating) {
    if (std::max(-lo, hi) > double(FLT_MAX))
      throw VolumeError(path, w.name + " values " + range() +
                                  " do not fit in float32, the type peakcast keeps floats as: rescale them first");
    return SourceType::F32;
  }
  if (lo >= 0 && hi <= 255) return SourceType::U8;
  if (lo >= -128 && hi <= 127) return SourceType::I8;
  if (lo >= 0 && hi <= 65535) return SourceType::U16;
  if (lo >= -32768 && hi <= 32767) return SourceType::I16;
  if (std::max(-lo, hi) <= 16777216.0) return SourceType::F32;
  throw VolumeError(path, w.name + " values " + range() +
                              " fit none of uint8, int8, uint16, int16 and are not exact in float32 (|v| <= 2^24)");
}

// The voxels of `from` inside options.region, as read_payload_region places them.
Volume crop(const fs::path& path, const Volume& from, const VoxelRegion& r) {
  VolumeHeader rh;
  rh.source = from.source_type();
  rh.spacing = from.spacing;
  rh.unit = from.unit;
  for (int a = 0; a < 3; ++a) {
    if (r.lo[a] < 0 || r.hi[a] > from.dims()[a] || r.lo[a] >= r.hi[a])
      throw VolumeError(path, "region on axis " + std::to_string(a) + " is not inside the volume");
    rh.dims[a] = r.hi[a] - r.lo[a];
    rh.origin[a] = from.origin[a] + double(r.lo[a]) * from.spacing[a];
  }
  Volume v(rh);
  const size_t bpv = voxel_bytes(from.type()), row = size_t(rh.dims[0]) * bpv;
  for (int64_t z = 0; z < rh.dims[2]; ++z)
    for (int64_t y = 0; y < rh.dims[1]; ++y) {
      const size_t src = size_t(((z + r.lo[2]) * from.dims()[1] + y + r.lo[1]) * from.dims()[0] + r.lo[0]) * bpv;
      std::memcpy(v.data() + size_t(z * rh.dims[1] + y) * row, from.data() + src, row);
    }
  v.source_dims = from.dims();
  v.region_lo = r.lo;
  return v;
}

template <typename T>
void fill(Volume& v, const WideType& w, const std::vector<uint8_t>& raw) {
  T* out = reinterpret_cast<T*>(v.data());
  const size_t n = size_t(v.voxel_count());
  for (size_t i = 0; i < n; ++i) out[i] = T(value_at(w, raw.data() + i * size_t(w.bytes)));
}

}  // namespace

std::optional<WideType> wide_metaimage_type(const std::string& element_type) {
  const std::string t = lower(trim(element_type));
  if (t == "met_double") return WideType{"MET_DOUBLE", 8, true, true};
  if (t == "met_int" || t == "met_long") return WideType{t == "met_int" ? "MET_INT" : "MET_LONG", 4, false, true};
  if (t == "met_uint" || t == "met_ulong") return WideType{t == "met_uint" ? "MET_UINT" : "MET_ULONG", 4, false, false};
  if (t == "met_long_long") return WideType{"MET_LONG_LONG", 8, false, true};
  if (t == "met_ulong_long") return WideType{"MET_ULONG_LONG", 8, false, false};
  return std::nullopt;
}

Volume read_converted(const fs::path& path, const VolumeHeader& h, const WideType& w, const PayloadSpec& payload,
                      const LoadOptions& options) {
  const size_t n = size_t(h.voxel_count()), total = n * size_t(w.bytes);
  std::vector<uint8_t> raw(total);
  LoadProgress progress(options, total);
  read_parts(payload, raw.data(), total, progress);
  if (h.big_endian != (std::endian::native == std::endian::big))
    for (size_t i = 0; i < n; ++i) std::reverse(raw.begin() + long(i) * w.bytes, raw.begin() + long(i + 1) * w.bytes);
  double lo = INFINITY, hi = -INFINITY;
  for (size_t i = 0; i < n; ++i) {
    const double v = value_at(w, raw.data() + i * size_t(w.bytes));
    if (std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
  }
  if (lo > hi) lo = hi = 0;  // nothing finite: the NaN/Inf policy decides
  VolumeHeader kept = h;
  kept.source = target_type(path, w, lo, hi);
  kept.big_endian = std::endian::native == std::endian::big;  // converted in host order
  Volume v(kept);
  switch (kept.source) {
    case SourceType::U8: fill<uint8_t>(v, w, raw); break;
    case SourceType::I8: fill<int8_t>(v, w, raw); break;
    case SourceType::U16: fill<uint16_t>(v, w, raw); break;
    case SourceType::I16: fill<int16_t>(v, w, raw); break;
    case SourceType::F32: fill<float>(v, w, raw); break;
  }
  raw = {};
  if (options.region) v = crop(path, v, *options.region);  // an MPI brick: the whole file was read
  LoadOptions local = options;
  local.region.reset();
  finish_volume(path, v, kept.big_endian, local);
  progress.done();
  return v;
}

}  // namespace peakcast::detail
