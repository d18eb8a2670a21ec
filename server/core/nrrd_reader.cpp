// NRRD (teem's format): attached .nrrd and detached .nhdr headers, every encoding (raw, txt,
// hex, gzip, bzip2), `spacings` or axis-aligned `space directions`, single, LIST and
// printf-style `data file`s; line and byte skips by the format's rules (data_parts.cpp).
#include <cctype>
#include <cmath>
#include <algorithm>
#include <array>
#include <bit>
#include <optional>
#include <cstdio>
#include <fstream>

#include "core/length_unit.h"
#include "core/volume_io_detail.h"

namespace fs = std::filesystem;

namespace peakcast::detail {
namespace {

// "(3.2,0,0)" -> three numbers; "none" -> empty.
std::vector<double> parse_vector(const fs::path& file, const std::string& text) {
  std::string t = trim(text);
  if (t == "none") return {};
  if (t.size() < 2 || t.front() != '(' || t.back() != ')') throw VolumeError(file, "malformed vector '" + t + "'");
  std::vector<double> out;
  std::string item;
  for (char c : t.substr(1, t.size() - 2) + ",") {
    if (c == ',') {
      out.push_back(parse_double(file, "space directions", trim(item)));
      item.clear();
    } else {
      item += c;
    }
  }
  return out;
}

std::vector<std::string> split_vectors(const std::string& s) {
  std::vector<std::string> out;
  std::string cur;
  int depth = 0;
  for (char c : s) {
    if (c == '(') depth++;
    if (c == ')') depth--;
    if (std::isspace(static_cast<unsigned char>(c)) && depth == 0) {
      if (!cur.empty()) out.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  if (!cur.empty()) out.push_back(cur);
  return out;
}

// What a NRRD header says, as its fields are read.
struct NrrdHeader {
  VolumeHeader h;
  PayloadSpec payload;
  std::string type, encoding = "raw", data_file;
  std::vector<std::string> list_files;
  bool have_sizes = false, list_mode = false;
  int dimension = 0;
  int64_t line_skip = 0;
  int64_t header_bytes = 0;
  std::array<std::string, 3> units;  // `space units` (or the axes' `units`), as written
  std::string units_field;
  std::vector<std::string> kinds;  // the axes' kinds, lower case
  int64_t times = 1;               // a 4-D file's time axis (the slowest): its size
};

// A field of quoted strings (`space units: "mm" "mm" "µm"`), unquoted.
std::vector<std::string> quoted_strings(const std::string& value) {
  std::vector<std::string> out;
  for (size_t i = value.find('"'); i != std::string::npos; i = value.find('"', i)) {
    const size_t end = value.find('"', i + 1);
    if (end == std::string::npos) break;
    out.push_back(value.substr(i + 1, end - i - 1));
    i = end + 1;
  }
  return out;
}

// Sets what one header field says; fields that do not change the voxels are ignored.
void parse_nrrd_field(const fs::path& path, const std::string& field, const std::string& value, NrrdHeader& n) {
  VolumeHeader& h = n.h;
  if (field == "type") {
    n.type = value;
  } else if (field == "dimension") {
    n.dimension = int(parse_int(path, field, value));
    if (n.dimension != 3 && n.dimension != 4)
      throw VolumeError(path, "dimension " + value + " is not supported (a 3D volume, or 4D with a time axis last)");
  } else if (field == "sizes") {
    auto parts = split_ws(value);
    if (n.dimension == 0 || int(parts.size()) != n.dimension)
      throw VolumeError(path,
                        "sizes must list one value per dimension (dimension " + std::to_string(n.dimension) + ")");
    for (int a = 0; a < 3; ++a) h.dims[a] = parse_int(path, field, parts[a]);
    if (n.dimension == 4) n.times = parse_int(path, field, parts[3]);
    n.have_sizes = true;
  } else if (field == "kinds") {
    for (const auto& k : split_ws(value)) n.kinds.push_back(lower(k));
  } else if (field == "spacings") {
    auto parts = split_ws(value);
    if (int(parts.size()) != std::max(n.dimension, 3)) throw VolumeError(path, "spacings must list one value per axis");
    for (int a = 0; a < 3; ++a) h.spacing[a] = lower(parts[a]) == "nan" ? 1.0 : parse_double(path, field, parts[a]);
  } else if (field == "space directions") {
    auto vecs = split_vectors(value);
    if (int(vecs.size()) != std::max(n.dimension, 3))
      throw VolumeError(path, "space directions must list one vector (or none) per axis");
    for (int a = 0; a < 3; ++a) {
      auto v = parse_vector(path, vecs[a]);
      if (v.empty()) continue;
      if (v.size() != 3) throw VolumeError(path, "space directions: need 3D vectors");
      for (int b = 0; b < 3; ++b)
        if (b != a && v[b] != 0.0)
          throw VolumeError(path, "space directions are not axis-aligned (oblique grids are not supported)");
      h.spacing[a] = std::abs(v[a]);
    }
  } else if (field == "space origin") {
    auto v = parse_vector(path, value);
    if (v.size() != 3) throw VolumeError(path, "space origin must be a 3D vector");
    h.origin = {v[0], v[1], v[2]};
  } else if (field == "axis mins" || field == "axismins") {
    auto parts = split_ws(value);
    for (size_t a = 0; a < 3 && a < parts.size(); ++a)
      if (lower(parts[a]) != "nan") h.origin[a] = parse_double(path, field, parts[a]);
  } else if (field == "space units" || (field == "units" && n.units_field != "space units")) {
    const auto u = quoted_strings(value);
    if (u.size() != (field == "units" ? size_t(std::max(n.dimension, 3)) : 3))
      throw VolumeError(path,
                        "'" + field + "' must list a quoted unit per " + (field == "units" ? "axis" : "space axis"));
    n.units = {u[0], u[1], u[2]};
    n.units_field = field;
  } else if (field == "encoding") {
    n.encoding = lower(value);
  } else if (field == "endian") {
    h.big_endian = lower(value) == "big";
  } else if (field == "byte skip") {
    n.payload.byte_skip = parse_int(path, field, value);
  } else if (field == "line skip") {
    n.line_skip = parse_int(path, field, value);
  } else if (field == "data file" || field == "datafile") {
    n.data_file = value;
    if (lower(split_ws(value).empty() ? "" : split_ws(value)[0]) == "list") n.list_mode = true;
  }
  // Other fields (space, kinds, centers, content, ...) do not change the voxels.
}

// Reads the header lines after the magic, up to the blank line before attached data (or the end of
// a detached header), and the LIST of data files when there is one.
NrrdHeader read_nrrd_header(const fs::path& path, std::ifstream& in) {
  NrrdHeader n;
  std::string line;
  for (int lines = 0; std::getline(in, line); ++lines) {
    if (lines > 10000) throw VolumeError(path, "header too long");
    if (n.list_mode) {
      if (!trim(line).empty()) n.list_files.push_back(trim(line));
      continue;
    }
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) break;  // attached data follows
    if (line[0] == '#') continue;
    if (line.find(":=") != std::string::npos) continue;  // key/value pairs: not ours
    auto colon = line.find(": ");
    if (colon == std::string::npos) throw VolumeError(path, "malformed header line '" + line + "'");
    std::string field = lower(trim(line.substr(0, colon)));
    std::string value = trim(line.substr(colon + 2));
    parse_nrrd_field(path, field, value, n);
  }
  n.header_bytes = in.tellg();
  return n;
}

// Refuses a header that lacks a required field or asks for what is not supported; sets the
// source type and the encoding.
void check_nrrd_fields(const fs::path& path, NrrdHeader& n) {
  if (n.type.empty()) throw VolumeError(path, "missing field 'type'");
  if (n.dimension == 0) throw VolumeError(path, "missing field 'dimension'");
  if (!n.have_sizes) throw VolumeError(path, "missing field 'sizes'");
  if (n.dimension == 4) {  // a time series: the 4th axis, the slowest, of kind time
    const bool leading_channels = !n.kinds.empty() && n.kinds[0] != "domain" && n.kinds[0] != "space";
    if (leading_channels)
      throw VolumeError(
          path, "a 4-D NRRD whose first axis is '" + n.kinds[0] +
                    "' holds channels, which peakcast does not read yet (one channel a file: NRRD or OME-Zarr)");
    if (n.kinds.size() != 4 || n.kinds[3] != "time")
      throw VolumeError(path, "a 4-D NRRD is read as a time series: its 4th axis needs 'kinds: ... time'");
    if (n.times < 1) throw VolumeError(path, "the time axis has " + std::to_string(n.times) + " points");
  }
  try {
    n.h.source = parse_source_type(n.type);
  } catch (const std::invalid_argument& e) {
    throw VolumeError(path, e.what());
  }
  const std::string& e = n.encoding;
  if (e == "raw") {
    n.payload.encoding = Encoding::Raw;
  } else if (e == "gzip" || e == "gz") {
    n.payload.encoding = Encoding::Gzip;
  } else if (e == "bzip2" || e == "bz2") {
    n.payload.encoding = Encoding::Bzip2;
  } else if (e == "txt" || e == "text" || e == "ascii") {
    n.payload.encoding = Encoding::Text;
    n.payload.text_type = n.h.source;
    n.h.big_endian = std::endian::native == std::endian::big;  // numbers as text: no byte order
  } else if (e == "hex") {
    n.payload.encoding = Encoding::Hex;
  } else {
    throw VolumeError(path, "unsupported encoding '" + n.encoding + "' (NRRD's: raw, txt, hex, gzip, bzip2)");
  }
  try {
    n.h.unit = common_unit(n.units, n.h.spacing, n.h.origin, "'" + n.units_field + "'");
  } catch (const std::invalid_argument& e) {
    throw VolumeError(path, e.what());
  }
}

// The files the voxels are in: attached after the header, or the detached header's `data file`
// (one file, a LIST, or a printf-style pattern over a range), each with an optional subdimension
// (each file then holds the first `subdim` axes), resolved by NRRD's rules (data_parts.cpp).
void locate_nrrd_data(const fs::path& path, NrrdHeader& n, const LoadOptions& options) {
  DataLayout l;
  const fs::path dir = path.parent_path();
  std::optional<int64_t> subdim;
  const auto parts = split_ws(n.data_file);
  if (n.data_file.empty()) {
    l.files = {path};
    l.attached_offset = n.header_bytes;
  } else if (n.list_mode) {
    for (auto& f : n.list_files) l.files.push_back(dir / f);
    if (parts.size() >= 2) subdim = parse_int(path, "data file", parts[1]);
  } else if (parts.size() >= 4) {  // printf-style: fmt min max step [subdim]
    l.files = pattern_files(path, parts[0], parts[1], parts[2], parts[3]);
    if (parts.size() >= 5) subdim = parse_int(path, "data file", parts[4]);
  } else {
    l.files = {dir / n.data_file};
  }
  const std::array<int64_t, 4> sizes = {n.h.dims[0], n.h.dims[1], n.h.dims[2], n.times};
  if (subdim) {
    if (*subdim < 1 || *subdim > n.dimension)
      throw VolumeError(
          path, "data file: subdimension " + std::to_string(*subdim) + " is not in 1.." + std::to_string(n.dimension));
    // A slab of every axis: the slowest axis is split evenly among the files; fewer axes: a file
    // for each index of the others.
    const int64_t slowest = sizes[size_t(n.dimension - 1)], count = int64_t(l.files.size());
    if (*subdim == n.dimension && (count == 0 || slowest % count != 0))
      throw VolumeError(path, "data file: " + std::to_string(count) + " slabs cannot split the slowest axis' " +
                                  std::to_string(slowest) + " evenly");
    l.files_expected = *subdim == n.dimension ? count : 1;
    for (int a = int(*subdim); a < n.dimension; ++a)
      if (__builtin_mul_overflow(l.files_expected, std::max<int64_t>(sizes[a], 0), &l.files_expected))
        throw VolumeError(path, "sizes overflow");
  }
  check_header(path, n.h, options);  // sizes >= 1 and within the limits, before their product
  l.total_bytes = int64_t(source_bytes(n.h.source));
  for (int a = 0; a < 4; ++a)
    if (__builtin_mul_overflow(l.total_bytes, sizes[a], &l.total_bytes))
      throw VolumeError(path, "sizes overflow 64-bit byte count");
  l.encoding = n.payload.encoding;
  l.line_skip = n.line_skip;
  l.byte_skip = n.payload.byte_skip;
  n.payload.files = l.files;
  n.payload.byte_skip = 0;
  // Nothing of a data file is looked at before the files' places are checked.
  check_payload_files(path, n.payload, options);
  n.payload.parts = resolve_parts(path, l);
}

}  // namespace

// The `data file: <pattern> <min> <max> <step>` form names slices with a printf-style pattern.
// File text never reaches a format function: the pattern is parsed here and must hold exactly one
// integer conversion `%[flags][width]d` (or `i`; flags from "-+ 0#", width at most 32), with `%%` for
// a literal percent sign. Anything else is refused naming the pattern.
std::string format_name(const fs::path& file, const std::string& pattern, long long value) {
  auto refuse = [&](const std::string& why) {
    throw VolumeError(file, "data file pattern '" + pattern.substr(0, 200) + "': " + why +
                                " (allowed: one %d with optional flags and width, and %%)");
  };
  std::string prefix, suffix, flags;
  int width = 0;
  bool seen = false;
  for (size_t i = 0; i < pattern.size(); ++i) {
    std::string& out = seen ? suffix : prefix;
    if (pattern[i] != '%') {
      out += pattern[i];
      continue;
    }
    if (++i >= pattern.size()) refuse("ends in a lone %");
    if (pattern[i] == '%') {
      out += '%';
      continue;
    }
    if (seen) refuse("more than one conversion");
    while (i < pattern.size() && std::string("-+ 0#").find(pattern[i]) != std::string::npos) flags += pattern[i++];
    while (i < pattern.size() && std::isdigit(static_cast<unsigned char>(pattern[i]))) {
      width = width * 10 + (pattern[i++] - '0');
      if (width > 32) refuse("field width over 32");
    }
    if (i >= pattern.size() || (pattern[i] != 'd' && pattern[i] != 'i'))
      refuse("only the integer conversions %d and %i are allowed");
    seen = true;
  }
  if (!seen) refuse("no %d conversion");
  // Format the number ourselves: sign, zero or space padding, left alignment.
  const bool left = flags.find('-') != std::string::npos;
  const bool zero = !left && flags.find('0') != std::string::npos;
  std::string digits = std::to_string(value < 0 ? -(value + 1) + 1ull : static_cast<unsigned long long>(value));
  std::string sign = value < 0                              ? "-"
                     : flags.find('+') != std::string::npos ? "+"
                     : flags.find(' ') != std::string::npos ? " "
                                                            : "";
  std::string number;
  const size_t len = sign.size() + digits.size();
  if (size_t(width) > len) {
    const size_t pad = size_t(width) - len;
    number = left   ? sign + digits + std::string(pad, ' ')
             : zero ? sign + std::string(pad, '0') + digits
                    : std::string(pad, ' ') + sign + digits;
  } else {
    number = sign + digits;
  }
  return prefix + number + suffix;
}

std::vector<fs::path> pattern_files(const fs::path& header, const std::string& pattern, const std::string& min,
                                    const std::string& max, const std::string& step) {
  const long long lo = parse_int(header, "data file", min), hi = parse_int(header, "data file", max);
  const long long by = parse_int(header, "data file", step);
  if (by == 0 || (hi - lo) / by < 0 || (hi - lo) / by > 1000000)
    throw VolumeError(header, "data file pattern: bad range " + min + " " + max + " " + step);
  std::vector<fs::path> files;
  for (long long i = lo; by > 0 ? i <= hi : i >= hi; i += by)
    files.push_back(header.parent_path() / format_name(header, pattern, i));
  return files;
}

Volume read_nrrd(const fs::path& path, const LoadOptions& options) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw VolumeError(path, "cannot open");
  std::string line;
  std::getline(in, line);
  if (line.rfind("NRRD000", 0) != 0) throw VolumeError(path, "not a NRRD file (no NRRD000x magic)");
  NrrdHeader n = read_nrrd_header(path, in);
  check_nrrd_fields(path, n);
  in.close();
  locate_nrrd_data(path, n, options);
  if (n.dimension == 3) return read_payload(path, n.h, n.payload, options);
  return read_time_point(path, n.h, n.times, n.payload, options);
}

}  // namespace peakcast::detail
