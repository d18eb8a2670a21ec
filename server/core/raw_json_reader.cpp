// Raw voxels with a JSON sidecar: {"dims": [x,y,z], "dtype": "uint16", "spacing": [..],
// "origin": [..], "endian": "little"|"big", "data_file": "v.raw", "encoding": "raw"|"gzip",
// "units": "µm", "values": "HU", "times": T (T volumes one after another: a time series)}.
// Open either the .json or the data file (its sidecar is `<file>.json` or `<stem>.json`).
#include <fstream>
#include <nlohmann/json.hpp>

#include "core/length_unit.h"
#include "core/volume_io_detail.h"

namespace fs = std::filesystem;

namespace peakcast::detail {
namespace {

// The sidecar's "units": one unit, or one per axis (x, y, z); spacing and origin in the finest.
void sidecar_values(const nlohmann::json& j, const fs::path& sidecar, VolumeHeader& h);
void sidecar_units(const nlohmann::json& j, const fs::path& sidecar, VolumeHeader& h) {
  sidecar_values(j, sidecar, h);  // and what the values are
  if (!j.contains("units")) return;
  const auto& u = j.at("units");
  if (!u.is_string() && !(u.is_array() && u.size() == 3))
    throw VolumeError(sidecar, "'units' must be a unit (\"µm\") or a list of 3");
  std::array<std::string, 3> names;
  for (int a = 0; a < 3; ++a) names[size_t(a)] = (u.is_string() ? u : u[size_t(a)]).get<std::string>();
  h.unit = common_unit(names, h.spacing, h.origin, "'units'");
}

// The sidecar's "times": how many volumes of its dims the data holds, one after another (1: one).
int64_t sidecar_times(const nlohmann::json& j, const fs::path& sidecar) {
  if (!j.contains("times")) return 1;
  const auto& t = j.at("times");
  if (!t.is_number_integer() || t.get<int64_t>() < 1 || t.get<int64_t>() > 1000000)
    throw VolumeError(sidecar, "'times' must be an integer from 1 to 1000000 (time points)");
  return t.get<int64_t>();
}

// The sidecar's "values": "HU" says the values are Hounsfield units (the viewer's CT presets).
void sidecar_values(const nlohmann::json& j, const fs::path& sidecar, VolumeHeader& h) {
  if (!j.contains("values")) return;
  if (j.at("values") != "HU") throw VolumeError(sidecar, "'values' must be \"HU\" (Hounsfield units) or absent");
  h.value_unit = "HU";
}

}  // namespace

Volume read_raw_json(const fs::path& path, const LoadOptions& options) {
  fs::path sidecar = path;
  if (lower(path.extension().string()) != ".json") {
    std::error_code ec;
    fs::path a = path.string() + ".json", b = fs::path(path).replace_extension(".json");
    if (fs::exists(a, ec))
      sidecar = a;
    else if (fs::exists(b, ec))
      sidecar = b;
    else
      throw VolumeError(path, "raw data needs a JSON sidecar (" + a.filename().string() + " or " +
                                  b.filename().string() + ") with dims and dtype");
  }
  nlohmann::json j;
  try {
    std::ifstream in(sidecar);
    if (!in) throw VolumeError(sidecar, "cannot open");
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw VolumeError(sidecar, std::string("invalid JSON: ") + e.what());
  }
  if (!j.is_object()) throw VolumeError(sidecar, "sidecar must be a JSON object");
  static const char* known[] = {"dims",     "dtype",     "spacing", "origin", "endian", "data_file",
                                "encoding", "byte_skip", "units",   "times",  "values"};
  for (auto& [key, _] : j.items())
    if (std::find(std::begin(known), std::end(known), key) == std::end(known))
      throw VolumeError(sidecar, "unknown key '" + key + "'");
  auto vec3 = [&](const char* key, bool integer) {
    const auto& v = j.at(key);
    if (!v.is_array() || v.size() != 3)
      throw VolumeError(sidecar, std::string("'") + key + "' must be an array of 3 numbers");
    for (auto& x : v)
      if (!x.is_number() || (integer && !x.is_number_integer()))
        throw VolumeError(sidecar, std::string("'") + key + "' must hold " + (integer ? "integers" : "numbers"));
    return v;
  };
  VolumeHeader h;
  PayloadSpec payload;
  const int64_t times = sidecar_times(j, sidecar);
  try {
    if (!j.contains("dims")) throw VolumeError(sidecar, "missing key 'dims'");
    if (!j.contains("dtype")) throw VolumeError(sidecar, "missing key 'dtype'");
    auto d = vec3("dims", true);
    for (int a = 0; a < 3; ++a) h.dims[a] = d[a].get<int64_t>();
    if (j.contains("spacing")) {
      auto s = vec3("spacing", false);
      for (int a = 0; a < 3; ++a) h.spacing[a] = s[a].get<double>();
    }
    if (j.contains("origin")) {
      auto o = vec3("origin", false);
      for (int a = 0; a < 3; ++a) h.origin[a] = o[a].get<double>();
    }
    sidecar_units(j, sidecar, h);
    h.source = parse_source_type(j.at("dtype").get<std::string>());
    std::string endian = j.value("endian", "little");
    if (endian != "little" && endian != "big") throw VolumeError(sidecar, "endian must be 'little' or 'big'");
    h.big_endian = endian == "big";
    std::string enc = j.value("encoding", "raw");
    if (enc == "gzip")
      payload.encoding = Encoding::Gzip;
    else if (enc != "raw")
      throw VolumeError(sidecar, "unsupported encoding '" + enc + "' (raw, gzip)");
    payload.byte_skip = j.value("byte_skip", int64_t(0));
    if (payload.byte_skip < 0) throw VolumeError(sidecar, "byte_skip must be >= 0");
    if (j.contains("data_file")) {
      payload.files = {sidecar.parent_path() / j.at("data_file").get<std::string>()};
    } else if (sidecar != path) {
      payload.files = {path};
    } else {
      fs::path stem = path.parent_path() / path.stem();  // v.raw.json -> v.raw; v.json -> v.raw
      payload.files = {stem.has_extension() ? stem : fs::path(stem.string() + ".raw")};
    }
  } catch (const nlohmann::json::exception& e) {
    throw VolumeError(sidecar, std::string("bad sidecar: ") + e.what());
  } catch (const std::invalid_argument& e) {
    throw VolumeError(sidecar, e.what());
  }
  if (times > 1) return read_time_point(sidecar, h, times, payload, options);
  return read_payload(sidecar, h, payload, options);
}

}  // namespace peakcast::detail
