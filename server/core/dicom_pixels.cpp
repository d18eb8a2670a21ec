#include "core/dicom_pixels.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>

#include <gdcmImageReader.h>

#include "core/volume_io_detail.h"

namespace fs = std::filesystem;

namespace peakcast::dicom {
namespace {

struct Box {
  Dims lo{0, 0, 0}, hi{0, 0, 0};
  int64_t nx() const { return hi[0] - lo[0]; }
  int64_t ny() const { return hi[1] - lo[1]; }
  int64_t nz() const { return hi[2] - lo[2]; }
};

// The decoded, sign-corrected stored values of the box's slices, and each slice's extremes.
struct Stored {
  std::vector<int32_t> lo, hi;  // per slice of the box
  VoxelArray<int16_t> values;   // 16-bit slices: the stored bits as int16 (uint16 read back as such)
  VoxelArray<uint8_t> bytes;    // 8-bit slices
};

std::string name(const SliceHeader& s) { return s.file.filename().string(); }

void check_format(const fs::path& dir, const SliceHeader& s) {
  if (s.samples != 1)
    throw VolumeError(dir, name(s) + " holds colour (" + std::to_string(s.samples) +
                               " samples a pixel): a volume is one value a voxel");
  if (s.frames != 1)
    throw VolumeError(dir, name(s) + " is a multi-frame file (" + std::to_string(s.frames) +
                               " frames): peakcast reads a series of single-frame slices");
  if (s.bits_allocated != 8 && s.bits_allocated != 16)
    throw VolumeError(dir, name(s) + " has " + std::to_string(s.bits_allocated) + " bits a pixel: 8 and 16 are read");
  if (s.bits_stored < 1 || s.bits_stored > s.bits_allocated)
    throw VolumeError(dir, name(s) + ": BitsStored " + std::to_string(s.bits_stored) + " is not within 1.." +
                               std::to_string(s.bits_allocated));
}

int32_t corrected(int32_t raw, const SliceHeader& s) {
  const int b = s.bits_stored;
  const uint32_t mask = b >= 32 ? ~0u : ((1u << b) - 1u);
  uint32_t u = uint32_t(raw) & mask;
  if (s.is_signed && b < 32 && (u >> (b - 1)) & 1u) u |= ~mask;  // sign-extend from the stored bits
  return int32_t(u);
}

// Decodes slice `s` (file order) into row-major box rows at `out` (nx * ny values).
void decode_slice(const fs::path& dir, const SliceHeader& s, const Box& box, int32_t& lo, int32_t& hi, int16_t* out16,
                  uint8_t* out8) {
  gdcm::ImageReader reader;
  reader.SetFileName(s.file.c_str());
  if (!reader.Read()) throw VolumeError(dir, name(s) + " cannot be read as a DICOM image");
  const gdcm::Image& image = reader.GetImage();
  if (int(image.GetColumns()) != s.cols || int(image.GetRows()) != s.rows)
    throw VolumeError(dir, name(s) + ": its pixel data is not Rows x Columns");
  const size_t bpp = size_t(s.bits_allocated / 8);
  std::vector<char> buf(image.GetBufferLength());
  if (buf.size() < size_t(s.cols) * size_t(s.rows) * bpp || !image.GetBuffer(buf.data()))
    throw VolumeError(dir, name(s) + ": its pixel data cannot be decoded (a transfer syntax GDCM does not read?)");
  lo = std::numeric_limits<int32_t>::max();
  hi = std::numeric_limits<int32_t>::min();
  for (int64_t y = box.lo[1]; y < box.hi[1]; ++y)
    for (int64_t x = box.lo[0]; x < box.hi[0]; ++x) {
      const size_t at = size_t(y * s.cols + x);
      int32_t raw;
      if (bpp == 1) {
        raw = s.is_signed ? int32_t(int8_t(buf[at])) : int32_t(uint8_t(buf[at]));
      } else {
        uint16_t u;
        std::memcpy(&u, buf.data() + 2 * at, 2);
        raw = s.is_signed ? int32_t(int16_t(u)) : int32_t(u);
      }
      const int32_t v = corrected(raw, s);
      lo = std::min(lo, v);
      hi = std::max(hi, v);
      const size_t o = size_t((y - box.lo[1]) * box.nx() + (x - box.lo[0]));
      if (out16)
        out16[o] = int16_t(uint16_t(uint32_t(v)));
      else
        out8[o] = uint8_t(uint32_t(v));
    }
}

bool integral(double v) { return std::abs(v - std::round(v)) < 1e-9; }

struct Kept {
  SourceType type = SourceType::F32;
  double lo = 0, hi = 0;  // the physical range
};

Kept kept_type(const std::vector<const SliceHeader*>& in_box, const Stored& st) {
  Kept k{SourceType::F32, std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
  bool ints = true, plain8 = true, signed_source = false;
  for (size_t i = 0; i < in_box.size(); ++i) {
    const SliceHeader& s = *in_box[i];
    const double a = s.slope * st.lo[i] + s.intercept, b = s.slope * st.hi[i] + s.intercept;
    k.lo = std::min({k.lo, a, b});
    k.hi = std::max({k.hi, a, b});
    ints &= integral(s.slope) && integral(s.intercept);
    plain8 &= s.bits_allocated == 8 && !s.is_signed && s.slope == 1.0 && s.intercept == 0.0;
    signed_source |= s.is_signed;
  }
  if (plain8)
    k.type = SourceType::U8;
  else if (ints && !signed_source && k.lo >= 0 && k.hi <= 65535)
    k.type = SourceType::U16;
  else if (ints && k.lo >= -32768 && k.hi <= 32767)
    k.type = SourceType::I16;
  else if (ints && k.lo >= 0 && k.hi <= 65535)
    k.type = SourceType::U16;
  return k;
}

template <typename T>
void fill(Volume& v, const std::vector<const SliceHeader*>& in_box, const Stored& st, const Kept& k, int64_t per) {
  T* out = reinterpret_cast<T*>(v.data());
  for (size_t i = 0; i < in_box.size(); ++i) {
    const SliceHeader& s = *in_box[i];
    for (int64_t j = 0; j < per; ++j) {
      const size_t at = size_t(int64_t(i) * per + j);
      const double stored = st.bytes.get() ? (s.is_signed ? double(int8_t(st.bytes[at])) : double(st.bytes[at]))
                                           : (s.is_signed ? double(st.values[at]) : double(uint16_t(st.values[at])));
      double p = s.slope * stored + s.intercept;
      if (s.monochrome1) p = k.lo + k.hi - p;
      out[at] = T(std::is_floating_point_v<T> ? p : std::round(p));
    }
  }
}

}  // namespace

Volume read_pixels(const fs::path& dir, const std::vector<SliceHeader>& slices, const SeriesGeometry& g,
                   const LoadOptions& options) {
  for (const SliceHeader& s : slices) check_format(dir, s);
  const SliceHeader& a = slices.front();
  VolumeHeader h;
  h.dims = {a.cols, a.rows, int64_t(slices.size())};
  h.spacing = {a.col_spacing, a.row_spacing, g.gap};
  h.origin = g.origin;
  h.unit = a.has_spacing ? "mm" : "";
  h.source = a.bits_allocated == 8 ? SourceType::U8 : SourceType::I16;  // re-checked once the values are known
  Box box{{0, 0, 0}, h.dims};
  if (options.region) {
    box = {options.region->lo, options.region->hi};
    for (int ax = 0; ax < 3; ++ax)
      if (box.lo[ax] < 0 || box.hi[ax] > h.dims[ax] || box.lo[ax] >= box.hi[ax])
        throw VolumeError(dir, "region on axis " + std::to_string(ax) + " is not inside the series' " +
                                   std::to_string(h.dims[ax]) + " voxels");
  }
  VolumeHeader rh = h;
  for (int ax = 0; ax < 3; ++ax) {
    rh.dims[ax] = box.hi[ax] - box.lo[ax];
    rh.origin[ax] = h.origin[ax] + double(box.lo[ax]) * h.spacing[ax];
  }
  LoadOptions local = options;
  local.region.reset();
  detail::check_header(dir, rh, local);
  const int64_t per = box.nx() * box.ny();
  Stored st;
  if (a.bits_allocated == 8)
    st.bytes = allocate_voxels<uint8_t>(size_t(per * box.nz()));
  else
    st.values = allocate_voxels<int16_t>(size_t(per * box.nz()));
  std::vector<const SliceHeader*> in_box;
  detail::LoadProgress progress(options, size_t(per * box.nz()));
  for (int64_t k = box.lo[2]; k < box.hi[2]; ++k) {
    const SliceHeader& s = slices[g.order[size_t(k)]];
    if (s.bits_allocated != a.bits_allocated)
      throw VolumeError(dir, name(s) + " and " + name(a) + " have different bits a pixel");
    in_box.push_back(&s);
    st.lo.push_back(0);
    st.hi.push_back(0);
    const size_t at = size_t((k - box.lo[2]) * per);
    decode_slice(dir, s, box, st.lo.back(), st.hi.back(), st.values.get() ? st.values.get() + at : nullptr,
                 st.bytes.get() ? st.bytes.get() + at : nullptr);
    progress.add(size_t(per));
  }
  const Kept k = kept_type(in_box, st);
  rh.source = k.type;
  if (k.type != h.source) detail::check_header(dir, rh, local);
  Volume v(rh);
  switch (k.type) {
    case SourceType::U8: fill<uint8_t>(v, in_box, st, k, per); break;
    case SourceType::I16: fill<int16_t>(v, in_box, st, k, per); break;
    case SourceType::U16: fill<uint16_t>(v, in_box, st, k, per); break;
    default: fill<float>(v, in_box, st, k, per); break;
  }
  st = {};
  detail::finish_volume(dir, v, std::endian::native == std::endian::big, local);
  if (options.region) {
    v.source_dims = h.dims;
    v.region_lo = box.lo;
  }
  progress.done();
  return v;
}

}  // namespace peakcast::dicom
