#include "core/volume_io.h"
#include "core/file_roots.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <memory>

#include "chunked/chunked_volume.h"
#include "core/dicom.h"
#include "core/parallel.h"
#include "core/volume_io_detail.h"

namespace fs = std::filesystem;

namespace peakcast {
namespace {

// A float volume's finite extremes (lo > hi when none is finite) and its non-finite voxels.
struct FiniteScan {
  float lo = std::numeric_limits<float>::infinity(), hi = -std::numeric_limits<float>::infinity();
  int64_t nonfinite = 0;
};
FiniteScan scan_finite(const Volume& v) {
  FiniteScan s;
  const auto* p = reinterpret_cast<const float*>(v.data());
  for (size_t i = 0, n = size_t(v.voxel_count()); i < n; ++i) {
    if (std::isfinite(p[i])) {
      s.lo = std::min(s.lo, p[i]);
      s.hi = std::max(s.hi, p[i]);
    } else {
      ++s.nonfinite;
    }
  }
  return s;
}

}  // namespace

namespace detail {

std::string trim(const std::string& s) {
  size_t b = s.find_first_not_of(" \t\r\n"), e = s.find_last_not_of(" \t\r\n");
  return b == std::string::npos ? std::string() : s.substr(b, e - b + 1);
}

std::string lower(std::string s) {
  for (auto& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::vector<std::string> split_ws(const std::string& s) {
  std::vector<std::string> out;
  size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && std::isspace(static_cast<unsigned char>(s[i]))) ++i;
    size_t j = i;
    while (j < s.size() && !std::isspace(static_cast<unsigned char>(s[j]))) ++j;
    if (j > i) out.push_back(s.substr(i, j - i));
    i = j;
  }
  return out;
}

double parse_double(const fs::path& file, const std::string& field, const std::string& text) {
  try {
    size_t used = 0;
    double v = std::stod(text, &used);
    if (used != text.size() || !std::isfinite(v)) throw std::invalid_argument("");
    return v;
  } catch (const std::exception&) {
    throw VolumeError(file, "field '" + field + "': '" + text + "' is not a finite number");
  }
}

int64_t parse_int(const fs::path& file, const std::string& field, const std::string& text) {
  try {
    size_t used = 0;
    long long v = std::stoll(text, &used);
    if (used != text.size()) throw std::invalid_argument("");
    return v;
  } catch (const std::exception&) {
    throw VolumeError(file, "field '" + field + "': '" + text + "' is not an integer");
  }
}

void check_header(const fs::path& file, const VolumeHeader& h, const LoadOptions& options) {
  int64_t count = 1;
  for (int a = 0; a < 3; ++a) {
    if (h.dims[a] <= 0)
      throw VolumeError(
          file, "dimension " + std::to_string(a) + " is " + std::to_string(h.dims[a]) + "; every size must be >= 1");
    if (__builtin_mul_overflow(count, h.dims[a], &count)) throw VolumeError(file, "sizes overflow 64-bit voxel count");
  }
  int64_t bytes = 0;
  if (__builtin_mul_overflow(count, int64_t(source_bytes(h.source)), &bytes))
    throw VolumeError(file, "sizes overflow 64-bit byte count");
  if (count > options.max_voxels && !options.region)  // a region is checked by its own size
    throw VolumeError(file, std::to_string(h.dims[0]) + "x" + std::to_string(h.dims[1]) + "x" +
                                std::to_string(h.dims[2]) + " = " + std::to_string(count) +
                                " voxels exceeds the limit of " + std::to_string(options.max_voxels));
  for (int a = 0; a < 3; ++a)
    if (!(h.spacing[a] > 0) || !std::isfinite(h.spacing[a])) throw VolumeError(file, "spacing must be finite and > 0");
  if (const std::string why = spacing_refusal(h.spacing, h.origin); !why.empty()) throw VolumeError(file, why);
  const int64_t voxel_mem = count * int64_t(voxel_bytes(storage_type(h.source)));
  if (options.memory_budget_bytes > 0 && !options.region && voxel_mem > options.memory_budget_bytes)
    throw VolumeError(file, std::to_string(voxel_mem >> 20) + " MiB of voxels exceeds the memory budget of " +
                                std::to_string(options.memory_budget_bytes >> 20) +
                                " MiB; a pyramid opens at a level that fits (peakcast convert IN OUT.zarr --pyramid)");
  if (options.on_header) options.on_header(h);
}

namespace {

template <typename T>
void byteswap_all(uint8_t* data, size_t count) {
  for (size_t i = 0; i < count; ++i) {
    uint8_t* p = data + i * sizeof(T);
    std::reverse(p, p + sizeof(T));
  }
}

}  // namespace

void finish_volume(const fs::path& file, Volume& v, bool big_endian, const LoadOptions& options) {
  const size_t n = size_t(v.voxel_count());
  const bool host_big = (std::endian::native == std::endian::big);
  if (big_endian != host_big) {
    if (v.type() == VoxelType::U16) byteswap_all<uint16_t>(v.data(), n);
    if (v.type() == VoxelType::F32) byteswap_all<float>(v.data(), n);
  }
  if (v.source_type() == SourceType::I8)
    for (size_t i = 0; i < n; ++i) v.data()[i] ^= 0x80;  // int8 + 128 as uint8
  if (v.source_type() == SourceType::I16) {
    auto* p = reinterpret_cast<uint16_t*>(v.data());
    for (size_t i = 0; i < n; ++i) p[i] ^= 0x8000;  // int16 + 32768 as uint16
  }
  if (v.type() == VoxelType::F32) {
    const FiniteScan f = scan_finite(v);
    if (f.nonfinite > 0) {
      switch (options.nonfinite) {
        case NonFinitePolicy::Refuse:
          throw VolumeError(file, std::to_string(f.nonfinite) + " NaN/Inf voxels (policy: refuse)");
        case NonFinitePolicy::Keep:  // the caller replaces them (replace_nonfinite computes the
          return;                    // statistics): none over NaN (its histogram bin is undefined)
        case NonFinitePolicy::Replace:
          replace_nonfinite(v, f.lo <= f.hi ? f.lo : 0.f, f.lo <= f.hi ? f.hi : 0.f);  // nothing finite: 0
          return;                                                                      // statistics done
      }
    }
  }
  if (options.statistics) v.finalize_statistics();
}

// The data files a header names, checked before any of them is looked at: one file only where
// options.single_file says so (an upload: never a word on whether another path exists), and
// every file inside the server's roots (core/file_roots.h; a link out is refused).
void check_payload_files(const fs::path& header_file, const PayloadSpec& payload, const LoadOptions& options) {
  if (payload.files.empty()) throw VolumeError(header_file, "no data file");
  if (options.single_file) {
    const fs::path self = header_file.lexically_normal();
    for (const fs::path& f : payload.files) {
      const fs::path n = f.lexically_normal();
      const bool beside = n.parent_path() == self.parent_path() && n.stem() == self.stem();  // id.json -> id.raw
      if (n != self && !beside)
        throw VolumeError(header_file,
                          "its header names another data file: an upload is one file "
                          "(send the voxels attached: .nrrd, .mha with ElementDataFile = LOCAL)");
    }
  }
  for (const fs::path& f : payload.files) file_roots::check(f);
}

Volume read_payload(const fs::path& header_file, const VolumeHeader& h, const PayloadSpec& payload,
                    const LoadOptions& options) {
  check_payload_files(header_file, payload, options);
  check_header(header_file, h, options);
  const size_t total = size_t(h.voxel_count()) * source_bytes(h.source);
  // Raw data: refuse a short file before allocating anything (parts: checked when resolved).
  if (payload.encoding == Encoding::Raw && payload.parts.empty()) {
    int64_t available = 0;
    for (size_t i = 0; i < payload.files.size(); ++i) {
      std::error_code ec;
      if (!fs::is_regular_file(payload.files[i], ec))
        throw VolumeError(payload.files[i], "no such file (data of " + header_file.filename().string() + ")");
      int64_t size = int64_t(fs::file_size(payload.files[i], ec));
      if (i == 0 && payload.byte_skip > 0) size -= payload.byte_skip;
      available += std::max<int64_t>(size, 0);
    }
    if (available < int64_t(total))
      throw VolumeError(payload.files.back(), "truncated: header " + header_file.filename().string() + " promises " +
                                                  std::to_string(total) + " data bytes, the data holds " +
                                                  std::to_string(available));
  }
  LoadProgress progress(options, total);
  if (options.region) {  // raw: checked above
    Volume v = read_payload_region(header_file, h, payload, options);
    progress.done();
    return v;
  }
  Volume v(h);
  if (!payload.parts.empty()) {
    read_parts(payload, v.data(), total, progress);
    finish_volume(header_file, v, h.big_endian, options);
    progress.done();
    return v;
  }
  size_t got = 0;
  for (size_t i = 0; i < payload.files.size() && got < total; ++i) {
    const bool last = (i + 1 == payload.files.size());
    const int64_t skip = (i == 0) ? payload.byte_skip : 0;
    size_t want = total - got;
    if (payload.encoding == Encoding::Raw) {
      std::error_code ec;
      int64_t fsize = int64_t(fs::file_size(payload.files[i], ec)) - std::max<int64_t>(skip, 0);
      if (!last) want = std::min<size_t>(want, size_t(std::max<int64_t>(fsize, 0)));
      got += read_raw(payload.files[i], skip, v.data() + got, want, last, progress);
    } else {
      got += read_compressed(payload.files[i], skip, payload.encoding, v.data() + got, want, progress);
    }
  }
  if (got < total)
    throw VolumeError(payload.files.back(),
                      "truncated: expected " + std::to_string(total) + " data bytes, got " + std::to_string(got));
  finish_volume(header_file, v, h.big_endian, options);
  progress.done();
  return v;
}

}  // namespace detail

namespace {

// The one volume header of a folder of slices it describes (headsq/quarter.nhdr); none when the
// folder holds TIFF slices (the stack) or no header; several are refused.
std::optional<fs::path> folder_header(const fs::path& path) {
  std::error_code ec;
  std::vector<fs::path> headers;
  bool tiffs = false;
  for (const auto& e : fs::directory_iterator(path, ec)) {
    const std::string x = detail::lower(e.path().extension().string());
    tiffs |= x == ".tif" || x == ".tiff";
    if (x == ".nhdr" || x == ".nrrd" || x == ".mhd" || x == ".mha") headers.push_back(e.path());
  }
  if (tiffs || headers.empty()) return std::nullopt;
  if (headers.size() > 1)
    throw VolumeError(path, "a folder with " + std::to_string(headers.size()) + " volume headers: open one of them (" +
                                headers[0].filename().string() + ", ...)");
  return headers[0];
}

Volume read_chunked(const fs::path& path, const LoadOptions& options) {
  const auto cv = chunked::open_chunked(path, {options.time_point, options.channel});
  const int level = options.memory_budget_bytes > 0 && !options.region
                        ? chunked::finest_level_within(*cv, options.level, options.memory_budget_bytes)
                        : options.level;
  Volume v = chunked::read_level(*cv, level, options);
  v.pyramid_level = level;
  v.pyramid_levels = int(cv->levels().size());
  v.full_dims = cv->levels()[0].dims;
  if (level > 0) v.full_spacing = cv->levels()[0].spacing;
  return v;
}

Volume read_by_format(const fs::path& path, const LoadOptions& options) {
  using namespace detail;
  std::error_code ec;
  const std::string ext = lower(path.extension().string());
  if (!dicom::split_series_path(path).series.empty()) return dicom::read_series(path, options);
  if (chunked::is_chunked_volume(path)) return read_chunked(path, options);
  // A folder named .dcm (an uploaded ZIP's slices) is a series whatever it holds: refused as one.
  if (fs::is_directory(path, ec) && (ext == ".dcm" || dicom::is_dicom_folder(path)))
    return dicom::read_series(path, options);
  if (fs::is_directory(path, ec) || ext == ".tif" || ext == ".tiff") {
    if (options.region)
      throw RegionNotReadable(path, "a region of a TIFF stack cannot be read (use NRRD, MetaImage or raw)");
    return read_tiff(path, options);
  }
  if (ext == ".nrrd" || ext == ".nhdr") return read_nrrd(path, options);
  if (ext == ".mhd" || ext == ".mha") return read_metaimage(path, options);
  if (ext == ".json" || ext == ".raw" || ext == ".gz") return read_raw_json(path, options);
  throw VolumeError(path, "unknown volume format '" + ext +
                              "' (expected .nrrd .nhdr .mhd .mha .raw+.json .tif, a directory of TIFF slices, "
                              "a folder of DICOM slices, an OME-Zarr or a Neuroglancer precomputed folder)");
}

}  // namespace

Volume load_volume(const fs::path& path, const LoadOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  std::error_code ec;
  file_roots::check(path);
  if (!fs::exists(dicom::split_series_path(path).folder, ec)) throw VolumeError(path, "no such file");
  if (fs::is_directory(path, ec) && path.extension() != ".dcm" && !chunked::is_chunked_volume(path) &&
      !dicom::is_dicom_folder(path))
    if (const auto header = folder_header(path)) {
      Volume h = load_volume(*header, options);
      h.name = path.filename().string();
      return h;
    }
  Volume v = read_by_format(path, options);
  const fs::path named = dicom::split_series_path(path).folder;  // a series: its folder's name
  v.name = (named.filename().empty() ? named.parent_path() : named).filename().string();
  v.source_path = path.string();
  v.load_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return v;
}

std::pair<float, float> finite_extremes(const Volume& v) {
  if (v.type() != VoxelType::F32) return {float(v.min_value), float(v.max_value)};
  const FiniteScan f = scan_finite(v);
  return {f.lo, f.hi};
}

int64_t count_nonfinite(const Volume& v, const Dims& lo, const Dims& hi) {
  if (v.type() != VoxelType::F32) return 0;
  const auto* p = reinterpret_cast<const float*>(v.data());
  int64_t n = 0;
  for (int64_t k = lo[2]; k < hi[2]; ++k)
    for (int64_t j = lo[1]; j < hi[1]; ++j) {
      const float* row = p + v.dims()[0] * (j + v.dims()[1] * k);
      for (int64_t i = lo[0]; i < hi[0]; ++i) n += !std::isfinite(row[i]);
    }
  return n;
}

void replace_nonfinite(Volume& v, float lo, float hi) {
  if (v.type() != VoxelType::F32) return;
  auto* p = reinterpret_cast<float*>(v.data());
  int64_t bad = 0;
  for (size_t i = 0, n = size_t(v.voxel_count()); i < n; ++i)
    if (!std::isfinite(p[i])) {
      p[i] = (p[i] > 0) ? hi : lo;  // NaN compares false: lo
      ++bad;
    }
  if (bad == 0) return;  // the statistics stand
  v.nonfinite_replaced += bad;
  v.finalize_statistics();
}

}  // namespace peakcast
