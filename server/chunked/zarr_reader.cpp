// OME-Zarr: NGFF 0.4 "multiscales" (axes t?, c?, z, y, x; a scale and translation per level) over
// zarr v2 arrays (C order, "." or "/" separated chunk keys, fill_value for missing chunks), or one
// bare 3D zarr array.
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>

#include "chunked/chunk_codec.h"
#include "chunked/formats.h"
#include "core/length_unit.h"
#include "core/volume_io_detail.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace peakcast::chunked {
namespace {

struct ZarrArray {
  fs::path dir;
  std::vector<int64_t> shape, chunks;  // in the array's axis order (x last)
  SourceType source = SourceType::U8;
  bool big_endian = false;
  CompressorSpec compressor;
  std::vector<uint8_t> fill;
  char separator = '.';
  int64_t chunk_bytes = 0;
};

// "<u2", "|u1", ">f4", ... (numpy's typestr).
std::pair<SourceType, bool> parse_dtype(const json& j, const fs::path& file) {
  if (!j.is_string())
    throw VolumeError(file, "dtype must be a string like \"<u2\" (structured dtypes are not volumes)");
  const std::string d = j;
  static const std::pair<const char*, SourceType> kinds[] = {{"u1", SourceType::U8},
                                                             {"i1", SourceType::I8},
                                                             {"u2", SourceType::U16},
                                                             {"i2", SourceType::I16},
                                                             {"f4", SourceType::F32}};
  if (d.size() == 3 && (d[0] == '<' || d[0] == '>' || d[0] == '|'))
    for (const auto& [name, type] : kinds)
      if (d.compare(1, 2, name) == 0) return {type, d[0] == '>'};
  throw VolumeError(file, "dtype '" + d + "' is not supported (u1, i1, u2, i2, f4)");
}

template <typename T>
std::vector<uint8_t> bytes_of(T value, bool big_endian) {
  std::vector<uint8_t> b(sizeof(T));
  std::memcpy(b.data(), &value, sizeof(T));
  if (big_endian != (std::endian::native == std::endian::big)) std::reverse(b.begin(), b.end());
  return b;
}

std::vector<uint8_t> parse_fill(const json& j, SourceType t, bool big, const fs::path& file) {
  double v = 0.0;
  if (j.is_null())
    v = 0.0;  // undefined in zarr v2: read as 0
  else if (j.is_number())
    v = j.get<double>();
  else if (j.is_string() && t == SourceType::F32 && (j == "NaN" || j == "Infinity" || j == "-Infinity"))
    v = j == "NaN" ? std::numeric_limits<double>::quiet_NaN() : (j == "Infinity" ? 1.0 : -1.0) * HUGE_VAL;
  else
    throw VolumeError(file, "fill_value must be a number or null (NaN, Infinity, -Infinity for floats)");
  auto integer = [&](double lo, double hi) {
    if (!(v >= lo && v <= hi) || v != std::floor(v))
      throw VolumeError(file, "fill_value " + j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) +
                                  " is not a " + to_string(t) + " value");
    return v;
  };
  switch (t) {
    case SourceType::U8: return bytes_of(uint8_t(integer(0, 255)), big);
    case SourceType::I8: return bytes_of(int8_t(integer(-128, 127)), big);
    case SourceType::U16: return bytes_of(uint16_t(integer(0, 65535)), big);
    case SourceType::I16: return bytes_of(int16_t(integer(-32768, 32767)), big);
    case SourceType::F32: return bytes_of(float(v), big);
  }
  return {};
}

std::vector<int64_t> int_list(const json& j, const char* key, const fs::path& file) {
  if (!j.contains(key) || !j[key].is_array()) throw VolumeError(file, std::string(key) + " must be a list of integers");
  std::vector<int64_t> out;
  for (const auto& e : j[key]) {
    if (!e.is_number_integer() || e.get<int64_t>() <= 0)
      throw VolumeError(file, std::string(key) + " must be a list of integers >= 1");
    out.push_back(e.get<int64_t>());
  }
  return out;
}

ZarrArray open_array(const fs::path& dir) {
  const fs::path file = dir / ".zarray";
  const json j = read_json_file(file);
  ZarrArray a;
  a.dir = dir;
  if (j.value("zarr_format", 0) != 2) throw VolumeError(file, "zarr_format must be 2 (zarr v3 is not supported)");
  a.shape = int_list(j, "shape", file);
  a.chunks = int_list(j, "chunks", file);
  if (a.shape.size() != a.chunks.size()) throw VolumeError(file, "shape and chunks differ in length");
  if (!j.contains("dtype")) throw VolumeError(file, "dtype is missing");
  std::tie(a.source, a.big_endian) = parse_dtype(j["dtype"], file);
  if (j.value("order", std::string("C")) != "C")
    throw VolumeError(file, "order must be \"C\" (Fortran order is not supported)");
  if (j.contains("filters") && !j["filters"].is_null() && !j["filters"].empty())
    throw VolumeError(file, "filters are not supported");
  try {
    a.compressor = parse_compressor(j.contains("compressor") ? j["compressor"] : json(nullptr));
  } catch (const std::invalid_argument& e) {
    throw VolumeError(file, e.what());
  }
  a.fill = parse_fill(j.contains("fill_value") ? j["fill_value"] : json(nullptr), a.source, a.big_endian, file);
  const std::string sep = j.contains("dimension_separator") && j["dimension_separator"].is_string()
                              ? j["dimension_separator"].get<std::string>()
                              : ".";
  if (sep != "." && sep != "/") throw VolumeError(file, "dimension_separator must be \".\" or \"/\"");
  a.separator = sep[0];
  std::vector<int64_t> factors = a.chunks;
  factors.push_back(int64_t(source_bytes(a.source)));
  a.chunk_bytes = checked_bytes(factors, file, "a chunk");
  return a;
}

// The axes' roles: for each array axis 't', 'c', 'z', 'y' or 'x'.
std::string axis_roles(const json& ms, size_t ndim, const fs::path& file) {
  std::string roles;
  if (!ms.contains("axes")) {  // NGFF 0.1/0.2: always 5D t, c, z, y, x
    if (ndim != 5) throw VolumeError(file, "multiscales without axes must be 5D (t, c, z, y, x)");
    return "tczyx";
  }
  if (!ms["axes"].is_array()) throw VolumeError(file, "multiscales.axes must be a list");
  for (const auto& ax : ms["axes"]) {
    const std::string name = ax.is_string() ? ax.get<std::string>()
                             : ax.is_object() && ax.contains("name") && ax["name"].is_string()
                                 ? ax["name"].get<std::string>()
                                 : "";
    const std::string type =
        ax.is_object() && ax.contains("type") && ax["type"].is_string() ? ax["type"].get<std::string>() : "";
    if (name == "x" || name == "y" || name == "z")
      roles += name;
    else if (type == "time" || name == "t")
      roles += 't';
    else if (type == "channel" || name == "c")
      roles += 'c';
    else
      throw VolumeError(file, "axis '" + name + "' is not a time, channel or x/y/z axis");
  }
  if (roles.size() != ndim)
    throw VolumeError(file,
                      std::to_string(roles.size()) + " axes for a " + std::to_string(ndim) + "-dimensional array");
  const std::string spatial = roles.size() >= 3 ? roles.substr(roles.size() - 3) : "";
  const std::string lead = roles.size() >= 3 ? roles.substr(0, roles.size() - 3) : roles;
  if (spatial != "zyx" || (lead != "" && lead != "t" && lead != "c" && lead != "tc"))
    throw VolumeError(file,
                      "axes must be [t,] [c,] z, y, x in that order (got " + roles + "); a 2D image is not a volume");
  return roles;
}

// The x, y and z axes' `unit`s as written ("" where absent; NGFF 0.4 names them "micrometer").
std::array<std::string, 3> axis_units(const json& ms) {
  std::array<std::string, 3> units;
  if (!ms.is_object() || !ms.contains("axes") || !ms["axes"].is_array()) return units;
  for (const auto& ax : ms["axes"]) {
    if (!ax.is_object() || !ax.contains("name") || !ax["name"].is_string()) continue;
    const std::string name = ax["name"];
    const int a = name == "x" ? 0 : name == "y" ? 1 : name == "z" ? 2 : -1;
    if (a >= 0 && ax.contains("unit") && ax["unit"].is_string()) units[size_t(a)] = ax["unit"];
  }
  return units;
}

// A coordinateTransformations list's scale and translation (1 and 0 where absent).
void transforms(const json& list, size_t ndim, std::vector<double>& scale, std::vector<double>& shift,
                const fs::path& file) {
  if (!list.is_array()) return;
  for (const auto& t : list) {
    const std::string type = t.is_object() ? t.value("type", std::string()) : "";
    const char* key = type == "scale" ? "scale" : type == "translation" ? "translation" : nullptr;
    if (!key || !t.contains(key)) continue;  // "identity", or a transformation by path: ignored
    const json& v = t[key];
    if (!v.is_array() || v.size() != ndim) throw VolumeError(file, std::string(key) + " must have one number per axis");
    for (size_t i = 0; i < ndim; ++i) {
      if (!v[i].is_number()) throw VolumeError(file, std::string(key) + " must have one number per axis");
      const double x = v[i].get<double>();
      if (type == "scale")
        scale[i] *= x;
      else
        shift[i] = shift[i] * 1.0 + x;
    }
  }
}

class ZarrVolume : public ChunkedVolume {
 public:
  ZarrVolume(const fs::path& dir, const ChunkSelect& select) : select_(select) {
    root_ = dir;
    format_ = "OME-Zarr";
    std::error_code ec;
    json ms;
    std::vector<std::string> paths;
    fs::path meta = dir / ".zattrs";
    if (fs::is_regular_file(meta, ec) && read_json_file(meta).contains("multiscales")) {
      const json attrs = read_json_file(meta);
      if (!attrs["multiscales"].is_array() || attrs["multiscales"].empty())
        throw VolumeError(meta, "multiscales must be a non-empty list");
      ms = attrs["multiscales"][0];
      if (!ms.is_object() || !ms.contains("datasets") || !ms["datasets"].is_array() || ms["datasets"].empty())
        throw VolumeError(meta, "multiscales[0].datasets must be a non-empty list");
      for (const auto& d : ms["datasets"]) {
        if (!d.is_object() || !d.contains("path") || !d["path"].is_string())
          throw VolumeError(meta, "every dataset needs a \"path\"");
        paths.push_back(d["path"]);
      }
    } else if (fs::is_regular_file(dir / ".zarray", ec)) {
      meta = dir / ".zarray";
      paths.push_back("");
    } else {
      throw VolumeError(meta, "no \"multiscales\" here and no .zarray: not an OME-Zarr image");
    }
    for (size_t i = 0; i < paths.size(); ++i) {
      ZarrArray a = open_array(paths[i].empty() ? dir : inside(dir, paths[i], meta));
      const size_t n = a.shape.size();
      const std::string roles = ms.is_null() ? (n == 3   ? "zyx"
                                                : n == 4 ? "czyx"
                                                : n == 5 ? "tczyx"
                                                         : "")
                                             : axis_roles(ms, n, meta);
      if (roles.empty()) throw VolumeError(a.dir / ".zarray", "a bare zarr array must be 3D (z, y, x), 4D or 5D");
      if (i == 0) {
        roles_ = roles;
        source_ = a.source;
        big_endian_ = a.big_endian;
      } else if (roles != roles_ || a.source != source_ || a.big_endian != big_endian_) {
        throw VolumeError(a.dir / ".zarray", "levels differ in axes or dtype");
      }
      std::vector<double> scale(n, 1.0), shift(n, 0.0);
      if (!ms.is_null()) {
        transforms(ms["datasets"][i].value("coordinateTransformations", json()), n, scale, shift, meta);
        std::vector<double> gs(n, 1.0), gt(n, 0.0);
        transforms(ms.value("coordinateTransformations", json()), n, gs, gt, meta);
        for (size_t k = 0; k < n; ++k) {
          scale[k] *= gs[k];
          shift[k] = shift[k] * gs[k] + gt[k];
        }
      }
      ChunkLevel L;
      L.name = paths[i].empty() ? "." : paths[i];
      for (int ax = 0; ax < 3; ++ax) {  // x, y, z = the last three axes, reversed
        const size_t k = n - 1 - size_t(ax);
        L.dims[ax] = a.shape[k];
        L.chunk[ax] = a.chunks[k];
        L.spacing[ax] = scale[k];
        L.origin[ax] = shift[k];
        if (!(scale[k] > 0) || !std::isfinite(scale[k])) throw VolumeError(meta, "scales must be finite and > 0");
      }
      try {  // every level in the finest of the axes' units (NGFF lets each axis have its own)
        unit_ = common_unit(axis_units(ms), L.spacing, L.origin, "multiscales.axes unit");
      } catch (const std::invalid_argument& e) {
        throw VolumeError(meta, e.what());
      }
      check_select(a, meta);
      if (const size_t t = roles_.find('t'); t != std::string::npos) time_points_ = a.shape[t];
      time_point_ = select_.time;
      levels_.push_back(L);
      fills_.push_back(a.fill);
      arrays_.push_back(std::move(a));
    }
  }

  int64_t decoded_chunk_bytes(int level) const override { return arrays_[size_t(level)].chunk_bytes; }

  std::optional<std::vector<uint8_t>> read_chunk(int level, const Dims& c) const override {
    const ZarrArray& a = arrays_[size_t(level)];
    const size_t n = a.shape.size();
    std::string key;
    int64_t lead_offset = 0;  // voxels before the (t, c) block inside the chunk
    int64_t block = a.chunks[n - 1] * a.chunks[n - 2] * a.chunks[n - 3];
    for (size_t k = 0; k < n; ++k) {
      int64_t index = 0;
      if (k >= n - 3)
        index = c[n - 1 - k];
      else {
        const int64_t want = roles_[k] == 't' ? select_.time : select_.channel;
        index = want / a.chunks[k];
        int64_t stride = 1;
        for (size_t m = k + 1; m < n - 3; ++m) stride *= a.chunks[m];
        lead_offset += (want % a.chunks[k]) * stride;
      }
      key += (k ? std::string(1, a.separator) : std::string()) + std::to_string(index);
    }
    if (!may_hold(level, a.dir, key)) return std::nullopt;  // not stored: the fill value
    const fs::path file = a.dir / key;
    const auto raw = read_file_if_there(file, a.chunk_bytes + (int64_t(1) << 20) + a.chunk_bytes / 8);
    if (!raw) return std::nullopt;
    std::vector<uint8_t> chunk = decode_chunk(a.compressor, *raw, size_t(a.chunk_bytes), file);
    const size_t bpv = source_bytes(source_);
    const ChunkLevel& L = levels_[size_t(level)];
    Dims box{};
    for (int ax = 0; ax < 3; ++ax) box[ax] = std::min(L.chunk[ax], L.dims[ax] - c[ax] * L.chunk[ax]);
    if (lead_offset == 0 && box == L.chunk && chunk.size() == size_t(block) * bpv) return chunk;  // no copy
    return crop_block(chunk.data() + size_t(lead_offset * block) * bpv, L.chunk, box, bpv);
  }

 private:
  void check_select(const ZarrArray& a, const fs::path& meta) const {
    const bool has_t = roles_.find('t') != std::string::npos, has_c = roles_.find('c') != std::string::npos;
    if (!has_t && select_.time != 0)
      throw VolumeError(meta, "the image has no time axis (time point " + std::to_string(select_.time) + ")");
    if (!has_c && select_.channel != 0)
      throw VolumeError(meta, "the image has no channel axis (channel " + std::to_string(select_.channel) + ")");
    for (size_t k = 0; k + 3 < roles_.size(); ++k) {
      const int64_t want = roles_[k] == 't' ? select_.time : select_.channel;
      if (want < 0 || want >= a.shape[k])
        throw VolumeError(meta, std::string(roles_[k] == 't' ? "time point " : "channel ") + std::to_string(want) +
                                    " is outside 0.." + std::to_string(a.shape[k] - 1));
    }
  }

  ChunkSelect select_;
  std::string roles_;
  std::vector<ZarrArray> arrays_;
};

}  // namespace

std::unique_ptr<ChunkedVolume> open_zarr(const fs::path& dir, const ChunkSelect& select) {
  return std::make_unique<ZarrVolume>(dir, select);
}

}  // namespace peakcast::chunked
