// TIFF stacks through OpenImageIO: a multi-page TIFF (one page per z slice) or a directory of
// numbered 2D TIFFs (sorted by the number in the name, so slice_2 comes before slice_10).
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <regex>

#include "core/file_roots.h"
#include "core/length_unit.h"
#include "core/volume_io_detail.h"

namespace fs = std::filesystem;
OIIO_NAMESPACE_USING

namespace peakcast::detail {
namespace {

SourceType source_from(const fs::path& file, TypeDesc t) {
  if (t == TypeDesc::UINT8) return SourceType::U8;
  if (t == TypeDesc::INT8) return SourceType::I8;
  if (t == TypeDesc::UINT16) return SourceType::U16;
  if (t == TypeDesc::INT16) return SourceType::I16;
  if (t == TypeDesc::FLOAT) return SourceType::F32;
  throw VolumeError(file, std::string("unsupported TIFF sample type ") + t.c_str());
}

// Natural order: compares embedded numbers by value.
bool natural_less(const std::string& a, const std::string& b) {
  size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    if (std::isdigit(static_cast<unsigned char>(a[i])) && std::isdigit(static_cast<unsigned char>(b[j]))) {
      size_t i2 = i, j2 = j;
      while (i2 < a.size() && std::isdigit(static_cast<unsigned char>(a[i2]))) ++i2;
      while (j2 < b.size() && std::isdigit(static_cast<unsigned char>(b[j2]))) ++j2;
      std::string na = a.substr(i, i2 - i), nb = b.substr(j, j2 - j);
      na.erase(0, std::min(na.find_first_not_of('0'), na.size()));
      nb.erase(0, std::min(nb.find_first_not_of('0'), nb.size()));
      if (na.size() != nb.size()) return na.size() < nb.size();
      if (na != nb) return na < nb;
      i = i2;
      j = j2;
    } else {
      if (a[i] != b[j]) return a[i] < b[j];
      ++i;
      ++j;
    }
  }
  return a.size() - i < b.size() - j;
}

std::unique_ptr<ImageInput> open_image(const fs::path& file) {
  file_roots::check(file);  // a slice linked out of the data directories
  auto in = ImageInput::open(file.string());
  if (!in) throw VolumeError(file, "cannot read TIFF: " + OIIO::geterror());
  return in;
}

// A field of ImageJ's ImageDescription ("ImageJ=1.54f\nimages=60\nchannels=2\nslices=10\n..."),
// "" when absent or when the description is not ImageJ's.
std::string imagej_field(const std::string& d, const std::string& key) {
  if (d.rfind("ImageJ=", 0) != 0) return "";
  const size_t at = d.find("\n" + key + "=");
  if (at == std::string::npos) return "";
  const size_t b = at + key.size() + 2, e = d.find('\n', b);
  return d.substr(b, e == std::string::npos ? std::string::npos : e - b);
}

double positive_number(const std::string& text) {
  char* end = nullptr;
  const double v = text.empty() ? 0.0 : std::strtod(text.c_str(), &end);
  return v > 0 && std::isfinite(v) && end && *end == '\0' ? v : 0.0;
}

// ImageJ's geometry (its ImageDescription's unit= and spacing=, and the resolution tags in pixels
// per unit): spacing and unit. Other TIFFs' resolution (72 dpi by default in most writers) says
// nothing of the voxels and is not read.
void imagej_geometry(const fs::path& file, const ImageSpec& spec, VolumeHeader& h) {
  const std::string d = spec.get_string_attribute("ImageDescription");
  if (d.rfind("ImageJ=", 0) != 0) return;
  std::string unit = imagej_field(d, "unit");
  if (const size_t u = unit.find("\\u00B5"); u != std::string::npos) unit.replace(u, 6, "µ");  // "\u00B5m"
  try {
    h.unit = length_symbol(unit, "ImageJ unit");
  } catch (const std::invalid_argument& e) {
    throw VolumeError(file, e.what());
  }
  const float xr = spec.get_float_attribute("XResolution", 0.f), yr = spec.get_float_attribute("YResolution", 0.f);
  if (xr > 0 && std::isfinite(1.0 / xr)) h.spacing.x = 1.0 / xr;
  if (yr > 0 && std::isfinite(1.0 / yr)) h.spacing.y = 1.0 / yr;
  if (const double dz = positive_number(imagej_field(d, "spacing")); dz > 0) h.spacing.z = dz;
}

// An ImageJ hyperstack's pages, channels fastest, then slices, then frames (ImageJ's czt order):
// which page holds slice z of the time point and channel read.
struct Hyperstack {
  int64_t channels = 1, slices = 0, frames = 1;
  int64_t time = 0, channel = 0;
  int64_t page(int64_t z) const { return channel + channels * (z + slices * time); }
};

// A multi-page TIFF's pages as a hyperstack: ImageJ's channels= slices= frames= when it says them
// (checked against the pages), else every page a slice. Refuses a time point or channel not there.
Hyperstack hyperstack_of(const fs::path& file, const ImageSpec& spec, int64_t pages, const LoadOptions& options) {
  const std::string d = spec.get_string_attribute("ImageDescription");
  Hyperstack s;
  const double c = positive_number(imagej_field(d, "channels")), f = positive_number(imagej_field(d, "frames"));
  s.channels = c >= 1 && c == std::floor(c) ? int64_t(c) : 1;
  s.frames = f >= 1 && f == std::floor(f) ? int64_t(f) : 1;
  s.slices = pages / (s.channels * s.frames);
  if (s.slices * s.channels * s.frames != pages || s.slices < 1)
    throw VolumeError(file, "ImageJ says " + std::to_string(s.channels) + " channels x " + std::to_string(s.frames) +
                                " frames, which does not divide its " + std::to_string(pages) + " pages");
  s.time = options.time_point;
  s.channel = options.channel;
  if (s.time < 0 || s.time >= s.frames)
    throw VolumeError(file, "time point " + std::to_string(s.time) + " is outside 0.." + std::to_string(s.frames - 1));
  if (s.channel < 0 || s.channel >= s.channels)
    throw VolumeError(file,
                      "channel " + std::to_string(s.channel) + " is outside 0.." + std::to_string(s.channels - 1));
  return s;
}

void check_slice(const fs::path& file, const ImageSpec& spec, const VolumeHeader& h) {
  if (spec.nchannels != 1)
    throw VolumeError(file, "TIFF slice has " + std::to_string(spec.nchannels) + " channels; need 1");
  if (spec.width != h.dims[0] || spec.height != h.dims[1] || spec.depth != 1)
    throw VolumeError(file, "TIFF slice is " + std::to_string(spec.width) + "x" + std::to_string(spec.height) +
                                ", the first was " + std::to_string(h.dims[0]) + "x" + std::to_string(h.dims[1]));
  if (source_from(file, spec.format) != h.source) throw VolumeError(file, "TIFF slices differ in sample type");
  // OIIO 2.4 reads a strip-compressed TIFF a strip at a time into a buffer of RowsPerStrip
  // scanlines, without clamping RowsPerStrip to the height: a damaged directory claiming
  // 1229520900 rows made it allocate 4.9 GB for a 4x4 image (found by fuzz_tiff). RowsPerStrip
  // may legally exceed the height (2^32-1 means "one strip"), so only a buffer past the image
  // itself plus 1 MiB is refused.
  const int64_t rps = int64_t(uint32_t(spec.get_int_attribute("tiff:RowsPerStrip", 0)));
  if (rps > spec.height && rps != 0xFFFFFFFFLL &&
      rps * int64_t(spec.scanline_bytes(true)) > int64_t(spec.image_bytes(true)) + (int64_t(1) << 20))
    throw VolumeError(file, "TIFF RowsPerStrip " + std::to_string(rps) + " far exceeds the image height " +
                                std::to_string(spec.height) + " (a damaged directory)");
}

void read_slice(const fs::path& file, ImageInput& in, int subimage, const VolumeHeader& h, uint8_t* dst) {
  static const TypeDesc formats[] = {TypeDesc::UINT8, TypeDesc::INT8, TypeDesc::UINT16, TypeDesc::INT16,
                                     TypeDesc::FLOAT};
  if (!in.read_image(subimage, 0, 0, 1, formats[int(h.source)], dst))
    throw VolumeError(file, "cannot read TIFF data: " + in.geterror());
}

}  // namespace

Volume read_tiff(const fs::path& path, const LoadOptions& options) {
  std::error_code ec;
  std::vector<fs::path> slices;
  if (fs::is_directory(path, ec)) {
    for (auto& e : fs::directory_iterator(path, ec)) {
      std::string ext = lower(e.path().extension().string());
      if (e.is_regular_file() && (ext == ".tif" || ext == ".tiff")) slices.push_back(e.path());
    }
    if (slices.empty()) throw VolumeError(path, "directory holds no .tif/.tiff slices");
    std::sort(slices.begin(), slices.end(), [](const fs::path& a, const fs::path& b) {
      return natural_less(a.filename().string(), b.filename().string());
    });
  }
  VolumeHeader h;
  const fs::path first = slices.empty() ? path : slices.front();
  auto in = open_image(first);
  const ImageSpec spec0 = in->spec();
  h.dims = {spec0.width, spec0.height, 0};
  h.source = source_from(first, spec0.format);
  imagej_geometry(first, spec0, h);
  Hyperstack stack;
  if (slices.empty()) {  // multi-page: count the subimages
    int pages = 0;
    while (in->seek_subimage(pages, 0)) ++pages;
    stack = hyperstack_of(path, spec0, pages, options);
    h.dims[2] = stack.slices;
    h.time_point = stack.time;
    h.time_points = stack.frames;
  } else {
    h.dims[2] = int64_t(slices.size());
  }
  check_header(path, h, options);
  Volume v(h);
  const size_t slice_bytes = size_t(h.dims[0] * h.dims[1]) * source_bytes(h.source);
  LoadProgress progress(options, slice_bytes * size_t(h.dims[2]));
  for (int64_t z = 0; z < h.dims[2]; ++z) {
    uint8_t* dst = v.data() + size_t(z) * slice_bytes;
    if (slices.empty()) {
      const int page = int(stack.page(z));
      if (!in->seek_subimage(page, 0)) throw VolumeError(path, "cannot seek to page " + std::to_string(page));
      check_slice(path, in->spec(), h);
      read_slice(path, *in, page, h, dst);
    } else {
      auto slice = z == 0 ? std::move(in) : open_image(slices[z]);
      check_slice(slices[z], slice->spec(), h);
      read_slice(slices[z], *slice, 0, h, dst);
    }
    progress.add(slice_bytes);
  }
  // OIIO delivers native-endian samples; signed ones still need the shift.
  finish_volume(path, v, std::endian::native == std::endian::big, options);
  progress.done();
  return v;
}

}  // namespace peakcast::detail
