// What an uploaded body is: its format found from its first bytes (NRRD with attached data,
// MetaImage .mha with LOCAL data, TIFF, or raw voxels whose header came with the request), and a
// multipart/form-data body taken apart into its JSON header and its data. A header that names
// another file (a detached NRRD, an .mhd) is refused: an upload is one file, and the server
// never opens a path a client chose.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

namespace peakcast {

// DicomZip: a ZIP of a DICOM series' slices, kept as a folder of them (session/upload_zip.h).
enum class UploadFormat { Nrrd, MetaImage, Tiff, Raw, DicomZip };
const char* extension_of(UploadFormat f);  // ".nrrd", ".mha", ".tif", ".raw", ".dcm" (a folder)

// Throws UploadRefusal (415) for a body of no known format, or a header naming another file.
UploadFormat sniff_upload(const std::filesystem::path& file, bool raw_header_given);

// A multipart/form-data body in `file` (boundary from `content_type`): the part named "header"
// (JSON) if any, and the data: the part named "data" or "file", or the only other part. The
// data is moved into `data_out`; `file` is removed. Throws UploadRefusal (400) naming what is
// wrong.
struct MultipartUpload {
  std::optional<nlohmann::json> header;
  std::string filename;  // the data part's filename, if it had one
};
MultipartUpload split_multipart(const std::filesystem::path& file, const std::string& content_type,
                                const std::filesystem::path& data_out);

// The raw header of query parameters or a JSON part, checked: dims (3 positive integers), dtype
// (uint8, int8, uint16, int16, float32), optional spacing and origin (3 numbers), endian. The
// sidecar the raw reader takes, pointing at `data_file`. Throws UploadRefusal (400).
nlohmann::json raw_sidecar(const nlohmann::json& header, const std::string& data_file);
// Raw voxels: the body holds exactly what the sidecar's dims and dtype need, and every axis has at
// least 2 voxels (a volume that can never render is not kept). Throws UploadRefusal (400) naming
// both sizes.
void check_raw_body(const nlohmann::json& sidecar, int64_t body_bytes);

// An upload's name as kept and shown: UTF-8 (bad bytes replaced), no control characters, at most
// limits::kMaxUploadNameLength bytes cut at a character boundary; "upload" when nothing is left.
std::string clean_upload_name(const std::string& name);

}  // namespace peakcast
