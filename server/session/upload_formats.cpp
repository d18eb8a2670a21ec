#include "session/upload_formats.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <vector>

#include "core/length_unit.h"
#include "core/utf8.h"
#include "core/volume_io.h"
#include "session/upload_store.h"

namespace fs = std::filesystem;

namespace peakcast {
namespace {

constexpr size_t kSniffBytes = 64 * 1024;        // a header must be within this
constexpr size_t kMultipartHeadBytes = 1 << 20;  // the parts before the data, with their headers

UploadRefusal bad(const std::string& message) { return UploadRefusal(400, "bad_upload", message); }
UploadRefusal unsupported(const std::string& message) { return UploadRefusal(415, "unsupported_upload", message); }

std::string head_of(const fs::path& file, size_t n) {
  std::ifstream in(file, std::ios::binary);
  std::string s(n, '\0');
  in.read(s.data(), std::streamsize(n));
  s.resize(size_t(in.gcount()));
  return s;
}

std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// The header lines of a text header (NRRD, MetaImage): up to the first blank line when
// `to_blank` (NRRD's header ends there), else every line of the head (a MetaImage reader reads
// past blank lines and comments).
std::vector<std::string> header_lines(const std::string& head, bool to_blank = true) {
  std::vector<std::string> out;
  size_t i = 0;
  while (i < head.size()) {
    size_t e = head.find('\n', i);
    if (e == std::string::npos) e = head.size();
    std::string line = head.substr(i, e - i);
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() && to_blank) break;
    out.push_back(line);
    i = e + 1;
  }
  return out;
}

// A key as the readers compare it: lower case, without any white space ("Data File " -> "datafile").
std::string squeezed(const std::string& key) {
  std::string out;
  for (char c : key)
    if (!std::isspace(static_cast<unsigned char>(c))) out += char(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

bool is_metaimage(const std::string& head) {
  static const char* keys[] = {"objecttype", "ndims", "comment", "transformtype", "dimsize", "elementtype"};
  const auto lines = header_lines(head);
  if (lines.empty()) return false;
  const auto eq = lines[0].find('=');
  if (eq == std::string::npos) return false;
  const std::string key = squeezed(lines[0].substr(0, eq));
  return std::find(std::begin(keys), std::end(keys), key) != std::end(keys);
}

}  // namespace

const char* extension_of(UploadFormat f) {
  switch (f) {
    case UploadFormat::Nrrd: return ".nrrd";
    case UploadFormat::MetaImage: return ".mha";
    case UploadFormat::Tiff: return ".tif";
    case UploadFormat::Raw: return ".raw";
    case UploadFormat::DicomZip: return ".dcm";
  }
  return ".raw";
}

UploadFormat sniff_upload(const fs::path& file, bool raw_header_given) {
  if (raw_header_given) return UploadFormat::Raw;  // the request said what the bytes are
  const std::string head = head_of(file, kSniffBytes);
  if (head.rfind("NRRD000", 0) == 0) {
    for (const std::string& line : header_lines(head)) {
      const auto colon = line.find(':');
      if (colon == std::string::npos || line.compare(colon, 2, ":=") == 0) continue;  // key/value pairs
      if (squeezed(line.substr(0, colon)) == "datafile")
        throw unsupported(
            "a detached NRRD header names another file (its 'data file' field): an upload is one "
            "file, send the .nrrd with its data attached");
    }
    return UploadFormat::Nrrd;
  }
  if (head.size() >= 4 &&
      (head.compare(0, 4, std::string("II*\0", 4)) == 0 || head.compare(0, 4, std::string("MM\0*", 4)) == 0 ||
       head.compare(0, 4, std::string("II+\0", 4)) == 0))
    return UploadFormat::Tiff;
  if (head.size() >= 4 && (head.compare(0, 4, "PK\x03\x04") == 0 || head.compare(0, 4, "PK\x05\x06") == 0))
    return UploadFormat::DicomZip;  // a ZIP: of a DICOM series' slices (refused by the reader when it is not)
  if (is_metaimage(head)) {
    for (const std::string& line : header_lines(head, false)) {
      const auto eq = line.find('=');
      if (eq == std::string::npos || squeezed(line.substr(0, eq)) != "elementdatafile") continue;
      std::string value = line.substr(eq + 1);
      value.erase(0, value.find_first_not_of(" \t"));
      value.erase(value.find_last_not_of(" \t") + 1);
      if (lower(value) != "local")
        throw unsupported(
            "a MetaImage header whose data is in another file (ElementDataFile other than LOCAL) is "
            "not one file: send an .mha (ElementDataFile = LOCAL)");
      break;  // the last field: the voxels follow
    }
    return UploadFormat::MetaImage;
  }
  throw unsupported(
      "the body is neither NRRD (data attached), MetaImage (.mha), TIFF, a ZIP of a DICOM series, nor raw "
      "voxels with their header (dims and dtype as query parameters or a JSON part)");
}

nlohmann::json raw_sidecar(const nlohmann::json& h, const std::string& data_file) {
  if (!h.is_object()) throw bad("the raw header must be a JSON object");
  static const char* known[] = {"dims", "dtype", "spacing", "origin", "endian", "units", "times"};
  for (auto& [key, _] : h.items())
    if (std::find(std::begin(known), std::end(known), key) == std::end(known))
      throw bad("raw header: unknown key '" + key.substr(0, 40) +
                "' (dims, dtype, spacing, origin, endian, units, times)");
  auto triple = [&](const char* key, bool positive_int) {
    const auto& v = h.at(key);
    if (!v.is_array() || v.size() != 3) throw bad(std::string("raw header: ") + key + " must be 3 numbers");
    for (const auto& x : v) {
      if (!x.is_number() || !std::isfinite(x.get<double>()))
        throw bad(std::string("raw header: ") + key + " must be 3 finite numbers");
      if (positive_int && (!x.is_number_integer() || x.get<int64_t>() < 1))
        throw bad(std::string("raw header: ") + key + " must be 3 integers >= 1");
    }
    return v;
  };
  if (!h.contains("dims") || !h.contains("dtype")) throw bad("raw voxels need their header: dims and dtype");
  nlohmann::json out = {{"dims", triple("dims", true)}, {"data_file", data_file}};
  static const char* dtypes[] = {"uint8", "int8", "uint16", "int16", "float32"};
  if (!h["dtype"].is_string() ||
      std::find(std::begin(dtypes), std::end(dtypes), h["dtype"].get<std::string>()) == std::end(dtypes))
    throw bad("raw header: dtype must be uint8, int8, uint16, int16 or float32");
  out["dtype"] = h["dtype"];
  if (h.contains("spacing")) {
    out["spacing"] = triple("spacing", false);
    for (const auto& x : out["spacing"])
      if (!(x.get<double>() > 0)) throw bad("raw header: spacing must be > 0");
  }
  if (h.contains("origin")) out["origin"] = triple("origin", false);
  {  // the scale a volume draws right at: refused here, before any voxel is sent
    glm::dvec3 spacing{1.0}, origin{0.0};
    for (int a = 0; a < 3; ++a) {
      if (out.contains("spacing")) spacing[a] = out["spacing"][a].get<double>();
      if (out.contains("origin")) origin[a] = out["origin"][a].get<double>();
    }
    if (const std::string why = spacing_refusal(spacing, origin); !why.empty()) throw bad("raw header: " + why);
  }
  if (h.contains("units")) {  // one unit of length for the three axes
    if (!h["units"].is_string()) throw bad("raw header: units must be a unit of length such as um or mm");
    try {
      out["units"] = length_symbol(h["units"].get<std::string>(), "raw header: units");
    } catch (const std::invalid_argument& e) {
      throw bad(e.what());
    }
  }
  if (h.contains("times")) {  // a time series: that many volumes of dims, one after another
    if (!h["times"].is_number_integer() || h["times"].get<int64_t>() < 1 || h["times"].get<int64_t>() > 1000000)
      throw bad("raw header: times must be an integer from 1 to 1000000 (time points)");
    out["times"] = h["times"];
  }
  if (h.contains("endian")) {
    if (h["endian"] != "little" && h["endian"] != "big") throw bad("raw header: endian must be little or big");
    out["endian"] = h["endian"];
  }
  return out;
}

void check_raw_body(const nlohmann::json& sidecar, int64_t body_bytes) {
  static const std::pair<const char*, int64_t> sizes[] = {
      {"uint8", 1}, {"int8", 1}, {"uint16", 2}, {"int16", 2}, {"float32", 4}};
  int64_t per = 0;
  for (const auto& [name, n] : sizes)
    if (sidecar.at("dtype") == name) per = n;
  int64_t need = per;
  std::string dims;
  for (const auto& d : sidecar.at("dims")) {
    const int64_t n = d.get<int64_t>();
    if (n < 2)
      throw bad("raw header: every axis of a volume needs at least 2 voxels (dims " + json_text(sidecar.at("dims")) +
                ")");
    if (__builtin_mul_overflow(need, n, &need)) throw bad("raw header: dims overflow a 64-bit size");
    dims += (dims.empty() ? "" : "x") + std::to_string(n);
  }
  if (const int64_t times = sidecar.value("times", int64_t(1)); times > 1) {
    if (__builtin_mul_overflow(need, times, &need)) throw bad("raw header: dims overflow a 64-bit size");
    dims += " x " + std::to_string(times) + " time points";
  }
  if (need != body_bytes)
    throw bad("raw voxels: dims " + dims + " of " + sidecar.at("dtype").get<std::string>() + " need " +
              std::to_string(need) + " bytes; the body holds " + std::to_string(body_bytes));
}

std::string clean_upload_name(const std::string& name) {
  std::string printable;
  for (char c : name)
    if (static_cast<unsigned char>(c) >= 0x20 && c != 0x7f) printable += c;
  std::string out = clean_utf8(printable, limits::kMaxUploadNameLength);
  return out.empty() ? "upload" : out;
}

MultipartUpload split_multipart(const fs::path& file, const std::string& content_type, const fs::path& data_out) {
  std::string boundary;
  if (auto b = content_type.find("boundary="); b != std::string::npos) {
    boundary = content_type.substr(b + 9);
    boundary = boundary.substr(0, boundary.find(';'));
    if (boundary.size() >= 2 && boundary.front() == '"') boundary = boundary.substr(1, boundary.size() - 2);
  }
  if (boundary.empty() || boundary.size() > 200) throw bad("multipart/form-data without a boundary");
  const std::string delim = "--" + boundary, next = "\r\n" + delim;
  const std::string head = head_of(file, kMultipartHeadBytes);
  size_t pos = head.find(delim);
  if (pos == std::string::npos) throw bad("multipart body without its boundary");
  MultipartUpload out;
  for (;;) {
    pos += delim.size();
    if (head.compare(pos, 2, "--") == 0) throw bad("multipart body without a data part");
    if (head.compare(pos, 2, "\r\n") != 0) throw bad("malformed multipart body");
    const size_t headers_end = head.find("\r\n\r\n", pos);
    if (headers_end == std::string::npos) throw bad("multipart part headers too long or cut");
    const std::string headers = lower(head.substr(pos + 2, headers_end - pos - 2));
    auto param = [&](const std::string& key) -> std::optional<std::string> {
      const auto k = headers.find(key + "=\"");
      if (k == std::string::npos) return std::nullopt;
      const auto s = k + key.size() + 2, e = headers.find('"', s);
      return headers.substr(s, e - s);
    };
    const std::string name = param(" name").value_or(param(";name").value_or(""));
    const size_t content = headers_end + 4;
    if (name == "header") {
      const size_t end = head.find(next, content);
      if (end == std::string::npos) throw bad("the JSON part is too large or the body cut");
      try {
        out.header = nlohmann::json::parse(head.substr(content, end - content));
      } catch (const nlohmann::json::exception& e) {
        throw bad(std::string("the JSON part is not JSON: ") + e.what());
      }
      pos = end + 2;
      continue;
    }
    // The data: the rest of the body up to the closing delimiter, found from the end.
    out.filename = param("filename").value_or("");
    const auto size = fs::file_size(file);
    const size_t tail_n = size_t(std::min<uintmax_t>(size, 4096));
    std::ifstream in(file, std::ios::binary);
    std::string tail(tail_n, '\0');
    in.seekg(std::streamoff(size - tail_n));
    in.read(tail.data(), std::streamsize(tail_n));
    const size_t close = tail.rfind(next);
    if (close == std::string::npos || size - tail_n + close < content)
      throw bad("multipart body cut: no closing boundary");
    const uintmax_t end = size - tail_n + close;
    if (tail.find(next, close + 1) != std::string::npos || tail.compare(close + next.size(), 2, "--") != 0)
      throw bad("multipart data must be the last part (the JSON 'header' part first)");
    std::ofstream o(data_out, std::ios::binary | std::ios::trunc);
    in.clear();
    in.seekg(std::streamoff(content));
    std::vector<char> buf(1 << 20);
    for (uintmax_t left = end - content; left > 0;) {
      const auto n = std::streamsize(std::min<uintmax_t>(left, buf.size()));
      in.read(buf.data(), n);
      if (in.gcount() != n) throw bad("multipart body cut");
      o.write(buf.data(), n);
      left -= uintmax_t(n);
    }
    if (!o) throw UploadRefusal(507, "upload_failed", "the upload could not be written on the server");
    in.close();
    fs::remove(file);
    return out;
  }
}

}  // namespace peakcast
