// DICOM series through GDCM: the slice headers by gdcm::Scanner (only the tags named here are
// kept: no identifier is read into anything), the pixels by gdcm::ImageReader (which decodes the
// compressed transfer syntaxes Debian's GDCM carries: JPEG, JPEG-LS, JPEG 2000, RLE).
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <mutex>
#include <sstream>

#include <gdcmImageReader.h>
#include <gdcmScanner.h>
#include <gdcmTrace.h>

#include "core/dicom.h"
#include "core/dicom_pixels.h"
#include "core/file_roots.h"

namespace fs = std::filesystem;

namespace peakcast::dicom {
namespace {

const gdcm::Tag kSeriesUid(0x0020, 0x000e), kDescription(0x0008, 0x103e), kModality(0x0008, 0x0060),
    kPosition(0x0020, 0x0032), kOrientation(0x0020, 0x0037), kPixelSpacing(0x0028, 0x0030), kThickness(0x0018, 0x0050),
    kRows(0x0028, 0x0010), kCols(0x0028, 0x0011), kFrames(0x0028, 0x0008), kSamples(0x0028, 0x0002),
    kBitsAllocated(0x0028, 0x0100), kBitsStored(0x0028, 0x0101), kPixelRepresentation(0x0028, 0x0103),
    kPhotometric(0x0028, 0x0004), kIntercept(0x0028, 0x1052), kSlope(0x0028, 0x1053);

constexpr size_t kMaxFiles = 100000;

// GDCM's own messages can quote what a file holds: they never reach the log.
void quiet() {
  static std::once_flag once;
  std::call_once(once, [] {
    gdcm::Trace::SetDebug(false);
    gdcm::Trace::SetWarning(false);
    gdcm::Trace::SetError(false);
  });
}

std::string text(const gdcm::Scanner& s, const std::string& file, const gdcm::Tag& t) {
  const char* v = s.GetValue(file.c_str(), t);
  if (!v) return "";
  std::string out(v);
  while (!out.empty() && (out.back() == ' ' || out.back() == '\0')) out.pop_back();
  while (!out.empty() && out.front() == ' ') out.erase(out.begin());
  return out;
}

// A DICOM multi-valued decimal string ("1.5\2.5\-3"): its numbers, or none when any is not one.
std::vector<double> numbers(const std::string& s) {
  std::vector<double> out;
  std::stringstream in(s);
  std::string part;
  while (std::getline(in, part, '\\')) {
    char* end = nullptr;
    const double v = std::strtod(part.c_str(), &end);
    if (end == part.c_str() || !std::isfinite(v)) return {};
    out.push_back(v);
  }
  return out;
}

double number(const std::string& s, double fallback) {
  const std::vector<double> v = numbers(s);
  return v.size() == 1 ? v[0] : fallback;
}

std::vector<std::string> slice_files(const fs::path& dir) {
  std::vector<std::string> files;
  std::error_code ec;
  for (auto it = fs::directory_iterator(dir, ec); !ec && it != fs::directory_iterator(); it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.empty() || name[0] == '.' || !it->is_regular_file(ec)) continue;
    if (files.size() >= kMaxFiles)
      throw VolumeError(dir, "more than " + std::to_string(kMaxFiles) + " files: not read as one DICOM series");
    files.push_back(it->path().string());
  }
  if (ec) throw VolumeError(dir, "cannot list the folder");
  std::sort(files.begin(), files.end());
  return files;
}

SliceHeader slice_header(const gdcm::Scanner& s, const std::string& f) {
  SliceHeader h;
  h.file = f;
  h.series_uid = text(s, f, kSeriesUid);
  h.description = text(s, f, kDescription);
  h.modality = text(s, f, kModality);
  if (const auto p = numbers(text(s, f, kPosition)); p.size() == 3) {
    h.has_position = true;
    h.position = {p[0], p[1], p[2]};
  }
  if (const auto o = numbers(text(s, f, kOrientation)); o.size() == 6) {
    h.has_orientation = true;
    h.row = {o[0], o[1], o[2]};
    h.col = {o[3], o[4], o[5]};
  }
  if (const auto sp = numbers(text(s, f, kPixelSpacing)); sp.size() == 2 && sp[0] > 0 && sp[1] > 0) {
    h.has_spacing = true;
    h.row_spacing = sp[0];
    h.col_spacing = sp[1];
  }
  h.thickness = number(text(s, f, kThickness), 0.0);
  h.rows = int(number(text(s, f, kRows), 0));
  h.cols = int(number(text(s, f, kCols), 0));
  h.frames = int(number(text(s, f, kFrames), 1));
  h.samples = int(number(text(s, f, kSamples), 1));
  h.bits_allocated = int(number(text(s, f, kBitsAllocated), 0));
  h.bits_stored = int(number(text(s, f, kBitsStored), h.bits_allocated));
  h.is_signed = number(text(s, f, kPixelRepresentation), 0) == 1;
  h.monochrome1 = text(s, f, kPhotometric) == "MONOCHROME1";
  h.slope = number(text(s, f, kSlope), 1.0);
  h.intercept = number(text(s, f, kIntercept), 0.0);
  return h;
}

// Every DICOM file of the folder that names a series, by series UID.
std::map<std::string, std::vector<SliceHeader>> scan(const fs::path& dir) {
  quiet();
  const std::vector<std::string> files = slice_files(dir);
  for (const std::string& f : files) file_roots::check(f);
  gdcm::Scanner s;
  for (const gdcm::Tag& t :
       {kSeriesUid, kDescription, kModality, kPosition, kOrientation, kPixelSpacing, kThickness, kRows, kCols, kFrames,
        kSamples, kBitsAllocated, kBitsStored, kPixelRepresentation, kPhotometric, kIntercept, kSlope})
    s.AddTag(t);
  s.Scan(files);
  std::map<std::string, std::vector<SliceHeader>> series;
  for (const std::string& f : files) {
    if (!s.IsKey(f.c_str())) continue;  // not DICOM, or not readable as it
    SliceHeader h = slice_header(s, f);
    if (h.series_uid.empty() || h.rows <= 0 || h.cols <= 0) continue;  // a DICOMDIR, a report: no image
    series[h.series_uid].push_back(std::move(h));
  }
  return series;
}

SeriesSummary summary(const std::vector<SliceHeader>& slices) {
  const SliceHeader& a = slices.front();
  return {a.series_uid, a.description, a.modality, int64_t(slices.size()), a.rows, a.cols};
}

std::string described(const SeriesSummary& s) {
  return "'" + (s.description.empty() ? std::string("(no description)") : s.description) + "' (" + s.uid + ", " +
         std::to_string(s.slices) + " slices)";
}

// The series the path names among those found: by UID, else by description (which must be one).
const std::vector<SliceHeader>& choose(const fs::path& dir, const std::string& wanted,
                                       const std::map<std::string, std::vector<SliceHeader>>& series) {
  if (series.empty()) throw VolumeError(dir, "no DICOM image slices in this folder");
  std::string names;
  for (const auto& [uid, slices] : series) names += (names.empty() ? "" : ", ") + described(summary(slices));
  if (wanted.empty()) {
    if (series.size() == 1) return series.begin()->second;
    throw VolumeError(dir, std::to_string(series.size()) + " DICOM series in this folder: open one as FOLDER#UID or " +
                               "FOLDER#DESCRIPTION: " + names);
  }
  if (auto it = series.find(wanted); it != series.end()) return it->second;
  const std::vector<SliceHeader>* found = nullptr;
  for (const auto& [uid, slices] : series)
    if (slices.front().description == wanted) {
      if (found) throw VolumeError(dir, "several series are described '" + wanted + "': name one by UID: " + names);
      found = &slices;
    }
  if (!found) throw VolumeError(dir, "no series '" + wanted + "' in this folder: " + names);
  return *found;
}

}  // namespace

bool is_dicom_folder(const fs::path& dir) {
  std::error_code ec;
  int looked = 0;
  for (auto it = fs::directory_iterator(dir, ec); !ec && it != fs::directory_iterator() && looked < 16;
       it.increment(ec)) {
    if (!it->is_regular_file(ec) || it->path().filename().string().front() == '.') continue;
    ++looked;
    try {
      file_roots::check(it->path());  // a link out of the data directories is not looked into
    } catch (const VolumeError&) {
      continue;
    }
    char mark[4] = {};
    FILE* f = std::fopen(it->path().c_str(), "rb");
    if (!f) continue;
    const bool ok = std::fseek(f, 128, SEEK_SET) == 0 && std::fread(mark, 1, 4, f) == 4;
    std::fclose(f);
    if (ok && std::memcmp(mark, "DICM", 4) == 0) return true;
  }
  return false;
}

std::vector<SeriesSummary> list_series(const fs::path& dir) {
  std::vector<SeriesSummary> out;
  for (const auto& [uid, slices] : scan(dir)) out.push_back(summary(slices));
  return out;
}

Volume read_series(const fs::path& path, const LoadOptions& options) {
  const SeriesPath sp = split_series_path(path);
  std::error_code ec;
  if (!fs::is_directory(sp.folder, ec)) throw VolumeError(sp.folder, "no such DICOM folder");
  const auto series = scan(sp.folder);
  const std::vector<SliceHeader>& slices = choose(sp.folder, sp.series, series);
  const SeriesGeometry g = order_slices(sp.folder, slices);
  Volume v = read_pixels(sp.folder, slices, g, options);
  const SliceHeader& a = slices.front();
  v.modality = a.modality;
  v.description = a.description;
  if (a.modality == "CT") v.value_unit = "HU";
  return v;
}

}  // namespace peakcast::dicom
