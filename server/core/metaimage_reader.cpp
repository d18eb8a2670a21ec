// MetaImage (ITK/VTK): .mhd + detached data (one file, a LIST or a pattern of slice files), .mha
// with LOCAL data; raw or zlib-compressed; MET_DOUBLE and the 32/64-bit integer types converted to
// a kept type (metaimage_wide.cpp).
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
  bool local = false;             // ElementDataFile = LOCAL: the data follows the header (.mha)
  int64_t header_bytes = 0;       // where the header ends
  std::vector<std::string> list;  // ElementDataFile = LIST: the file names on the lines after it
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
  const auto data_file = split_ws(m.fields["elementdatafile"]);
  if (!data_file.empty() && lower(data_file[0]) == "list")
    for (int lines = 0; std::getline(in, line); ++lines) {
      if (lines > 1000000) throw VolumeError(path, "ElementDataFile LIST: more than a million files");
      if (!trim(line).empty()) m.list.push_back(trim(line));
    }
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
  const std::string type = need(path, fields, "elementtype");
  try {
    h.source = wide_metaimage_type(type) ? SourceType::F32 : parse_source_type(type);
  } catch (const std::invalid_argument& e) {
    throw VolumeError(path, std::string(e.what()) +
                                " (or MET_DOUBLE, MET_INT, MET_UINT, MET_LONG, MET_ULONG, "
                                "MET_LONG_LONG, MET_ULONG_LONG, converted)");
  }
  for (const char* key : {"elementbyteordermsb", "binarydatabyteordermsb"})
    if (fields.count(key)) h.big_endian = lower(fields[key]) == "true";
  return h;
}

// The slab dimension of a LIST or pattern's files ("2D", "2" or absent: NDims - 1) as the count
// of files it asks for.
int64_t files_for(const fs::path& path, const std::string& dim, const VolumeHeader& h, int64_t files) {
  std::string d = lower(dim);
  if (d.empty()) return h.dims[2];
  if (d.back() == 'd') d.pop_back();
  const int64_t n = parse_int(path, "ElementDataFile", d);
  if (n == 3) return files;  // slabs of all three axes: checked as equal shares
  if (n == 2) return h.dims[2];
  if (n == 1) return h.dims[1] * h.dims[2];
  throw VolumeError(path, "ElementDataFile: a file dimension of " + dim + " (need 1, 2 or 3)");
}

// Where the voxels are: after the header (LOCAL), in the one file ElementDataFile names, in a LIST
// of files or a pattern's (`slice%03d.raw 1 93 1 [2]`: min, max, step, file dimension), and
// whether they are zlib-compressed. HeaderSize (-1: the data is a file's last bytes) is in each file.
PayloadSpec metaimage_payload(const fs::path& path, MetaImageHeader& m, const VolumeHeader& h, int64_t element_bytes,
                              const LoadOptions& options) {
  Fields& fields = m.fields;
  PayloadSpec payload;
  if (fields.count("compresseddata") && lower(fields["compresseddata"]) == "true") payload.encoding = Encoding::Zlib;
  const std::string data_file = need(path, fields, "elementdatafile");
  const auto words = split_ws(data_file);
  const int64_t header_size = fields.count("headersize") ? parse_int(path, "HeaderSize", fields["headersize"]) : 0;
  const bool list = !words.empty() && lower(words[0]) == "list";
  if (!list && words.size() < 4 && element_bytes == 0) {  // one file, as before: its first bytes
    if (m.local) {
      payload.files = {path};
      payload.byte_skip = m.header_bytes;
    } else {
      payload.files = {path.parent_path() / data_file};
      payload.byte_skip = header_size;
    }
    return payload;
  }
  DataLayout l;
  if (m.local) {
    l.files = {path};
    l.attached_offset = m.header_bytes;
  } else if (list) {
    for (const auto& f : m.list) l.files.push_back(path.parent_path() / f);
    l.files_expected = files_for(path, words.size() > 1 ? words[1] : "", h, int64_t(l.files.size()));
  } else if (words.size() >= 4) {
    l.files = pattern_files(path, words[0], words[1], words[2], words[3]);
    l.files_expected = files_for(path, words.size() > 4 ? words[4] : "", h, int64_t(l.files.size()));
  } else {
    l.files = {path.parent_path() / data_file};
  }
  if (header_size < -1) throw VolumeError(path, "HeaderSize " + std::to_string(header_size) + ": -1 or >= 0");
  l.encoding = payload.encoding;
  l.byte_skip = header_size;
  l.skip_in_file = true;
  l.last_bytes = "'HeaderSize = -1'";
  l.total_bytes = h.voxel_count() * (element_bytes ? element_bytes : int64_t(source_bytes(h.source)));
  payload.files = l.files;
  check_payload_files(path, payload, options);  // before any data file is looked at
  payload.parts = resolve_parts(path, l);
  return payload;
}

}  // namespace

Volume read_metaimage(const fs::path& path, const LoadOptions& options) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw VolumeError(path, "cannot open");
  MetaImageHeader m = read_metaimage_header(path, in);
  in.close();
  const VolumeHeader h = metaimage_volume_header(path, m.fields);
  const auto wide = wide_metaimage_type(m.fields["elementtype"]);
  check_header(path, h, options);  // sizes and limits (a converted type: as float32) before any data
  const PayloadSpec payload = metaimage_payload(path, m, h, wide ? wide->bytes : 0, options);
  if (wide) return read_converted(path, h, *wide, payload, options);
  return read_payload(path, h, payload, options);
}

}  // namespace peakcast::detail
