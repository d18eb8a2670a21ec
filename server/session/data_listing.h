// What the data directories offer a viewer (GET /api/files, docs/rest.md): one folder at a time,
// the volumes it can open and the folders to look into, by names relative to the data
// directories: no server path is ever shown.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace peakcast {

// {"dir": dir, "entries": [{"name", "path", "kind", "bytes"}...], "truncated": bool}, entries
// sorted by name, folders first. kind: "volume" (a file load_volume opens: NRRD, MetaImage, TIFF,
// raw with its JSON sidecar), "stack" (a folder that opens as one volume: TIFF slices, a
// single header, a chunked pyramid), "folder" (one to look into). `path` is what to open or list next. Throws
// VolumeError for a folder outside the data directories, a missing one, or none configured.
nlohmann::json list_data_dir(const std::vector<std::filesystem::path>& roots, const std::string& dir,
                             size_t max_entries = 1000);

}  // namespace peakcast
