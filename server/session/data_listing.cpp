#include "session/data_listing.h"

#include <algorithm>
#include <fstream>
#include <map>

#include "chunked/chunked_volume.h"
#include "core/dicom.h"
#include "core/volume_io.h"

namespace fs = std::filesystem;

namespace peakcast {
namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}

bool is_header(const std::string& ext) { return ext == ".nrrd" || ext == ".nhdr" || ext == ".mhd" || ext == ".mha"; }
bool is_tiff(const std::string& ext) { return ext == ".tif" || ext == ".tiff"; }

// Raw voxels are a volume with their JSON sidecar (`<file>.json` or `<stem>.json`) only; a .raw
// beside a header is that header's data.
bool raw_with_sidecar(const fs::path& p) {
  std::error_code ec;
  for (const fs::path& s : {fs::path(p.string() + ".json"), fs::path(p).replace_extension(".json")}) {
    if (!fs::is_regular_file(s, ec) || fs::file_size(s, ec) > (1u << 20) || ec) continue;
    std::ifstream in(s);
    nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
    if (j.is_object() && j.contains("dims")) return true;
  }
  return false;
}

// What a folder opens as: a chunked volume (OME-Zarr, Neuroglancer precomputed), TIFF slices
// without a header, or exactly one header.
bool opens_as_stack(const fs::path& dir) {
  if (chunked::is_chunked_volume(dir)) return true;
  std::error_code ec;
  int headers = 0;
  bool tiffs = false;
  size_t seen = 0;  // a folder of a million chunks is told by its first entries
  for (auto it = fs::directory_iterator(dir, ec); !ec && it != fs::directory_iterator() && seen < 4096;
       it.increment(ec), ++seen) {
    const std::string x = lower(it->path().extension().string());
    tiffs |= is_tiff(x);
    headers += is_header(x);
  }
  return (tiffs && headers == 0) || (!tiffs && headers == 1);
}

// A folder of DICOM slices: one entry per series (its description, modality and size), the
// path naming the series (FOLDER#UID) when the folder holds several. Empty when none is found.
std::vector<nlohmann::json> dicom_entries(const fs::path& dir, const std::string& name, const std::string& path) {
  std::vector<dicom::SeriesSummary> series;
  try {
    series = dicom::list_series(dir);
  } catch (const VolumeError&) {
    return {};  // too many files, unreadable: listed as a folder
  }
  std::vector<nlohmann::json> out;
  for (const dicom::SeriesSummary& s : series) {
    const bool one = series.size() == 1;
    nlohmann::json e = {{"name", one ? name : name + "#" + (s.description.empty() ? s.uid : s.description)},
                        {"path", one ? path : path + "#" + s.uid},
                        {"kind", "volume"},
                        {"format", "dicom"},
                        {"bytes", 0},
                        {"dims", {s.cols, s.rows, s.slices}},
                        {"modality", s.modality},
                        {"description", s.description}};
    out.push_back(std::move(e));
  }
  return out;
}

}  // namespace

nlohmann::json list_data_dir(const std::vector<fs::path>& roots, const std::string& dir, size_t max_entries) {
  if (fs::path(dir).is_absolute()) throw VolumeError(dir, "name a folder relative to the data directories");
  if (dir.find('\0') != std::string::npos) throw VolumeError("dir", "a folder name holds no NUL byte");
  // resolve_in_roots refuses what leaves the data directories (.., symlinks) and what is missing.
  const fs::path wanted = dir.empty() ? fs::path(".") : fs::path(dir);
  std::map<std::string, nlohmann::json> entries;  // by name: a folder in two roots is listed once
  bool found = false, truncated = false;
  for (const fs::path& root : roots) {
    fs::path folder;
    try {
      folder = resolve_in_roots(wanted, {root});
    } catch (const VolumeError&) {
      continue;
    }
    std::error_code ec;
    if (!fs::is_directory(folder, ec)) continue;
    found = true;
    const fs::path top = fs::weakly_canonical(root, ec);
    for (const auto& e : fs::directory_iterator(folder, ec)) {
      const std::string name = e.path().filename().string();
      if (name.empty() || name[0] == '.' || entries.count(name)) continue;
      // A link out of the data directories is not offered (opening it would be refused).
      const fs::path rel = fs::weakly_canonical(e.path(), ec).lexically_relative(top);
      if (ec || rel.empty() || *rel.begin() == "..") continue;
      const std::string ext = lower(e.path().extension().string());
      std::string kind;
      int64_t bytes = 0;
      const std::string path = dir.empty() ? name : (fs::path(dir) / name).lexically_normal().string();
      if (e.is_directory(ec) && dicom::is_dicom_folder(e.path())) {
        bool listed = false;
        for (nlohmann::json& s : dicom_entries(e.path(), name, path)) {
          if (entries.size() >= max_entries) {
            truncated = true;
            break;
          }
          const std::string key = s["name"].get<std::string>();  // before s is moved from
          entries[key] = std::move(s);
          listed = true;
        }
        if (truncated) break;
        if (listed) continue;  // else: no series found, a folder
      }
      if (e.is_directory(ec)) {
        kind = opens_as_stack(e.path()) ? "stack" : "folder";
      } else if (e.is_regular_file(ec)) {
        if (is_header(ext) || is_tiff(ext) || ((ext == ".raw" || ext == ".gz") && raw_with_sidecar(e.path())))
          kind = "volume";
        bytes = int64_t(e.file_size(ec));
      }
      if (kind.empty()) continue;
      if (entries.size() >= max_entries) {
        truncated = true;
        break;
      }
      entries[name] = {{"name", name}, {"path", path}, {"kind", kind}, {"bytes", bytes}};
    }
  }
  if (roots.empty()) throw VolumeError(dir, "no data directory is configured");
  if (!found) resolve_in_roots(wanted, roots);  // throws the reason: outside, or missing
  if (!found) throw VolumeError(dir, "not a folder in the data directories");
  nlohmann::json list = nlohmann::json::array();
  for (int folders = 1; folders >= 0; --folders)
    for (auto& [_, e] : entries)
      if ((e["kind"] != "volume") == bool(folders)) list.push_back(e);
  return {{"dir", fs::path(dir).lexically_normal().string()}, {"entries", list}, {"truncated", truncated}};
}

}  // namespace peakcast
