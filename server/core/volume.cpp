#include "core/volume.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "core/parallel.h"
#include "core/value_counts.h"

namespace peakcast {

const char* to_string(VoxelType t) {
  switch (t) {
    case VoxelType::U8: return "uint8";
    case VoxelType::U16: return "uint16";
    case VoxelType::F32: return "float32";
  }
  return "?";
}

const char* to_string(SourceType t) {
  switch (t) {
    case SourceType::U8: return "uint8";
    case SourceType::I8: return "int8";
    case SourceType::U16: return "uint16";
    case SourceType::I16: return "int16";
    case SourceType::F32: return "float32";
  }
  return "?";
}

size_t voxel_bytes(VoxelType t) { return t == VoxelType::U8 ? 1 : t == VoxelType::U16 ? 2 : 4; }

size_t source_bytes(SourceType t) { return voxel_bytes(storage_type(t)); }

VoxelType storage_type(SourceType t) {
  switch (t) {
    case SourceType::U8:
    case SourceType::I8: return VoxelType::U8;
    case SourceType::U16:
    case SourceType::I16: return VoxelType::U16;
    case SourceType::F32: return VoxelType::F32;
  }
  return VoxelType::U8;
}

double storage_offset(SourceType t) { return t == SourceType::I8 ? -128.0 : t == SourceType::I16 ? -32768.0 : 0.0; }

SourceType parse_source_type(const std::string& raw) {
  std::string n;
  for (char c : raw) n += char(std::tolower(static_cast<unsigned char>(c)));
  // NRRD spellings (spec: "Basic type names"), MetaImage MET_* and the short forms.
  if (n == "uint8" || n == "uchar" || n == "unsigned char" || n == "uint8_t" || n == "met_uchar") return SourceType::U8;
  if (n == "int8" || n == "signed char" || n == "int8_t" || n == "met_char") return SourceType::I8;
  if (n == "uint16" || n == "ushort" || n == "unsigned short" || n == "unsigned short int" || n == "uint16_t" ||
      n == "met_ushort")
    return SourceType::U16;
  if (n == "int16" || n == "short" || n == "short int" || n == "signed short" || n == "signed short int" ||
      n == "int16_t" || n == "met_short")
    return SourceType::I16;
  if (n == "float32" || n == "float" || n == "met_float") return SourceType::F32;
  throw std::invalid_argument("unsupported voxel type '" + raw + "' (supported: uint8, int8, uint16, int16, float32)");
}

Volume::Volume(const VolumeHeader& h)
    : spacing(h.spacing),
      origin(h.origin),
      value_offset(storage_offset(h.source)),
      unit(h.unit),
      value_unit(h.value_unit),
      time_point(h.time_point),
      time_points(h.time_points),
      dims_(h.dims),
      type_(storage_type(h.source)),
      source_(h.source),
      data_(allocate_voxels<uint8_t>(size_t(h.voxel_count()) * voxel_bytes(storage_type(h.source)) + kTailPadding)) {
  std::fill_n(data_.get() + byte_size(), kTailPadding, uint8_t(0));
}

Volume Volume::header_only(const VolumeHeader& h) {
  Volume v;
  v.spacing = h.spacing;
  v.origin = h.origin;
  v.value_offset = storage_offset(h.source);
  v.unit = h.unit;
  v.value_unit = h.value_unit;
  v.time_point = h.time_point;
  v.time_points = h.time_points;
  v.dims_ = h.dims;
  v.type_ = storage_type(h.source);
  v.source_ = h.source;
  return v;
}

namespace {

// The bin of a stored value (finalize_statistics, box_histogram): scale = bins / (hi - lo).
inline int histogram_bin(double stored, double lo, double scale, int bins) {
  return std::clamp(int((stored - lo) * scale), 0, bins - 1);
}

// Integer voxels: one pass counting every stored value (256 or 65536 bins per worker), from
// which the range and the 1024-bin histogram follow exactly (the same bins as two passes over
// the voxels would give). Float voxels keep the two passes (no finite set of values).
template <typename T>
void integer_statistics(const T* data, size_t n, double& lo_out, double& hi_out, std::vector<uint64_t>& histogram,
                        int bins) {
  constexpr size_t kValues = size_t(1) << (8 * sizeof(T));
  std::vector<std::vector<uint64_t>> counts{static_cast<size_t>(hardware_threads())};
  parallel_chunks(n, [&](size_t begin, size_t end, int worker) {
    auto& c = counts[size_t(worker)];
    if (c.empty()) c.assign(kValues, 0);
    for (size_t i = begin; i < end; ++i) ++c[data[i]];
  });
  std::vector<uint64_t> all(kValues, 0);
  for (const auto& c : counts)
    if (!c.empty())
      for (size_t v = 0; v < kValues; ++v) all[v] += c[v];
  size_t lo = 0, hi = kValues - 1;
  while (lo < kValues && all[lo] == 0) ++lo;
  while (hi > lo && all[hi] == 0) --hi;
  if (lo == kValues) lo = hi = 0;  // no voxels
  lo_out = double(lo);
  hi_out = double(hi);
  histogram.assign(size_t(bins), 0);
  const double span = double(hi) - double(lo);
  const double scale = span > 0 ? bins / span : 0.0;
  for (size_t v = lo; v <= hi && lo < kValues; ++v)
    if (all[v]) histogram[size_t(histogram_bin(double(v), double(lo), scale, bins))] += all[v];
}

}  // namespace

void Volume::finalize_statistics() {
  const auto t0 = std::chrono::steady_clock::now();
  struct Timer {  // statistics_ms on every path out
    Volume& v;
    std::chrono::steady_clock::time_point t0;
    ~Timer() {
      v.statistics_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    }
  } timer{*this, t0};
  const size_t n = size_t(voxel_count());
  if (type_ != VoxelType::F32) {
    double lo = 0, hi = 0;
    if (type_ == VoxelType::U8)
      integer_statistics(data_.get(), n, lo, hi, histogram, kHistogramBins);
    else
      integer_statistics(reinterpret_cast<const uint16_t*>(data_.get()), n, lo, hi, histogram, kHistogramBins);
    min_value = lo + value_offset;
    max_value = hi + value_offset;
    border_histogram = whole_border_histogram(lo, hi);
    return;
  }
  struct Partial {
    double lo = std::numeric_limits<double>::infinity();
    double hi = -std::numeric_limits<double>::infinity();
  };
  std::vector<Partial> parts(hardware_threads());
  parallel_chunks(n, [&](size_t begin, size_t end, int worker) {
    Partial p;
    for (size_t i = begin; i < end; ++i) {
      double v = stored(i);
      p.lo = std::min(p.lo, v);
      p.hi = std::max(p.hi, v);
    }
    parts[worker].lo = std::min(parts[worker].lo, p.lo);
    parts[worker].hi = std::max(parts[worker].hi, p.hi);
  });
  Partial all;
  for (auto& p : parts) {
    all.lo = std::min(all.lo, p.lo);
    all.hi = std::max(all.hi, p.hi);
  }
  if (n == 0) all.lo = all.hi = 0.0;
  min_value = all.lo + value_offset;
  max_value = all.hi + value_offset;

  std::vector<std::vector<uint64_t>> hist(parts.size(), std::vector<uint64_t>(kHistogramBins, 0));
  const double lo = all.lo, span = all.hi - all.lo;
  const double scale = span > 0 ? kHistogramBins / span : 0.0;
  parallel_chunks(n, [&](size_t begin, size_t end, int worker) {
    auto& h = hist[worker];
    for (size_t i = begin; i < end; ++i) h[size_t(histogram_bin(stored(i), lo, scale, kHistogramBins))]++;
  });
  histogram.assign(kHistogramBins, 0);
  for (auto& h : hist)
    for (int b = 0; b < kHistogramBins; ++b) histogram[b] += h[b];
  border_histogram = whole_border_histogram(all.lo, all.hi);
}

std::vector<uint64_t> Volume::whole_border_histogram(double stored_lo, double stored_hi) const {
  if (voxel_count() == 0) return {};
  return box_border_histogram({0, 0, 0}, dims_, {0, 0, 0}, {dims_[0] - 1, dims_[1] - 1, dims_[2] - 1}, stored_lo,
                              stored_hi);
}

std::vector<uint64_t> Volume::box_value_counts(const Dims& lo, const Dims& hi) const {
  for (int a = 0; a < 3; ++a)
    if (lo[a] < 0 || hi[a] > dims_[a] || lo[a] > hi[a])
      throw std::invalid_argument("box_value_counts: box outside the volume");
  if (!has_voxels()) throw std::logic_error("box_value_counts: the voxels were dropped");
  if (type_ == VoxelType::F32) throw std::logic_error("box_value_counts: float voxels have no finite set of values");
  const size_t values = type_ == VoxelType::U8 ? 256 : 65536;
  const size_t tables = size_t(value_count_tables(type_)), planes = size_t(hi[2] - lo[2]);
  const size_t per = (planes + tables - 1) / tables;
  std::vector<std::vector<uint64_t>> parts(tables);
  parallel_for(
      tables,
      [&](size_t worker) {  // contiguous planes per table
        const size_t begin = std::min(planes, worker * per), end = std::min(planes, begin + per);
        auto& c = parts[worker];
        c.assign(values, 0);
        for (int64_t k = lo[2] + int64_t(begin); k < lo[2] + int64_t(end); ++k)
          for (int64_t j = lo[1]; j < hi[1]; ++j) {
            const size_t row = size_t(dims_[0] * (j + dims_[1] * k));
            if (type_ == VoxelType::U8)
              for (int64_t i = lo[0]; i < hi[0]; ++i) ++c[data_[row + size_t(i)]];
            else
              for (int64_t i = lo[0]; i < hi[0]; ++i)
                ++c[reinterpret_cast<const uint16_t*>(data_.get())[row + size_t(i)]];
          }
      },
      int(tables));
  std::vector<uint64_t> all(values, 0);
  for (const auto& c : parts)
    for (size_t v = 0; v < c.size(); ++v) all[v] += c[v];
  return all;
}

std::vector<uint64_t> Volume::histogram_of_counts(const std::vector<uint64_t>& counts, double stored_lo,
                                                  double stored_hi) {
  const double span = stored_hi - stored_lo;
  const double scale = span > 0 ? kHistogramBins / span : 0.0;
  std::vector<uint64_t> h(kHistogramBins, 0);
  for (size_t v = 0; v < counts.size(); ++v)
    if (counts[v]) h[size_t(histogram_bin(double(v), stored_lo, scale, kHistogramBins))] += counts[v];
  return h;
}

std::vector<uint64_t> Volume::box_histogram(const Dims& lo, const Dims& hi, double stored_lo, double stored_hi) const {
  for (int a = 0; a < 3; ++a)
    if (lo[a] < 0 || hi[a] > dims_[a] || lo[a] > hi[a])
      throw std::invalid_argument("box_histogram: box outside the volume");
  if (!has_voxels()) throw std::logic_error("box_histogram: the voxels were dropped");
  const double span = stored_hi - stored_lo;
  const double scale = span > 0 ? kHistogramBins / span : 0.0;
  std::vector<std::vector<uint64_t>> parts(size_t(hardware_threads()), std::vector<uint64_t>(kHistogramBins, 0));
  parallel_chunks(size_t(hi[2] - lo[2]), [&](size_t begin, size_t end, int worker) {
    auto& h = parts[size_t(worker)];
    for (int64_t k = lo[2] + int64_t(begin); k < lo[2] + int64_t(end); ++k)
      for (int64_t j = lo[1]; j < hi[1]; ++j) {
        const size_t row = size_t(dims_[0] * (j + dims_[1] * k));
        for (int64_t i = lo[0]; i < hi[0]; ++i)
          h[size_t(histogram_bin(stored(row + size_t(i)), stored_lo, scale, kHistogramBins))]++;
      }
  });
  std::vector<uint64_t> h(kHistogramBins, 0);
  for (const auto& p : parts)
    for (int b = 0; b < kHistogramBins; ++b) h[size_t(b)] += p[size_t(b)];
  return h;
}

void Volume::for_each_border_voxel(const Dims& lo, const Dims& hi, const Dims& face_lo, const Dims& face_hi,
                                   const std::function<void(double)>& count) const {
  for (int a = 0; a < 3; ++a)
    if (lo[a] < 0 || hi[a] > dims_[a] || lo[a] > hi[a])
      throw std::invalid_argument("for_each_border_voxel: box outside the volume");
  if (!has_voxels()) throw std::logic_error("for_each_border_voxel: the voxels were dropped");
  const auto on_x = [&](int64_t i) { return i >= lo[0] && i < hi[0]; };
  for (int64_t k = lo[2]; k < hi[2]; ++k)
    for (int64_t j = lo[1]; j < hi[1]; ++j) {
      const size_t row = size_t(dims_[0] * (j + dims_[1] * k));
      if (k == face_lo[2] || k == face_hi[2] || j == face_lo[1] || j == face_hi[1]) {
        for (int64_t i = lo[0]; i < hi[0]; ++i) count(stored(row + size_t(i)));
        continue;
      }
      if (on_x(face_lo[0])) count(stored(row + size_t(face_lo[0])));
      if (face_hi[0] != face_lo[0] && on_x(face_hi[0])) count(stored(row + size_t(face_hi[0])));
    }
}

std::vector<uint64_t> Volume::box_border_histogram(const Dims& lo, const Dims& hi, const Dims& face_lo,
                                                   const Dims& face_hi, double stored_lo, double stored_hi) const {
  const double span = stored_hi - stored_lo;
  const double scale = span > 0 ? kHistogramBins / span : 0.0;
  std::vector<uint64_t> h(kHistogramBins, 0);
  for_each_border_voxel(lo, hi, face_lo, face_hi,
                        [&](double v) { h[size_t(histogram_bin(v, stored_lo, scale, kHistogramBins))]++; });
  return h;
}

std::string Volume::to_string() const {
  std::ostringstream s;
  s << "Volume{" << (name.empty() ? "" : name + " ") << dims_[0] << "x" << dims_[1] << "x" << dims_[2] << " "
    << peakcast::to_string(source_) << " spacing (" << spacing.x << "," << spacing.y << "," << spacing.z << ") origin ("
    << origin.x << "," << origin.y << "," << origin.z << ") range [" << min_value << "," << max_value << "]}";
  return s.str();
}

}  // namespace peakcast
