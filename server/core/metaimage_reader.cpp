// MetaImage (ITK/VTK): .mhd + detached data, .mha with LOCAL data; raw or zlib-compressed.
#include <fstream>
#include <map>

#include "core/volume_io_detail.h"

namespace fs = std::filesystem;

namespace peakcast::detail {

namespace {

using Fields = std::map<std::string, std::string>;

// The header's fields, keys in lower case, up to ElementDataFile (always the last field).
struct MetaImageHeader {
  Fields fields;
  bool local = false;        // ElementDataFile = LOCAL: the data follows the header (.mha)
  int64_t header_bytes = 0;  // where the header ends
};

// Reads the header lines up to and including ElementDataFile.
MetaImageHeader read_metaimage_header(const fs::path& path, std::ifstream& in) {
  MetaImageHeader m;
  std::string line;
  for (int lines = 0; std::getline(in, line); ++lines) {
    if (lines > 1000) throw VolumeError(path, "header too long (no ElementDataFile)");
    auto eq = line.find('=');
    if (eq == std::string::npos) {
      if (trim(line).empty()) continue;
      throw VolumeError(path, "malformed header line '" + trim(line) + "'");
    }
    std::string key = lower(trim(line.substr(0, eq))), value = trim(line.substr(eq + 1));
    m.fields[key] = value;
    if (key == "elementdatafile") {  // always the last field
      m.local = lower(value) == "local";
      break;
    }
  }
  m.header_bytes = in.tellg();
  return m;
}

// A field the header must have.
std::string need(const fs::path& path, const Fields& fields, const std::string& key) {
  auto it = fields.find(key);
  if (it == fields.end()) throw VolumeError(path, "missing field '" + key + "'");
  return it->second;
}

// A field that lists three values.
std::vector<std::string> numbers(const fs::path& path, Fields& fields, const std::string& key) {
  auto parts = split_ws(fields[key]);
  if (parts.size() != 3) throw VolumeError(path, "field '" + key + "' must list 3 values");
  return parts;
}

// The volume's dims, spacing, origin, type and byte order; refuses what is not a single-channel,
// axis-aligned 3D grid.
VolumeHeader metaimage_volume_header(const fs::path& path, Fields& fields) {
  if (parse_int(path, "NDims", need(path, fields, "ndims")) != 3)
    throw VolumeError(path, "NDims " + fields["ndims"] + " is not supported (need 3)");
  if (fields.count("elementnumberofchannels") &&
      parse_int(path, "ElementNumberOfChannels", fields["elementnumberofchannels"]) != 1)
    throw VolumeError(path, "only single-channel images are supported");

  VolumeHeader h;
  need(path, fields, "dimsize");
  auto dims = numbers(path, fields, "dimsize");
  for (int a = 0; a < 3; ++a) h.dims[a] = parse_int(path, "DimSize", dims[a]);
  const std::string spacing_key = fields.count("elementspacing") ? "elementspacing"
                                  : fields.count("elementsize")  ? "elementsize"
                                                                 : "";
  if (!spacing_key.empty()) {
    auto s = numbers(path, fields, spacing_key);
    for (int a = 0; a < 3; ++a) h.spacing[a] = parse_double(path, spacing_key, s[a]);
  }
  for (const char* key : {"offset", "position", "origin"})
    if (fields.count(key)) {
      auto o = numbers(path, fields, key);
      for (int a = 0; a < 3; ++a) h.origin[a] = parse_double(path, key, o[a]);
      break;
    }
  if (fields.count("transformmatrix")) {
    auto m = split_ws(fields["transformmatrix"]);
    const char* identity[] = {"1", "0", "0", "0", "1", "0", "0", "0", "1"};
    for (size_t i = 0; i < m.size() && i < 9; ++i)
      if (parse_double(path, "TransformMatrix", m[i]) != std::stod(identity[i]))
        throw VolumeError(path, "non-identity TransformMatrix (oblique grids are not supported)");
  }
  try {
    h.source = parse_source_type(need(path, fields, "elementtype"));
  } catch (const std::invalid_argument& e) {
    throw VolumeError(path, e.what());
  }
  for (const char* key : {"elementbyteordermsb", "binarydatabyteordermsb"})
    if (fields.count(key)) h.big_endian = lower(fields[key]) == "true";
  return h;
}

// Where the voxels are: after the header (LOCAL) or in the one file ElementDataFile names, and
// whether they are zlib-compressed.
PayloadSpec metaimage_payload(const fs::path& path, MetaImageHeader& m) {
  Fields& fields = m.fields;
  PayloadSpec payload;
  if (fields.count("compresseddata") && lower(fields["compresseddata"]) == "true") payload.encoding = Encoding::Zlib;
  std::string data_file = need(path, fields, "elementdatafile");
  if (m.local) {
    payload.files = {path};
    payload.byte_skip = m.header_bytes;
  } else {
    if (split_ws(data_file).size() != 1 || lower(data_file) == "list")
      throw VolumeError(path, "ElementDataFile lists/patterns are not supported");
    payload.files = {path.parent_path() / data_file};
    if (fields.count("headersize")) payload.byte_skip = parse_int(path, "HeaderSize", fields["headersize"]);
  }
  return payload;
}

}  // namespace

Volume read_metaimage(const fs::path& path, const LoadOptions& options) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw VolumeError(path, "cannot open");
  MetaImageHeader m = read_metaimage_header(path, in);
  const VolumeHeader h = metaimage_volume_header(path, m.fields);
  const PayloadSpec payload = metaimage_payload(path, m);
  return read_payload(path, h, payload, options);
}

}  // namespace peakcast::detail
